"""Contact law (eq 1-13, 26-27) and velocity adjustment at separation (eq 18-24), NumPy path."""
import numpy as np
import pytest

from engines.compiled import contact as compiled_contact
from engines.model.contact import (
    ContactLaw,
    ContactSettings,
    SeparationEvent,
    separation_adjustment,
)


def _press(spring, path, kn=1e6, f_max=2.0, eps_m=0.0):
    """Disc 0 (mobile, r = 1 mm) moved along x into disc 1 (fixed) by the overlaps in ``path``;
    returns the normal force on disc 1 at each step (compression > 0)."""
    r = np.array([1e-3, 1e-3])
    law = ContactLaw(ContactSettings(spring=spring, kn=kn, eta_n=0.0, ks=0.0, eta_s=0.0, f_max=f_max, eps_m=eps_m),
                     r, mobile=np.array([True, False]))
    x_prev, forces = None, []
    for overlap in path:
        xz = np.array([[-(2e-3 + eps_m - overlap), 0.0], [0.0, 0.0]])
        du = np.zeros_like(xz) if x_prev is None else xz - x_prev
        F, M, _ = law.forces(xz, du, np.zeros(2), 1e-6)
        forces.append(F[1, 0])
        x_prev = xz
    return np.array(forces)


def _load_unload(peak=4e-6, n=400):
    up = np.linspace(0, peak, n)
    return np.concatenate([up, up[::-1]]), up


def test_linear_spring_is_kn_times_overlap():
    path, _ = _load_unload()
    np.testing.assert_allclose(_press("a", path), 1e6 * path, rtol=1e-9, atol=1e-12)


def test_spring_c_plateau_and_same_path_on_unloading():
    path, up = _load_unload()
    f = _press("c", path)
    np.testing.assert_allclose(f, np.minimum(1e6 * path, 2.0), rtol=1e-9, atol=1e-12)
    assert f.max() == pytest.approx(2.0)
    np.testing.assert_allclose(f[: len(up)], f[len(up):][::-1], atol=1e-9)  # retraces


def test_spring_d_plateau_and_residual_overlap():
    path, up = _load_unload()
    f = _press("d", path)
    assert f.max() == pytest.approx(2.0)
    # unloading from the cap follows kn: zero force once the overlap has dropped by f_max/kn
    residual = path.max() - 2.0 / 1e6
    unload = path[len(up):]
    np.testing.assert_allclose(f[len(up):], np.maximum(2.0 - 1e6 * (path.max() - unload), 0), atol=1e-9)
    assert np.all(f[len(up):][unload < residual - 1e-12] == 0)  # still overlapping, no force
    # c and d differ only after the cap was reached
    np.testing.assert_allclose(_press("c", up[:150]), _press("d", up[:150]), atol=1e-12)


def test_eps_m_lets_force_act_across_a_gap():
    path = np.linspace(0, 1e-6, 50)
    f = _press("b", path, eps_m=5e-6)  # overlap counted from r_i + r_j + eps_m
    np.testing.assert_allclose(f, 1e6 * path, rtol=1e-9, atol=1e-12)


def test_coulomb_and_action_reaction():
    """Tangential sliding is capped at mu e_n (eq 11); forces are equal and opposite and the
    moments are -r f_s on both discs (eq 13)."""
    r = np.array([1e-3, 2e-3])
    s = ContactSettings(spring="a", kn=1e6, eta_n=0.0, ks=1e8, eta_s=0.0, mu=0.5)
    law = ContactLaw(s, r, mobile=np.array([True, True]))
    xz = np.array([[0.0, 0.0], [3e-3 - 1e-6, 0.0]])  # overlap 1 um along x
    law.forces(xz, np.zeros((2, 2)), np.zeros(2), 1e-6)
    du = np.array([[0.0, 5e-8], [0.0, 0.0]])  # disc 0 slides up: ks du = 5 N > mu e_n
    F, M, _ = law.forces(xz + du, du, np.zeros(2), 1e-6)
    np.testing.assert_allclose(F[0], -F[1], atol=1e-15)
    d = (xz + du)[1] - (xz + du)[0]
    n = d / np.hypot(*d)
    t = np.array([-n[1], n[0]])
    e_n = 1e6 * 1e-6  # eq 3a: the sliding increment is tangential, e_n is unchanged
    assert -F[0] @ n == pytest.approx(e_n, rel=1e-5)
    assert abs(F[0] @ t) == pytest.approx(0.5 * e_n, rel=1e-5)  # capped at mu e_n
    np.testing.assert_allclose(M / r, M[0] / r[0])  # both -r f_s


def test_no_tension_and_release():
    path = np.concatenate([np.linspace(0, 2e-6, 50), np.linspace(2e-6, -1e-6, 80)])
    f = _press("a", path)
    assert np.all(f >= -1e-12) and np.all(f[path < 0] == 0)


def test_separation_pattern_a_restitution():
    """A free disc leaving a wall: afterwards -Vn''/Vn = e exactly (eq 19, 22-23)."""
    ev = SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=2.0)  # it hit the wall at 2 m/s
    vel = np.array([[-1.5, 0.3], [0.0, 0.0]])  # leaving at 1.5 m/s, tangential 0.3 kept
    fix = separation_adjustment([ev], np.array([0, 5]), vel, np.array([1.0, np.inf]), np.array([True, False]), 0.001)
    v = fix[0]
    assert -(v[0] - 0.0) / 2.0 == pytest.approx(0.001 * -1 * -1)  # -Vn''_ij / Vn_ij = e
    assert v[1] == 0.3


def test_separation_pattern_d_conserves_momentum():
    ev = SeparationEvent(0, 1, np.array([0.0, 1.0]), vn_collision=1.0)
    vel = np.array([[0.1, -0.8], [0.0, 0.6]])
    m = np.array([2.0, 3.0])
    fix = separation_adjustment([ev], np.array([0, 0]), vel, m, np.array([True, True]), 0.01)
    p_before = m @ vel
    p_after = m[0] * fix[0] + m[1] * fix[1]
    np.testing.assert_allclose(p_after, p_before, atol=1e-12)
    vn_rel = fix[0] @ [0, 1] - fix[1] @ [0, 1]  # approach velocity after
    assert vn_rel == pytest.approx(-0.01 * 1.0)


def test_slow_separation_is_not_adjusted():
    ev = SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=2.0)
    vel = np.array([[-0.001, 0.0], [0.0, 0.0]])  # already slower than e Vn
    fix = separation_adjustment([ev], np.array([0, 5]), vel, np.array([1.0, np.inf]), np.array([True, False]), 0.001)
    np.testing.assert_allclose(fix[0], vel[0])


@pytest.mark.parametrize("kw,field", [(dict(spring="e"), "spring"), (dict(kn=0.0), "kn"), (dict(mu=-1.0), "mu"),
                                      (dict(eps_m=-1e-4), "eps_m"), (dict(f_max=0.0), "f_max")])
def test_bad_contact_settings(kw, field):
    with pytest.raises(ValueError, match=field):
        ContactSettings(**kw)


def test_separation_pattern_c_partner_first():
    """Fig. 3(c): i leaves j while j leaves a wall k; j is adjusted against k first, then i
    against the new j, so -Vn''_ij / Vn_ij = e for the pair (i, j) too."""
    e = 0.01
    ev_ij = SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=1.0)  # i at left of j
    ev_jk = SeparationEvent(1, 2, np.array([1.0, 0.0]), vn_collision=2.0)  # j at left of wall k
    vel = np.array([[-0.5, 0.0], [-0.3, 0.0], [0.0, 0.0]])
    fix = separation_adjustment([ev_ij, ev_jk], np.array([0, 0, 3]), vel, np.array([1.0, 1.0, np.inf]),
                                np.array([True, True, False]), e)
    # approach velocity after = v_a . n - v_b . n = -e Vn at collision
    assert fix[1][0] - 0.0 == pytest.approx(-e * 2.0)  # j leaves the wall k
    assert fix[0][0] - fix[1][0] == pytest.approx(-e * 1.0)  # i leaves the adjusted j


def test_touching_pairs_counts_and_forces_for_plots():
    """Three discs in a row, the middle one overlapping both neighbours, a fourth far away: two
    touching pairs with their normal forces kn x overlap, counts 1, 2, 1, 0."""
    r = np.full(4, 1e-3)
    xz = np.array([[0.0, 0.0], [2e-3 - 1e-6, 0.0], [4e-3 - 3e-6, 0.0], [10e-3, 0.0]])
    law = ContactLaw(ContactSettings(spring="a", kn=1e6, eta_n=0.0), r, mobile=np.ones(4, bool))
    law.forces(xz, np.zeros((4, 2)), np.zeros(4), 1e-6)
    np.testing.assert_array_equal(law.touch_count(), [1, 2, 1, 0])
    pairs, fn, es = law.contact_pairs()
    order = np.argsort(pairs[:, 0])
    np.testing.assert_array_equal(pairs[order], [[0, 1], [1, 2]])
    np.testing.assert_allclose(fn[order], [1.0, 2.0], rtol=1e-9)
    np.testing.assert_array_equal(es, [0.0, 0.0])       # head-on: no tangential spring


def test_forces_do_not_depend_on_the_neighbour_list_bookkeeping():
    """The Verlet list is bookkeeping: a law whose list is rebuilt as discs drift (default skin) gives
    the same forces, step by step, as one whose list never needs rebuilding (a skin wider than the
    box), while the whole cluster drifts by many skins, pairs slide (history in e_s, spring d's
    e_n), separate and a far disc arrives and touches."""
    rng = np.random.default_rng(3)
    n = 12
    r = 1e-3 * (0.8 + 0.2 * rng.random(n))
    base = np.column_stack([np.arange(n) % 4 * 1.8e-3, np.arange(n) // 4 * 1.8e-3]) + 2e-5 * rng.standard_normal((n, 2))
    base[-1] = [12e-3, 1.8e-3]                   # far away at first, it comes in from the right
    s = ContactSettings(spring="d", kn=1e6, eta_n=0.5, ks=5e5, eta_s=0.2, mu=0.4, f_max=0.8)
    lazy = ContactLaw(s, r, mobile=np.ones(n, bool))
    wide = ContactLaw(s, r, mobile=np.ones(n, bool), skin=1.0)
    x_prev, dt = base.copy(), 1e-6
    for k in range(120):
        xz = base + [-1e-4 * k, 3e-5 * k]        # drift: 12 mm left over the run, many skins
        xz = xz + 2e-5 * np.column_stack([np.sin(0.1 * k + np.arange(n)), np.cos(0.13 * k + 2 * np.arange(n))])
        xz[-1, 0] -= 0.8e-4 * k                  # the far disc closes in
        du = xz - x_prev
        Fa, Ma, sa = lazy.forces(xz, du, np.zeros(n), dt)
        Fb, Mb, sb = wide.forces(xz, du, np.zeros(n), dt)
        np.testing.assert_allclose(Fa, Fb, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(Ma, Mb, rtol=1e-12, atol=1e-15)
        assert sorted((e.i, e.j) for e in sa) == sorted((e.i, e.j) for e in sb)
        x_prev = xz
    assert lazy.list_builds > 5 and wide.list_builds == 1
    assert wide.touch_count()[-1] > 0            # the far disc did arrive


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_an_approaching_disc_is_never_missed(direction):
    """A disc closing in on a fixed one from three skins beyond reach, in steps of 0.3 skin from
    either side: it touches at the same step, with the same force, as with a list that holds every pair."""
    r = np.array([1e-3, 1e-3])
    s = ContactSettings(spring="a", kn=1e6, eta_n=0.0, ks=0.0, eta_s=0.0)
    lazy = ContactLaw(s, r, mobile=np.array([True, False]))
    wide = ContactLaw(s, r, mobile=np.array([True, False]), skin=1.0)
    step = 0.3 * lazy.skin
    start = 2e-3 + 3 * lazy.skin
    x_prev = None
    for k in range(20):
        xz = np.array([[direction * (start - k * step), 0.0], [0.0, 0.0]])
        du = np.zeros_like(xz) if x_prev is None else xz - x_prev
        Fa, _, _ = lazy.forces(xz, du, np.zeros(2), 1e-6)
        Fb, _, _ = wide.forces(xz, du, np.zeros(2), 1e-6)
        np.testing.assert_array_equal(Fa, Fb)
        x_prev = xz
    assert wide.touch_count()[0] == 1 and abs(Fa[0, 0]) > 0


@pytest.mark.parametrize("spring", ["a", "b", "c", "d"])
def test_contact_law_and_separation_adjustment_match_the_reference(spring):
    """Eq 1-13, 25-27 and 18-24 against the independent reference (engines/reference/model.py: one record
    per ordered pair, written from the paper) along a run of colliding, sliding, rolling and
    separating discs (dashpots, friction cap, every spring): the same forces and moments on every
    particle and the same adjusted velocities, step by step."""
    from engines.reference import model as ref
    from engines.run import scene as sc
    from packing.packing import Packing

    rng = np.random.default_rng({"a": 1, "b": 2, "c": 3, "d": 4}[spring])
    n = 14
    r = 1e-3 * (0.7 + 0.3 * rng.random(n))
    xz = np.column_stack([np.arange(n) % 4 * 2.05e-3, np.arange(n) // 4 * 2.05e-3])
    group = np.zeros(n, int)
    group[[0, 3]] = 1                                   # two fixed discs
    tables = sc.validate({"scene": {"name": "t"}, "material": {"g": 0.0}, "water": {"enabled": False},
                          "contact": {"spring": spring, "kn": 1e7, "eta_n": 2.0, "ks": 4e6, "eta_s": 0.7, "mu": 0.3,
                                      "f_max": 0.6, "eps_m": 2e-5 if spring == "b" else 0.0, "restitution": 0.001},
                          "numerics": {"dt": 2e-7}}).as_dict()
    model = ref.ReferenceModel(tables, Packing(xz, r, group, np.ones(n)))
    mobile = group == 0
    model.v[mobile] = 2.0 * rng.standard_normal((mobile.sum(), 2))
    model.omega[mobile] = 300.0 * rng.standard_normal(mobile.sum())
    c = tables["contact"]
    law = ContactLaw(ContactSettings(**{k: c[k] for k in ("spring", "kn", "eta_n", "ks", "eta_s", "mu", "restitution",
                                                           "f_max", "eps_m", "separation_adjustment")}), r, mobile)
    records = ref.PairRecords(model.s, model.r, mobile, np.float64)
    dt, adjusted, touched = model.dt, 0, 0
    for _ in range(1500 if spring in "ab" else 600):
        du, dpsi = model.x - model.x_prev, model.psi - model.psi_prev
        F, M, separations = law.forces(model.x, du, dpsi, dt)
        F_ref, M_ref, left = records.forces(model.x, du, dpsi, dt)
        scale = max(np.abs(F_ref).max(), 1e-3)
        np.testing.assert_allclose(F[mobile], F_ref[mobile], rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(M[mobile], M_ref[mobile], rtol=0, atol=1e-9 * scale * r.max())
        touched += int(law.touching.sum())
        if separations:
            fixes = separation_adjustment(separations, law.touch_count(), du / dt, model.mass, mobile, c["restitution"])
            fixes_ref = ref.adjust_free_particles(left, records.contacts_of(), du / dt, model.mass, c["restitution"])
            assert sorted(k for k in fixes if not np.array_equal(fixes[k], (du / dt)[k])) == sorted(fixes_ref)
            for k, v in fixes_ref.items():
                np.testing.assert_allclose(fixes[k], v, rtol=1e-9, atol=1e-12)
            adjusted += len(fixes_ref)
        model.step()
    assert touched > 100
    assert adjusted > 0 or spring in "cd"    # the capped springs absorb so much that no disc flies free


def test_a_pair_that_touched_without_approach_separates_freely():
    """Eq 19 scales the separation by the approach velocity of the collision: a contact made at
    rest (Vn_ij = 0, e.g. a grain settling onto another) gives no bound, so two discs pushed apart
    (by the water, say) keep their velocities."""
    ev = SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=0.0)
    vel = np.array([[-0.2, 0.1], [0.3, 0.0]])
    fix = separation_adjustment([ev], np.array([0, 0]), vel, np.array([1.0, 2.0]), np.array([True, True]), 0.01)
    np.testing.assert_array_equal(fix[0], vel[0])
    np.testing.assert_array_equal(fix[1], vel[1])


def test_isolated_pair_after_a_disc_that_left_two_walls():
    """Eq 24 for an isolated pair (3, 4) in the same step as a disc 0 that left two walls (pattern
    b, eq 22-23 with the smaller Rk): the pair keeps its normal momentum and separates at e Vn."""
    e = 0.01
    evs = [SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=1.0),
           SeparationEvent(0, 2, np.array([0.0, 1.0]), vn_collision=1.0),
           SeparationEvent(3, 4, np.array([1.0, 0.0]), vn_collision=2.0)]
    vel = np.array([[-0.5, -0.2], [0.0, 0.0], [0.0, 0.0], [-0.4, 0.0], [0.6, 0.0]])
    m = np.array([1.0, np.inf, np.inf, 2.0, 3.0])
    fix = separation_adjustment(evs, np.array([0, 4, 4, 0, 0]), vel, m, np.array([True, False, False, True, True]), e)
    assert m[3] * fix[3][0] + m[4] * fix[4][0] == pytest.approx(m[3] * vel[3, 0] + m[4] * vel[4, 0], abs=1e-14)
    assert fix[3][0] - fix[4][0] == pytest.approx(-e * 2.0, rel=1e-12)
    # disc 0: Rk = e Vn / |Vn'| for each wall, 0.02 along x and 0.05 along z; the smaller one, along its normal
    np.testing.assert_allclose(fix[0], [-0.5 * 0.02, -0.2], rtol=1e-12)


def test_a_disc_at_rest_left_by_a_receding_wall_is_not_scaled():
    """Eq 22 scales the leaving disc's own normal velocity; a disc at rest that a wall moves away
    from (Vn_i = 0) has none to scale and keeps its velocity."""
    ev = SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=1.0)
    vel = np.array([[0.0, 0.4], [2.0, 0.0]])
    fix = separation_adjustment([ev], np.array([0, 3]), vel, np.array([1.0, np.inf]), np.array([True, False]), 0.01)
    np.testing.assert_array_equal(fix[0], [0.0, 0.4])


@pytest.mark.parametrize("law_class", [ContactLaw, compiled_contact.ContactLaw])
def test_discs_exactly_touching_are_in_contact(law_class):
    """Eq 1: contact when r_i + r_j >= R_ij, so discs exactly touching (overlap 0, exact in binary)
    and approaching at 0.1 m/s feel the dashpot eta_n du_n / dt (the spring is still 0) and count
    as touching."""
    r = np.array([0.5, 0.5])
    law = law_class(ContactSettings(spring="a", kn=1e6, eta_n=2.0, ks=0.0, eta_s=0.0), r,
                     mobile=np.array([True, True]))
    dt = 1e-6
    xz = np.array([[0.0, 0.0], [1.0, 0.0]])
    F, _, _ = law.forces(xz, np.array([[1e-7, 0.0], [0.0, 0.0]]), np.zeros(2), dt)
    np.testing.assert_array_equal(law.touch_count(), [1, 1])
    np.testing.assert_allclose(F, [[-2.0 * 0.1, 0.0], [2.0 * 0.1, 0.0]], rtol=1e-9)


def test_pattern_b_takes_the_smallest_factor_over_all_qualifying_walls():
    """Eq 22-23, pattern b: of the walls a disc left, those it leaves faster than e Vn give a factor
    Rk = -e Vn / Vn'; the smallest wins, whatever the order of the events, and a wall it leaves
    slowly (first here) is skipped, not the end of the search."""
    e = 0.01
    evs = [SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=100.0),   # slow: 0.5 < e 100
           SeparationEvent(0, 2, np.array([0.0, 1.0]), vn_collision=1.0),     # Rk = 0.01 / 0.2 = 0.05
           SeparationEvent(0, 3, np.array([1.0, 0.0]), vn_collision=1.0)]     # Rk = 0.01 / 0.5 = 0.02
    vel = np.array([[-0.5, -0.2], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    m, mobile = np.array([1.0, np.inf, np.inf, np.inf]), np.array([True, False, False, False])
    fix = separation_adjustment(evs, np.array([0, 3, 3, 3]), vel, m, mobile, e)
    np.testing.assert_allclose(fix[0], [-0.5 * 0.02, -0.2], rtol=1e-12)


def test_separation_pattern_c_with_the_wall_first_in_the_pair():
    """Fig. 3(c) with the wall k listed first in its pair (a lower index): j (index 1) leaves k
    (to its left) and i (index 2, above it). j is adjusted against k alone first (its separation
    from i would give the smaller factor, but i is free), then i against the new j."""
    e = 0.01
    ev_kj = SeparationEvent(0, 1, np.array([1.0, 0.0]), vn_collision=2.0)   # wall k at left of j
    ev_ji = SeparationEvent(1, 2, np.array([0.0, 1.0]), vn_collision=1.0)   # i above j
    vel = np.array([[0.0, 0.0], [0.3, -0.4], [0.0, 0.1]])
    fix = separation_adjustment([ev_kj, ev_ji], np.array([3, 0, 0]), vel, np.array([np.inf, 1.0, 1.0]),
                                np.array([False, True, True]), e)
    np.testing.assert_allclose(fix[1], [e * 2.0, -0.4], rtol=1e-12)         # j leaves k at e Vn_kj
    assert fix[2][0] == 0.0
    assert fix[2][1] - fix[1][1] == pytest.approx(e * 1.0, rel=1e-12)      # i leaves the adjusted j at e Vn_ji


@pytest.mark.parametrize("law_class", [ContactLaw, compiled_contact.ContactLaw])
def test_eps_m_wider_than_the_skin_is_in_the_pair_list(law_class):
    """Eq 26 with eps_m larger than the neighbour list's skin (0.25 r): two discs 0.35 mm apart with
    eps_m = 0.4 mm touch from the first step, with the spring kn (r_i + r_j + eps_m - R)."""
    r = np.array([1e-3, 1e-3])
    law = law_class(ContactSettings(spring="a", kn=1e6, eta_n=0.0, eps_m=0.4e-3), r,
                     mobile=np.array([True, True]))
    xz = np.array([[0.0, 0.0], [2.35e-3, 0.0]])
    F, _, _ = law.forces(xz, np.zeros((2, 2)), np.zeros(2), 1e-6)
    np.testing.assert_array_equal(law.touch_count(), [1, 1])
    np.testing.assert_allclose(F[1], [1e6 * 0.05e-3, 0.0], rtol=1e-9, atol=1e-12)


def test_settings_accept_any_positive_stiffness_and_refuse_a_zero_force_cap():
    """kn > 0 is the only bound on the stiffness (0.5 N/m is soft, not wrong); f_max (eq 27) must be
    > 0 for every spring, as in a scene file (a and b never read it)."""
    assert ContactSettings(kn=0.5).kn == 0.5
    for spring in ("a", "c", "d"):
        with pytest.raises(ValueError, match=r"\[contact\] f_max: must be > 0"):
            ContactSettings(spring=spring, f_max=0.0)


@pytest.mark.parametrize("law_class", [ContactLaw, compiled_contact.ContactLaw])
def test_touching_at_is_what_a_step_would_give_without_taking_it(law_class):
    """ContactLaw.touching_at: the touching pairs, normal and elastic shear forces that ``forces``
    would give at the next positions (a stepped copy of the law), also when the pair list is
    stale there and a pair it did not list touches; the law itself is left as it was (state,
    list, builds). ``keep`` evaluates a subset of the listed pairs."""
    import copy
    rng = np.random.default_rng(5)
    n = 16
    r = 1e-3 * (0.9 + 0.1 * rng.random(n))
    xz = np.column_stack([np.arange(n) % 4 * 1.9e-3, np.arange(n) // 4 * 1.9e-3])
    s = ContactSettings(spring="d", kn=1e5, eta_n=0.3, ks=4e4, eta_s=0.1, mu=0.5, f_max=2.0)
    law = law_class(s, r, mobile=np.arange(n) >= 4)
    dt, x_prev = 1e-6, xz
    for step in range(6):
        x = x_prev + 2e-5 * rng.standard_normal(xz.shape)
        law.forces(x, x - x_prev, 1e-3 * rng.standard_normal(n), dt)
        x_prev = x
    for stale in (False, True):
        x = x_prev + 1e-6 * rng.standard_normal(xz.shape)
        x[5] = x[4] + [r[4] + r[5] - 1e-6, 0.0]         # a listed pair pressed together
        if stale:                                        # disc 15 jumps next to disc 0: not listed
            x[15] = x[0] - [r[0] + r[15] - 1e-6, 0.0]
        du, dpsi = x - x_prev, 1e-3 * rng.standard_normal(n)
        before = (law.state.copy(), law.i.copy(), law.list_builds)
        pairs, fn, es = law.touching_at(x, du, dpsi, dt)
        assert np.array_equal(law.state, before[0]) and np.array_equal(law.i, before[1])
        assert law.list_builds == before[2]
        stepped = copy.deepcopy(law)
        stepped.forces(x, du, dpsi, dt)
        assert stepped.list_builds == before[2] + stale
        for got, expected in zip((pairs, fn, es), stepped.contact_pairs()):
            assert np.array_equal(got, expected)
        assert [4, 5] in pairs.tolist() and ([0, 15] in pairs.tolist()) == stale and len(fn) > 5
        low = pairs.min(axis=1) < 8
        sub = law.touching_at(x, du, dpsi, dt, keep=lambda i, j: np.minimum(i, j) < 8)
        for got, expected in zip(sub, (pairs[low], fn[low], es[low])):
            assert np.array_equal(got, expected)


@pytest.mark.parametrize("law_class", [ContactLaw, compiled_contact.ContactLaw])
def test_a_stored_pair_list_that_does_not_fit_is_refused(law_class):
    """checkpoint_restored: the pair list of a few steps passes; a list position of another shape,
    j or state not one row per pair, a disc index below 0 or at n are each refused in one line."""
    rng = np.random.default_rng(2)
    xz = np.column_stack([np.arange(6) * 1.9e-3, np.zeros(6)])
    law = law_class(ContactSettings(spring="a", kn=1e6), np.full(6, 1e-3), np.ones(6, bool))
    law.forces(xz, 1e-7 * rng.standard_normal(xz.shape), np.zeros(6), 1e-6)
    assert len(law.i) and law.i.min() == 0 and law.j.max() == 5
    law.checkpoint_restored()
    good = {name: getattr(law, name).copy() for name in ("i", "j", "state", "xz_list")}
    bad = [("xz_list", good["xz_list"][:-1], r"^pair list: xz_list has shape \(5, 2\), expected \(6, 2\)$"),
           ("j", good["j"][:-1], r"^pair list: i .* do not fit$"), ("state", good["state"][:, :5], "do not fit"),
           ("i", np.where(np.arange(len(good["i"])) == 0, -1, good["i"]), r"^pair list: disc indices outside \[0, 6\)$"),
           ("j", np.where(np.arange(len(good["j"])) == 0, 6, good["j"]), r"outside \[0, 6\)")]
    for name, value, message in bad:
        setattr(law, name, value)
        with pytest.raises(ValueError, match=message):
            law.checkpoint_restored()
        setattr(law, name, good[name])
    law.xz_list = None   # no list built yet
    law.checkpoint_restored()
