"""Flat walls (SPEC §2.6) on the compiled path: the compiled WaterModel builds and re-meshes its pores
by the compiled steps (engines.compiled.pores, tests/compiled/test_pores.py) and runs its water steps
by kernels.water_step, to the NumPy model's results."""
import numpy as np
import pytest

from engines.compiled import kernels
from engines.compiled import pores as kp
from engines.compiled import water_model as cwm
from engines.model import pores as pg
from engines.model import water_model as wm
from engines.model.flat_walls import FlatWall, WallVertices
from engines.model.pore_water import WaterSettings
from engines.model.schedule import Schedule
from tests.compiled.test_pores import assert_same_network
from tests.layouts import random_sequential


def test_the_wall_vertices_are_placed_as_the_models():
    rng = np.random.default_rng(1)
    xz = rng.uniform(1.0, 9.0, (7, 2))
    walls = (FlatWall(1, 0.0, +1), FlatWall(0, 0.0, +1), FlatWall(0, 10.0, -1, "drained"), FlatWall(1, 10.0, -1))
    wv = WallVertices(walls, len(xz))
    want = wv.positions(xz)
    got = wv.positions(xz + 5.0)  # the corners stay; the kernel overwrites the rest
    kernels.place_wall_vertices(xz, got, np.array([w.axis for w in walls]), np.array([w.position for w in walls]))
    assert np.array_equal(got, want)


def boxed_discs(seed=2, size=12.0):
    """A loose random packing in a box: an inflow bottom, a drained right side, undrained others."""
    rng = np.random.default_rng(seed)
    xz, r = random_sequential(rng.uniform(1.2, 2.0, 300), size - 2.0, size - 2.0, rng)
    walls = (FlatWall(1, 0.0, +1, "inflow"), FlatWall(0, 0.0, +1), FlatWall(0, size, -1, "drained"),
             FlatWall(1, size, -1))
    return xz + 1.0, r, walls


@pytest.mark.parametrize("smoothing", [False, True])
def test_the_compiled_water_model_with_flat_walls_is_the_numpy_one(smoothing):
    """The discs drifting and shaken for 60 steps, rebuilt every 20 (the water moves between meshes):
    the compiled class builds and re-meshes by the compiled steps, the same networks and re-meshing
    rules as the NumPy one; W, the disc forces and the walls' forces agree to round-off at every step."""
    xz0, r, walls = boxed_discs()
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=50.0, q_w=0.02, smoothing=smoothing, transfer="conserving")
    models = [cls(s, r, np.zeros(len(r), np.int64), xz0, 0.0, 0.8 * r.mean(), 1e-4, Schedule(rebuild_interval=20),
                  flat_walls=walls) for cls in (wm.WaterModel, cwm.WaterModel)]
    rng = np.random.default_rng(0)
    drift = 0.2 * rng.standard_normal(xz0.shape)  # [m] by the end: pores split and merge (rule b)
    for k in range(60):
        xz = xz0 + k / 60 * drift + 0.02 * np.sin(0.1 * k) * rng.standard_normal(xz0.shape) * 0.1
        for m in models:
            m.step(k, xz)
        a, b = models
        np.testing.assert_allclose(b.water.W, a.water.W, rtol=1e-12)
        np.testing.assert_allclose(b.F, a.F, rtol=1e-10, atol=1e-12 * np.abs(a.F).max())
        # U to round-off of E_w (eq 32 divides W - A by W ~ A) along a wall of 12 m
        np.testing.assert_allclose(b.F_walls, a.F_walls, rtol=1e-12, atol=1e-14 * s.E_w * 12.0)
        if k % 20 == 0:
            assert_same_network(b.water.net, a.water.net)
            assert np.array_equal(b.water.rule, a.water.rule)
    assert (b.build_steps, b.remesh_steps) == (kp.BUILD, kp.REMESH)
    assert a.n_rebuilds == b.n_rebuilds == 2 and np.all(a.F_walls != 0) and a.water.balance.inflow > 0
    assert a.water.remesh_counts["b"] > 0 and a.water.remesh_counts["a"] > 0


def test_compiled_flat_walls_keep_the_uniform_pressure_balance():
    """A uniform U in every pore of the compiled model: no force on any disc, U x wetted length on
    each wall (the water step's eq 33 and flat_wall_forces kernels)."""
    xz, r, walls = boxed_discs(seed=5)
    s = WaterSettings(E_w=240.0, k1=0.0, k2=0.0, k3=0.0, q_w=0.0)
    m = cwm.WaterModel(s, r, np.zeros(len(r), np.int64), xz, 0.0, 0.8 * r.mean(), 1e-4, flat_walls=walls)
    U = 30.0
    m.water.W = pg.measure(m.water.net, xz, r).void_area * s.E_w / (s.E_w - U)  # eq 32 inverted
    m.advance(1e-4, xz)
    assert np.abs(m.F).max() < 1e-12 * U
    wetted = np.zeros(len(walls))
    net, meas = m.water.net, pg.measure(m.water.net, xz, r)
    k, w = pg.wall_edges(net)
    np.add.at(wetted, w, meas.link_length[k])
    np.testing.assert_allclose(m.F_walls, U * wetted, rtol=1e-12)


@pytest.mark.parametrize("wall, xz", [(FlatWall(1, 0.0, +1), [[1.0, 1.0], [3.0, 1.0]]),
                                      (FlatWall(1, 2.0, -1), [[1.0, 1.0], [3.0, 1.0]]),
                                      (FlatWall(0, 0.0, +1), [[1.0, 1.0], [1.0, 3.0]]),
                                      (FlatWall(0, 2.0, -1), [[1.0, 1.0], [1.0, 3.0]])])
def test_the_one_pore_of_two_discs_on_each_wall_pushes_it(wall, xz):
    """Two touching discs on a wall close one pore (pore 0, on the left or the right of the wall
    edge as the wall faces): at pressure U the wall feels U x its wetted length, the gap between
    the feet (the water step's flat_wall_forces)."""
    xz, r = np.array(xz), np.ones(2)
    s = WaterSettings(E_w=240.0, k1=0.0, k2=0.0, k3=0.0, q_w=0.0)
    m = cwm.WaterModel(s, r, np.zeros(2, np.int64), xz, 0.0, 0.5, 1e-4, flat_walls=(wall,))
    U = 30.0
    m.water.W = pg.measure(m.water.net, xz, r).void_area * s.E_w / (s.E_w - U)  # eq 32 inverted
    m.advance(1e-4, xz)
    assert m.water.net.n_pores == 1
    np.testing.assert_allclose(m.F_walls, [U * 2.0], rtol=1e-12)


def test_the_compiled_water_model_follows_moving_walls_as_the_numpy_one():
    """Both classes with the box shaken around fixed discs (every wall translated by the same
    oscillating x, 0.3 m, move_walls at every step) and rebuilt every 20 steps: W, the disc and wall forces agree to
    round-off at every step; the right wall's water force changes as its face moves (were the
    kernels' faces or corners left at the build, the compiled forces would part)."""
    xz0, r, walls = boxed_discs()
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=50.0, q_w=0.02, transfer="conserving")
    models = [cls(s, r, np.zeros(len(r), np.int64), xz0, 0.0, 0.8 * r.mean(), 1e-4, Schedule(rebuild_interval=20),
                  flat_walls=walls) for cls in (wm.WaterModel, cwm.WaterModel)]
    pushes = []
    for k in range(60):
        shift = np.zeros((len(walls), 2))
        shift[:, 0] = 0.3 * np.sin(0.2 * k)
        for m in models:
            m.move_walls(shift)
            m.step(k, xz0)
        a, b = models
        np.testing.assert_allclose(b.water.W, a.water.W, rtol=1e-12)
        np.testing.assert_allclose(b.F, a.F, rtol=1e-10, atol=1e-12 * np.abs(a.F).max())
        np.testing.assert_allclose(b.F_walls, a.F_walls, rtol=1e-12)
        pushes.append(a.F_walls[2])
    assert a.n_rebuilds == b.n_rebuilds == 2 and np.ptp(pushes) > 0.1 * np.abs(pushes).max()
