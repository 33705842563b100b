"""Pore geometry (SPEC §2.2): exact areas, Euler's formula, independent walk, forces (eq 33)."""
import numpy as np
import pytest

from engines.model import pores as pg
from engines.model.pores import faces, links, triangulation
from engines.reference import model as ref
from packing.layouts import hex_lattice, random_discs
from tests.layouts import square_lattice
from tests.oracles import interior_angles, pore_polygon, void_area_by_triangles


@pytest.mark.parametrize("gap", [0.0, 0.05])
def test_hex_lattice_void_area_exact(gap):
    r, a = 1.0, 2.0 + gap  # spacing a, gap below l_m
    xz = hex_lattice(7, 6, a)
    net = pg.build_pores(xz, np.full(len(xz), r), l_m=0.1)
    m = pg.measure(net, xz, np.full(len(xz), r))
    exact = np.sqrt(3) / 4 * a**2 - np.pi * r**2 / 2  # triangle minus three 60-degree sectors
    assert net.n_pores == 2 * 6 * 5  # 2 (nx - 1) (nz - 1) triangles
    np.testing.assert_allclose(m.void_area, exact, rtol=1e-12)


@pytest.mark.parametrize("gap", [0.0, 0.05])
def test_square_lattice_void_area_exact(gap):
    r, a = 1.0, 2.0 + gap
    xz = square_lattice(6, 5, a)
    rr = np.full(len(xz), r)
    net = pg.build_pores(xz, rr, l_m=0.1)  # diagonals (2.83 a) are not links
    m = pg.measure(net, xz, rr)
    assert net.n_pores == 5 * 4
    np.testing.assert_allclose(m.void_area, a**2 - np.pi * r**2, rtol=1e-12)
    assert all(len(c) == 1 and len(c[0]) == 4 for c in (pore_polygon(net, p) for p in range(net.n_pores)))


def test_link_state_contact_versus_gap():
    xz = np.array([[0.0, 0.0], [1.99, 0.0], [1.0, 1.9]])  # overlap, gap 0.05 < l_m, gap 0.1 < l_m
    r = np.ones(3)
    net = pg.build_pores(xz, r, l_m=0.2)
    m = pg.measure(net, xz, r)
    state = {tuple(l): c for l, c in zip(net.links.tolist(), m.link_contact)}
    assert state[(0, 1)] and not state[(0, 2)] and not state[(1, 2)]
    assert net.n_pores == 1 and net.pore_surface.all()
    xz[1, 0] = 2.0   # exactly touching: a contact (eq 43b: the centres within r_i + r_j + eps_m)
    assert pg.measure(net, xz, r).link_contact[[tuple(l) for l in net.links.tolist()].index((0, 1))]


def test_euler_formula_random_packing():
    rng = np.random.default_rng(1)
    xz, r = random_discs(300, rng)
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean())
    # bounded faces = E - V + C (components of the link graph, isolated discs included)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    n = len(r)
    g = coo_matrix((np.ones(len(net.links)), (net.links[:, 0], net.links[:, 1])), shape=(n, n))
    c, _ = connected_components(g, directed=False)
    assert net.n_pores + net.n_closed == len(net.links) - n + c
    assert net.n_pores > 100


def _reference_pores(xz, r, l_m, walls=None):
    """The reference's pores (engines/reference/model.py: its own Delaunay candidates, union-find faces
    and the paper's walk over its own link lists), keyed by vertex set."""
    group = np.zeros(len(r), int) if walls is None else walls
    pores = ref.build_pores(xz, r, group, 0.0, l_m)
    return pores, {vs: p for p, vs in enumerate(pores.vertex_sets)}


def test_areas_against_the_reference_walk():
    """Every pore of build_pores is a pore of the reference's independent walk with the same vertex
    set, polygon area and void area (eq 29), rattlers and islands included."""
    rng = np.random.default_rng(2)
    xz, r = random_discs(200, rng)
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean())
    m = pg.measure(net, xz, r)
    rp, by_set = _reference_pores(xz, r, 0.7 * r.mean())
    geo = ref.measure(rp, xz, r, 0.0)
    assert net.n_pores == rp.n_pores > 100
    for p in range(net.n_pores):
        q = by_set[frozenset(net.vertices_of(p).tolist())]
        assert m.polygon_area[p] == pytest.approx(geo.polygon_area[q], rel=1e-10, abs=1e-15)
        assert m.void_area[p] == pytest.approx(geo.void_area[q], rel=1e-9, abs=1e-13)
    # discs whose every surrounding face is a pore lie wholly inside the region: 2 pi of angles
    total = np.zeros(len(r))
    for corners in interior_angles(net, m).values():
        for v, angle in corners.items():
            total[v] += angle
    inner = np.isclose(total, 2 * np.pi, rtol=1e-9)
    assert inner.sum() > 50
    assert np.all(total <= 2 * np.pi + 1e-9)


def _arc_forces(U, r, a1, a2, n=64):
    """-U r times the integral of the outward normal (cos a, sin a) over each arc a1 -> a2 (a2 > a1),
    by n-point Gauss-Legendre quadrature: the left-hand side of eq 33 integrated numerically. (K, 2)."""
    t, w = np.polynomial.legendre.leggauss(n)
    half = 0.5 * (a2 - a1)
    a = half[:, None] * t + (0.5 * (a2 + a1))[:, None]
    return -(U * r * half)[:, None] * np.column_stack([np.cos(a) @ w, np.sin(a) @ w])


@pytest.mark.parametrize("seed", [3, 8])
def test_eq33_against_arc_integrals_with_non_uniform_pressure(seed):
    """Random U per pore: the force on every disc equals the sum over the pores around it of the
    numerically integrated pressure on its arc inside each pore. The arcs come from the reference's
    independent walk (corner disc d, the arc from the direction d -> next counter-clockwise over the
    interior angle), not from the telescoped sum that pressure_forces uses."""
    rng = np.random.default_rng(seed)
    xz, r = random_discs(150, rng)
    l_m = 0.7 * r.mean()
    net = pg.build_pores(xz, r, l_m=l_m)
    m = pg.measure(net, xz, r)
    U = rng.uniform(-50.0, 200.0, net.n_pores)
    F = pg.pressure_forces(net, r, U, m)
    rp, by_set = _reference_pores(xz, r, l_m)
    U_ref = np.empty(rp.n_pores)
    for p in range(net.n_pores):
        U_ref[by_set[frozenset(net.vertices_of(p).tolist())]] = U[p]
    d, nxt = rp.corner_disc, rp.corner_next
    theta = ref.corner_angles(xz, d, rp.corner_prev, nxt)
    a1 = np.arctan2(xz[nxt, 1] - xz[d, 1], xz[nxt, 0] - xz[d, 0])
    expected = np.zeros_like(xz)
    np.add.at(expected, d, _arc_forces(U_ref[rp.corner_pore], r[d], a1, a1 + theta))
    scale = np.abs(U).max() * r.max()
    np.testing.assert_allclose(F, expected, rtol=0, atol=1e-12 * scale)
    assert np.abs(F).max() > 0.1 * scale  # the pressures are far from uniform: real forces


def test_measure_matches_triangles_after_motion():
    """Per-step areas (walk + eq 29) equal the triangle reference, also after the discs moved
    between rebuilds; link directions crossing the +-pi cut do not matter. The corner angles give
    the same sectors."""
    rng = np.random.default_rng(4)
    xz, r = random_discs(300, rng)
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean())
    for _ in range(5):
        xz = xz + 0.02 * r.mean() * rng.standard_normal(xz.shape)
        m = pg.measure(net, xz, r)
        np.testing.assert_allclose(m.void_area, void_area_by_triangles(net, xz, r), rtol=1e-9, atol=1e-13)
        # the corner angles are the sectors' (eq 29 corner by corner, against its sum over links)
        by_corners = 0.5 * np.bincount(net.corner_pore, m.corner_angle * net.corner_r2, minlength=net.n_pores)
        np.testing.assert_allclose(by_corners + net.rattler_area, m.sector_area, rtol=1e-12)


def test_eq33_single_arc():
    """A right-angle corner: the arc from alpha1 = 0 to alpha2 = pi/2 gets F = U r (-1, -1)."""
    xz = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    r = np.ones(3)
    net = pg.build_pores(xz, r, l_m=5.0)
    U = 7.0
    F = pg.pressure_forces(net, r, [U], pg.measure(net, xz, r))
    np.testing.assert_allclose(F[0], [-U, -U], rtol=1e-12)  # eq 33 with alpha1 = 0, alpha2 = 90 deg


def test_linear_pressure_archimedes():
    """U = G z at the pore centroids. On a regular hexagonal packing the net force on an inner
    disc is exactly -G times its hexagonal cell area 2 sqrt(3) r^2: the pore-averaged pressure
    acts on the disc plus its share of the void. Against Archimedes (-G pi r^2) this is the
    stated discretisation error 2 sqrt(3)/pi - 1 = 10.3 %."""
    r, G = 1.0, 50.0
    xz = hex_lattice(9, 9, 2.0)
    rr = np.full(len(xz), r)
    net = pg.build_pores(xz, rr, l_m=0.1)
    U = G * pg.pore_centroids(net, xz)[:, 1]
    F = pg.pressure_forces(net, rr, U, pg.measure(net, xz, rr))
    centre = np.argmin(np.hypot(*(xz - xz.mean(axis=0)).T))
    np.testing.assert_allclose(F[centre], [0.0, -G * 2 * np.sqrt(3) * r**2], atol=1e-9)
    assert abs(F[centre, 1] / (-G * np.pi * r**2) - 1) < 0.11
    # any direction: gradient along x
    U = G * pg.pore_centroids(net, xz)[:, 0]
    F = pg.pressure_forces(net, rr, U, pg.measure(net, xz, rr))
    np.testing.assert_allclose(F[centre], [-G * 2 * np.sqrt(3) * r**2, 0.0], atol=1e-9)


def test_walls_and_surface():
    """A box of wall discs open at the top: bottom pores touch the bottom wall, only top pores
    are on the free surface, and wall-wall edges are not surface."""
    xz, r, walls = _box_with_particles()
    net = pg.build_pores(xz, r, l_m=1.2, walls=walls)
    cz = pg.pore_centroids(net, xz)[:, 1]
    assert net.pore_touches["bottom"].any() and net.pore_touches["left"].any()
    assert net.pore_surface.any()
    assert cz[net.pore_surface].min() > cz[net.pore_touches["bottom"]].max()
    assert not (net.pore_surface & net.pore_touches["bottom"]).any()


def _box_with_particles():
    a = 2.0
    xz = hex_lattice(6, 5, a, origin=(1.5 * a, a * np.sqrt(3) / 2))
    bottom = np.column_stack([np.arange(0, 9) * a, np.zeros(9)])
    left = np.column_stack([np.zeros(5), np.arange(1, 6) * a])
    right = np.column_stack([np.full(5, 8 * a), np.arange(1, 6) * a])
    walls = np.concatenate([np.zeros(len(xz), int), np.full(9, pg.WALL_BOTTOM),
                            np.full(5, pg.WALL_LEFT), np.full(5, pg.WALL_RIGHT)])
    allxz = np.vstack([xz, bottom, left, right])
    return allxz, np.ones(len(allxz)), walls


@pytest.mark.parametrize("xz", [np.zeros((0, 2)), np.array([[0.0, 0.0], [1.0, 0.0]]),
                                np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])])
def test_degenerate_inputs_give_no_pores(xz):
    r = np.full(len(xz), 0.5)
    net = pg.build_pores(xz, r, l_m=0.1)
    m = pg.measure(net, xz, r)
    assert net.n_pores == 0 and m.void_area.size == 0
    assert np.all(pg.pressure_forces(net, r, np.zeros(0), m) == 0)


def test_rattler_without_links_is_subtracted_not_crashing():
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, np.sqrt(3)], [1.0, 1 / np.sqrt(3)]])
    r = np.array([1.0, 1.0, 1.0, 0.1])  # the small disc at the centroid is linked to nobody
    net = pg.build_pores(xz, r, l_m=0.01)
    m = pg.measure(net, xz, r)
    assert net.n_pores == 1
    assert not np.isin(3, net.links).any()
    np.testing.assert_allclose(m.void_area[0], np.sqrt(3) - np.pi / 2 - np.pi * 0.01, rtol=1e-12)
    F = pg.pressure_forces(net, r, [10.0], pg.measure(net, xz, r))
    assert np.all(np.isfinite(F)) and np.all(F[3] == 0)


def test_degenerate_pore_is_closed():
    # three touching discs around a vanishing pore: void area ~ 0 -> closed, not a pore
    r = np.ones(3)
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.05]])  # almost collinear, heavily overlapping
    net = pg.build_pores(xz, r, l_m=0.1)
    assert net.n_pores == 0 and net.n_closed == 1


@pytest.mark.parametrize("kw, message", [
    (dict(xz=np.array([[0.0, 0.0], [0.0, np.nan]])), r"^xz: non-finite value nan at flat index 3$"),
    (dict(r=np.array([1.0, np.inf])), r"^r: non-finite value inf at flat index 1$"),
    (dict(r=np.array([1.0, -1.0])), r"^r must be > 0, got r\[1\] = -1.0$"),
    (dict(r=np.array([1.0, 0.0])), r"^r must be > 0, got r\[1\] = 0.0$"),
    (dict(r=np.array([1.0])), r"^r: expected shape \(2,\), got \(1,\)$"),
    (dict(xz=np.zeros((2, 3))), r"^xz: expected shape \(None, 2\), got \(2, 3\)$"),
    (dict(eps_m=-1e-3), r"^eps_m must be finite and >= 0, got -0.001$"),
    (dict(l_m=-1e-3), r"^l_m must be finite and >= 0, got -0.001$"),
    (dict(degenerate_fraction=-1.0), r"^degenerate_fraction must be finite and >= 0, got -1.0$"),
    (dict(walls=np.zeros(3, np.int64)), r"^walls: expected shape \(2,\), got \(3,\)$"),
])
def test_bad_input_is_refused_in_one_line_naming_the_field(kw, message):
    args = dict(xz=np.array([[0.0, 0.0], [3.0, 0.0]]), r=np.array([1.0, 1.0]), eps_m=0.0, l_m=0.0)
    with pytest.raises(ValueError, match=message):
        pg.build_pores(**{**args, **kw})


def test_finite_arrays_come_back_as_floats():
    a = pg.check_finite_array("n", [1, 2])
    assert a.dtype == np.float64 and a.tolist() == [1.0, 2.0]


@pytest.mark.parametrize("xz", [np.zeros((0, 2)), np.array([[0.0, 0.0], [1.0, 0.0]]),
                                np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])])
def test_a_network_without_pores_is_well_formed_and_usable(xz):
    """Degenerate inputs give a network with every array empty and correctly shaped, the scene's
    eps_m, l_m and the closure area a_min = 1e-4 mean(pi r^2), on which the water and force code
    run without special cases."""
    from engines.model.pore_water import PoreWater, WaterSettings
    r = np.full(len(xz), 0.5)
    net = pg.build_pores(xz, r, eps_m=0.01, l_m=0.1, walls=np.full(len(xz), pg.WALL_BOTTOM))
    assert (net.n_discs, net.n_pores, net.n_closed, net.eps_m, net.l_m) == (len(xz), 0, 0, 0.01, 0.1)
    assert net.a_min == pytest.approx(1e-4 * np.pi * 0.25 if len(xz) else 0.0)
    for name in ("links", "link_pores", "throat_conns", "link_vec0"):
        assert getattr(net, name).shape == (0, 2), name
    assert net.tri.shape == (0, 3) and net.pore_vertex_ptr.tolist() == [0]
    for name in ("tri_pore", "throat_link", "pore_surface", "pore_vertex_idx", "pore_signature", "he_org",
                 "he_dst", "he_left", "he_next", "corner_pore", "corner_disc", "corner_link",
                 "corner_next_link", "corner_sign", "corner_r2", "corner_theta0", "rattler_area", "sector_area0",
                 "link_turn_weight"):
        assert getattr(net, name).shape == (0,), name
    assert sorted(net.pore_touches) == ["bottom", "left", "right"]
    assert all(v.shape == (0,) and v.dtype == bool for v in net.pore_touches.values())
    assert (net.pore_surface.dtype, net.pore_vertex_ptr.dtype, net.pore_signature.dtype) == (bool, np.int64, np.uint64)
    m = pg.measure(net, xz, r)
    assert pg.pore_centroids(net, xz).shape == (0, 2)
    w = PoreWater(net, m.void_area, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=1.0))
    w.advance(1.0, m.void_area, m.link_contact)
    assert w.darcy_limit(m.void_area, m.link_contact) == np.inf and w.total_water() == 0.0


def test_centroids_and_polygons_of_a_square_lattice():
    """Each pore of a square lattice (spacing a) is its cell: the walk visits its 4 corners
    counter-clockwise (positive shoelace area a^2) and the area-weighted centroid is the cell centre."""
    a = 2.05
    xz = square_lattice(5, 4, a, origin=(3.0, -1.0))
    r = np.ones(len(xz))
    net = pg.build_pores(xz, r, l_m=0.1)
    cen = pg.pore_centroids(net, xz)
    for p in range(net.n_pores):
        (cycle,) = pore_polygon(net, p)
        corners = xz[cycle]
        assert len(cycle) == 4 and set(cycle) == set(net.vertices_of(p).tolist())
        shoelace = 0.5 * np.sum(corners[:, 0] * np.roll(corners[:, 1], -1) - np.roll(corners[:, 0], -1) * corners[:, 1])
        assert shoelace == pytest.approx(a * a, rel=1e-12)
        np.testing.assert_allclose(cen[p], corners.mean(axis=0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(void_area_by_triangles(net, xz, r), a * a - np.pi, rtol=1e-12)


def test_link_state_counts_eps_m_as_contact():
    """Eq 43 with eps_m > 0: a link whose gap is below eps_m is a contact (k2); above it, not."""
    r = np.ones(3)
    xz = np.array([[0.0, 0.0], [2.03, 0.0], [1.0, 1.75]])   # gaps 0.03 (0-1), 0.016 (0-2), 0.031 (1-2)
    net = pg.build_pores(xz, r, eps_m=0.02, l_m=0.2)
    m = pg.measure(net, xz, r)
    state = {tuple(l): c for l, c in zip(net.links.tolist(), m.link_contact)}
    gaps = {k: np.hypot(*(xz[k[1]] - xz[k[0]])) - 2.0 for k in state}
    assert state == {k: g <= 0.02 for k, g in gaps.items()}
    assert sorted(state.values()) == [False, False, True]


def test_pore_signatures_identify_vertex_sets():
    """Different vertex sets have different signatures (rule (a) relies on it), here for every pore
    of a random packing against every other; a rebuild at the same positions gives the same ones;
    the keys of the discs are distinct."""
    rng = np.random.default_rng(9)
    xz, r = random_discs(400, rng)
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean())
    sets = [frozenset(net.vertices_of(p).tolist()) for p in range(net.n_pores)]
    sig = net.pore_signature.tolist()
    assert len(set(sets)) == len(sets) == len(set(sig))
    again = pg.build_pores(xz + 1e-9, r, l_m=0.7 * r.mean())
    assert {frozenset(again.vertices_of(p).tolist()): s for p, s in enumerate(again.pore_signature.tolist())} == dict(zip(sets, sig))
    keys = faces._mix64(np.arange(100000))
    assert len(np.unique(keys)) == 100000


def test_interior_angles_of_every_pore_walk_sum_to_k_minus_2_pi():
    """The closed walk around a pore with K corners turns through (K - 2) pi of interior angles
    (eq 29), dangling links included (2 pi at the tip, the base disc met twice and summed)."""
    rng = np.random.default_rng(14)
    xz, r = random_discs(300, rng)
    keep = rng.random(len(r)) > 0.35                # holes: dangling links and pinches appear
    xz, r = xz[keep], r[keep]
    net = pg.build_pores(xz, r, l_m=0.9 * r.mean())
    m = pg.measure(net, xz, r)
    angles = interior_angles(net, m)
    repeated = 0
    for p in range(net.n_pores):
        cycles = pore_polygon(net, p)
        if len(cycles) != 1:
            continue
        k = len(cycles[0])
        repeated += k > len(set(cycles[0]))
        assert sum(angles[p].values()) == pytest.approx((k - 2) * np.pi, rel=1e-9)
    assert repeated > 0


def test_the_outer_boundary_of_a_pore_with_an_island_comes_first():
    """A ring of 8 linked discs around a linked pair that touches none of them: one pore whose walk
    has two cycles, the ring's (8 corners) first, then the island's (2), clockwise (negative area)."""
    ring = 6.0 * np.array([[np.cos(a), np.sin(a)] for a in np.arange(8) * np.pi / 4])
    xz = np.vstack([ring, [[-0.8, 0.0], [0.8, 0.0]]])
    r = np.concatenate([np.full(8, 2.2), [0.7, 0.7]])
    net = pg.build_pores(xz, r, l_m=0.3)
    assert net.n_pores == 1
    cycles = pore_polygon(net, 0)
    assert [len(c) for c in cycles] == [8, 2] and set(cycles[1]) == {8, 9}


def test_locate_points_in_triangles_edges_count_as_inside():
    """Point location (used for the rattlers off the regular triangulation): the first triangle
    holding each point, a point on an edge inside, a point outside every triangle -1; millimetre
    coordinates, two triangles of a square split along its diagonal."""
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0], [2.0, 2.0]]) * 1e-3
    tri = np.array([[0, 1, 2], [1, 3, 2]])                     # both counter-clockwise
    points = np.array([[0.5, 0.5], [1.5, 1.5], [3.0, 3.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0],
                       [-1.0, 1.0], [1.5, -0.1]]) * 1e-3
    # inside 0, inside 1, outside, on 0's edges ab and ca, on the shared diagonal (first: 0), on 1's
    # edge ab, outside beside edge ca of 0 (two of its three sides positive), below edge ab
    np.testing.assert_array_equal(triangulation._locate(xz, tri, points), [0, 1, -1, 0, 0, 0, 1, -1, -1])


def test_three_touching_discs_make_one_pore():
    """The smallest packing with a pore: three equal touching discs, void sqrt(3) r^2 - pi r^2 / 2."""
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, np.sqrt(3)]])
    net = pg.build_pores(xz, np.ones(3))
    assert net.n_pores == 1 and len(net.links) == 3
    np.testing.assert_allclose(pg.measure(net, xz, np.ones(3)).void_area, [np.sqrt(3) - np.pi / 2], rtol=1e-12)


def _edges_of(tri):
    return {tuple(sorted(e)) for t in tri.tolist() for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}


@pytest.mark.parametrize("seed", range(4))
def test_edge_insertion_by_flips_keeps_a_triangulation(seed):
    """Sloan's edge insertion (the hidden eq 28 pairs, READINGS D4) on a long segment across a
    random Delaunay triangulation (many crossed edges, some in non-convex quadrilaterals): after
    it k - l is an edge, the triangles are as many, all counter-clockwise, cover the same area,
    every edge bounds at most two of them, and only crossed edges were replaced."""
    rng = np.random.default_rng(seed)
    xz = rng.random((60, 2))
    from scipy.spatial import Delaunay
    tri = triangulation._ccw(xz, Delaunay(xz).simplices)
    k, l = int(np.argmin(xz.sum(axis=1))), int(np.argmax(xz.sum(axis=1)))   # opposite corners
    ft = links._FlipTriangulation(xz, tri)
    edges = ft.crossed_edges(k, l)
    assert edges is not None and len(edges) >= 6
    ft.insert(k, l, edges)
    new = ft.triangles()
    assert (k, l) in ft.third or (l, k) in ft.third
    assert len(new) == len(tri) and np.all(triangulation._signed_area(xz[new]) > 0)
    assert triangulation._signed_area(xz[new]).sum() == pytest.approx(triangulation._signed_area(xz[tri]).sum(), rel=1e-12)
    count = {}
    for t in new.tolist():
        for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            count[tuple(sorted(e))] = count.get(tuple(sorted(e)), 0) + 1
    assert max(count.values()) == 2
    crossed = {tuple(sorted(e)) for e in edges}
    assert _edges_of(tri) - crossed <= _edges_of(new)
    # the flipped triangulation answers further walks from k and l (their neighbour sets kept up to date)
    for v in (k, l):
        for m in range(len(xz)):
            if m != v and tuple(sorted((v, m))) not in _edges_of(new):
                got = ft.crossed_edges(v, m)
                assert got is not None and {tuple(sorted(e)) for e in got} == _proper_crossings(xz, new, v, m)


def test_edge_insertion_that_cannot_converge_stops_naming_the_link():
    """A crossed edge whose quadrilateral is never convex would be retried forever: the insertion
    stops after its budget (a safety stop: a real insertion always has a flippable edge) with an
    error naming the link."""
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 1.0], [1.0, 0.2]])    # 3 inside triangle 0, 1, 2
    tri = triangulation._ccw(xz, np.array([[0, 1, 3], [1, 2, 3], [2, 0, 3]]))
    ft = links._FlipTriangulation(xz, tri)
    # edge 1-3 lies between triangles (0, 1, 3) and (1, 2, 3): their quadrilateral is not convex at 3
    with pytest.raises(RuntimeError, match="link 0-2 did not converge"):
        ft.insert(0, 2, [(1, 3)])


def _proper_crossings(xz, tri, k, l):
    """The triangulation edges that the segment k-l crosses at an interior point of both (written
    out from orientations, independently of _FlipTriangulation's walk)."""
    o = links._orient
    p = [tuple(v) for v in xz.tolist()]
    out = set()
    for a, b in _edges_of(tri):
        if {a, b} & {k, l}:
            continue
        if o(p[k], p[l], p[a]) * o(p[k], p[l], p[b]) < 0 and o(p[a], p[b], p[k]) * o(p[a], p[b], p[l]) < 0:
            out.add((a, b))
    return out


@pytest.mark.parametrize("seed", range(3))
def test_crossed_edges_are_those_the_segment_crosses_in_order(seed):
    """The walk from k to l returns exactly the edges the segment crosses, in order along it."""
    from scipy.spatial import Delaunay
    xz = np.random.default_rng(10 + seed).random((40, 2))
    tri = triangulation._ccw(xz, Delaunay(xz).simplices)
    k, l = int(np.argmin(xz[:, 0])), int(np.argmax(xz[:, 0]))
    edges = links._FlipTriangulation(xz, tri).crossed_edges(k, l)
    assert {tuple(sorted(e)) for e in edges} == _proper_crossings(xz, tri, k, l) and len(edges) >= 3
    d = xz[l] - xz[k]
    t = [np.linalg.solve(np.column_stack([d, xz[a] - xz[b]]), xz[a] - xz[k])[0] for a, b in edges]
    assert np.all(np.diff(t) > 0) and 0 < t[0] and t[-1] < 1


def test_crossed_edges_through_a_vertex_and_past_one_behind():
    """Integer coordinates, B exactly on the line through k and l: the segment k -> F runs through
    B (None: no edge can be inserted), while k -> l, with B behind k, crosses its edges as usual."""
    from scipy.spatial import Delaunay
    xz = np.array([[0.0, 0.0], [2.0, 4.0], [1.5, 1.8], [0.5, 2.2], [-2.0, 0.0], [1.0, -2.0],
                   [-2.0, -4.0], [-3.0, -3.0], [-1.0, -2.0]])
    k, l, F, B = 0, 1, 6, 8          # B last: k's other neighbours are looked at first
    tri = triangulation._ccw(xz, Delaunay(xz).simplices)
    assert (k, B) in _edges_of(tri) and (k, l) not in _edges_of(tri)
    ft = links._FlipTriangulation(xz, tri)
    assert ft.crossed_edges(k, F) is None
    edges = ft.crossed_edges(k, l)
    assert edges is not None and {tuple(sorted(e)) for e in edges} == _proper_crossings(xz, tri, k, l)


def test_crossed_edges_through_a_vertex_further_along():
    """Integer coordinates, disc 2 exactly on the segment 0 -> 1 but not joined to 0 (the edge 3-4
    lies between): the walk reaches 2 and stops (None), while 0 -> 5 crosses 3-4 and 2-3."""
    from scipy.spatial import Delaunay
    xz = np.array([[0, 0], [4, 0], [2, 0], [1, 0.5], [1, -0.5], [3, 0.5], [3, -0.5], [2, 3], [2, -3]], float)
    tri = triangulation._ccw(xz, Delaunay(xz).simplices)
    assert not {(0, 1), (0, 2)} & _edges_of(tri)
    ft = links._FlipTriangulation(xz, tri)
    assert ft.crossed_edges(0, 1) is None
    assert {tuple(sorted(e)) for e in ft.crossed_edges(0, 5)} == _proper_crossings(xz, tri, 0, 5) == {(3, 4), (2, 3)}


def test_the_link_range_is_checked_in_median_radii_and_holds_the_contact_range():
    """check_lengths: l_m within LINK_RANGE x the median radius (both ends allowed), eps_m <= l_m;
    each refusal names the caller's field. Radii of median 1 mm and mean 2 mm: the median counts."""
    r = np.array([1e-3, 1e-3, 4e-3])
    lo, hi = pg.LINK_RANGE
    for l_m in (lo * 1e-3, hi * 1e-3):
        pg.check_lengths(l_m, l_m, r)
    for l_m, ratio in ((0.99 * lo * 1e-3, f"{0.99 * lo:.3g}"), (1.01 * hi * 1e-3, f"{1.01 * hi:.3g}")):
        with pytest.raises(ValueError, match=rf"^link_range = {l_m:.3g} m is {ratio} x the median disc radius 0.001 m, "
                                             r"outside .* and of link_range \(both in m\)$"):
            pg.check_lengths(l_m, 0.0, r, names=("link_range", "contact_range"))
    with pytest.raises(ValueError, match=r"^contact_range = 0.000101 m exceeds link_range = 0.0001 m: .* reduce "
                                         r"contact_range or raise link_range$"):
        pg.check_lengths(1e-4, 1.01e-4, r, names=("link_range", "contact_range"))
    with pytest.raises(ValueError, match=r"^eps_m = .* exceeds l_m"):
        pg.check_lengths(1e-4, 1.01e-4, r)


@pytest.mark.parametrize("flat", [False, True])
def test_a_stored_network_whose_arrays_do_not_fit_is_refused(flat):
    """PoreNetwork.checkpoint_restored: a network as built passes; an array one row too long, an
    index one past its range or one below it, a pore_touches of another length and pointers
    that do not start each pore's vertices are each refused naming what is wrong (a kernel would
    read out of bounds). With flat walls the indices run over the wall vertices too."""
    from dataclasses import replace

    from engines.model.flat_walls import FlatWall
    from engines.model.pores.network import CHECKPOINT_SHAPES
    rng = np.random.default_rng(4)
    xz, r = random_discs(60, rng)
    walls = (FlatWall(1, xz[:, 1].min() - r.max(), +1),) if flat else ()
    net = pg.build_pores(xz, r, l_m=0.3 * r.mean(), walls=np.zeros(len(r), np.int64), flat_walls=walls)
    net.checkpoint_restored()
    n_vertices = net.wall_vertices.n_vertices if flat else len(r)
    assert (net.pore_walls is not None) == flat and net.link_pores.min() == -1
    sizes = {"P": net.n_pores, "L": len(net.links), "H": 2 * len(net.links), "K": len(net.corner_pore),
             "T": len(net.throat_conns), "S": len(net.pore_vertex_idx), "V": n_vertices}
    for name, (shape, lo, hi) in CHECKPOINT_SHAPES.items():
        a = getattr(net, name)
        if a is None:
            continue
        with pytest.raises(ValueError, match=r"^pore network: (\w+ has shape|pore_vertex_ptr is not)"):
            replace(net, **{name: np.concatenate([a, a[:1]], axis=0)}).checkpoint_restored()
        if lo is None:
            continue
        top = sizes[hi] + (name == "pore_vertex_ptr")
        for value in (lo - 1, top):
            bad = a.copy()
            bad.flat[-1 if name == "pore_vertex_ptr" else 0] = value
            with pytest.raises(ValueError, match=rf"^pore network: ({name} holds indices outside \[{lo}, {top}\)"
                                                 r"|pore_vertex_ptr is not)"):
                replace(net, **{name: bad}).checkpoint_restored()
    with pytest.raises(ValueError, match=r"pore_touches\['bottom'\] has shape"):
        replace(net, pore_touches={**net.pore_touches, "bottom": np.zeros(net.n_pores + 1, bool)}).checkpoint_restored()
    ptr = net.pore_vertex_ptr.copy()
    ptr[[1, 2]] = ptr[[2, 1]]
    for bad in (ptr, np.append(net.pore_vertex_ptr[:-1], net.pore_vertex_ptr[-1] - 1)):
        with pytest.raises(ValueError, match="pore_vertex_ptr is not the start of each pore's vertices"):
            replace(net, pore_vertex_ptr=bad).checkpoint_restored()


def test_crossed_edges_from_every_vertex_of_the_hull():
    """From each hull vertex (one of its edges has no triangle on its left) to every vertex it is
    not joined to, the walk returns the edges the segment crosses."""
    from scipy.spatial import ConvexHull, Delaunay
    xz = np.random.default_rng(5).random((30, 2))
    tri = triangulation._ccw(xz, Delaunay(xz).simplices)
    ft, edges = links._FlipTriangulation(xz, tri), _edges_of(tri)
    for k in ConvexHull(xz).vertices.tolist():
        for m in range(len(xz)):
            if m != k and tuple(sorted((k, m))) not in edges:
                got = ft.crossed_edges(k, m)
                assert got is not None and {tuple(sorted(e)) for e in got} == _proper_crossings(xz, tri, k, m)


def test_eq28_pairs_count_the_range_at_any_radius_and_touching_pairs():
    """Eq 28 pairs: discs of radius 2 exactly touching (reach 0) are a pair, one reach further
    apart too, beyond it not; a single disc has none, as a (0, 2) int array."""
    xz = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 4.3], [20.0, 0.0], [24.5, 0.0]])
    pairs = links.eq28_pairs(xz, np.full(5, 2.0), 0.3)
    assert sorted(map(tuple, pairs.tolist())) == [(0, 1), (0, 2)]
    np.testing.assert_array_equal(links.eq28_pairs(xz[:2], np.full(2, 2.0), 0.0), [[0, 1]])
    alone = links.eq28_pairs(xz[:1], np.full(1, 2.0), 0.3)
    assert alone.shape == (0, 2) and alone.dtype == np.int64


def test_a_network_keeps_its_lengths_and_counts_no_insertion_where_none_was_needed():
    """A hexagonal lattice: every eq 28 pair is a Delaunay edge already (n_inserted = 0), and the
    network holds the eps_m and l_m it was built with."""
    xz = hex_lattice(6, 5, 2.1)
    net = pg.build_pores(xz, np.ones(len(xz)), eps_m=0.02, l_m=0.2)
    assert (net.n_inserted, net.eps_m, net.l_m) == (0, 0.02, 0.2) and net.n_pores > 20
