"""The quick-sand box with [walls] kind = "flat": YADE boxes in place of the wall discs, the pores
closed by them, their loads in history.csv; kind = "discs" as before. Short runs."""
import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing: make test installs it)

from engines.model import pores as pg
from engines.run import scene as scenes
from engines.run.runner import Run
from engines.yade.deposition import scene_packing
from postproc.run_files import read_history, read_snapshot, snapshot_files

WALL_COLUMNS = [f"wall_{w}_{part}" for w in ("bottom", "left", "right") for part in ("contact", "water")]
STEPS, EVERY = 400, 50


def quicksand(kind, law="yade"):
    return scenes.preset("quicksand_case1", {"contact": {"law": law, "spring": "b"}, "walls": {"kind": kind},
                                             "output": {"history_interval": EVERY, "snapshot_times": [0.0]}})


class MaxU:
    """Coupling hook: the largest U of the pores at each call."""

    def __init__(self):
        self.seen = []

    def __call__(self, cp):
        U = cp.water_engine.pressures() if cp.water_engine else cp.water_model.pressures(cp.positions())
        self.seen.append(float(U.max()))


def run(kind, out, figures=False, law="yade"):
    """A quick-sand run of STEPS steps; returns (the Run, max U of the pores at each history step)."""
    sc = quicksand(kind, law)
    r = Run(sc, scene_packing(sc), str(out), STEPS)
    max_U = MaxU()
    r.cp.hooks.insert(0, max_U)
    r.go(figures=figures)
    return r, np.array(max_U.seen)


def test_the_quick_sand_in_a_box_of_flat_walls_runs_physically(tmp_path):
    r, max_U = run("flat", tmp_path, figures=True)
    cp, sc = r.cp, r.scene
    summary = r.summarise("completed", [])
    assert summary["n_walls"] == 0 and len(cp.ids) == 45 and len(cp.wall_ids) == 3  # 45 spheres, 3 boxes
    assert summary["n_pores"] > 0 and summary["water_balance_error"] <= 1e-12
    assert len(max_U) == STEPS // EVERY + 1 and np.all(max_U <= sc.water.E_w)  # eq 32 at every history step
    xz = cp.positions()
    for wall in cp.flat_walls.values():  # no grain through a wall
        assert np.all(wall.gap(xz, 0.0) > 0)
    h = read_history(str(tmp_path / "history.csv"))
    assert all(c in h for c in WALL_COLUMNS)
    rest = slice(1, None)  # after the first step: the row at t = 0 precedes every contact and water step
    load = h["wall_bottom_contact"][rest] + h["wall_bottom_water"][rest]
    assert np.all(load > 0) and h["wall_bottom_contact"][1] > 0  # the lowest particle starts on the flat bottom
    faces = {code: w.position for code, w in cp.flat_walls.items()}
    width = faces[pg.WALL_RIGHT] - faces[pg.WALL_LEFT]
    assert np.all(h["wall_bottom_water"][rest] > 0)  # the inflow raises U on the bottom wall's edges ...
    assert np.all(h["wall_bottom_water"] <= sc.water.E_w * width)  # ... each U <= E_w over at most its width
    # the snapshot's pores index the discs and the walls' vertices, which it stores
    snap = read_snapshot(snapshot_files(str(tmp_path))[0])
    assert snap["tri"].max() < len(snap["vertices"]) and len(snap["xz"]) == 45
    assert (tmp_path / "snapshots.png").exists()


def test_the_quick_sand_on_flat_walls_runs_with_the_papers_law(tmp_path):
    """The paper's law meets the flat walls itself (its NumPy classes: engines.model.paper_law; no
    YADE boxes): the same physical checks, its own wall loads in history.csv."""
    r, max_U = run("flat", tmp_path, law="paper")
    cp, sc = r.cp, r.scene
    summary = r.summarise("completed", [])
    assert cp.wall_ids == {} and summary["n_pores"] > 0 and summary["water_balance_error"] <= 1e-12
    assert np.all(max_U <= sc.water.E_w)
    xz = cp.positions()
    assert all(np.all(wall.gap(xz, 0.0) > 0) for wall in cp.flat_walls.values())
    h = read_history(str(tmp_path / "history.csv"))
    rest = slice(1, None)
    assert np.all(h["wall_bottom_contact"][rest] + h["wall_bottom_water"][rest] > 0)
    assert np.all(h["wall_bottom_water"][rest] > 0)


def test_wall_discs_give_no_boxes_and_no_wall_columns(tmp_path):
    r, max_U = run("discs", tmp_path)
    h = read_history(str(tmp_path / "history.csv"))
    assert r.cp.wall_ids == {} and len(r.cp.ids) == len(r.cp.packing.r) == 76
    cols = r.rec.columns
    assert not any(c.startswith("wall_") for c in h) and cols[cols.index("remesh_change") + 1] == "sv_band1"
    assert np.all(max_U <= r.scene.water.E_w)


@pytest.mark.parametrize("kind", ["discs", "flat"])
def test_the_blocks_start_at_the_bottom_of_the_box(kind):
    """The pressure blocks and the porosity window stand on the bottom wall's face, the wall discs'
    inner face or the flat bottom (moved back to the lowest particle)."""
    from engines.yade.coupling import YadeCoupling
    sc = quicksand(kind)
    pk = scene_packing(sc)
    cp = YadeCoupling(sc, pk)
    bottom = cp.flat_walls[pg.WALL_BOTTOM].position if kind == "flat" else pk.inner_faces()[pg.WALL_BOTTOM]
    mob = pk.mobile
    assert cp.block_bounds[0][0] == cp.window.z0 == bottom
    assert (bottom == np.min(pk.xz[mob, 1] - pk.r[mob])) == (kind == "flat")


@pytest.mark.parametrize("law", ["yade", "paper"])
def test_a_shaken_box_of_flat_walls_moves_its_walls_with_the_base(law, tmp_path):
    """[walls] kind = "flat" with a cosine [loading] moving the box: with YADE's law the boxes follow
    the base (the TranslationEngine) and the WaterEngine reads them every water step; with the
    paper's law its core moves its walls itself. Either way the pores' faces stand where the base
    has carried the walls, every U <= E_w, water conserved."""
    sc = scenes.preset("quicksand_case1", {
        "contact": {"law": law, "spring": "b"}, "walls": {"kind": "flat"},
        "loading": {"type": "cosine", "moves": "box", "amplitude": 15.0, "frequency": 50.0},
        "output": {"history_interval": EVERY, "snapshot_times": [0.0]}})
    from yade import O
    r = Run(sc, scene_packing(sc), str(tmp_path), STEPS)
    max_U = MaxU()
    r.cp.hooks.insert(0, max_U)
    cp = r.cp
    boxes = {i: O.bodies[i].state.pos[0] for i in cp.wall_ids.values()}
    r.go(figures=False)
    disp = cp.base_motion()[2]
    assert disp > 1e-7  # the cosine has moved the base by 1.2 um in 0.4 ms (15/2 t^2)
    for i, x0 in boxes.items():
        assert O.bodies[i].state.pos[0] - x0 == pytest.approx(disp, rel=1e-9)
    if law == "yade":  # the engine read the boxes at its last water step, before the last step moved them
        wm, disp = cp.water_engine.model, disp - cp.wall_engine.velocity * sc.numerics.dt
    else:  # the core moved its walls at the end of the step (f)
        wm = cp.core.water_model
    start = np.array([w.position for w in cp.flat_walls.values()])
    x_walls = np.array([w.axis == 0 for w in cp.flat_walls.values()])
    np.testing.assert_allclose(wm.wall_vertices.faces(), start + disp * x_walls, rtol=0, atol=1e-15)
    summary = r.summarise("completed", [])
    assert summary["water_balance_error"] <= 1e-12 and np.all(np.array(max_U.seen) <= sc.water.E_w)


@pytest.mark.parametrize("law", ["yade", "paper"])
def test_the_flat_walls_contacts_count_in_the_effective_stress(law, tmp_path):
    """YadeCoupling.stress_contacts holds each particle's contact with the flat bottom (YADE's box
    contacts, or the paper's law's feet) at the face, pushing up by the bottom wall's contact load
    (the same interactions with YADE's law; the paper's law's feet evaluated at the positions now
    against its last step's forces), and the bands' columns are in the history. After 20 steps,
    before the inflow lifts the bed off the bottom."""
    r = Run(quicksand("flat", law), scene_packing(quicksand("flat", law)), str(tmp_path), 20)
    r.go(figures=False)
    cp = r.cp
    c = cp.stress_contacts(cp.positions())
    face = cp.flat_walls[pg.WALL_BOTTOM].position
    on_bottom = np.abs(c.point[:, 1] - face) < 0.1 * cp.packing.r.min()
    assert on_bottom.any() and np.all(np.isin(c.disc, np.flatnonzero(cp.packing.mobile)))
    assert c.force[on_bottom, 1].sum() == pytest.approx(cp.wall_loads()["bottom"][0], rel=1e-9 if law == "yade" else 0.1)
    h = read_history(str(tmp_path / "history.csv"))
    assert h["sv_band1"][-1] > 0 and np.isfinite(h["ru_band1"][1:]).all()
    if law == "yade":  # YADE finds its contacts in the first step: r_u's reference is the second row
        assert h["sv_band1"][0] == 0 and np.isnan(h["ru_band1"][0])
