"""Porosity of a fixed window: exact disc-rectangle areas."""
import numpy as np
import pytest
from scipy.integrate import quad

from engines.model.observe import Window, box_window, disc_rectangle_area, porosity, quadrant_area
from engines.yade.deposition import wall_box
from packing.packing import Packing
from tests.layouts import square_lattice

R = 0.45e-3


def _area(c, r, win):
    return float(disc_rectangle_area(np.array([c]), np.array([r]), *win)[0])


def _segment(d, r):
    """Area of the disc of radius r beyond a line at distance d from its centre (0 <= d <= r)."""
    return r * r * np.arccos(d / r) - d * np.sqrt(r * r - d * d)


def test_inside_outside_corner_and_edge():
    win = (0.0, 1.0, 0.0, 1.0)
    assert _area((0.5, 0.5), 0.2, win) == pytest.approx(np.pi * 0.04, rel=1e-14)
    assert _area((1.5, 0.5), 0.2, win) == 0.0 and _area((0.5, -0.21), 0.2, win) == 0.0
    assert _area((0.0, 0.0), 0.2, win) == pytest.approx(np.pi * 0.04 / 4, rel=1e-14)
    assert _area((1.0, 1.0), 0.2, win) == pytest.approx(np.pi * 0.04 / 4, rel=1e-14)
    assert _area((0.5, 1.0), 0.2, win) == pytest.approx(np.pi * 0.04 / 2, rel=1e-14)
    for d in (0.05, 0.13, 0.199):
        assert _area((0.5, 1.0 - d), 0.2, win) == pytest.approx(np.pi * 0.04 - _segment(d, 0.2), rel=1e-12)
        assert _area((-d, 0.5), 0.2, win) == pytest.approx(_segment(d, 0.2), rel=1e-10)


@pytest.mark.parametrize("c", [(0.07, 0.13), (-0.05, 0.11), (0.15, -0.12), (-0.1, -0.1), (0.3, 0.0)])
def test_straddling_a_corner_against_quadrature(c):
    """A disc over the corner (0, 0) of the window [0, 1]^2: against a numerical integral of the
    chord inside the window."""
    r = 0.2

    def inside_height(x):
        h = np.sqrt(max(r * r - (x - c[0]) ** 2, 0.0))
        return max(0.0, min(c[1] + h, 1.0) - max(c[1] - h, 0.0))

    ref = quad(inside_height, max(0.0, c[0] - r), c[0] + r, epsabs=1e-14, limit=200)[0]
    assert _area(c, r, (0.0, 1.0, 0.0, 1.0)) == pytest.approx(ref, rel=1e-9, abs=1e-14)


def test_lattice_cut_through_the_centres():
    """Touching discs on a square lattice of spacing 2r, window edges through rows and columns of
    centres: edge discs are halved, corner discs quartered, each 2r x 2r cell holds pi r^2 of disc:
    porosity 1 - pi/4."""
    nx, nz = 7, 5
    xz = square_lattice(nx + 1, nz + 1, 2 * R)
    win = Window(0.0, nx * 2 * R, 0.0, nz * 2 * R)
    assert porosity(xz, np.full(len(xz), R), win) == pytest.approx(1 - np.pi / 4, rel=1e-13)
    # top edge r/2 above the top row of centres: the bottom row is halved, the top row loses only
    # its cap beyond r/2, the side columns are halved
    win = Window(0.0, nx * 2 * R, 0.0, nz * 2 * R + 0.5 * R)
    solid = nx * (0.5 * np.pi * R**2 + (nz - 1) * np.pi * R**2 + np.pi * R**2 - _segment(0.5 * R, R))
    assert porosity(xz, np.full(len(xz), R), win) == pytest.approx(1 - solid / win.area, rel=1e-12)


def test_additive_over_a_split_window():
    rng = np.random.default_rng(3)
    xz = rng.random((300, 2)) * 0.02
    r = R * (0.5 + rng.random(300))
    x0, x1, z0, z1 = 0.002, 0.017, 0.003, 0.015
    whole = disc_rectangle_area(xz, r, x0, x1, z0, z1)
    xs, zs = 0.0093, 0.0071
    parts = sum(disc_rectangle_area(xz, r, a, b, c, d) for a, b in ((x0, xs), (xs, x1)) for c, d in ((z0, zs), (zs, z1)))
    np.testing.assert_allclose(parts, whole, rtol=1e-12, atol=1e-20)
    assert np.all(whole >= -1e-20) and np.all(whole <= np.pi * r**2 * (1 + 1e-12))
    assert quadrant_area(1.0, 1.0, 0.5) == pytest.approx(np.pi * 0.25)


def test_box_window_and_shift():
    walls, groups = wall_box(10, 6, R)
    xz = np.vstack([[[4 * R, 3 * R]], walls])
    pk = Packing(xz, np.concatenate([[R], np.full(len(walls), R)]), np.concatenate([[0], groups]), np.ones(len(xz)))
    win = box_window(pk, [0.0, 0.5])
    assert (win.x0, win.x1) == pytest.approx((R, 9 * 2 * R - R))
    assert (win.z0, win.z1) == pytest.approx((R, R + 0.5 * 3 * R))
    moved = win.shifted(1e-4)
    assert moved.x0 - win.x0 == pytest.approx(1e-4) and moved.area == pytest.approx(win.area)
    with pytest.raises(ValueError, match="x0 < x1"):
        Window(1.0, 0.0, 0.0, 1.0)
