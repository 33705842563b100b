"""Compiled rebuild (engines.compiled.pores) against the readable NumPy path: the same network (integer
arrays equal, floats to 1e-12 relative) and the same re-meshing, on packings that exercise every
branch: lattices (cocircular ties), random packings with walls, holes (dangling links, pinches),
rattlers in and off the triangulation, a hidden eq 28 pair put in by flips, closed faces, and inputs
without pores."""
import dataclasses

import numpy as np
import pytest

from engines.compiled import pores as kp
from engines.model import pores as pg
from engines.model.pore_water import PoreWater, WaterSettings, pressure, pressures_by_rule
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
        if isinstance(x, dict):
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


def _build(name, **kw):
    xz, r, walls, eps_m, l_m = PACKINGS[name]()
    return pg.build_pores(xz, r, eps_m, l_m, walls=walls, **kw)


@pytest.mark.parametrize("name", PACKINGS)
def test_compiled_build_gives_the_same_network(name):
    assert_same_network(_build(name, steps=kp.BUILD), _build(name))


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
    want = pg._lifted_points(xz, r)
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
    assert sorted(map(tuple, kp.missing_pairs(xz, r, eps_m + l_m, tri).tolist())) == expected


def _moved(seed, jitter):
    """An old network of a loose packing and a new one after every disc moved by ~jitter radii."""
    xz, r, walls, eps_m, l_m = _loose(seed, 2e-4, 3.5e-4)
    rng = np.random.default_rng(seed)
    xz2 = xz + jitter * r.mean() * rng.standard_normal(xz.shape)
    old = pg.build_pores(xz, r, eps_m, l_m, walls=walls)
    new = pg.build_pores(xz2, r, eps_m, l_m, walls=walls)
    return old, new, xz2, r, rng


@pytest.mark.parametrize("seed,jitter", [(0, 0.02), (1, 0.1), (2, 0.3)])
def test_compiled_rules_give_the_same_pressures(seed, jitter):
    old, new, xz2, r, rng = _moved(seed, jitter)
    U_old = rng.standard_normal(old.n_pores)
    valid = rng.random(old.n_pores) > 0.2  # pinched old pores pass on nothing
    U, rule = pressures_by_rule(old, U_old, valid, new)
    Uc, rule_c = pressures_by_rule(old, U_old, valid, new, kp.REMESH)
    assert_same(rule_c, rule, "rule")
    assert_same(Uc, U, "U")
    assert set(np.unique(rule)) >= {1, 2, 3}


def test_spread_reaches_pores_far_from_any_known_one_in_rounds():
    """Rule (c) on a chain 0-1-2-3 with U known at 0 only: one pore further each round."""
    conns = np.array([[0, 1], [2, 1], [2, 3], [1, 0]])
    for spread in (kp.spread_to_neighbours, __import__("engines.model.pore_water", fromlist=["x"]).spread_to_neighbours):
        U, rule = np.array([2.0, np.nan, np.nan, np.nan, np.nan]), np.zeros(5, np.int8)
        spread(U, rule, conns)
        np.testing.assert_array_equal(U[:4], 2.0)
        assert np.isnan(U[4]) and rule.tolist() == [0, 3, 3, 3, 0]


@pytest.mark.parametrize("jitter", [0.0, 0.02, 0.3, 3.0])
def test_compiled_overlaps_are_the_same(jitter):
    old, new, xz2, r, _ = _moved(3, jitter)
    for got, want in zip(kp.REMESH.pore_overlaps(old, new, xz2), pg.pore_overlaps(old, new, xz2)):
        assert_same(got, want, "overlaps")


def test_compiled_clip_areas_of_triangles_in_all_positions():
    rng = np.random.default_rng(7)
    subj, clip = rng.random((2000, 3, 2)), rng.random((2000, 3, 2))
    for t in (subj, clip):
        cw = pg._signed_area(t) < 0
        t[cw] = t[cw][:, [0, 2, 1]]
    scratch = np.empty((9, 2)), np.empty((9, 2))
    assert_same([kp._clip_area(P, Q, *scratch) for P, Q in zip(subj, clip)], pg._clip_areas(subj, clip), "areas")
    assert_same([kp._clip_area(P, P, *scratch) for P in subj], np.abs(pg._signed_area(subj)), "a triangle with itself")


@pytest.mark.parametrize("transfer", ["paper", "conserving"])
def test_compiled_remesh_moves_the_same_water(transfer):
    old, new, xz2, r, rng = _moved(4, 0.05)
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
