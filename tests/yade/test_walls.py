"""YADE's Box and Wall bodies as flat walls of the pores (engines.yade.walls, SPEC §2.6): the face
each gives, each refusal in one line naming the body, and the WaterEngine with them."""
import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing)

from engines.model.flat_walls import FlatWall
from engines.yade.contract import ContractError
from engines.yade.walls import flat_walls

W, H, R = 10e-3, 8e-3, 0.5e-3
XZ = np.array([[2e-3, 1e-3], [5e-3, 4e-3], [8e-3, 7e-3]])  # disc centres inside the box [m]


def aabb():
    """utils.aabbWalls around [0, W] x [0, H] (y: +-2R): the ids (left, right, front, back, bottom, top)."""
    from yade import O, utils
    O.reset()
    return [O.bodies.append(w) for w in utils.aabbWalls([(0, -2 * R, 0), (W, 2 * R, H)], thickness=R)]


def test_the_in_plane_boxes_of_aabb_walls_give_their_inner_faces():
    from yade import O
    left, right, _, _, bottom, top = aabb()
    got = flat_walls(O.bodies, {bottom: "inflow", left: "undrained", right: "drained", top: "undrained"}, XZ)
    want = [FlatWall(1, 0.0, +1, "inflow"), FlatWall(0, 0.0, +1), FlatWall(0, W, -1, "drained"), FlatWall(1, H, -1)]
    for g, w in zip(got, want):
        assert (g.axis, g.inward, g.boundary) == (w.axis, w.inward, w.boundary)
        assert g.position == pytest.approx(w.position, abs=1e-15)


def test_a_yade_wall_gives_its_plane():
    from yade import O, utils
    O.reset()
    i = O.bodies.append(utils.wall(0.5e-3, axis=2))
    j = O.bodies.append(utils.wall(9e-3, axis=0, sense=-1))
    assert flat_walls(O.bodies, {i: "inflow", j: "drained"}, XZ) == [FlatWall(1, 0.5e-3, +1, "inflow"),
                                                                      FlatWall(0, 9e-3, -1, "drained")]


def refused(make, xz=XZ, boundary="undrained"):
    from yade import O
    i = make()
    with pytest.raises(ContractError) as e:
        flat_walls(O.bodies, {i: boundary}, xz)
    assert str(e.value).startswith(f"body {i}: ") and "\n" not in str(e.value)
    return str(e.value)


def test_each_wall_the_engine_cannot_take_is_refused_in_one_line():
    from yade import O, Quaternion, Vector3, utils
    front = aabb()[2]
    assert "facing along y" in refused(lambda: front)
    O.reset()
    assert "facing along y" in refused(lambda: O.bodies.append(utils.wall(-2 * R, axis=1)))
    assert "sense 1" in refused(lambda: O.bodies.append(utils.wall(9e-3, axis=0, sense=1)))
    assert "both sides" in refused(lambda: O.bodies.append(utils.wall(5e-3, axis=0)))
    tilted = utils.box((W / 2, 0, -R), (W, 2 * R, R / 2))
    tilted.state.ori = Quaternion(Vector3(0, 1, 0), 0.1)
    assert "rotated Box" in refused(lambda: O.bodies.append(tilted))
    turning = utils.box((W / 2, 0, -R), (W, 2 * R, R / 2))
    turning.state.angVel = Vector3(0, 1.0, 0)
    assert "turns" in refused(lambda: O.bodies.append(turning))
    corner = utils.box((-R, 0, -R), (R / 2, 2 * R, R / 2))
    assert "two of its faces" in refused(lambda: O.bodies.append(corner))
    assert "a Facet" in refused(lambda: O.bodies.append(utils.facet([(0, 0, -1e-3), (1e-3, 0, -1e-3), (0, 0, -2e-3)])))
    assert "boundary 'open'" in refused(lambda: O.bodies.append(utils.wall(0.0, axis=2)), boundary="open")
    assert "not in O.bodies" in refused(lambda: 999)


def test_the_engine_with_flat_walls_is_the_same_by_runner_compiled_drive_and_numpy():
    """aabb_box's scene (fresh, the dry settling skipped) with the water on: the PyRunner, drive
    compiled and the NumPy model (compiled=False) give the same run (the first two bit for bit,
    the NumPy model to round-off), and the water's push on the walls."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import aabb_box as ex
    runs = []
    for how, compiled in (("runner", True), ("compiled", True), ("runner", False)):
        bottom, left, right, grains = ex.build_box()
        water = WaterEngine(grains, {}, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=1e-4, transfer="paper"), l_m=1.3e-4,
                            water_interval=4, compiled=compiled,
                            flat_walls={bottom: "inflow", left: "undrained", right: "undrained"})
        if how == "runner":
            O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
            O.run(300, True)
        else:
            water.drive(300)
        # W by the pores' vertex sets: centres apart by round-off, qhull may list the same triangles,
        # and so number the same pores, in another order
        net = water.model.water.net
        runs.append((water.io.positions(), water.model.water.W[np.argsort(net.pore_signature)], water.wall_forces(),
                     np.sort(net.pore_signature)))
        assert water.model.water.balance.inflow > 0 and water.model.water.balance_error() < 1e-12
        assert runs[-1][2][bottom][1] < 0 and runs[-1][2][left][0] < 0 < runs[-1][2][right][0]  # pushed outward
    assert np.array_equal(runs[1][0], runs[0][0]) and np.array_equal(runs[1][1], runs[0][1])
    np.testing.assert_allclose(runs[2][0], runs[0][0], rtol=0, atol=1e-12)
    assert np.array_equal(runs[2][3], runs[0][3])  # the same pores
    np.testing.assert_allclose(runs[2][1], runs[0][1], rtol=1e-9)


def test_the_engine_follows_a_wall_that_a_translation_engine_moves():
    """aabb_box's scene with its right box driven outwards at 1 cm/s by a TranslationEngine: each
    water step the pores' right face is where the box's inner face is (drive then takes the
    Python steps, which read it); the pores next to it grow, and a box that starts to spin is
    refused in one line."""
    from yade import O, Vector3
    from yade.wrapper import TranslationEngine

    from engines.model.pore_water import WaterSettings
    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import aabb_box as ex
    bottom, left, right, grains = ex.build_box()
    water = WaterEngine(grains, {}, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=1e-4), l_m=1.3e-4,
                        flat_walls={bottom: "inflow", left: "undrained", right: "undrained"})
    face0 = water.model.wall_vertices.faces()[2]
    x0 = O.bodies[right].state.pos[0]
    O.engines = O.engines[:-1] + [TranslationEngine(ids=[right], translationAxis=(1, 0, 0), velocity=1e-2),
                                  O.engines[-1]]
    assert water._walls_may_move()
    water.drive(200)
    moved = O.bodies[right].state.pos[0] - x0
    assert moved == pytest.approx(200 * 1e-2 * O.dt, rel=1e-9)
    # the last water step read the box before the last O.step moved it by 1e-2 dt
    assert water.model.wall_vertices.faces()[2] - face0 == pytest.approx(moved - 1e-2 * O.dt, rel=1e-9)
    assert water.model.water.balance_error() < 1e-12
    O.bodies[right].state.angVel = Vector3(0, 0.5, 0)
    with pytest.raises(ContractError, match=rf"^body {right}: a Box that turns"):
        water()
