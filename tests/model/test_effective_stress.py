"""Love–Weber effective stress, its invariants, regions and r_u (engines.model.effective_stress, SPEC §2.8)."""
import numpy as np
import pytest

from engines.model import effective_stress as es


def test_two_pressed_discs_give_f_times_branch_over_area():
    """Two particles on the x axis pressed by f_n: sigma'_xx = f_n R / A (both sides counted),
    nothing else; the contact point is in the middle of the overlap."""
    r, delta, fn = 1e-3, 1e-5, 2.0
    xz = np.array([[0.0, 0.0], [2 * r - delta, 0.0]])
    c = es.pair_contacts(xz, np.array([r, r]), [[0, 1]], [fn], [0.0], np.array([True, True]))
    assert np.allclose(c.point, [[r - delta / 2, 0.0]] * 2)
    A = 4e-6
    s = es.region_stress(xz, c, -1.0, 1.0, [(-1e-3, 1e-3)], np.array([A]))[0]
    assert s == pytest.approx([fn * (2 * r - delta) / A, 0.0, 0.0], abs=1e-9)
    v, h, p, q = es.invariants(s)
    assert (v, h) == (s[1], s[0]) and p == pytest.approx(s[0] / 2) and q == pytest.approx(s[0] / 2)


def test_shear_force_gives_the_symmetric_off_diagonal():
    """A shear force f_s on a pair along x (t = (0, 1) for n = (1, 0); the force on i is -f_s t):
    -f ⊗ b has f_s R / A in zx only, its symmetric part half of it in xz; q the radius of Mohr's circle."""
    r, fs, A = 1e-3, 0.5, 1e-6
    xz = np.array([[0.0, 0.0], [2 * r, 0.0]])
    c = es.pair_contacts(xz, np.array([r, r]), [[0, 1]], [0.0], [fs], np.array([True, True]))
    s = es.region_stress(xz, c, -1.0, 1.0, [(-1.0, 1.0)], np.array([A]))[0]
    assert s == pytest.approx([0.0, 0.0, 0.5 * fs * 2 * r / A])
    assert es.invariants(s)[3] == pytest.approx(0.5 * fs * 2 * r / A)


def test_a_wall_contact_counts_for_its_particle_only():
    """A particle resting on a wall disc below: sigma'_zz = f_n (r - delta/2) / A (its own branch
    only); the same disc resting on a flat wall's foot (radius 0) gives its branch to the face."""
    r, rw, delta, fn, A = 1e-3, 0.5e-3, 2e-5, 3.0, 1e-5
    xz = np.array([[0.0, 0.0], [0.0, -(r + rw - delta)]])
    c = es.pair_contacts(xz, np.array([r, rw]), [[0, 1]], [fn], [0.0], np.array([True, False]))
    assert list(c.disc) == [0]
    assert c.force[0] == pytest.approx([0.0, fn])  # pushed up
    s = es.region_stress(xz, c, -1.0, 1.0, [(-1.0, 1.0)], np.array([A]))[0]
    assert s == pytest.approx([0.0, fn * (r - delta / 2) / A, 0.0])
    foot = np.array([[0.0, 0.0], [0.0, -(r - delta)]])  # the face r - delta below the centre
    c = es.pair_contacts(foot, np.array([r, 0.0]), [[0, 1]], [fn], [0.0], np.array([True, False]))
    assert es.region_stress(foot, c, -1.0, 1.0, [(-1.0, 1.0)], np.array([A]))[0][1] == pytest.approx(fn * (r - delta / 2) / A)


def test_region_takes_the_contacts_whose_point_lies_in_it():
    """A contact counts in the band holding its contact point, not in the bands of the centres."""
    r = 1e-3
    xz = np.array([[0.0, 0.0], [0.0, 2 * r]])  # the contact point at z = r
    c = es.pair_contacts(xz, np.array([r, r]), [[0, 1]], [1.0], [0.0], np.array([True, True]))
    bounds = [(-r, 0.5 * r), (0.5 * r, 1.5 * r), (1.5 * r, 3 * r)]
    s = es.region_stress(xz, c, -1.0, 1.0, bounds, np.ones(3))
    assert s[:, 1] == pytest.approx([0.0, 2 * r, 0.0])


def test_disc_stress_is_over_the_disc_area_by_solid_fraction():
    r, fn, n = 1e-3, 1.0, 0.25
    xz = np.array([[0.0, 0.0], [2 * r, 0.0]])
    c = es.pair_contacts(xz, np.array([r, r]), [[0, 1]], [fn], [0.0], np.array([True, True]))
    s = es.disc_stress(xz, np.array([r, r]), c, n)
    assert s[:, 0] == pytest.approx([fn * r * (1 - n) / (np.pi * r * r)] * 2)
    assert np.all(s[:, 1:] == 0)


def test_bands_areas_and_the_pressure_ratio():
    assert es.bands(0.0, 8.0) == [(float(k), float(k + 1)) for k in range(8)]
    with pytest.raises(ValueError, match="top > bottom"):
        es.bands(1.0, 1.0)
    assert list(es.region_areas(0.0, 2.0, [(0.0, 1.0), (1.0, 10.0)], 1.5)) == [2.0, 1.0]
    U = es.region_pressure(np.array([0.5, 0.6, 1.5]), np.array([1.0, 3.0, 1.0]), np.array([4.0, 8.0, 2.0]),
                           [(0.0, 1.0), (1.0, 2.0), (2.0, 3.0)])
    assert U[:2] == pytest.approx([7.0, 2.0]) and np.isnan(U[2])
    ru = es.pore_pressure_ratio([50.0, 1.0, 1.0], [100.0, 0.0, -1.0])
    assert ru[0] == 0.5 and np.isnan(ru[1:]).all()


def test_overburden_of_a_stack_of_discs():
    """One column of touching discs of diameter d in a box of width d: the buoyant weight above z,
    averaged over a band holding whole discs, is the weight above the band plus half the band's."""
    r, w, k = 1e-3, 1e4, 6
    xz = np.column_stack([np.zeros(k), r + 2 * r * np.arange(k)])
    weight = w * np.pi * r * r
    ob = es.overburden(xz, np.full(k, r), w, -r, r, [(0.0, 4 * r), (4 * r, 12 * r)], samples=400)
    assert ob == pytest.approx([(4 + 1) * weight / (2 * r), 2 * weight / (2 * r)], rel=1e-4)
