"""Love–Weber effective stress, its invariants, regions and r_u (engines.model.effective_stress, SPEC §2.8)."""
import copy
import functools

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
    assert es.bands(0.0, 8.0, 8) == [(float(k), float(k + 1)) for k in range(8)]
    with pytest.raises(ValueError, match="top > bottom"):
        es.bands(1.0, 1.0, 8)
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


# -- a settled column ---------------------------------------------------------------------------------
R = 0.5e-3                      # the mean radius [m] of the column's discs
RHO, RHO_W, G = 2700.0, 1000.0, 9.81


@functools.lru_cache(maxsize=None)
def settled_column(unit_weight, n=700, steps=12000, boosted=5000):
    """About n polydisperse discs (packing.layouts.random_discs: radii 0.7-1 R on a jittered
    hexagonal lattice, width/height 0.5) between frictionless flat walls at their outermost edges
    (left, right, bottom; mu = 0) settled with the paper's law (compiled twin, spring a) under the
    unit weight [N/m^3] (rho g dry, (rho - rho_w) g submerged): ten times it and local damping 0.3
    for the first ``boosted`` steps (the discs fall into the lattice's gaps sooner), then itself
    and local damping 0.7: (PaperLaw,
    centres, radii, x of the left and the right wall)."""
    from engines.compiled.paper_law import PaperLaw
    from engines.model.contact import ContactSettings
    from engines.model.flat_walls import FlatWall
    from packing.layouts import random_discs
    xz, r = random_discs(n, np.random.default_rng(7), r_mean=R, r_spread=0.3, aspect=0.5)
    x0, x1, z0 = (xz[:, 0] - r).min(), (xz[:, 0] + r).max(), (xz[:, 1] - r).min()
    xz = xz - [0.0, z0]
    mass = RHO * np.pi * r ** 2
    dt = 1e-5
    law = PaperLaw(ContactSettings(spring="a", kn=1.4e6, eta_n=5.2, ks=3.5e5, eta_s=1.3, mu=0.0,
                                   separation_adjustment=False), r, np.ones(len(r), bool), mass, 0.5 * mass * r ** 2,
                   dt, (FlatWall(1, 0.0, 1), FlatWall(0, x0, 1), FlatWall(0, x1, -1)))
    v = np.zeros_like(xz)
    load = np.zeros_like(xz)
    for k in range(steps):
        load[:, 1] = -unit_weight * np.pi * r ** 2 * (10.0 if k < boosted else 1.0)
        F, _ = law.step(xz)
        F = F + load
        F -= (0.3 if k < boosted else 0.7) * np.abs(F) * np.sign(v)  # local damping
        v += F / mass[:, None] * dt
        xz = xz + v * dt
    return law, xz, r, x0, x1


@pytest.mark.parametrize("unit_weight", [RHO * G, (RHO - RHO_W) * G], ids=["dry", "submerged"])
def test_settled_column_carries_its_buoyant_overburden(unit_weight):
    """sigma'_v by band of a settled column between frictionless walls equals the buoyant overburden
    within 5 % in the bands more than 2 diameters from the bed's bottom and top (SPEC §2.8)."""
    law, xz, r, x0, x1 = settled_column(unit_weight)
    width = x1 - x0
    c = law.stress_contacts(xz)
    top = float(np.max(xz[:, 1] + r))
    bounds = es.bands(0.0, top, 8)
    s = es.region_stress(xz, c, x0, x1, bounds, es.region_areas(x0, x1, bounds, top))
    sv = es.invariants(s)[0]
    expected = es.overburden(xz, r, unit_weight, x0, x1, bounds)
    inner = [k for k, (z0, z1) in enumerate(bounds) if z0 >= 4 * R and z1 <= top - 4 * R]
    assert len(inner) >= 4
    assert sv[inner] == pytest.approx(expected[inner], rel=0.05)
    # and independently of overburden(): the weight of the discs whose centre lies above each band's middle
    mid = np.array([0.5 * (a + b) for a, b in bounds])
    above = np.array([unit_weight * np.sum(np.pi * r[xz[:, 1] > z] ** 2) / width for z in mid])
    assert sv[inner] == pytest.approx(above[inner], rel=0.08)
    # at rest the contacts, the walls' included, carry the weight
    assert np.sum(c.force[:, 1]) == pytest.approx(unit_weight * np.pi * np.sum(r ** 2), rel=1e-2)


def test_a_uniform_pore_pressure_changes_no_effective_stress():
    """The settled column closed by a lid above its top, its pores at one excess pressure U: eq 33
    pushes no particle (the pores around each close), so stepping on with the water's forces leaves
    every contact, and sigma' by band, as stepping without them does."""
    from engines.model import pores as pg
    from engines.model.flat_walls import FlatWall
    law, xz, r, x0, x1 = settled_column(RHO * G)
    top = float(np.max(xz[:, 1] + r))
    walls = (FlatWall(1, 0.0, 1), FlatWall(0, x0, 1), FlatWall(0, x1, -1), FlatWall(1, top + 0.1 * R, -1))
    net = pg.build_pores(xz, r, l_m=0.8 * r.mean(), flat_walls=walls)
    U = 500.0  # [N/m], about the bottom band's sigma'_v x 1 m
    F_water = pg.pressure_forces(net, r, np.full(net.n_pores, U), pg.measure(net, xz, r))
    assert np.abs(F_water).max() < 1e-9 * U * R
    bounds = es.bands(0.0, top, 8)
    areas = es.region_areas(x0, x1, bounds, top)
    load = np.zeros_like(xz)
    load[:, 1] = -RHO * G * np.pi * r ** 2
    mass = RHO * np.pi * r ** 2
    stress = []
    for extra in (0.0, F_water):
        stepped, x, v = copy.deepcopy(law), xz.copy(), np.zeros_like(xz)
        for _ in range(200):
            F = stepped.step(x)[0] + load + extra
            v += F / mass[:, None] * stepped.dt
            x = x + v * stepped.dt
        stress.append(es.region_stress(x, stepped.stress_contacts(x), x0, x1, bounds, areas))
    np.testing.assert_allclose(stress[1], stress[0], rtol=1e-6, atol=1e-6)
    assert stress[0][:, 1].max() > 100.0  # the bands carry their weight
