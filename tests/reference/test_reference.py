"""The NumPy reference of seed 000 (engines/reference/model.py) against exact and analytic results.

Contact: head-on restitution of a linear spring-dashpot, the separation adjustment (eq 18-24),
the four normal springs of Fig. 5 released from a pressed state. Pores and water: the void area of
a hexagonal packing, eq 33 on a uniform pressure, eq 38 equalisation, water conservation in a
closed network and the budget with boundary fluxes.
"""

import numpy as np
import pytest

from engines.reference import model as ref
from engines.run import scene as sc
from packing.layouts import hex_lattice
from packing.packing import Packing
from tests.scene_helpers import make_scene

R = 0.45e-3  # disc radius [m]


def packing(xz, group):
    xz = np.asarray(xz, float)
    return Packing(xz, np.full(len(xz), R), np.asarray(group), np.ones(len(xz)))


def run_until_apart(model, max_steps=100000):
    """Step until the discs have touched and then no pair touches; one more step."""
    touched = False
    for _ in range(max_steps):
        model.step()
        if model.contact.in_contact.any():
            touched = True
        elif touched:
            model.step()
            return
    raise AssertionError("the discs never separated")


# -- contact ---------------------------------------------------------------------------------------
def head_on(dt, v0=0.1, eta=5.2, adjust=False, gap=0.0):
    """Two equal free discs approaching at v0 [m/s], touching at k = 0 when gap = 0."""
    s = make_scene(contact={"spring": "a", "eta_n": eta, "separation_adjustment": adjust}, numerics={"dt": dt})
    m = ref.ReferenceModel(s, packing([[0.0, 0.0], [2 * R + gap, 0.0]], [0, 0]))
    m.v[:, 0] = [v0 / 2, -v0 / 2]
    return s, m


@pytest.mark.parametrize("dt", [1e-7, 5e-8])
def test_head_on_restitution_of_linear_spring_dashpot(dt):
    """e = exp(-zeta pi / sqrt(1 - zeta^2)), zeta = eta / (2 sqrt(m_eff kn)), m_eff = m/2.

    Tolerance 4 zeta omega_n dt: the contact starts and ends inside a step, so the first and the
    last step in contact can each carry up to one step of dashpot impulse eta v dt too much or too
    little, a relative error 2 zeta omega_n dt each (first order in dt; the elastic part of the same
    quantisation is second order). At dt = 1e-7 s this is 1.1e-3 (t_c / dt = 780 steps)."""
    s, m = head_on(dt, gap=3e-9)  # an arbitrary phase of the first touch within a step
    run_until_apart(m)
    m_eff = m.mass[0] / 2
    omega_n = np.sqrt(s.contact.kn / m_eff)
    zeta = s.contact.eta_n / (2 * np.sqrt(m_eff * s.contact.kn))
    e_exact = np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))
    e = (m.v[1, 0] - m.v[0, 0]) / 0.1
    assert abs(e - e_exact) <= 4 * zeta * omega_n * dt
    np.testing.assert_allclose(m.v.sum(axis=0), 0.0, atol=1e-15)  # equal masses: momentum stays 0


def test_separation_adjustment_isolated_pair_conserves_momentum():
    """Pattern (d): both discs free, touching only each other: -Vn''/Vn = e and momentum kept (eq 24)."""
    s = make_scene(contact={"spring": "a", "separation_adjustment": True})
    pk = Packing(np.array([[0.0, 0.0], [2 * R + 1e-8, 0.0]]), np.full(2, R), np.zeros(2, int), np.array([1.0, 3.0]))
    m = ref.ReferenceModel(s, pk)
    m.v[:, 0] = [0.05, -0.05]
    p0 = m.mass @ m.v
    run_until_apart(m)
    np.testing.assert_allclose((m.v[1, 0] - m.v[0, 0]) / 0.1, s.contact.restitution, rtol=1e-9)
    # eq 24 works on v = du/dt, whose round-off is ulp(x)/dt per disc: the momentum is kept to that
    resolution = np.spacing(np.abs(m.x).max()) / s.numerics.dt
    np.testing.assert_allclose(m.mass @ m.v, p0, rtol=0, atol=4 * m.mass.sum() * resolution)


def test_separation_adjustment_against_a_wall():
    """Pattern (a): a disc leaving a fixed wall disc keeps -Vn''/Vn = e of its impact speed."""
    s = make_scene(contact={"spring": "a", "separation_adjustment": True})
    m = ref.ReferenceModel(s, packing([[0.0, 0.0], [2 * R + 1e-8, 0.0]], [2, 0]))
    m.v[1, 0] = -0.1
    run_until_apart(m)
    np.testing.assert_allclose(m.v[1, 0], s.contact.restitution * 0.1, rtol=1e-9)
    assert m.v[0, 0] == 0 and m.x[0, 0] == 0  # the wall did not move


def pressed(spring, overlap, eps_m=0.0, eta=0.0, dt=2e-8):
    """A free disc pressed into a fixed wall disc by ``overlap`` [m] (delta at k = 0), at rest."""
    s = make_scene(contact={"spring": spring, "eta_n": eta, "eps_m": eps_m}, numerics={"dt": dt})
    # the free disc starts at x = 0, where positions resolve its small displacements best
    return s, ref.ReferenceModel(s, packing([[overlap - 2 * R - eps_m, 0.0], [0.0, 0.0]], [2, 0]))


@pytest.mark.parametrize("spring", ["a", "b", "c", "d"])
def test_pressed_disc_released(spring):
    """Released from delta0 = 2 f_max/kn, the normal force along the path is exactly
    a, b: kn delta;  c: min(kn delta, f_max) (the f_max plateau, then its loading line);
    d: f_max - kn (delta0 - delta) (unloads along kn from the cap, zero at delta0 - f_max/kn: the
    residual overlap), and the exit speed is sqrt(2 (stored energy) / m). Force: from second differences
    of positions, to 1e-6 f_max (the round-off of x ~ 1e-6 m is ~1e-22 m against a dt^2 ~ 6e-13 m); exit speed: rtol 1e-4 (the exit falls inside a step where the
    force is already ~ 0: second order, (omega dt)^2 ~ 3e-7 at dt = 2e-8 s)."""
    eps_m = 2e-5 if spring == "b" else 0.0
    s = make_scene()
    kn, f_max = s.contact.kn, s.contact.f_max
    delta0 = 2 * f_max / kn
    s, m = pressed(spring, delta0, eps_m)
    mass, dt = m.mass[1], s.numerics.dt
    x, force, delta = [m.x[1, 0]], [], []
    while True:
        delta.append(2 * R + eps_m - (m.x[1, 0] - m.x[0, 0]))
        m.step()
        x.append(m.x[1, 0])
        if delta[-1] < 0:
            break
    force = mass * np.diff(x, 2) / dt**2  # force at steps 1.. (second differences)
    delta = np.array(delta[1:])
    expected = {"a": kn * delta, "b": kn * delta, "c": np.minimum(kn * delta, f_max),
                "d": np.maximum(f_max - kn * (delta0 - delta), 0.0)}[spring]
    np.testing.assert_allclose(force, np.where(delta >= 0, expected, 0.0), rtol=0, atol=1e-6 * f_max)
    energy = {"a": kn * delta0**2 / 2, "b": kn * delta0**2 / 2, "c": f_max * delta0 - f_max**2 / (2 * kn),
              "d": f_max**2 / (2 * kn)}[spring]
    np.testing.assert_allclose(m.v[1, 0], np.sqrt(2 * energy / mass), rtol=1e-4)
    if spring == "c":
        assert np.sum(np.isclose(force, f_max, rtol=1e-6)) > 10  # the plateau
    if spring == "d":  # the force vanished with the disc still overlapping by delta0 - f_max/kn
        zero = np.flatnonzero(force <= 0)[0]
        assert abs(delta[zero] - (delta0 - f_max / kn)) <= abs(m.v[1, 0]) * dt


@pytest.mark.parametrize("spring", ["c", "d"])
def test_impact_beyond_the_cap(spring):
    """A disc hits a wall disc with kinetic energy above f_max^2/(2 kn) (eta = 0): spring c is elastic
    (it retraces its loading path: exit speed = impact speed); spring d returns only f_max^2/(2 kn)
    and leaves a residual overlap E/f_max - f_max/(2 kn) when its force vanishes."""
    s, m = pressed(spring, -1e-9)
    v0 = 0.1
    m.v[1, 0] = -v0
    kn, f_max, mass = s.contact.kn, s.contact.f_max, m.mass[1]
    energy = mass * v0**2 / 2
    assert energy > f_max**2 / (2 * kn)
    residual = None
    touched = False
    while not (touched and not m.contact.in_contact.any()):
        m.step()
        touched |= bool(m.contact.in_contact.any())
        if touched and residual is None and m.v[1, 0] > 0 and m.contact.e_n.max() == 0:
            residual = 2 * R - (m.x[1, 0] - m.x[0, 0])
    m.step()
    if spring == "c":
        np.testing.assert_allclose(m.v[1, 0], v0, rtol=1e-4)
    else:
        np.testing.assert_allclose(m.v[1, 0], f_max / np.sqrt(kn * mass), rtol=1e-4)
        np.testing.assert_allclose(residual, energy / f_max - f_max / (2 * kn), rtol=0, atol=2 * v0 * s.numerics.dt)


# -- pores and water --------------------------------------------------------------------------------
def test_void_area_of_hexagonal_packing_is_exact():
    """Nearest-neighbour links of a hexagonal lattice (spacing a): every lattice triangle is a pore
    of void area sqrt(3)/4 a^2 - pi r^2 / 2 (eq 29)."""
    a, r = 1.0e-3, 0.42e-3
    xz = hex_lattice(7, 6, a, origin=(0.01, 0.02))
    pores = ref.build_pores(xz, np.full(len(xz), r), np.zeros(len(xz), int), 0.0, 0.25 * a)
    assert pores.n_pores == 5 * 12  # 5 strips between the 6 rows, 12 triangles each
    geo = ref.measure(pores, xz, np.full(len(xz), r), 0.0)
    np.testing.assert_allclose(geo.void_area, np.sqrt(3) / 4 * a**2 - np.pi * r**2 / 2, rtol=1e-11)


def test_uniform_pressure_exerts_no_force_on_an_inner_disc():
    """Eq 33 summed over the pores around a disc surrounded by pores of equal U cancels; on a
    single triangular pore the force on each disc is 2 U r sin(theta/2) towards the outside."""
    a, r = 1.0e-3, 0.45e-3
    xz = hex_lattice(5, 5, a)
    rr = np.full(len(xz), r)
    pores = ref.build_pores(xz, rr, np.zeros(len(xz), int), 0.0, 0.2 * a)
    geo = ref.measure(pores, xz, rr, 0.0)
    F = ref.pressure_forces(pores, xz, rr, np.full(pores.n_pores, 37.0), geo.corner_angle)
    inner = 12  # the centre of the 5 x 5 lattice
    assert np.all(np.isin(np.arange(len(xz))[inner], pores.corner_disc))
    assert np.hypot(*F[inner]) < 1e-13 * 37.0 * r
    tri = xz[[0, 1, 5]]
    one = ref.build_pores(tri, rr[:3], np.zeros(3, int), 0.0, 0.2 * a)
    g1 = ref.measure(one, tri, rr[:3], 0.0)
    F1 = ref.pressure_forces(one, tri, rr[:3], np.array([37.0]), g1.corner_angle)
    np.testing.assert_allclose(np.hypot(F1[:, 0], F1[:, 1]), 2 * 37.0 * r * np.sin(np.pi / 6), rtol=1e-12)
    outward = tri - tri.mean(axis=0)
    assert np.all(np.sum(F1 * outward, axis=1) > 0)
    np.testing.assert_allclose(F1.sum(axis=0), 0.0, atol=1e-15)


def test_two_pores_equalise_at_k_dt_one():
    """Eq 37-41: with k dt = 1 one step moves W' = (A_j W_i - A_i W_j)/(A_i + A_j), after which the
    two pressures are equal (water conserved)."""
    xz = np.array([[-1.2, 0.0], [1.2, 0.0], [0.0, 1.0], [0.0, -1.0]]) * 1e-3
    r = np.full(4, 0.5e-3)
    pores = ref.build_pores(xz, r, np.full(4, ref.LEFT), 0.0, 1.5e-3)
    assert pores.n_pores == 2 and len(pores.throats) == 1
    geo = ref.measure(pores, xz, r, 0.0)
    s = ref.read_settings(sc.validate({"scene": {"name": "w"}, "water": {"E_w": 1000.0, "k1": 50.0, "k2": 0.5}}).as_dict())
    w = ref.Water(pores, geo.void_area, s, np.float64)
    w.W = geo.void_area * np.array([1.1, 0.95])
    total = w.total()
    w.advance(1 / s.k1, geo.void_area, geo.link_contact)
    U = ref.pore_pressure(w.W, geo.void_area, s.E_w)
    assert abs(U[0] - U[1]) < 1e-12 * s.E_w
    assert abs(w.total() - total) < 1e-15 * total


def boxed_column(closed, seed=3):
    """Particles in a box of wall discs (bottom row, two side columns, and for ``closed`` a top row
    of side-wall discs), hexagonal with jittered smaller radii so they move under gravity."""
    rng = np.random.default_rng(seed)
    a = 2 * R
    xz = hex_lattice(8, 7, a)
    col, row = np.arange(len(xz)) % 8, np.arange(len(xz)) // 8
    group = np.where(row == 0, ref.BOTTOM, np.where(col == 0, ref.LEFT, np.where(col == 7, ref.RIGHT, 0)))
    if closed:
        group = np.where(row == 6, ref.LEFT, group)
    r = np.where(group == 0, R * (0.85 + 0.1 * rng.random(len(xz))), R)
    return Packing(xz, r, group, np.ones(len(xz)))


def wet_scene(g=9.81, **water):
    return make_scene(material={"g": g}, water={"enabled": True, **water},
                      contact={"separation_adjustment": True}, numerics={"dt": 1e-6, "rebuild_interval": 100})


def test_water_conserved_in_a_closed_network():
    pk = boxed_column(closed=True)
    m = ref.ReferenceModel(wet_scene(q_w=0.0, g=100.0), pk)
    assert not m.pores.surface.any() and m.pores.n_pores > 50
    W0 = m.water.total()
    for _ in range(300):  # includes pore rebuilds at k = 100, 200
        m.step()
    moved = np.max(np.abs(m.x - pk.xz)) / R
    assert moved > 1e-3  # the particles did move and the areas changed
    U = ref.pore_pressure(m.water.W, m._measure().void_area, m.water.E_w)
    assert np.max(np.abs(U)) > 1e-3
    exchanged = m.water.total() - m.water.remesh_change
    assert abs(exchanged - W0) <= 300 * 1e-16 * W0 * 4  # round-off of 300 sums, not a budget term


def test_water_balanced_by_boundary_fluxes():
    pk = boxed_column(closed=False)
    m = ref.ReferenceModel(wet_scene(q_w=5e-4), pk)
    assert m.pores.surface.any() and m.pores.bottom.any()
    w = m.water
    w.W *= 1.01  # U ~ 0.01 E_w everywhere: the surface drains at once
    w.initial = w.total()
    for _ in range(300):
        m.step()
    assert w.inflow > 0 and w.surface_out > 0
    assert w.balance_error() < 1e-13
    assert w.total() > w.initial


def test_rebuild_at_unchanged_positions_keeps_every_pressure():
    """Rule (a): rebuilding at the same positions finds every vertex set again; U and W unchanged."""
    pk = boxed_column(closed=False)
    m = ref.ReferenceModel(wet_scene(q_w=5e-4), pk)
    for _ in range(20):
        m.step()
    A = m._measure().void_area
    U = ref.pore_pressure(m.water.W, A, m.water.E_w)
    new = m._build()
    m.water.remesh(new, m._measure(new).void_area, A)
    np.testing.assert_allclose(ref.pore_pressure(m.water.W, m._measure(new).void_area, m.water.E_w), U, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.longdouble])
def test_state_stays_in_the_requested_dtype(dtype):
    pk = boxed_column(closed=False)
    m = ref.ReferenceModel(wet_scene(q_w=5e-4), pk, dtype)
    for _ in range(5):
        m.step()
    for arr in (m.x, m.v, m.psi, m.omega, m.mass, m.water.W, m.F_pressure, m.contact.e_n, m.contact.e_s):
        assert arr.dtype == dtype


# -- the reference's own readings (docs/READINGS.md) and analytic checks -----------------------------
def test_third_law_holds_without_being_built_in():
    """Each ordered pair (i, j) computes the force on i alone: in a jammed cluster of free discs with
    sliding, rolling and all springs active, the forces still sum to zero and the moments are
    -r_i f_s on both sides, because record (j, i) is the exact mirror of (i, j)."""
    rng = np.random.default_rng(7)
    xz = hex_lattice(5, 5, 1.9 * R) + 0.05 * R * rng.standard_normal((25, 2))
    pk = Packing(xz, np.full(25, R), np.zeros(25, int), np.ones(25))
    s = make_scene(contact={"spring": "d", "f_max": 0.5})
    m = ref.ReferenceModel(s, pk)
    m.v = 0.05 * rng.standard_normal(m.v.shape)
    m.omega = 50.0 * rng.standard_normal(m.omega.shape)
    for _ in range(20):
        m.step()
    F, M, _ = m.contact.forces(m.x, m.x - m.x_prev, m.psi - m.psi_prev, m.dt)
    assert np.abs(F).max() > 0.1
    np.testing.assert_allclose(F.sum(axis=0), 0.0, atol=1e-14 * np.abs(F).sum())
    assert np.count_nonzero(m.contact.in_contact) % 2 == 0     # every touching pair seen from both sides


def test_drained_side_in_the_reference_drains_with_k3():
    """The same analytic case as tests/model/test_pore_water.py, on the reference's own Water:
    W - A shrinks by exactly (1 - k3 h) per step; undrained it stays."""
    xz = np.array([[-1.2, 0.0], [1.2, 0.0], [0.0, 1.0], [0.0, -1.0]]) * 1e-3
    r = np.full(4, 0.5e-3)
    pores = ref.build_pores(xz, r, np.full(4, ref.LEFT), 0.0, 1.5e-3)
    geo = ref.measure(pores, xz, r, 0.0)
    assert pores.side.all() and not pores.surface.any()
    for sides, factor in (("drained", 1 - 7.0 * 1e-3), ("undrained", 1.0)):
        s = ref.read_settings(sc.validate({"scene": {"name": "w"}, "water": {
            "E_w": 1000.0, "k1": 50.0, "k2": 0.5, "k3": 7.0, "sides": sides}}).as_dict())
        w = ref.Water(pores, geo.void_area, s, np.float64)
        w.W = geo.void_area * 1.05
        for _ in range(40):
            w.advance(1e-3, geo.void_area, geo.link_contact)
        np.testing.assert_allclose(w.W - geo.void_area, 0.05 * geo.void_area * factor**40, rtol=1e-10)


def test_wall_kinematics_under_a_constant_input():
    """§6.1's constant-(average-)acceleration method: under a constant a, x_w(n dt) = a (n dt)^2 / 2
    exactly (READINGS D1)."""
    s = make_scene(loading={"type": "cosine", "amplitude": 3.0, "frequency": 1e-12, "moves": "bottom"},
                   numerics={"dt": 1e-6})
    pk = packing([[0.0, 0.0], [5 * R, 0.0]], [ref.BOTTOM, 0])
    m = ref.ReferenceModel(s, pk)
    for _ in range(200):
        m.step()
    assert m.x[0, 0] == pytest.approx(3.0 * (200e-6) ** 2 / 2, rel=1e-9)
    assert m.walls.v == pytest.approx(3.0 * 200e-6, rel=1e-12)
    assert m.x[1, 0] == 5 * R                                   # the particle was not moved


def test_average_acceleration_on_a_linear_ramp(tmp_path):
    """a(t) = c t (a record of two samples): with a_bar = c (t_n + dt/2) the velocity is exact,
    v = c t^2 / 2, and each step adds c dt^3 / 4 where the exact motion adds c dt^3 / 6 to the
    displacement's cubic term, so u(t) = c t^3 / 6 + c t dt^2 / 12 at every step (READINGS D1)."""
    ramp = tmp_path / "ramp.txt"
    ramp.write_text("0.0 0.0\n1.0 2.0\n")        # c = 2 m/s^3
    loading = {"type": "record", "record": str(ramp), "time_scale": 1.0, "amplitude_scale": 1.0,
               "record_units": "m/s2"}
    c = 2.0
    for dt in (1e-3, 7e-3):
        n = int(round(0.7 / dt))
        t = dt * np.arange(1, n + 1)
        motion = ref.WallMotion(ref.input_acceleration(loading), dt)
        u = np.cumsum([motion.step(k) for k in range(n)])
        np.testing.assert_allclose(u, c * t**3 / 6 + c * t * dt**2 / 12, rtol=1e-10)
        assert motion.v == pytest.approx(c * t[-1] ** 2 / 2, rel=1e-12)
    assert ref.input_acceleration({"type": "none"}) is None


def test_record_is_linear_between_samples_and_zero_outside(tmp_path):
    """READINGS D1: a digital record samples a continuous motion: linear between samples, rescaled
    by time_scale and amplitude_scale, in its units; 0 before its start and after its end."""
    rec = tmp_path / "rec.txt"
    rec.write_text("# t [s], a [g]\n0.01 0.0\n0.02 0.5\n0.04 -0.25\n")
    loading = {"type": "record", "record": str(rec), "time_scale": 0.5, "amplitude_scale": 2.0}
    g0 = ref.G0
    a = ref.input_acceleration(loading)
    assert a(0.0) == 0.0 and a(0.004) == 0.0                  # before the first sample (t = 0.005)
    assert a(0.0075) == pytest.approx(0.5 * g0, rel=1e-12)      # halfway to the 2nd sample at t = 0.01
    assert a(0.01) == pytest.approx(g0, rel=1e-12)
    assert a(0.015) == pytest.approx((g0 - 0.5 * g0) / 2, rel=1e-12)
    assert a(0.02) == pytest.approx(-0.5 * g0, rel=1e-12) and a(0.03) == 0.0
    in_gal = ref.input_acceleration({**loading, "record_units": "gal"})
    assert in_gal(0.01) == pytest.approx(0.01)     # 0.5 gal x 2 = 1 gal = 0.01 m/s^2
    cos = ref.input_acceleration({"type": "cosine", "amplitude": 15.0, "frequency": 50.0})
    assert cos(0.0) == 15.0 and cos(0.01) == pytest.approx(-15.0) and cos(0.005) == pytest.approx(0.0, abs=1e-12)


def test_rule_c_for_a_surface_pore_averages_pores_only():
    """READINGS D2: "その間隙と境界をともにするまわりのすべての図形の水圧の平均値" - a surface pore without
    (a) or (b) gets the plain mean of its neighbouring pores; the outside is not a figure."""
    pk = boxed_column(closed=False)
    m = ref.ReferenceModel(wet_scene(q_w=0.0), pk)
    pores = m.pores
    p = int(np.flatnonzero(pores.surface & np.array([len(n) > 0 for n in pores.neighbours]))[0])
    U_old = np.linspace(10.0, 30.0, pores.n_pores)
    valid = np.ones(pores.n_pores, bool)
    valid[p] = False
    nb = sorted(pores.neighbours[p])
    U, rule = ref.inherit_pressures(pores, U_old, valid, pores)
    assert rule[p] == "c" and rule.count("a") == pores.n_pores - 1
    assert U[p] == pytest.approx(U_old[nb].mean(), rel=1e-14)


def kite(h=1.31, r_side=1.0, r_end=0.64, l_m=0.66):
    """a = (-1, 0), c = (1, 0) of radius r_end; b = (0, h), d = (0, -h) of radius r_side [mm]. The
    regular triangulation takes the diagonal a-c when d lies outside the orthogonal circle of
    a, b, c: h^2 + r_end^2 > 1 + r_side^2 (here 2.126 > 2). Gaps: a-c 2 - 2 r_end = 0.72, b-d
    2 h - 2 r_side = 0.62, the sides 0.008; with l_m = 0.66 b-d is an eq 28 pair, a-c is not."""
    x = np.array([[-1.0, 0.0], [0.0, h], [1.0, 0.0], [0.0, -h]]) * 1e-3
    r = np.array([r_end, r_side, r_end, r_side]) * 1e-3
    return x, r, l_m * 1e-3


def test_regular_triangulation_hides_an_eq28_pair_that_the_flip_inserts():
    """READINGS D4: the lower hull of the lifted points (x, z, x^2 + z^2 - r^2) has the diagonal
    a-c (not a link); the hidden eq 28 pair b-d crosses no link, so it is put in by a flip: two
    pores (a, b, d), (b, c, d) instead of one quadrilateral."""
    x, r, l_m = kite()
    tris = ref.regular_triangles(x, r)
    edges = {tuple(sorted(e)) for t in tris for e in zip(t, t[1:] + t[:1])}
    assert (0, 2) in edges and (1, 3) not in edges and len(tris) == 2
    def is_link(i, j):
        return r[i] + r[j] + l_m >= np.hypot(*(x[i] - x[j]))
    flipped, inserted = ref.insert_hidden_links(x, r, tris, l_m, is_link)
    assert inserted == 1 and sorted(sorted(t) for t in flipped) == [[0, 1, 3], [1, 2, 3]]
    kept, inserted = ref.insert_hidden_links(x, r, tris, l_m, lambda i, j: True)   # a-c a link: b-d crosses it
    assert inserted == 0 and sorted(map(sorted, kept)) == [[0, 1, 2], [0, 2, 3]]
    pores = ref.build_pores(x, r, np.zeros(4, int), 0.0, l_m)
    assert sorted(map(sorted, pores.vertex_sets)) == [[0, 1, 3], [1, 2, 3]]
    assert sorted(map(tuple, pores.links.tolist())) == [(0, 1), (0, 3), (1, 2), (1, 3), (2, 3)]
    short = ref.build_pores(x, r, np.zeros(4, int), 0.0, 0.6e-3)    # b-d not an eq 28 pair: one pore
    assert [sorted(v) for v in short.vertex_sets] == [[0, 1, 2, 3]]
    # equal radii: the lifted points lie on a paraboloid and the lower hull is the Delaunay triangulation
    from scipy.spatial import Delaunay
    pts = np.random.default_rng(4).random((40, 2))
    assert sorted(map(sorted, ref.regular_triangles(pts, np.full(40, 0.01)))) == \
        sorted(map(sorted, Delaunay(pts).simplices.tolist()))


def non_overlapping_discs(seed, n=120, size=1.2e-2):
    """n discs of radii 0.1-1 mm dropped at random into a square, rejected where they would overlap."""
    rng = np.random.default_rng(seed)
    xz, r = np.zeros((n, 2)), np.zeros(n)
    k = 0
    while k < n:
        p, q = rng.random(2) * size, rng.uniform(0.1e-3, 1.0e-3)
        if np.all(np.hypot(*(xz[:k] - p).T) >= q + r[:k]):
            xz[k], r[k] = p, q
            k += 1
    return xz, r


def test_of_two_crossing_hidden_pairs_the_closer_is_linked():
    """READINGS D4: two eq 28 pairs hidden by the triangulation that cross each other cannot both
    be links; the one with the smaller gap R - r_i - r_j is put in first (then the other crosses a link)."""
    x, r = non_overlapping_discs(34)
    pores = ref.build_pores(x, r, np.zeros(len(r), int), 0.0, 1.5e-3)
    links = {tuple(l) for l in pores.links.tolist()}
    gap = lambda i, j: np.hypot(*(x[i] - x[j])) - r[i] - r[j]
    assert (59, 69) in links and (72, 105) not in links
    assert ref._crosses(x[59], x[69], x[72], x[105]) and gap(59, 69) < gap(72, 105) <= 1.5e-3


def test_pores_agree_with_the_fast_path_on_packings_with_hidden_pairs():
    """The reference's links and pores (written from the reading) against engines.model.pores's
    (regular triangulation, flips, gap order) on random packings where insertion happens."""
    from engines.model import pores as pg
    inserted = 0
    for seed in range(6):
        x, r = non_overlapping_discs(seed)
        l_m = (0.5e-3, 1.5e-3, 3e-3)[seed % 3]
        pores = ref.build_pores(x, r, np.zeros(len(r), int), 0.0, l_m)
        net = pg.build_pores(x, r, eps_m=0.0, l_m=l_m)
        assert {tuple(l) for l in pores.links.tolist()} == {tuple(l) for l in net.links.tolist()}
        assert set(pores.vertex_sets) == {frozenset(net.vertices_of(p).tolist()) for p in range(net.n_pores)}
        inserted += net.n_inserted
    assert inserted >= 5, inserted


def tied_column():
    """A bottom row of three wall discs and a left column of three wall discs above its first disc,
    side walls on springs (Fig. 27), one particle far from them, no gravity."""
    xz = [[0.0, 0.0], [2 * R, 0.0], [4 * R, 0.0], [0.0, 2 * R], [0.0, 4 * R], [0.0, 6 * R], [20 * R, 20 * R]]
    scene = make_scene(loading={"side_walls": "springs"}, contact={"ks_wall": 1.5e5, "eta_s_wall": 0.6})
    return scene, packing(xz, [ref.BOTTOM] * 3 + [ref.LEFT] * 3 + [ref.PARTICLE])


def test_column_ties_chain_the_corner_and_the_column_bottom_to_top():
    scene, pk = tied_column()
    lower, upper = ref.column_ties(pk.xz[::-1], pk.group[::-1])   # order of the discs must not matter
    assert (lower.tolist(), upper.tolist()) == ([6, 3, 2], [3, 2, 1])


@pytest.mark.parametrize("kind", ["spring", "dashpot"])
def test_tie_force_on_a_displaced_column_disc(kind):
    """The middle disc of a column moved by dx (or moving at v) from rest: its two ties pull it back by
    -2 k's dx (or -2 eta's v), each neighbour gets +k's dx (+eta's v), and it moves in x only."""
    scene, pk = tied_column()
    m = ref.ReferenceModel(scene, pk)
    ks, eta, dt = scene.contact.ks_wall, scene.contact.eta_s_wall, m.dt
    dx, v0 = 1e-6, 0.01
    if kind == "spring":
        m.x[4, 0] += dx
        m.x_prev[4, 0] += dx                  # at rest: du = 0
        expected, c = -2 * ks * dx, ks * dx
    else:
        m.x_prev[4, 0] -= v0 * dt             # du / dt = v0 at the rest positions
        expected, c = -2 * eta * v0, eta * v0
    m.step()
    F = m.v[:, 0] * m.mass / dt               # v = F / m dt from rest
    np.testing.assert_allclose(F[3:6], [c, expected, c], rtol=1e-9)
    assert np.all(m.v[:3] == 0) and np.all(m.v[:, 1] == 0) and np.all(m.x[:, 1] == pk.xz[:, 1])


def test_a_column_shifted_rigidly_with_its_corner_feels_no_tie():
    scene, pk = tied_column()
    m = ref.ReferenceModel(scene, pk)
    m.x[[0, 3, 4, 5], 0] += 3e-5
    m.x_prev[:] = m.x
    m.step()
    one_tie = scene.contact.ks_wall * 3e-5 / m.mass.min() * m.dt   # the speed one stretched tie would give
    assert 0 < one_tie and np.abs(m.v).max() < 1e-9 * one_tie


def test_the_blocks_stand_on_a_flat_bottom_wall_under_a_particle_pressed_into_it():
    """Without bottom wall discs the blocks start at a flat bottom wall's face, not at the lowest
    particle's bottom (a particle at rest on the wall overlaps it by its weight's overlap)."""
    from engines.reference.model import FlatWall, block_bounds
    xz, r, group = np.array([[0.0, 0.9999e-3], [0.0, 3e-3]]), np.array([1e-3, 1e-3]), np.zeros(2, int)
    floor = (FlatWall(0, -2e-3, 1, "undrained"), FlatWall(1, 0.0, 1, "inflow"))
    (z0, z1), = block_bounds(xz, r, group, [[0.0, 1.0]], floor)
    assert (z0, z1) == (0.0, 4e-3)
    assert block_bounds(xz, r, group, [[0.0, 1.0]])[0][0] == pytest.approx(-1e-7)  # no wall: the lowest bottom
