"""The boundary kinds' one table (engines.model.groups.BOUNDARY_KINDS), each tried once with a toy
kind added to it and nothing else: a flat-wall word (the NumPy water model and its compiled twin
follow it) and a disc group (packing files, the pores, the water's masks and the scene's flat walls
follow it, in a copy of the tree whose table has one row more)."""
import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np

from engines import ROOT
from engines.compiled import water_model as cwm
from engines.model import groups
from engines.model import water_model as wm
from engines.model.flat_walls import FlatWall
from engines.model.pore_water import WaterSettings
from engines.model.schedule import Schedule
from tests.compiled.test_flat_walls import boxed_discs

OPEN = groups.BoundaryKind("open", 0, True, "surface", ())  # a toy word: a face at U = 0 through k1, as the bed's top


def run_box(cls, right, k3, steps=20):
    """(W, balance) of water model ``cls`` on boxed_discs with its right wall's word ``right`` after
    ``steps`` steps of the discs drifting (rebuilt every 10)."""
    xz0, r, walls = boxed_discs()
    walls = walls[:2] + (FlatWall(walls[2].axis, walls[2].position, walls[2].inward, right),) + walls[3:]
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=k3, q_w=0.02)
    m = cls(s, r, np.zeros(len(r), np.int64), xz0, 0.0, 0.8 * r.mean(), 1e-4, Schedule(rebuild_interval=10),
            flat_walls=walls)
    drift = 0.1 * np.random.default_rng(0).standard_normal(xz0.shape)
    for k in range(steps):
        m.step(k, xz0 + k / steps * drift)
    return m.water.W.copy(), m.water.balance


def test_a_toy_flat_wall_word_in_the_table_only(monkeypatch):
    """A word added to the table: a wall of it drains its pores through k1 as the bed's top does, so
    with k3 = k1 the box's water is that of a drained wall to round-off, booked as surface outflow
    instead of side outflow; the compiled twin gives the NumPy model's water."""
    monkeypatch.setattr(groups, "BOUNDARY_KINDS", groups.BOUNDARY_KINDS + (OPEN,))
    W_drained, b_drained = run_box(wm.WaterModel, "drained", k3=200.0)
    W_open, b_open = run_box(wm.WaterModel, "open", k3=0.0)
    W_twin, b_twin = run_box(cwm.WaterModel, "open", k3=0.0)
    assert b_drained.side_outflow != 0.0 and b_drained.surface_outflow == 0.0  # (U < 0 there: water is drawn in)
    assert b_open.side_outflow == 0.0
    np.testing.assert_allclose(b_open.surface_outflow, b_drained.side_outflow, rtol=1e-12)
    np.testing.assert_allclose(W_open, W_drained, rtol=1e-12)
    np.testing.assert_allclose(W_twin, W_open, rtol=1e-12)
    np.testing.assert_allclose(b_twin.surface_outflow, b_open.surface_outflow, rtol=1e-12)


TOP_ROW = '    BoundaryKind("top",       4,     False, "undrained", (1, -1)),  # a toy lid of wall discs\n'
TOY_LID = textwrap.dedent("""
    import numpy as np
    from engines.model import groups, pore_dem, pore_water
    from engines.model import pores as pg
    from engines.run import scene as scenes
    from packing.packing import Packing

    rng = np.random.default_rng(4)
    row = [(x, 0.0) for x in range(11)]  # wall discs of radius 0.5 touching: bottom, sides, lid
    side = [(0.0, z) for z in range(1, 8)] + [(10.0, z) for z in range(1, 8)]
    lid = [(x, 8.0) for x in range(11)]
    grains = [(x, z) for x in range(1, 10) for z in range(1, 8)]  # radius 0.45, 0.05 m from their neighbours
    xz = np.array(row + side + lid + grains, float)
    group = np.array([1] * 11 + [2] * 7 + [3] * 7 + [4] * 11 + [0] * len(grains))
    xz[group == 0] += rng.uniform(-0.02, 0.02, (len(grains), 2))
    r = np.where(group == 0, 0.45, 0.5)
    pk = Packing(xz, r, group, np.ones(len(r)))  # the packing takes code 4 (a group of the table)
    net = pg.build_pores(pk.xz, pk.r, l_m=0.3, walls=pk.group)
    masks = pore_water.boundary_masks(net, "drained")
    top, sides = net.pore_touches["top"], net.pore_touches["left"] | net.pore_touches["right"]
    assert top.any() and np.array_equal(masks["undrained"], top), "the lid's pores are undrained"
    assert np.array_equal(masks["drained"], sides) and not masks["surface"].any()  # the box is closed
    sc = scenes.validate({"scene": {"name": "toy"}, "walls": {"kind": "flat"}, "water": {"enabled": True}})
    lid = pore_dem.scene_flat_walls(sc.settings, pk)[4]
    assert (lid.axis, lid.inward, lid.boundary) == (1, -1, "undrained") and lid.position <= 7.5, lid
    print("lid", float(lid.position), int(top.sum()))
""")


def test_a_toy_disc_group_in_the_table_only(tmp_path):
    """A lid of wall discs (group 4, undrained, its face below it) added as one row of the table in a
    copy of the tree: a packing with it is read, its pores are undrained (not the sides' drained,
    not the surface) and a flat-wall scene puts an undrained wall at its face."""
    for package in ("engines", "packing"):
        shutil.copytree(os.path.join(ROOT, package), tmp_path / package,
                        ignore=shutil.ignore_patterns("__pycache__"))
    table = tmp_path / "engines" / "model" / "groups.py"
    text = table.read_text()
    bottom = next(line for line in text.splitlines(keepends=True) if line.lstrip().startswith('BoundaryKind("bottom"'))
    table.write_text(text.replace(bottom, bottom + TOP_ROW, 1))
    done = subprocess.run([sys.executable, "-c", TOY_LID], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(tmp_path)})
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.startswith("lid ")
