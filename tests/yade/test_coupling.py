"""The YADE path on the quick-sand scene: rest, inflow, water balance, dry scenes, outputs."""
import json
import os

import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing: make test installs it)

from engines.compiled.water_model import WaterModel
from engines.model import pore_water
from engines.run import scene as scenes
from engines.run.runner import run_scene
from engines.yade.coupling import YadeCoupling, simulate
from engines.yade.deposition import deposit, scene_packing


@pytest.fixture(scope="module")
def packing():
    return scene_packing(scenes.preset("quicksand_case1"))


def test_bodies_have_per_unit_thickness_mass(packing):
    from yade import O
    sc = scenes.preset("quicksand_case1")
    YadeCoupling(sc, packing)
    i = int(np.flatnonzero(packing.mobile)[0])
    m = sc.material.rho * packing.density_factor[i] * np.pi * packing.r[i] ** 2
    assert O.bodies[i].state.mass == pytest.approx(m, rel=1e-12)
    assert O.bodies[i].state.inertia[1] == pytest.approx(0.5 * m * packing.r[i] ** 2, rel=1e-12)


def test_inflow_lifts_the_bed_and_raises_the_bottom_pressure_first(packing):
    """§5.2, Fig. 21: with inflow the bottom block's pressure rises at once and leads the surface
    block, bounded by E_w (eq 32), and the water gained is the inflow less the surface outflow
    (the budget closes to round-off). Without inflow the same deposit stays put: its pressures and
    displacements are a small fraction (< 5 %) of those the inflow causes in the same time."""
    n = 2000
    wet = simulate(scenes.preset("quicksand_case1"), packing, n, 500)
    still = simulate(scenes.preset("quicksand_case1", {"water": {"q_w": 0.0}}), packing, n, 500)
    t, xz, U, water, err = wet.arrays()
    assert np.all(U[:, 0] > U[:, 1]) and np.all(U[:, 0] > 0)
    assert np.all(U < scenes.preset("quicksand_case1").water.E_w)
    assert water[-1] > water[0] and err.max() < 1e-11
    _, xz0, U0, _, err0 = still.arrays()
    moved = np.abs(xz[-1] - packing.xz).max()
    assert np.abs(xz0[-1] - packing.xz).max() < 0.05 * moved
    assert np.nanmax(np.abs(U0)) < 0.05 * U[-1, 0]
    assert err0.max() < 1e-12


def test_a_dry_scene_runs_no_water_code(packing, monkeypatch):
    def forbidden(*a, **k):
        raise AssertionError("water code ran in a dry scene")
    monkeypatch.setattr(pore_water.PoreWater, "advance", forbidden)
    monkeypatch.setattr(pore_water.PoreWater, "__init__", forbidden)
    sc = scenes.preset("quicksand_case1", {"water": {"enabled": False}})
    traj = simulate(sc, packing, 500, 500)
    assert np.all(np.isnan(traj.arrays()[2]))


def test_run_scene_outputs_and_a_failed_run_keeps_history(packing, tmp_path, monkeypatch):
    sc = scenes.preset("quicksand_case1", {"output": {"snapshot_times": [0.0, 0.001], "history_interval": 50}})
    summary = run_scene(sc, packing, str(tmp_path / "ok"), duration=0.001)
    for name in ("history.csv", "summary.json", "pressure_blocks.png", "snapshots.png", "history_panels.png"):
        assert os.path.exists(tmp_path / "ok" / name), name
    assert summary["steps"] == 1000 and summary["n_pores"] > 0
    assert json.load(open(tmp_path / "ok" / "summary.json"))["parameters"]["water"]["k1"] == 200.0
    # a run that crashes half way (here: at its first pore rebuild): history so far and a checkpoint remain
    def crash(self, xz, k=None):  # noqa: ARG001
        raise RuntimeError("simulated crash")
    monkeypatch.setattr(WaterModel, "rebuild", crash)
    # (3,000 steps: longer than SHORT_RUN, so through O.run as real runs go)
    bad = scenes.preset("quicksand_case1", {"numerics": {"rebuild_interval": 2500}, "output": {"history_interval": 50}})
    with pytest.raises(RuntimeError, match="simulated crash"):
        run_scene(bad, packing, str(tmp_path / "bad"), duration=0.003)
    rows = open(tmp_path / "bad" / "history.csv").read().strip().splitlines()
    assert len(rows) == 1 + 51  # rows at k = 0, 50, ..., 2500 (before step 2500 crashed)
    assert os.path.exists(tmp_path / "bad" / "failure_state.npz") and os.path.exists(tmp_path / "bad" / "checkpoint.npz")
    summary = json.load(open(tmp_path / "bad" / "summary.json"))
    assert "failed" in summary["status"] and summary["checkpoint"]["step"] == 0  # the one written at the start


def test_deposit():
    sc = scenes.preset("quicksand_case1", {"packing": {"source": "deposit", "n_particles": 12, "n_bottom": 8,
                                                       "n_side": 6, "settle_time": 0.05, "seed": 7}})
    pk = deposit(sc)
    mob = pk.mobile
    assert mob.sum() == 12 and (~mob).sum() == 8 + 2 * 5
    walls = pk.xz[~mob]
    assert np.all(pk.xz[mob, 0] > walls[:, 0].min()) and np.all(pk.xz[mob, 0] < walls[:, 0].max())
    assert np.all(pk.xz[mob, 1] > 0) and np.all(pk.density_factor[~mob] == 1)
    assert np.any(pk.density_factor[mob] == 5.0)


def test_deposit_against_flat_walls():
    """[walls] kind = "flat": the discs deposit against the flat walls at the wall discs' inner
    faces, not into the dips between wall discs: none past a face by more than the overlap their
    weight gives, the lowest resting on the bottom face."""
    sc = scenes.preset("quicksand_case1_flat", {"packing": {"source": "deposit", "n_particles": 30, "n_bottom": 8,
                                                            "n_side": 8, "settle_time": 0.05, "seed": 7}})
    pk = deposit(sc)
    m = pk.mobile
    faces = pk.inner_faces()
    (x, z), r = pk.xz[m].T, pk.r[m]
    sink = 1e-6  # [m]: 100x the overlap of the bed's weight on one contact (kn = 1.4e6 N/m)
    assert np.all(x - r > faces[2] - sink) and np.all(x + r < faces[3] + sink) and np.all(z - r > faces[1] - sink)
    assert (z - r).min() == pytest.approx(faces[1], abs=sink)
    dips = deposit(scenes.preset("quicksand_case1", {"packing": {
        "source": "deposit", "n_particles": 30, "n_bottom": 8, "n_side": 8, "settle_time": 0.05, "seed": 7}}))
    assert (dips.xz[dips.mobile, 1] - dips.r[dips.mobile]).min() < faces[1] - 10 * sink  # a disc in a dip
