"""Compiled rebuild (engines.compiled.pores) against the readable NumPy path: the same network (integer
arrays equal, floats to 1e-12 relative) and the same re-meshing, on packings that exercise every
branch: lattices (cocircular ties), random packings with walls, holes (dangling links, pinches),
rattlers in and off the triangulation, a hidden eq 28 pair put in by flips, closed faces, and inputs
without pores; and with flat walls (SPEC §2.6): a random packing in a box, lattices resting on
walls, discs beyond the walls' reach, hidden disc-foot links."""
import copy
import dataclasses

import numpy as np
import pytest

from engines.compiled import pores as kp
from engines.compiled.pores.overlaps import _clip_area
from engines.model import pores as pg
from engines.model.pores import links, overlaps, triangulation
from engines.model.flat_walls import FlatWall, WallVertices
from engines.model.pore_water import PoreWater, WaterSettings, near_vertex_sets, pressure, pressures_by_rule
from packing.layouts import hex_lattice, random_discs
from packing.psd import sample_diameters
from tests.layouts import random_sequential, square_lattice

RTOL = 1e-12


def assert_same(a, b, what):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, what
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        scale = max(np.max(np.abs(b), initial=0.0), 1e-300)
        assert np.max(np.abs(a - b), initial=0.0) <= RTOL * scale, what
    else:
        assert a.dtype == b.dtype and np.array_equal(a, b), what


def assert_same_network(a, b):
    for f in dataclasses.fields(pg.PoreNetwork):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, WallVertices):
            assert x.walls == y.walls and x.n == y.n, f.name
            for k in ("owner", "bits", "corners"):
                assert_same(getattr(x, k), getattr(y, k), f"{f.name}.{k}")
        elif isinstance(x, dict):
            assert x.keys() == y.keys(), f.name
            for k in x:
                assert_same(x[k], y[k], f"{f.name}[{k}]")
        else:
            assert_same(x, y, f.name)


def _holes(seed):
    """Random discs with a third removed: dangling links, pinched pores, islands."""
    rng = np.random.default_rng(seed)
    xz, r = random_discs(300, rng)
    keep = rng.random(len(r)) > 0.35
    return xz[keep], r[keep], None, 0.0, 0.9 * r[keep].mean()


def _walled(seed):
    """Random discs squeezed together (overlaps) with a bottom row and side columns as walls."""
    rng = np.random.default_rng(seed)
    xz, r = random_discs(300, rng)
    xz = 0.98 * xz
    walls = np.zeros(len(r), np.int64)
    walls[xz[:, 1] < xz[:, 1].min() + 0.5] = pg.WALL_BOTTOM
    walls[(xz[:, 0] < xz[:, 0].min() + 0.5) & (walls == 0)] = pg.WALL_LEFT
    walls[(xz[:, 0] > xz[:, 0].max() - 0.5) & (walls == 0)] = pg.WALL_RIGHT
    return xz, r, walls, 0.02, 0.1


def _loose(seed, eps_m, l_m):
    """Random sequential addition of the paper's diameters: gaps of all sizes, hidden eq 28 pairs."""
    rng = np.random.default_rng(seed)
    xz, r = random_sequential(sample_diameters(450, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, rng), 0.021, 0.021, rng)
    return xz, r, None, eps_m, l_m


def _rattlers():
    """Small discs: one linked to nobody inside a pore, one with an empty power cell, one dangling."""
    big = np.array([[0.0, 0.0], [4.2, 0.0], [2.1, 4.2 * np.sqrt(3) / 2]])
    centre = big.mean(axis=0)
    dangling = big[0] + 2.1 * (centre - big[0]) / np.linalg.norm(centre - big[0])
    far = big + [[10.0, 0.0]]
    xz = np.vstack([big, dangling, far, far.mean(axis=0), far[0] + [0.3, 0.2]])
    r = np.array([2.0, 2.0, 2.0, 0.05, 2.0, 2.0, 2.0, 0.05, 0.1])
    return xz, r, None, 0.0, 0.25


def _ring():
    """40 discs in a ring, linked to their neighbours only: one pore of 38 triangles (many vertices)."""
    a = np.arange(40) * 2 * np.pi / 40
    rad = 13.1 * (1 + 1e-3 * np.random.default_rng(2).standard_normal(40))
    return np.column_stack([rad * np.cos(a), rad * np.sin(a)]), np.ones(40), None, 0.0, 0.1


def _kite():
    return np.array([[-1.6, 0.0], [1.6, 0.0], [0.0, 1.2], [0.0, -2.1]]), np.ones(4), None, 0.0, 1.25


PACKINGS = {
    "hex": lambda: (hex_lattice(9, 8, 2.05), np.ones(72), None, 0.0, 0.1),
    "square": lambda: (square_lattice(7, 6, 2.0), np.ones(42), None, 0.0, 0.1),
    "holes-14": lambda: _holes(14),
    "holes-3": lambda: _holes(3),
    "walled": lambda: _walled(5),
    "loose-seismic": lambda: _loose(0, 2e-4, 3.5e-4),
    "loose-quicksand": lambda: _loose(1, 0.0, 1.3e-4),
    "rattlers": _rattlers,
    "kite": _kite,
    "ring": _ring,
    "closed-face": lambda: (np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.05], [1.0, 3.0]]), np.ones(4), None, 0.0, 0.1),
    "collinear": lambda: (np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]), np.full(3, 0.5), None, 0.0, 0.1),
    "coincident": lambda: (np.zeros((3, 2)), np.full(3, 0.5), None, 0.0, 0.1),
    "two": lambda: (np.array([[0.0, 0.0], [1.0, 0.0]]), np.full(2, 0.5), None, 0.0, 0.1),
}


# flat walls (SPEC §2.6)
def _boxed(seed, eps_m, l_m):
    """_loose's packing in a box of four flat walls at the discs' extremes (the outermost discs touch
    them, the others at gaps of all sizes)."""
    xz, r, _, _, _ = _loose(seed, eps_m, l_m)
    lo, hi = (xz - r[:, None]).min(axis=0), (xz + r[:, None]).max(axis=0)
    walls = (FlatWall(1, lo[1], +1, "inflow"), FlatWall(0, lo[0], +1), FlatWall(0, hi[0], -1, "drained"),
             FlatWall(1, hi[1], -1))
    return xz, r, eps_m, l_m, walls


def _hex_on_a_wall():
    """A hexagonal bed of touching discs resting on a flat bottom (cocircular ties, collinear feet);
    the rows above the first are out of the wall's reach."""
    return hex_lattice(9, 6, 2.0, origin=(1.0, 1.0)), np.ones(54), 0.0, 0.1, (FlatWall(1, 0.0, +1),)


def _square_in_a_box():
    """A square lattice of touching discs touching the four walls of its box (its corners)."""
    walls = (FlatWall(1, 0.0, +1), FlatWall(0, 0.0, +1), FlatWall(0, 14.0, -1), FlatWall(1, 12.0, -1))
    return square_lattice(7, 6, 2.0, origin=(1.0, 1.0)), np.ones(42), 0.0, 0.1, walls


FLAT = {
    "box-quicksand": lambda: _boxed(1, 0.0, 1.3e-4),
    "box-reach": lambda: _boxed(0, 2e-4, 3.5e-4),  # eps_m, l_m > 0: discs near a wall beyond its reach
    "box-long-lm": lambda: _boxed(2, 0.0, 1e-3),    # disc-foot links the regular triangulation hides
    "hex-on-a-wall": _hex_on_a_wall,
    "square-in-a-box": _square_in_a_box,
}


def _build(name, **kw):
    """The network of PACKINGS[name] (wall discs by code) or of FLAT[name] (flat walls)."""
    if name in FLAT:
        xz, r, eps_m, l_m, flat_walls = FLAT[name]()
        return pg.build_pores(xz, r, eps_m, l_m, flat_walls=flat_walls, **kw)
    xz, r, walls, eps_m, l_m = PACKINGS[name]()
    return pg.build_pores(xz, r, eps_m, l_m, walls=walls, **kw)


@pytest.mark.parametrize("name", [*PACKINGS, *FLAT])
def test_compiled_build_gives_the_same_network(name):
    assert_same_network(_build(name, steps=kp.BUILD), _build(name))


@pytest.mark.parametrize("steps", [pg.NUMPY_BUILD, kp.BUILD], ids=["numpy", "compiled"])
def test_a_face_of_exactly_a_min_is_closed(steps):
    """A face is a pore when its void exceeds a_min (eq 29): one linked triangle of area 1/2 of discs
    so small that their sectors vanish (void 1/2 exactly) is closed at a_min = 1/2 and a pore one
    rounding step below it."""
    xz, r, tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.full(3, 1e-200), np.array([[0, 1, 2]])
    for a_min, pores, closed in ((0.5, 0, 1), (np.nextafter(0.5, 0.0), 1, 0)):
        assert steps.faces(xz, r, tri, 2.0, a_min)[4:6] == (pores, closed)


def test_the_packings_exercise_every_branch():
    """The cases above are not vacuous: flips, closed faces, rattlers, dangling links, walls occur."""
    nets = {name: _build(name) for name in PACKINGS}
    assert nets["kite"].n_inserted == 1 and nets["loose-seismic"].n_inserted > 0
    assert nets["closed-face"].n_closed == 1 and nets["collinear"].n_pores == 0
    np.testing.assert_allclose(nets["rattlers"].rattler_area, [0.0, np.pi * (0.05**2 + 0.1**2)], rtol=1e-12)
    assert 8 not in nets["rattlers"].tri and 8 in nets["rattlers"].pore_vertex_idx  # empty power cell
    for name in ("rattlers", "holes-14"):
        twin = np.r_[np.arange(len(nets[name].links)) + len(nets[name].links), np.arange(len(nets[name].links))]
        assert np.any(nets[name].he_next == twin), name  # a dangling link
    assert nets["walled"].pore_touches["bottom"].any() and nets["walled"].pore_surface.any()
    assert nets["ring"].n_pores == 1 and len(nets["ring"].tri) == 38


@pytest.mark.parametrize("name", PACKINGS)
def test_the_lifted_points_are_bit_for_bit_those_of_numpy(name):
    """The hull of the same points: qhull makes the same choices, even between cocircular discs."""
    xz, r = PACKINGS[name]()[:2]
    want = triangulation._lifted_points(xz, r)
    got = kp.lifted_points(xz, r, xz.mean(axis=0))
    assert (got is None and want is None) or np.array_equal(got, want)


@pytest.mark.parametrize("name", ["loose-seismic", "holes-14", "walled"])
def test_missing_pairs_are_those_of_the_numpy_search(name):
    xz, r, _, eps_m, l_m = PACKINGS[name]()
    tri = pg.regular_triangulation(xz, r)
    pairs = pg.eq28_pairs(xz, r, eps_m + l_m)
    edges = {tuple(sorted(e)) for t in tri.tolist() for e in zip(t, t[1:] + t[:1])}
    vertex = np.isin(np.arange(len(r)), tri)
    expected = sorted(tuple(p) for p in pairs.tolist() if tuple(p) not in edges and vertex[p].all())
    assert sorted(map(tuple, kp._missing_pairs(xz, r, eps_m + l_m, tri).tolist())) == expected


def _moved(seed, jitter, flat=False):
    """An old network of a loose packing and a new one after every disc moved by ~jitter radii;
    ``flat``: in _boxed's box of flat walls, a centre moved out of it reflected back in."""
    xz, r, eps_m, l_m, walls = _boxed(seed, 2e-4, 3.5e-4)
    rng = np.random.default_rng(seed)
    xz2 = xz + jitter * r.mean() * rng.standard_normal(xz.shape)
    if flat:
        lo, hi = (xz - r[:, None]).min(axis=0), (xz + r[:, None]).max(axis=0)  # _boxed's walls
        xz2 = hi - np.abs(hi - (lo + np.abs(xz2 - lo)))
    flat_walls = walls if flat else ()
    old = pg.build_pores(xz, r, eps_m, l_m, flat_walls=flat_walls)
    new = pg.build_pores(xz2, r, eps_m, l_m, flat_walls=flat_walls)
    return old, new, xz2, r, rng


@pytest.mark.parametrize("flat", [False, True])
@pytest.mark.parametrize("seed,jitter", [(0, 0.02), (1, 0.1), (2, 0.3)])
def test_compiled_rules_give_the_same_pressures(seed, jitter, flat):
    old, new, xz2, r, rng = _moved(seed, jitter, flat)
    U_old = rng.standard_normal(old.n_pores)
    valid = rng.random(old.n_pores) > 0.2  # pinched old pores pass on nothing
    U, rule = pressures_by_rule(old, U_old, valid, new)
    Uc, rule_c = pressures_by_rule(old, U_old, valid, new, kp.REMESH)
    assert_same(rule_c, rule, "rule")
    assert_same(Uc, U, "U")
    assert set(np.unique(rule)) >= {1, 2, 3}
    if flat:  # rules (a) and (b) on vertex sets with a wall in them
        assert {1, 2} <= set(rule[new.pore_walls.any(axis=0)].tolist())


@pytest.mark.parametrize("flat", [False, True])
def test_rule_b_is_the_same_for_every_new_pore(flat):
    """Rule (b) on both paths asked for every new pore (pressures_by_rule asks only for those rule (a)
    left), and for each of the first pores alone (a pore's search marks the old pores it met by the
    new pore's id: nothing is marked before the first)."""
    old, new, _, _, rng = _moved(0, 0.02, flat)
    U_old = rng.standard_normal(old.n_pores)
    valid = np.ones(old.n_pores, bool)
    todo = np.arange(new.n_pores)
    want = near_vertex_sets(old, U_old, valid, new, todo)
    assert np.isfinite(want[:4]).all()
    assert_same(kp.REMESH.near_vertex_sets(old, U_old, valid, new, todo), want, "U by rule (b)")
    for p in range(4):
        assert_same(kp.REMESH.near_vertex_sets(old, U_old, valid, new, todo[p:p + 1]), want[p:p + 1], f"pore {p}")


def test_spread_reaches_pores_far_from_any_known_one_in_rounds():
    """Rule (c) on a chain 0-1-2-3 with U known at 0 only: one pore further each round."""
    conns = np.array([[0, 1], [2, 1], [2, 3], [1, 0]])
    for spread in (kp.spread_to_neighbours, __import__("engines.model.pore_water", fromlist=["x"]).spread_to_neighbours):
        U, rule = np.array([2.0, np.nan, np.nan, np.nan, np.nan]), np.zeros(5, np.int8)
        spread(U, rule, conns)
        np.testing.assert_array_equal(U[:4], 2.0)
        assert np.isnan(U[4]) and rule.tolist() == [0, 3, 3, 3, 0]


@pytest.mark.parametrize("flat", [False, True])
@pytest.mark.parametrize("jitter", [0.0, 0.02, 0.3, 3.0])
def test_compiled_overlaps_are_the_same(jitter, flat):
    old, new, xz2, r, _ = _moved(3, jitter, flat)
    for got, want in zip(kp.REMESH.pore_overlaps(old, new, xz2), pg.pore_overlaps(old, new, xz2)):
        assert_same(got, want, "overlaps")


def test_compiled_clip_areas_of_triangles_in_all_positions():
    rng = np.random.default_rng(7)
    subj, clip = rng.random((2000, 3, 2)), rng.random((2000, 3, 2))
    for t in (subj, clip):
        cw = triangulation._signed_area(t) < 0
        t[cw] = t[cw][:, [0, 2, 1]]
    scratch = np.empty((9, 2)), np.empty((9, 2))
    assert_same([_clip_area(P, Q, *scratch) for P, Q in zip(subj, clip)], overlaps._clip_areas(subj, clip), "areas")
    assert_same([_clip_area(P, P, *scratch) for P in subj], np.abs(triangulation._signed_area(subj)), "a triangle with itself")


@pytest.mark.parametrize("flat", [False, True])
@pytest.mark.parametrize("transfer", ["paper", "conserving"])
def test_compiled_remesh_moves_the_same_water(transfer, flat):
    old, new, xz2, r, rng = _moved(4, 0.05, flat)
    A_old, A_new = pg.measure(old, xz2, r).void_area, pg.measure(new, xz2, r).void_area
    W0 = A_old * (1 + 0.1 * rng.random(old.n_pores))
    waters = []
    for steps in (None, kp.REMESH):
        w = PoreWater(old, A_old, WaterSettings(E_w=2400.0, k1=1e3, k2=1e2, transfer=transfer), W=W0)
        counts = w.remesh(new, A_new, A_old, xz=xz2, steps=steps)
        waters.append((w, counts))
    (w, counts), (wc, counts_c) = waters
    assert counts_c == counts and counts["b"] > 0
    assert_same(wc.W, w.W, "W")
    assert_same(wc.rule, w.rule, "rule")
    for f in dataclasses.fields(w.balance):
        want = getattr(w.balance, f.name)
        assert getattr(wc.balance, f.name) == pytest.approx(want, rel=RTOL, abs=RTOL * w.total_water()), f.name
    assert_same(pressure(wc.W, A_new, 2400.0), pressure(w.W, A_new, 2400.0), "U")


def test_a_wall_code_out_of_range_is_refused():
    xz, r, _, eps_m, l_m = PACKINGS["hex"]()
    walls = np.zeros(len(r), np.int64)
    walls[5] = 7
    for steps in (None, kp.BUILD):
        with pytest.raises(ValueError, match="walls: codes must be 0-3, got 7"):
            pg.build_pores(xz, r, eps_m, l_m, walls=walls, steps=steps)


def test_the_flat_wall_packings_exercise_every_branch():
    """Corners, wall pores of exact lattices, discs beyond the reach of a wall but within twice it
    (no foot), hidden disc-foot links put in by flips."""
    nets = {name: _build(name) for name in FLAT}
    on_walls = nets["square-in-a-box"].pore_walls
    # along a wall of n discs: n - 1 pores between their feet and the two corner pores
    assert on_walls.sum(axis=1).tolist() == [8, 7, 7, 8] and (on_walls.sum(axis=0) == 2).sum() == 4
    xz, r, eps_m, l_m, walls = FLAT["box-reach"]()
    net, reach = nets["box-reach"], eps_m + l_m
    w, i = np.nonzero([(wall.gap(xz, r) > reach) & (wall.gap(xz, r) < 2 * reach) for wall in walls])
    assert len(i) > 5 and not np.isin(net.wall_vertices.foot(w, i), net.tri).any()
    net, missing = nets["box-long-lm"], _missing_with_flat_walls("box-long-lm", links._missing_pairs)[1]
    feet = missing[missing[:, 1] >= net.n_discs]  # a disc and its own foot, not in the regular triangulation
    m = net.wall_vertices.n_vertices
    assert len(feet) and np.isin(feet @ [m, 1], net.links @ [m, 1]).any()


def _missing_with_flat_walls(name, missing_pairs):
    """The missing pairs of the regular triangulation of FLAT[name]'s build, by missing_pairs, and
    the NumPy ones."""
    xz, r, eps_m, l_m, walls = FLAT[name]()
    wv, reach = WallVertices(walls, len(r)), eps_m + l_m
    points, radii, active = wv.positions(xz), wv.radii(r), wv.active(xz, r, reach)
    tri = active[pg.regular_triangulation(points[active], radii[active])]
    return missing_pairs(points, radii, reach, tri, wv), links._missing_pairs(points, radii, reach, tri, wv)


@pytest.mark.parametrize("name", ["box-reach", "box-long-lm"])
def test_missing_pairs_with_flat_walls_are_those_of_numpy(name):
    got, want = _missing_with_flat_walls(name, kp._missing_pairs)
    assert sorted(map(tuple, got.tolist())) == sorted(map(tuple, want.tolist())) and len(want)


def _owner_shifted(wv):
    """``wv`` with each foot given to the next disc: a rule that links a disc to another disc's foot."""
    bad = copy.copy(wv)
    bad.owner = np.where((wv.owner >= 0) & (np.arange(wv.n_vertices) >= wv.n), (wv.owner + 1) % wv.n, wv.owner)
    return bad


def _off_the_walls(wv):
    """``wv`` with no wall vertex on a wall: a rule that links no two wall vertices (no wall edge)."""
    bad = copy.copy(wv)
    bad.bits = np.zeros_like(wv.bits)
    return bad


@pytest.mark.parametrize("name,wrong", [("hex-on-a-wall", _owner_shifted), ("box-long-lm", _owner_shifted),
                                        ("square-in-a-box", _off_the_walls), ("box-long-lm", _off_the_walls)])
def test_a_wrong_link_rule_in_the_kernels_gives_another_network(name, wrong):
    """The comparisons above can fail: the kernels given the vertices' owner or bits of a wrong
    link rule build a network other than the NumPy one."""
    def missing_pairs(xz, r, reach, tri, wall_vertices):
        return kp._missing_pairs(xz, r, reach, tri, wrong(wall_vertices))

    def faces(*args, wall_vertices):
        return kp._faces(*args, wall_vertices=wrong(wall_vertices))

    steps = kp.BUILD._replace(missing_pairs=missing_pairs, faces=faces)
    with pytest.raises(AssertionError):
        assert_same_network(_build(name, steps=steps), _build(name))


def test_the_conserving_transfer_onto_new_wall_pores_is_the_same_on_both_paths():
    """A hexagonal bed lowered by half a radius onto a flat bottom: the new network has pores between
    the bottom row and the wall where the old one had none, and their top edges lie on the old
    pores' bottom edges (the row's centres). Clipping two triangles that share an edge leaves a
    sliver of round-off size or nothing, by the last bits of the positions; such a sliver must not
    hand a new pore a share of an old pore's water. The NumPy path at xz and the compiled one at xz
    changed in the last bits move the same water (to 1e-9; with the slivers: 7e-3), and the 8 new
    wall pores overlap no old pore on either."""
    walls = (FlatWall(1, 0.0, +1, "inflow"), FlatWall(0, 0.0, +1), FlatWall(0, 18.0, -1))
    xz = hex_lattice(8, 6, 2.0, origin=(1.0, 1.0))
    r = np.ones(len(xz))
    old = pg.build_pores(xz + [0.0, 0.5], r, 0.0, 0.1, flat_walls=walls)
    new = pg.build_pores(xz, r, 0.0, 0.1, flat_walls=walls)
    W0 = pg.measure(old, xz, r).void_area * (1 + 0.1 * np.random.default_rng(5).random(old.n_pores))

    def moved(x, steps):
        A_old, A_new = pg.measure(old, x, r).void_area, pg.measure(new, x, r).void_area
        w = PoreWater(old, A_old, WaterSettings(E_w=2400.0, k1=1e3, k2=1e2, transfer="conserving"), W=W0)
        return w.remesh(new, A_new, A_old, xz=x, steps=steps)["unmatched"], w.W

    unmatched, W = moved(xz, None)
    assert unmatched == 8
    for d in range(8):  # with the old code, d = 5 and 6 gave one sliver on both paths
        x = xz * (1 + d * 1e-15)
        for steps in (None, kp.REMESH):
            unmatched_d, W_d = moved(x, steps)
            assert unmatched_d == 8
            np.testing.assert_allclose(W_d, W, rtol=1e-9, atol=0)
