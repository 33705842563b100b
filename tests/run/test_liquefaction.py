"""The seismic box in the engine: the driven base, the side walls on springs, the
drained side flux, the porosity window of the history, and the liquefaction script. Short runs."""
import json
import os
import re
import subprocess

import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing: make test installs it)

from engines import ROOT
from engines.compiled.water_model import WaterModel
from engines.model import ground_motion as gm
from engines.model import pores as pg
from engines.model.observe import box_window, porosity
from engines.model.pore_dem import disc_masses, water_model
from engines.model.pore_water import WaterBalance
from engines.run import scene as scenes
from engines.run.runner import run_scene
from engines.yade.coupling import YadeCoupling
from engines.yade.deposition import wall_box
from packing.packing import Packing
from postproc.run_files import read_history
from tests.oracles import base_history

R_W = 0.55e-3  # wall disc radius of the seismic box [m]


def preset(case, **tables):
    return scenes.preset(f"liquefaction_case{case}", tables or None)


def packing_of(sc):
    return Packing.load(sc.packing.file)


def walls_and_one_particle(particle_xz):
    """The seismic box's 47 wall discs (walls 10x denser) and one particle of radius 0.4 mm."""
    xz, group = wall_box(25, 12, R_W)
    return Packing(np.vstack([xz, particle_xz]), np.r_[np.full(len(xz), R_W), 0.4e-3], np.r_[group, pg.WALL_NONE],
                   np.r_[np.full(len(xz), 10.0), 1.0])


def run_recording(cp, n, every):
    """Run n steps and return the positions after every ``every`` steps (k = every, 2 every, ...)."""
    seen = []
    cp.schedule.set_output(every)
    cp.hooks.append(lambda c: seen.append(c.positions()) if c.step_index > 0 else None)
    cp.run(n)
    return np.array(seen)


@pytest.mark.parametrize("case,law", [(7, "paper"), (2, "paper"), (None, "yade")])
def test_driven_base_follows_the_integrated_input(case, law):
    """The bottom wall sits on the BaseMotion displacement u_k after every step k (El Centro and
    the cosine with the paper's law; the cosine with YADE's law on the quick-sand box)."""
    if law == "paper":
        sc = preset(case)
        pk = packing_of(sc)
    else:
        sc = scenes.preset("quicksand_case1", {"contact": {"law": "yade", "spring": "a"}, "water": {"enabled": False},
                                               "loading": {"type": "cosine", "amplitude": 15.0, "frequency": 50.0}})
        from engines.yade.deposition import scene_packing
        pk = scene_packing(sc)
    n, every = 400, 50
    cp = YadeCoupling(sc, pk)
    xs = run_recording(cp, n, every)
    t, a, v, u = base_history(gm.input_acceleration(sc.settings), sc.numerics.dt, n)
    bottom = pk.group == pg.WALL_BOTTOM
    moved = xs[:, bottom, 0] - pk.xz[bottom, 0]
    ulp = np.spacing(np.abs(pk.xz[:, 0]).max())  # round-off of a coordinate: x += v dt each step
    np.testing.assert_allclose(moved, np.repeat(u[every::every, None], bottom.sum(), axis=1), rtol=0, atol=n * ulp)
    assert np.abs(u).max() > 1e6 * n * ulp  # it moved
    np.testing.assert_array_equal(xs[:, bottom, 1], np.broadcast_to(pk.xz[bottom, 1], xs[:, bottom, 1].shape))
    assert cp.base_motion() == (a[-1], v[-1], u[-1])


def test_side_walls_on_springs_follow_their_ties():
    """With no particle touching them, the side columns move only through the ties of Fig. 27 on
    the shaken base: YADE's integration matches m x'' = tie forces (v += F/m dt, x += v dt, the tie
    velocities du/dt of the step) computed here with NumPy; z and the particle stay put (g = 0)."""
    pk = walls_and_one_particle([12 * R_W * 2, 5e-3])
    sc = preset(2, material={"g": 0.0})
    n = 300
    cp = YadeCoupling(sc, pk)
    xs = run_recording(cp, n, 1)
    ties, dt = cp.core.ties, sc.numerics.dt
    m = disc_masses(sc.settings, pk)[0]
    _, _, _, u = base_history(gm.input_acceleration(sc.settings), dt, n)
    x_prev, x, v = pk.xz[:, 0].copy(), pk.xz[:, 0].copy(), np.zeros(len(pk.r))
    side = ties.moving
    bottom = pk.group == pg.WALL_BOTTOM
    ulp = np.spacing(np.abs(pk.xz[:, 0]).max())
    for k in range(n):
        f = ties.forces(x, (x - x_prev) / dt)
        x_prev = x.copy()
        v[side] += f[side] / m[side] * dt
        x[side] += v[side] * dt
        x[bottom] = pk.xz[bottom, 0] + u[k + 1]
        np.testing.assert_allclose(xs[k, side, 0], x[side], rtol=0, atol=n * ulp)
    assert np.abs(x[side] - pk.xz[side, 0]).max() > 1e6 * n * ulp  # the columns did move
    np.testing.assert_array_equal(xs[-1, :, 1], pk.xz[:, 1])
    np.testing.assert_array_equal(xs[-1, -1], pk.xz[-1])


def test_a_particle_pushes_its_side_wall_out():
    """A particle pressed into a left-wall disc (no shaking) pushes that disc towards -x; the ties
    pull its neighbours along and the base corner stays put."""
    xz, group = wall_box(25, 12, R_W)
    col = np.flatnonzero(group == pg.WALL_LEFT)
    target = col[5]
    pk = walls_and_one_particle(xz[target] + [R_W + 0.4e-3 - 2e-6, 0.0])
    sc = preset(2, material={"g": 0.0}, loading={"type": "none"})
    cp = YadeCoupling(sc, pk)
    cp.run(200)
    dx = cp.positions()[:, 0] - pk.xz[:, 0]
    assert dx[target] < -1e-9 and dx[col[4]] < 0 and dx[col[6]] < 0
    assert dx[target] < dx[col[4]] and dx[target] < dx[col[6]]
    assert np.all(dx[pk.group == pg.WALL_BOTTOM] == 0.0) and np.all(dx[pk.group == pg.WALL_RIGHT] == 0.0)


def test_drained_side_flux_in_the_water_engine():
    """One compiled water step of case 3 at a uniform U0 > 0: the side outflow is
    dt sum k3 W U / E_w over the open pores touching a side wall (0 with undrained sides), the
    surface outflow the same with k1 over the surface pores, and the budget closes."""
    for case, k3 in ((3, 1e3), (1, 0.0)):
        sc = preset(case)
        pk = packing_of(sc)
        wm = water_model(sc.settings, pk, WaterModel)
        w, s = wm.water, sc.water
        A = pg.measure(w.net, pk.xz, pk.r).void_area
        U0 = 100.0
        w.W = A * s.E_w / (s.E_w - U0)
        w.balance = WaterBalance(initial=w.total_water())
        W0, dt = w.W.copy(), sc.numerics.dt
        wm.advance(dt, pk.xz)
        open_ = A > w.net.a_min
        side = (w.net.pore_touches["left"] | w.net.pore_touches["right"]) & open_
        assert side.sum() >= 10
        expected = dt * k3 * np.sum(W0[side] * U0) / s.E_w
        assert w.balance.side_outflow == pytest.approx(expected, rel=1e-9, abs=0.0)
        surface = w.net.pore_surface & open_
        assert w.balance.surface_outflow == pytest.approx(dt * s.k1 * np.sum(W0[surface] * U0) / s.E_w, rel=1e-9)
        assert w.balance_error() < 1e-14


def test_history_porosity_is_the_window_porosity_and_the_columns(tmp_path):
    """run_scene on the seismic box: the history's porosity is the void fraction of the fixed
    window (moved with the base), the base columns follow the input, the side-wall shifts are
    relative to the base."""
    sc = preset(1, output={"history_interval": 100, "snapshot_times": []})
    pk = packing_of(sc)
    run_scene(sc, pk, str(tmp_path), duration=3e-4)
    h = read_history(str(tmp_path / "history.csv"))
    for col in ["t", "porosity", "base_acc", "base_disp", "water_balance_error", "remesh_change"] + \
               [f"U_block{b}" for b in range(1, 7)]:
        assert col in h and np.all(np.isfinite(h[col])), col
    csv = 1e-8  # history.csv holds 9 significant digits
    win = box_window(pk, sc.output.porosity_window)
    assert h["porosity"][0] == pytest.approx(porosity(pk.xz[pk.mobile], pk.r[pk.mobile], win), rel=csv)
    t, a, v, u = base_history(gm.input_acceleration(sc.settings), sc.numerics.dt, 300)
    np.testing.assert_allclose(h["base_disp"], u[::100][:len(h["t"])], rtol=csv, atol=0)
    np.testing.assert_allclose(h["base_acc"], a[::100][:len(h["t"])], rtol=csv)
    assert np.all(np.abs(h["side_left_dx"]) < 2e-6) and np.any(h["side_left_dx"] != 0)  # about 1 µm by 0.3 ms


def yade_script(*args, cwd):
    return subprocess.run(["yade", "-n", "-x", os.path.join(ROOT, "yade_scripts/liquefaction.py"), *args], cwd=cwd,
                          env=dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg"), capture_output=True, text=True,
                          timeout=600)


def test_liquefaction_script_outputs(tmp_path):
    run = yade_script("--case", "1", "--duration", "2e-4", "--transfer", "conserving", "--out", "run", cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    out = tmp_path / "run"
    for name in ("history.csv", "summary.json", "blocks.png", "snapshots.png", "history_panels.png"):
        assert (out / name).exists(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 200 and summary["wall_seconds"] > 0
    assert summary["parameters"]["water"]["transfer"] == "conserving"
    assert summary["provenance"]["overrides"]["water"] == {"transfer": "conserving"}


@pytest.mark.parametrize("args,match", [(["--case", "8"], "--case"), (["--case", "1", "--dt", "1e-3"], "[numerics] dt"),
                                        (["--case", "2", "--transfer", "paper"], "--transfer")])
def test_liquefaction_script_refuses_in_one_line(tmp_path, capsys, args, match):
    from yade_scripts import liquefaction
    with pytest.raises(SystemExit) as ex:
        liquefaction.main(args + ["--out", str(tmp_path / "bad")])
    message = str(ex.value.code) if isinstance(ex.value.code, str) else capsys.readouterr().err
    assert ex.value.code != 0 and match in message and len(message.strip().splitlines()) == 1, message
    assert not (tmp_path / "bad").exists()


def test_tie_time_step_is_refused_before_the_run(tmp_path):
    """dt above sqrt(m_min / k's) of the side-wall ties: refused by preflight (one line naming
    ks_wall, nothing written) and by the engine at construction."""
    from engines.compiled.pore_dem import PoreDEM
    from engines.run.preflight import InputError, preflight
    sc = preset(1, contact={"ks_wall": 1e11})
    pk = packing_of(sc)
    side = np.isin(pk.group, [pg.WALL_LEFT, pg.WALL_RIGHT])   # the column discs that move on the ties
    limit = np.sqrt((sc.material.rho * pk.density_factor * np.pi * pk.r**2)[side].min() / 1e11)
    assert limit < sc.numerics.dt
    with pytest.raises(InputError, match=r"ks_wall = 1e\+11 N/m") as err:
        preflight(sc, pk, str(tmp_path / "out"))
    stated = [float(x) for x in re.findall(r"(\d[\d.]*(?:e[-+]?\d+)?) s\b", str(err.value))]
    assert "\n" not in str(err.value) and any(abs(x / limit - 1) < 5e-3 for x in stated), (limit, str(err.value))
    assert not (tmp_path / "out").exists()
    with pytest.raises(ValueError, match="side-wall ties"):
        PoreDEM(sc.settings, pk)
    assert limit * np.sqrt(10) > sc.numerics.dt
    preflight(preset(1, contact={"ks_wall": 1e10}), pk, str(tmp_path / "out"))  # a limit sqrt(10) x longer: accepted


def test_drainage_time_constants_of_small_networks():
    """yade_scripts/liquefaction_drainage.time_constants: one pore draining to the outside decays
    with tau = c / g_b; two equal pores joined by a throat g (no outlet) equalise with tau = c / 2g
    and keep their mean (no decaying mode)."""
    from types import SimpleNamespace

    from engines.model.pore_water import FlowState
    from yade_scripts.liquefaction_drainage import time_constants

    def water(conns, g, g_b, c):
        z = np.zeros(len(c))
        fl = FlowState(z, z, z, z, np.array(g, float), np.array(g_b, float), np.array(c, float))
        net = SimpleNamespace(throat_conns=np.array(conns, np.int64).reshape(-1, 2))
        return SimpleNamespace(net=net, flows=lambda A, lc: fl)

    assert time_constants(water([], [], [3e-7], [6e-10]), np.ones(1), None) == pytest.approx([2e-3])
    tau = time_constants(water([[0, 1]], [5e-7], [0.0, 0.0], [6e-10, 6e-10]), np.ones(2), None)
    assert tau == pytest.approx([6e-10 / (2 * 5e-7)])
