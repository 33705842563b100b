"""The compiled regular triangulation (engines.compiled.regular) against Qhull's lower hull (the
NumPy build): the same triangles wherever it answers, and the hull left to Qhull at every tie."""
import numpy as np
import pytest

from engines.compiled import pores as kp
from engines.compiled import regular
from engines.model import pores as pg
from engines.model.pores import build
from engines.model.flat_walls import WallVertices
from packing.layouts import hex_lattice, random_discs
from packing.packing import Packing
from packing.psd import sample_diameters
from tests.compiled.test_pores import FLAT, PACKINGS
from tests.layouts import random_sequential, square_lattice

ANSWER = {regular.UNSURE: "unsure", regular.COLLINEAR: "collinear", regular.DONE: "done"}


def triangulate(xz, r):
    """(answer name, triangles) of regular.regular_triangles."""
    a, tri = regular.regular_triangles(np.ascontiguousarray(xz, float), np.ascontiguousarray(r, float))
    return ANSWER[a], tri


def seismic_packing(moved=0.0, seed=1):
    """The seismic box at rest (rows of wall discs on straight lines), its discs moved by ~moved [m]."""
    pk = Packing.load("yade_scripts/scenes/liquefaction_packing.csv")
    return pk.xz + moved * np.random.default_rng(seed).standard_normal(pk.xz.shape), pk.r


def _layouts():
    """Packings of every kind the engines meet: loose, jittered, overlapping, near-lattice, boxed."""
    out = {"seismic": seismic_packing(), "seismic-moved": seismic_packing(1e-5)}
    for seed in range(6):
        rng = np.random.default_rng(seed)
        out[f"loose-{seed}"] = random_sequential(sample_diameters(300, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, rng),
                                                 0.02, 0.02, rng)
        out[f"jittered-{seed}"] = random_discs(int(rng.integers(20, 400)), rng)
        xz, r = random_sequential(rng.uniform(0.2, 2.0, 300), 15.0, 15.0, rng)
        out[f"overlapping-{seed}"] = (xz + 0.05 * rng.standard_normal(xz.shape), r)
        out[f"near-hex-{seed}"] = (hex_lattice(10, 9, 2.0) + 1e-3 * rng.standard_normal((90, 2)),
                                   1.0 + 1e-3 * rng.standard_normal(90))
    for name, make in FLAT.items():  # the discs and the wall vertices of a build (flat walls)
        xz, r, eps_m, l_m, walls = make()
        wv = WallVertices(walls, len(xz))
        active = wv.active(xz, r, eps_m + l_m)
        out[f"flat-{name}"] = wv.positions(xz)[active], wv.radii(r)[active]
    for name in ("holes-14", "walled", "loose-seismic", "kite", "ring", "closed-face"):
        out[name] = PACKINGS[name]()[:2]
    return out


LAYOUTS = _layouts()


@pytest.mark.parametrize("name", LAYOUTS)
def test_the_triangles_are_those_of_the_hull(name):
    """Packings without ties: certain, and the very array of the hull's lower facets."""
    xz, r = LAYOUTS[name]
    answer, tri = triangulate(xz, r)
    assert answer == ("unsure" if name in ("flat-hex-on-a-wall", "flat-square-in-a-box") else "done")
    if answer == "done":
        np.testing.assert_array_equal(tri, pg.regular_triangulation(xz, r))


@pytest.mark.parametrize("name, answer", [("hex", "unsure"), ("square", "unsure"), ("rattlers", "unsure"),
                                          ("collinear", "collinear"), ("coincident", "collinear"),
                                          ("two", "collinear")])
def test_ties_are_left_to_the_hull(name, answer):
    """Cocircular discs (lattices; two mirrored triangles), collinear or coincident centres: no
    triangle decided; the build answers as the hull does."""
    xz, r = PACKINGS[name]()[:2]
    assert triangulate(xz, r)[0] == answer
    want = pg.regular_triangulation(xz, r)
    got = pg.regular_triangulation(xz, r, kp.BUILD)
    assert (got is None and want is None) or np.array_equal(got, want)


def test_three_discs_make_one_triangle():
    """The smallest packing with a triangle: the third disc in the insertion order is the first off
    the line of the first two."""
    answer, tri = triangulate(np.array([[0.0, 0.0], [1.0, 0.0], [0.2, 1.0]]), np.full(3, 0.1))
    assert answer == "done" and tri.tolist() == [[0, 1, 2]]


def test_nested_discs_go_in_largest_first():
    """Disc 6 inside the big disc 5 and disc 7 inside 6 (not inside 5): with 7 inserted before 6 the
    insertion answers unsure (a flip 6 needs is not convex); the insertion order puts 6 first:
    certain, the hull's triangles."""
    xz = np.array([[0.0, 0.0], [5.0, 0.0], [2.5, 4.5], [0.0, 3.0], [5.0, 3.0], [2.0, 1.0], [3.2, 1.0], [3.55, 1.0]])
    r = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 0.5, 0.2])
    scale = np.ptp(xz, axis=0).max()  # as regular_triangles scales them
    x, z, w = (xz[:, 0] - xz[:, 0].mean()) / scale, (xz[:, 1] - xz[:, 1].mean()) / scale, (r / scale) ** 2
    order = regular._insertion_order(x, z, w)
    assert order[-2:].tolist() == [6, 7]
    assert regular._regular_from(x, z, w, order)[0] == regular.DONE
    assert regular._regular_from(x, z, w, np.append(order[:-2], [7, 6]))[0] == regular.UNSURE
    answer, tri = triangulate(xz, r)
    assert answer == "done"
    np.testing.assert_array_equal(tri, pg.regular_triangulation(xz, r))


def test_a_disc_inside_another_power_cell_is_in_no_triangle():
    """A small disc near the centre of a large one in a packing: hidden, as in the lower hull."""
    xz, r = LAYOUTS["loose-0"]
    big = int(np.argmax(r))
    xz, r = np.vstack([xz, xz[big] + 0.2 * r[big]]), np.append(r, 0.1 * r[big])
    answer, tri = triangulate(xz, r)
    assert answer == "done" and len(r) - 1 not in tri
    np.testing.assert_array_equal(tri, pg.regular_triangulation(xz, r))


def test_the_power_test_and_the_chord():
    """The predicates' signs: a point inside the unit circle of three equal discs is inside their
    power circle, and more so the larger its disc; a small disc between two large ones on a line
    lies above their chord (hidden) where they overlap, an equal one below it."""
    x, z = np.array([1.0, 0.0, -1.0, 0.0]), np.array([0.0, 1.0, 0.0, 0.0])
    inside = regular._power(x, z, np.zeros(4), 0, 1, 2, 3)[0]
    assert 0 < inside < regular._power(x, z, np.array([0, 0, 0, 0.5]), 0, 1, 2, 3)[0]
    assert regular._power(x, z + np.array([0, 0, 0, 2.0]), np.zeros(4), 0, 1, 2, 3)[0] < 0  # (0, 2): outside
    line_x, line_z = np.array([0.0, 1.0, 2.0]), np.zeros(3)
    assert regular._above_chord(line_x, line_z, np.array([2.25, 0.01, 2.25]), 0, 1, 2)[0] > 0
    assert regular._above_chord(line_x, line_z, np.full(3, 0.25), 0, 1, 2)[0] < 0


def test_the_compiled_build_skips_the_hull_in_a_run(monkeypatch):
    """The seismic box rebuilt as it shakes: every build certain, none left to the hull."""
    calls = []
    hull = build.ConvexHull
    monkeypatch.setattr(build, "ConvexHull", lambda *a, **k: calls.append(1) or hull(*a, **k))
    for moved in (0.0, 2e-5, 5e-5):
        xz, r = seismic_packing(moved, seed=3)
        net = pg.build_pores(xz, r, 2e-4, 3.5e-4, steps=kp.BUILD)
        assert net.n_pores > 250
    assert calls == []


def test_a_tie_within_round_off_is_left_to_the_hull():
    """A square lattice moved by 1e-12 of its spacing: its cocircular quadruples are no longer exact
    ties, but too close to them to be decided: unsure, the hull's."""
    xz = square_lattice(7, 6, 2.0) + 2e-12 * np.random.default_rng(4).standard_normal((42, 2))
    assert triangulate(xz, np.ones(42))[0] == "unsure"


def test_a_disc_that_a_later_one_hides_is_unsure():
    """Inserted before the larger disc that covers it, a small disc would have to leave the
    triangulation, which flips cannot do (a quadrilateral to flip is not convex): the insertion
    answers unsure. The insertion order puts such discs last: regular_triangles is certain here."""
    xz = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 3.5], [2.1, 1.2], [2.0, 1.0]])
    r = np.array([1.0, 1.0, 1.0, 0.1, 1.5])
    answer = regular._regular_from(xz[:, 0].copy(), xz[:, 1].copy(), r ** 2, np.arange(5))[0]
    assert answer == regular.UNSURE
    assert triangulate(xz, r)[0] == "done"
    np.testing.assert_array_equal(triangulate(xz, r)[1], pg.regular_triangulation(xz, r))
