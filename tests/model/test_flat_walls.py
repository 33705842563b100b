"""Flat walls as pore boundaries (SPEC §2.6): exact wall pores, forces on discs and walls (eq 33),
corners, boundary flows, re-meshing with walls."""
import numpy as np
import pytest

from engines.model import pores as pg
from engines.model.flat_walls import FlatWall, WallVertices
from engines.model.pore_water import PoreWater, WaterSettings, pressures_by_rule, rule_counts
from engines.model.schedule import Schedule
from engines.model.water_model import WaterModel
from tests.layouts import random_sequential, square_lattice
from tests.oracles import pore_polygon

R = 1.0


def bottom(boundary="undrained", z=0.0):
    return FlatWall(1, z, +1, boundary)


def box(width, height, boundaries=("undrained",) * 4):
    """Bottom, left, right, top walls of the box [0, width] x [0, height] [m]."""
    b, left, right, top = boundaries
    return (FlatWall(1, 0.0, +1, b), FlatWall(0, 0.0, +1, left), FlatWall(0, width, -1, right),
            FlatWall(1, height, -1, top))


def lattice_box(nx, nz, gap=0.0):
    """nx x nz equal touching discs of radius R in a square lattice, ``gap`` [m] from the four walls
    of their box."""
    xz = square_lattice(nx, nz, 2 * R, origin=(R + gap, R + gap))
    return xz, np.full(len(xz), R), box(2 * R * nx + 2 * gap, 2 * R * nz + 2 * gap)


def random_box(seed, size=12.0):
    """A loose random packing of 25-40 discs (radii 0.6-1.0 m) inside a closed box of side ``size`` [m]."""
    rng = np.random.default_rng(seed)
    xz, r = random_sequential(rng.uniform(1.2, 2.0, 300), size - 2.0, size - 2.0, rng)
    return xz + 1.0, r, box(size, size)


def arc_forces(net, xz, r, U):
    """eq 33 summed over the pores, from the pores' polygons: on the arc of disc v between the
    directions to its next and previous polygon vertices, F = U r (-(sin a2 - sin a1), cos a2 - cos a1).
    An oracle for pores.pressure_forces (N, 2) [N/m]."""
    P, n = pg.vertex_positions(net, xz), len(r)
    F = np.zeros((n, 2))
    for p in range(net.n_pores):
        for cycle in pore_polygon(net, p):
            for k, v in enumerate(cycle):
                if v >= n:
                    continue  # a wall vertex: no disc
                u, w = P[cycle[k - 1]] - P[v], P[cycle[(k + 1) % len(cycle)]] - P[v]
                a1 = np.arctan2(w[1], w[0])
                a2 = a1 + np.mod(np.arctan2(u[1], u[0]) - a1, 2 * np.pi)
                F[v] += U[p] * r[v] * np.array([-(np.sin(a2) - np.sin(a1)), np.cos(a2) - np.cos(a1)])
    return F


@pytest.mark.parametrize("gap", [0.0, 0.07])
def test_a_row_on_a_flat_wall_has_exact_wall_pores(gap):
    n = 6
    xz = np.column_stack([2 * R * np.arange(n), np.full(n, R + gap)])
    r = np.full(n, R)
    net = pg.build_pores(xz, r, l_m=0.1, flat_walls=(bottom(),))
    m = pg.measure(net, xz, r)
    # the rectangle between two centres and their feet, 2R x (R + gap), less two quarter discs
    assert net.n_pores == n - 1
    np.testing.assert_allclose(m.void_area, 2 * R * (R + gap) - np.pi * R**2 / 2, rtol=1e-13)
    assert all(len(c) == 1 and len(c[0]) == 4 for c in (pore_polygon(net, p) for p in range(net.n_pores)))
    assert net.pore_walls.all() and all(n in net.vertices_of(p) for p in range(net.n_pores))  # the wall is vertex N
    assert net.pore_surface.all()  # the tops are free surface; the wall edges are not


def test_a_hexagonal_bed_on_a_flat_wall_has_exact_pores():
    n, gap = 6, 0.03
    row1 = np.column_stack([2 * R * np.arange(n), np.full(n, R + gap)])
    row2 = np.column_stack([R + 2 * R * np.arange(n - 1), np.full(n - 1, R + gap + np.sqrt(3) * R)])
    xz = np.vstack([row1, row2])
    r = np.full(len(xz), R)
    net = pg.build_pores(xz, r, l_m=0.1, flat_walls=(bottom(),))
    A = pg.measure(net, xz, r).void_area
    wall, triangle = 2 * R * (R + gap) - np.pi * R**2 / 2, np.sqrt(3) * R**2 - np.pi * R**2 / 2
    on = net.pore_walls[0]
    assert on.sum() == n - 1 and (~on).sum() == 2 * (n - 1) - 1  # the second row is out of the wall's reach
    np.testing.assert_allclose(A[on], wall, rtol=1e-13)
    np.testing.assert_allclose(A[~on], triangle, rtol=1e-13)


def test_a_disc_is_linked_to_its_own_foot_only():
    # a small disc tucked under a large one, both on the wall: the foot of the small disc is within
    # reach of the large disc (eq 28 with r = 0 would link them) but is not its link to the wall
    xz, r = np.array([[0.0, 1.0], [0.83, 0.1]]), np.array([1.0, 0.1])
    net = pg.build_pores(xz, r, l_m=0.3, flat_walls=(bottom(),))
    assert np.hypot(0.83, 1.0) <= r[0] + 0.3  # the small disc's foot is in the large one's reach
    a = np.arctan2(0.83, 0.9)  # at the large disc, between its foot and the small disc
    # the trapezoid of the two centres and their feet less the sectors a at the large disc and
    # pi - a at the small one (the right angles at the feet have no sector)
    exact = 0.83 * (1.0 + 0.1) / 2 - a * 1.0**2 / 2 - (np.pi - a) * 0.1**2 / 2
    assert net.n_pores == 1
    np.testing.assert_allclose(pg.measure(net, xz, r).void_area, [exact], rtol=1e-13)


def test_the_link_to_a_wall_is_a_contact_within_eps_m():
    gaps, eps_m = np.array([-0.01, 0.0, 0.03, 0.08]), 0.02
    xz = np.column_stack([2.2 * R * np.arange(4), R + gaps])
    r = np.full(4, R)
    net = pg.build_pores(xz, r, eps_m=eps_m, l_m=0.1, flat_walls=(bottom(),))
    m = pg.measure(net, xz, r)
    wv = net.wall_vertices
    to_wall = {int(i): c for (i, j), c in zip(net.links.tolist(), m.link_contact) if j >= 4 and wv.owner[j] == i}
    assert to_wall == {0: True, 1: True, 2: False, 3: False}  # eq 43 with the wall as a disc: gap <= eps_m
    np.testing.assert_allclose(m.link_length[[k for k, (i, j) in enumerate(net.links) if j >= 4 and wv.owner[j] == i]],
                               R + gaps, rtol=1e-14)


def test_a_uniform_pressure_pushes_no_disc_and_each_wall_by_its_wetted_length():
    for xz, r, walls in [lattice_box(4, 3), lattice_box(3, 3, gap=0.05), random_box(0), random_box(1)]:
        net = pg.build_pores(xz, r, l_m=0.8 * r.mean(), flat_walls=walls)
        m = pg.measure(net, xz, r)
        width, height = walls[2].position, walls[3].position
        assert net.n_closed == 0 and not net.pore_surface.any()
        np.testing.assert_allclose(m.polygon_area.sum(), width * height, rtol=1e-13)  # the walls close the box
        U = np.full(net.n_pores, 7.0)
        np.testing.assert_allclose(pg.pressure_forces(net, r, U, m), 0.0, atol=1e-12)
        np.testing.assert_allclose(pg.flat_wall_forces(net, U, m), 7.0 * np.array([width, height, height, width]),
                                   rtol=1e-13)


def test_a_wall_beyond_the_discs_reach_feels_no_water():
    """A lid far above an open bed has no edge: its force is 0, one entry per wall all the same."""
    xz, r, walls = lattice_box(4, 3)
    walls = walls[:3] + (FlatWall(1, 10 * walls[3].position, -1),)
    net = pg.build_pores(xz, r, l_m=0.8 * r.mean(), flat_walls=walls)
    m = pg.measure(net, xz, r)
    F = pg.flat_wall_forces(net, np.full(net.n_pores, 7.0), m)
    assert F.shape == (4,) and F[3] == 0.0 and np.all(F[:3] > 0)


def test_pressure_forces_are_the_arcs_of_eq_33_with_walls():
    rng = np.random.default_rng(5)
    for xz, r, walls in [lattice_box(4, 3, gap=0.05), random_box(2)]:
        net = pg.build_pores(xz, r, l_m=0.8 * r.mean(), flat_walls=walls)
        m = pg.measure(net, xz, r)
        U = rng.uniform(-5.0, 20.0, net.n_pores)
        np.testing.assert_allclose(pg.pressure_forces(net, r, U, m), arc_forces(net, xz, r, U), atol=1e-12)


def test_discs_and_walls_that_touch_take_the_whole_pore_pressure():
    # touching discs and walls: each pore is closed by its discs' arcs and its wall edges, so the
    # pressure on them sums to zero per pore, whatever U: discs + walls balance
    xz, r, walls = lattice_box(5, 4)
    net = pg.build_pores(xz, r, l_m=0.1, flat_walls=walls)
    m = pg.measure(net, xz, r)
    U = np.random.default_rng(3).uniform(-5.0, 20.0, net.n_pores)
    on_walls = -pg.flat_wall_forces(net, U, m)[:, None] * np.array([w.normal() for w in walls])
    np.testing.assert_allclose(pg.pressure_forces(net, r, U, m).sum(axis=0) + on_walls.sum(axis=0), 0.0, atol=1e-12)
    assert np.abs(on_walls).max() > 10.0


def test_two_walls_close_the_corner_pore():
    xz = square_lattice(3, 3, 2 * R, origin=(R, R))
    r = np.full(len(xz), R)
    walls = (FlatWall(1, 0.0, +1), FlatWall(0, 0.0, +1))
    net = pg.build_pores(xz, r, l_m=0.1, flat_walls=walls)
    m = pg.measure(net, xz, r)
    n = len(r)
    corner = [p for p in range(net.n_pores) if set(net.vertices_of(p).tolist()) == {0, n, n + 1}]
    assert len(corner) == 1  # disc 0, counted with both walls
    p = corner[0]
    np.testing.assert_allclose(m.void_area[p], R**2 - np.pi * R**2 / 4, rtol=1e-13)  # square less a quarter disc
    (cycle,) = pore_polygon(net, p)
    P = pg.vertex_positions(net, xz)
    assert len(cycle) == 4 and [0.0, 0.0] in P[cycle].tolist()  # disc 0, its two feet, the corner
    assert net.n_pores == 4 + 2 + 2 + 1  # lattice squares, wall pores along each wall, the corner
    U = np.zeros(net.n_pores)
    U[p] = 3.0
    np.testing.assert_allclose(pg.flat_wall_forces(net, U, m), [3.0 * R, 3.0 * R], rtol=1e-13)  # both edges


def test_wall_reactions_add_the_contacts_to_the_water():
    xz, r, walls = lattice_box(3, 2)
    net = pg.build_pores(xz, r, l_m=0.1, flat_walls=walls)
    m = pg.measure(net, xz, r)
    U = np.full(net.n_pores, 2.0)
    got = pg.wall_reactions(net, U, m, contact=[1.0, 0.0, 0.5, 0.0])
    np.testing.assert_allclose(got.water, 2.0 * np.array([6.0, 4.0, 4.0, 6.0]), rtol=1e-13)
    np.testing.assert_allclose(got.total, got.water + [1.0, 0.0, 0.5, 0.0], rtol=1e-15)


def run_water(walls, q_w=0.02, k3=50.0, steps=300):
    xz, r, _ = random_box(3)
    net = pg.build_pores(xz, r, l_m=0.8 * r.mean(), flat_walls=walls)
    m = pg.measure(net, xz, r)
    W0 = m.void_area * (1 + 0.05 * np.random.default_rng(0).random(net.n_pores))
    w = PoreWater(net, m.void_area, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=k3, q_w=q_w), W=W0)
    w.U0 = w.pressure(m.void_area)
    for _ in range(steps):
        w.advance(1e-4, m.void_area, m.link_contact)
    return net, w, m


def test_water_is_conserved_with_a_drained_and_an_inflow_wall():
    net, w, m = run_water(box(12.0, 12.0, ("inflow", "undrained", "drained", "undrained")))
    b = w.balance
    assert b.surface_outflow == 0.0 and b.side_outflow > 0
    inflow_pores = net.pore_walls[0].sum()
    assert inflow_pores >= 3
    np.testing.assert_allclose(b.inflow, 0.02 * inflow_pores * 300 * 1e-4, rtol=1e-12)  # q_w per pore of the wall
    assert w.balance_error() < 1e-13
    drained = net.flat_wall_pores("drained")
    U = w.pressure(m.void_area)
    assert drained.any() and U[net.pore_walls[0]].mean() > U[drained].mean()


def test_undrained_walls_let_no_water_through():
    net, w, m = run_water(box(12.0, 12.0), q_w=0.02, k3=50.0)  # no inflow or drained wall: q_w, k3 unused
    b = w.balance
    assert b.inflow == b.surface_outflow == b.side_outflow == 0.0
    assert abs(w.total_water() - b.initial) < 1e-14 * b.initial
    U = w.pressure(m.void_area)
    assert np.ptp(U) < 0.25 * np.ptp(w.U0)  # the water moved inside the box, towards equal pressures
    _, drained, _ = run_water(box(12.0, 12.0, ("undrained", "drained", "undrained", "undrained")))
    assert drained.balance.side_outflow > 0  # the same box with one drained wall loses water


def lifted_row(lift):
    """A row of 6 discs 0.05 m above a wall; disc 2 lifted by ``lift`` [m]."""
    xz = np.column_stack([2 * R * np.arange(6), np.full(6, R + 0.05)])
    xz[2, 1] += lift
    return xz, np.full(6, R)


def test_remeshing_counts_the_wall_as_one_vertex():
    xz, r = lifted_row(0.0)
    walls = (bottom("inflow"),)
    old = pg.build_pores(xz, r, l_m=0.1, flat_walls=walls)
    U_old = np.arange(1.0, old.n_pores + 1)
    U, rule = pressures_by_rule(old, U_old, np.ones(old.n_pores, bool), pg.build_pores(xz, r, l_m=0.1, flat_walls=walls))
    assert rule_counts(rule)["a"] == old.n_pores and np.array_equal(U, U_old)
    moved, _ = lifted_row(0.1)  # disc 2 out of the wall's reach: its two wall pores merge
    new = pg.build_pores(moved, r, l_m=0.1, flat_walls=walls)
    assert new.n_pores == old.n_pores - 1
    U, rule = pressures_by_rule(old, U_old, np.ones(old.n_pores, bool), new)
    merged = [p for p in range(new.n_pores) if set(new.vertices_of(p).tolist()) == {1, 2, 3, 6}]
    assert rule_counts(rule) == {"a": new.n_pores - 1, "b": 1, "c": 0, "d": 0} and rule[merged[0]] == 2
    both = [q for q in range(old.n_pores) if set(old.vertices_of(q).tolist()) in ({1, 2, 6}, {2, 3, 6})]
    assert U[merged[0]] == pytest.approx(U_old[both].mean(), rel=1e-15)


def test_a_water_model_with_flat_walls_rebuilds_and_conserves_water():
    xz, r = lifted_row(0.0)
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=0.01, transfer="conserving")
    model = WaterModel(s, r, np.zeros(6, np.int64), xz, 0.0, 0.1, 1e-4, Schedule(rebuild_interval=5),
                       flat_walls=(bottom("inflow"),))
    for k in range(1, 5):
        model.step(k, xz)
    moved, _ = lifted_row(0.1)
    model.step(5, moved)  # rebuilt: two wall pores merge
    assert model.n_rebuilds == 1 and model.water.net.n_pores == 4
    assert model.water.remesh_counts["b"] == 1
    b = model.water.balance
    assert b.inflow == pytest.approx(0.01 * 1e-4 * (4 * 5 + 4), rel=1e-12)  # 4 steps into 5 wall pores, 1 into 4
    assert abs(b.remesh_change) < 1e-14 * b.initial  # conserving: the merged pore covers the same ground
    assert model.water.balance_error() < 1e-13
    U = model.pressures(moved)
    m = pg.measure(model.water.net, moved, r)
    np.testing.assert_allclose(model.F_walls, pg.flat_wall_forces(model.water.net, U, m), rtol=1e-15)


def test_flat_walls_are_checked():
    xz, r = lifted_row(0.0)
    with pytest.raises(ValueError, match="disc 0 has its centre"):
        pg.build_pores(xz, r, l_m=0.1, flat_walls=(FlatWall(0, 0.5, +1),))
    with pytest.raises(ValueError, match="parallel walls must face each other"):
        pg.build_pores(xz, r, l_m=0.1, flat_walls=(FlatWall(0, -2.0, +1), FlatWall(0, -1.0, +1)))
    with pytest.raises(ValueError, match="boundary"):
        FlatWall(1, 0.0, +1, "open")
    with pytest.raises(ValueError, match="inward"):
        FlatWall(1, 0.0, 0)


def column_with_bottom(flat, nx=8, nz=8, gap=0.1, l_m=0.3):
    """nx x nz particles (radius R, gaps 0.1 R) between side columns of wall discs on a bottom row of
    wall discs or, ``flat``, on an inflow flat wall at that row's inner face z = R: (net, xz, r)."""
    s = 2 * R + gap
    part = square_lattice(nx, nz, s, origin=(s, s))
    sides = [np.column_stack([np.full(nz + 2, x), s * np.arange(1, nz + 3)]) for x in (0.0, (nx + 1) * s)]
    row = [] if flat else [np.column_stack([s * np.arange(nx + 2), np.zeros(nx + 2)])]
    xz = np.vstack([part, *row, *sides])
    codes = [np.zeros(len(part))] + [np.full(len(b), c) for b, c in zip(row + sides, ([] if flat else [1]) + [2, 3])]
    r = np.full(len(xz), R)
    net = pg.build_pores(xz, r, l_m=l_m, walls=np.concatenate(codes).astype(np.int64),
                         flat_walls=(bottom("inflow", z=R),) if flat else ())
    return net, xz, r


def test_a_flat_bottom_and_a_row_of_wall_discs_give_the_same_steady_bulk_pressures():
    """Steady inflow Q [m^2/s] through the bottom (q_w = Q / the bottom pores, 9 in both), out at
    the free surface: above the first particle row every pore is the same in both columns and, by
    the lattice's symmetry, carries the same flux Q / 9 upwards, so its steady U is the same
    whatever the bottom: the difference is the steady state's residual (the runs' 12 s are > 100
    relaxation times of the column: below 1e-9 of U), while the bottom pores themselves differ (a
    flat wall pore holds 0.74 R^2 of void, a wall-disc pore 1.27 R^2)."""
    U, key = [], []
    for flat in (False, True):
        net, xz, r = column_with_bottom(flat)
        m = pg.measure(net, xz, r)
        inflow = net.flat_wall_pores("inflow") | net.pore_touches["bottom"]
        w = PoreWater(net, m.void_area, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=0.6 / inflow.sum()))
        for _ in range(20000):
            w.advance(6e-4, m.void_area, m.link_contact)
        assert inflow.sum() == 9 and w.balance_error() < 1e-11
        particles = {tuple(net.vertices_of(p)): w.pressure(m.void_area)[p] for p in range(net.n_pores)
                     if np.all(net.vertices_of(p) < 64)}
        U.append(particles)
        key.append(set(particles))
    common = sorted(key[0] & key[1])
    assert len(common) == 49  # the 7 x 7 pores between the particles
    a, b = (np.array([u[k] for k in common]) for u in U)
    assert a.max() > 0.5  # N/m: a real gradient, 0.11 N/m a row
    np.testing.assert_allclose(b, a, rtol=1e-9)


def test_wall_vertices_link_along_a_common_wall_and_exist_within_reach():
    """WallVertices: two wall vertices are linked only when they lie on a common wall (two feet on
    the bottom, a foot and the corner of its wall; not feet on two walls); a disc's foot is a vertex
    of the build when its gap to the face is <= reach (eq 28, the equality included), a corner only
    when both its walls have one."""
    walls = (FlatWall(1, 0.0, +1), FlatWall(0, 0.0, +1))
    xz = np.array([[5.0, 1.5], [8.0, 1.2], [1.4, 6.0]])
    wv = WallVertices(walls, len(xz))
    corner = wv.foot(2, 0)
    feet_b, feet_l = wv.foot(0, np.arange(3)), wv.foot(1, np.arange(3))
    pairs = np.array([[feet_b[0], feet_b[1]], [feet_b[0], feet_l[2]], [feet_l[2], corner], [feet_b[1], corner],
                      [0, feet_b[0]], [0, feet_b[1]]])
    assert wv.is_link(pairs[:, 0], pairs[:, 1], np.zeros(len(pairs), bool)).tolist() == [True, False, True, True,
                                                                                       True, False]
    r = np.ones(3)
    active = set(wv.active(xz, r, 0.5).tolist())  # gaps to the bottom 0.5, 0.2, 5; to the left 4, 7, 0.4
    assert {feet_b[0], feet_b[1], feet_l[2], corner} <= active and not {feet_b[2], feet_l[0], feet_l[1]} & active
    far = xz + [2.0, 0.0]  # now no disc within reach of the left wall: no corner either
    assert set(wv.active(far, r, 0.5).tolist()) == {0, 1, 2, feet_b[0], feet_b[1]}


def test_a_translated_wall_closes_the_pores_where_it_stands():
    """WallVertices.move: a wall translated by (dx, dz) closes the pores as a FlatWall built at its
    new face: the same network and areas with the right wall moved out by 0.1 R and the top in by
    0.3 R; a translation along a face (the bottom by 0.7 R in x) moves no vertex."""
    xz, r, walls = random_box(3)
    moved = (walls[0], walls[1], FlatWall(0, walls[2].position + 0.1, -1), FlatWall(1, walls[3].position - 0.3, -1))
    wv = WallVertices(walls, len(r))
    wv.move([[0.7, 0.0], [0.0, 0.0], [0.1, 0.0], [0.0, -0.3]])
    np.testing.assert_array_equal(wv.faces(), [w.position for w in moved])
    a, b = (pg.build_pores(xz, r, l_m=0.3, flat_walls=f) for f in (wv, moved))
    assert a.n_pores == b.n_pores > 10
    for name in ("links", "pore_vertex_idx", "corner_pore", "throat_conns"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    np.testing.assert_array_equal(pg.vertex_positions(a, xz), pg.vertex_positions(b, xz))
    np.testing.assert_allclose(pg.measure(a, xz, r).void_area, pg.measure(b, xz, r).void_area, rtol=1e-15)
    with pytest.raises(ValueError, match="shift must be finite, of shape"):
        wv.move([[0.0, 0.0]])


def test_a_water_model_measures_at_its_moved_walls_and_rebuilds_there():
    """WaterModel.move_walls: after the right wall moves out by 0.2 R the void areas are those of
    the network at the new face, and a rebuild builds against it (water conserved)."""
    xz, r, walls = random_box(4)
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, transfer="conserving")
    model = WaterModel(s, r, np.zeros(len(r), np.int64), xz, 0.0, 0.3, 1e-4, flat_walls=walls)
    before = model.void_area(xz)
    shift = np.zeros((4, 2))
    shift[2, 0] = 0.2
    model.move_walls(shift)
    right = model.water.net.pore_walls[2]
    after = model.void_area(xz)
    assert right.sum() > 3 and np.all(after[right] > before[right]) and np.array_equal(after[~right], before[~right])
    model.rebuild(xz)
    assert np.allclose(model.water.net.wall_vertices.faces()[2], walls[2].position + 0.2)
    assert model.water.balance_error() < 1e-13


def test_the_wall_vertices_of_a_box_are_numbered_as_documented():
    """WallVertices of a box (bottom, left, right, top) for 3 discs: the feet N + w N + i, then one
    corner per pair of walls of different axes, owner -1 and both walls' bits; radii 0 for all of
    them; the links disc - foot of the active vertices, exactly."""
    walls = box(10.0, 10.0)
    wv = WallVertices(walls, 3)
    assert wv.corners.tolist() == [[0, 1], [0, 2], [1, 3], [2, 3]]
    assert wv.n_vertices == 3 + 4 * 3 + 4
    assert wv.owner.tolist() == [0, 1, 2] * 5 + [-1] * 4
    assert wv.bits.tolist() == [0] * 3 + [1] * 3 + [2] * 3 + [4] * 3 + [8] * 3 + [3, 5, 10, 12]
    np.testing.assert_array_equal(wv.radii([1.0, 2.0, 3.0]), [1.0, 2.0, 3.0] + [0.0] * 16)
    xz = np.array([[1.5, 1.2], [5.0, 1.2], [5.0, 5.0]])
    active = wv.active(xz, np.ones(3), 0.5)  # disc 0 in the corner (0.5 from the left: reach), disc 1 on the bottom
    assert active.tolist() == [0, 1, 2, 3, 4, 6, 15]
    assert wv.disc_feet(active).tolist() == [[0, 3], [1, 4], [0, 6]]


def test_bad_wall_sets_and_discs_on_a_face_are_refused_in_one_line():
    xz, r = lifted_row(0.0)
    with pytest.raises(ValueError, match=r"^flat wall 0 \(z = 0 m, inward \+1\): disc 2 has its centre at 0 m, not inside$"):
        xz_on = xz.copy()
        xz_on[2, 1] = 0.0  # on the face: refused, not only beyond it
        pg.build_pores(xz_on, r, l_m=0.1, flat_walls=(bottom(),))
    for a, b in ((FlatWall(0, 10.0, +1), FlatWall(0, 0.0, -1)), (FlatWall(0, 5.0, +1), FlatWall(0, 5.0, -1))):
        with pytest.raises(ValueError, match="parallel walls must face each other"):  # facing away; one plane
            WallVertices((a, b), 3)
    WallVertices((FlatWall(0, 0.0, +1), FlatWall(0, 10.0, -1)), 3)  # facing each other: taken
    with pytest.raises(TypeError, match="^flat_walls: expected FlatWall instances$"):
        WallVertices(({"axis": 0},), 3)
    with pytest.raises(ValueError, match=r"^FlatWall: axis must be 0 \(x = position\) or 1 \(z = position\), got 2$"):
        FlatWall(2, 0.0, +1)
    with pytest.raises(ValueError, match=r"^FlatWall: position must be finite \[m\], got nan$"):
        FlatWall(1, float("nan"), +1)


def test_the_tables_of_flat_walls_say_which_move():
    from engines.model.flat_walls import as_tables
    walls = box(10.0, 10.0)
    assert [w["moves"] for w in as_tables(walls)] == [False] * 4
    assert [w["moves"] for w in as_tables(walls, np.array([True, False, False, True]))] == [True, False, False, True]
    assert as_tables(walls)[2] == {"axis": "x", "position": 10.0, "inward": -1, "boundary": "undrained", "moves": False}


def test_disc_groups_and_flat_walls_of_one_kind_add_their_pores():
    """boundary_masks: a left column of drained wall discs ([water] sides = "drained") and a drained
    flat right wall: the drained pores are those of both, and the open top's are the surface's."""
    from engines.model.pore_water import boundary_masks
    xz, r, walls = lattice_box(4, 3)
    right = FlatWall(walls[2].axis, walls[2].position, walls[2].inward, "drained")
    x0 = xz[:, 0].min()
    column = np.column_stack([np.full(4, x0 - 2 * r.mean()), xz[:, 1].min() + 2 * r.mean() * np.arange(4)])
    xz2, r2 = np.vstack([xz, column]), np.concatenate([r, np.full(4, r.mean())])
    codes = np.concatenate([np.zeros(len(r), np.int64), np.full(4, pg.WALL_LEFT)])
    net = pg.build_pores(xz2, r2, l_m=0.8 * r.mean(), walls=codes, flat_walls=(walls[0], right))
    masks = boundary_masks(net, "drained")
    by_disc, by_wall = net.pore_touches["left"], net.flat_wall_pores("drained")
    assert by_disc.any() and by_wall.any() and (by_disc & ~by_wall).any() and (by_wall & ~by_disc).any()
    np.testing.assert_array_equal(masks["drained"], by_disc | by_wall)
    np.testing.assert_array_equal(masks["surface"], net.pore_surface)


def test_discs_out_of_a_walls_reach_build_an_empty_network_that_keeps_its_lengths():
    """Two discs far above a flat bottom: no pore, but the network keeps its discs, a_min, eps_m
    and l_m, and answers for its walls with arrays of no pore."""
    net = pg.build_pores(np.array([[0.0, 5.0], [3.0, 5.0]]), np.ones(2), l_m=0.5, eps_m=0.1,
                         flat_walls=(FlatWall(1, 0.0, +1),))
    assert (net.n_pores, net.n_discs, net.eps_m, net.l_m) == (0, 2, 0.1, 0.5)
    assert net.a_min == pytest.approx(1e-4 * np.pi, rel=1e-15)   # the default degenerate_fraction x pi r^2
    assert net.pore_walls.shape == (1, 0) and net.flat_wall_pores("inflow").shape == (0,)


def test_the_signatures_of_a_network_with_walls_are_those_of_its_vertex_sets():
    """Each pore's signature is the hash of its vertex set (a flat wall counted as one vertex), so
    re-meshing (rule a) finds the same set in any other network; and a wall word no wall has
    marks no pore, one entry per pore."""
    from engines.model.pores.faces import _set_signatures
    xz, r, walls = random_box(1)
    net = pg.build_pores(xz, r, l_m=0.8 * r.mean(), flat_walls=walls)
    assert net.n_pores > 10 and net.pore_walls.any()
    np.testing.assert_array_equal(net.pore_signature, _set_signatures(net.pore_vertex_ptr, net.pore_vertex_idx))
    assert net.flat_wall_pores("inflow").shape == (net.n_pores,) and not net.flat_wall_pores("inflow").any()
