"""The NumPy reference of seed 000 (engines/reference.py) against exact and analytic results.

Contact: head-on restitution of a linear spring-dashpot, the separation adjustment (eq 18-24),
the four normal springs of Fig. 5 released from a pressed state. Pores and water: the void area of
a hexagonal packing, eq 33 on a uniform pressure, eq 38 equalisation, water conservation in a
closed network and the budget with boundary fluxes. Plumbing of yade_scripts/crosscheck.py.
"""
import importlib.util
import json
import os

import numpy as np
import pytest

from engines import scene as sc
from engines import reference as ref
from packing.layouts import hex_lattice
from packing.packing import Packing

R = 0.45e-3  # disc radius [m]


def make_scene(**tables):
    """A validated scene: dry, no gravity, no separation adjustment unless overridden."""
    raw = {"scene": {"name": "test"}, "material": {"g": 0.0}, "water": {"enabled": False},
           "contact": {"separation_adjustment": False}, "numerics": {"dt": 1e-7}}
    for table, fields in tables.items():
        raw.setdefault(table, {}).update(fields)
    return sc.validate(raw)


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


# -- cross-check plumbing -----------------------------------------------------------------------------
def load_crosscheck():
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "yade_scripts", "crosscheck.py")
    spec = importlib.util.spec_from_file_location("crosscheck", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_crosscheck_plumbing_with_the_reference_on_both_sides(tmp_path):
    """The cross-check's machinery with the reference standing in for YADE: every case passes with
    identical trajectories, the JSON holds the features and counts, and a deliberately different
    'other implementation' (start moved by 1e-9 m) fails."""
    cc = load_crosscheck()

    def stand_in(scene, pk, n, every, hooks=(), **kw):
        return ref.simulate_reference(scene, pk, n, every, readings=ref.FAST_CODE_READINGS, **kw)

    small = cc.FeatureCase("small_settling", cc.settling_build(numerics={"rebuild_interval": 5}), 150, 10,
                           rules="a", readings=("rule_c_counts_outside",))
    contact = [c for c in cc.contact_cases() if c.name in ("head_on_collision", "pressed_release_d")]
    result = cc.run_cases(stand_in, stand_in, cases=contact, features=[small],
                          paper_simulate=ref.simulate_reference)
    assert result["passed"], [c["why"] for c in result["cases"] + result["feature_cases"] if not c["passed"]]
    for case in result["cases"]:
        assert case["metrics"]["max_position_diff_rel"] == 0.0
    feat = result["feature_cases"][0]
    assert feat["window"]["max_position_diff_rel"] == 0.0 and feat["counts"]["ref"]["rebuilds"] >= 20
    assert feat["features"]["water"] and "reading_disagreements" in feat
    path = cc.write_json(result, str(tmp_path))
    with open(path) as f:
        back = json.load(f)
    assert {c["name"] for c in back["cases"]} >= {"head_on_collision", "pressed_release_d"}
    assert back["feature_cases"][0]["name"] == "small_settling"

    def shaken(scene, pk, n, every, hooks=(), **kw):
        moved = Packing(pk.xz + 1e-9, pk.r, pk.group, pk.density_factor)
        return stand_in(scene, moved, n, every, **kw)
    bad = cc.run_cases(shaken, stand_in, cases=[], features=[small])
    assert not bad["passed"] and not bad["feature_cases"][0]["checks"]["positions_in_window"]


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
    """The same analytic case as tests/test_pore_water.py, on the reference's own Water:
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


@pytest.mark.parametrize("wall_step, steps_factor", [("constant_acceleration", lambda n: n * n / 2),
                                                     ("symplectic_euler", lambda n: n * (n + 1) / 2)])
def test_wall_kinematics_under_a_constant_input(wall_step, steps_factor):
    """§6.1's constant-acceleration method: under a constant a, x_w(n dt) = a (n dt)^2 / 2 exactly;
    the fast code's symplectic Euler moves a dt^2 n (n + 1) / 2 (READINGS D1)."""
    s = make_scene(loading={"type": "cosine", "amplitude": 3.0, "frequency": 1e-12, "moves": "bottom"},
                   numerics={"dt": 1e-6})
    pk = packing([[0.0, 0.0], [5 * R, 0.0]], [ref.BOTTOM, 0])
    m = ref.ReferenceModel(s, pk, readings={"wall_step": wall_step})
    for _ in range(200):
        m.step()
    assert m.x[0, 0] == pytest.approx(3.0 * 1e-12 * steps_factor(200), rel=1e-9)
    assert m.wall_v == pytest.approx(3.0 * 200e-6, rel=1e-12)
    assert m.x[1, 0] == 5 * R                                   # the particle was not moved


def test_record_held_or_interpolated(tmp_path):
    """READINGS D1: between samples the record's acceleration is held ("hold", §6.1's
    constant-acceleration method) or interpolated ("linear", the fast code); 0 after its end."""
    rec = tmp_path / "rec.txt"
    rec.write_text("0.0 0.0\n0.02 0.5\n0.04 -0.25\n")
    loading = {"type": "record", "record": str(rec), "time_scale": 0.5, "amplitude_scale": 2.0}
    g0 = ref.G0
    hold, linear = ref.input_acceleration(loading, "hold"), ref.input_acceleration(loading, "linear")
    assert hold(0.005) == 0.0 and linear(0.005) == pytest.approx(0.5 * g0)
    assert hold(0.01) == pytest.approx(g0) and hold(0.015) == pytest.approx(g0)
    assert linear(0.015) == pytest.approx((g0 - 0.5 * g0) / 2)
    assert hold(0.02) == pytest.approx(-0.5 * g0) and hold(0.03) == 0.0 and linear(0.03) == 0.0
    in_gal = ref.input_acceleration({**loading, "record_units": "gal"}, "hold")
    assert in_gal(0.01) == pytest.approx(0.01)     # 0.5 gal x 2 = 1 gal = 0.01 m/s^2


def test_rule_c_reading_for_a_surface_pore():
    """READINGS D2: the reference averages over neighbouring pores only; with the fast code's
    reading the outer face adds a neighbour at U = 0."""
    pk = boxed_column(closed=False)
    m = ref.ReferenceModel(wet_scene(q_w=0.0), pk)
    pores = m.pores
    p = int(np.flatnonzero(pores.surface & np.array([len(n) > 0 for n in pores.neighbours]))[0])
    U_old = np.linspace(10.0, 30.0, pores.n_pores)
    valid = np.ones(pores.n_pores, bool)
    valid[p] = False
    nb = sorted(pores.neighbours[p])
    for outside, extra in ((False, 0), (True, 1)):
        U, rule = ref.inherit_pressures(pores, U_old, valid, pores, outside)
        assert rule[p] == "c" and rule.count("a") == pores.n_pores - 1
        assert U[p] == pytest.approx(U_old[nb].sum() / (len(nb) + extra), rel=1e-14)
