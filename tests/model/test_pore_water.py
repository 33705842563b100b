"""Pore water (SPEC §2.3): eq 38 equalisation, conservation, boundary balance, stability, re-meshing."""
import numpy as np
import pytest

from engines.model import pores as pg
from engines.model.limits import DarcyStabilityError
from engines.model.pore_water import PoreWater, WaterSettings, buoyancy, pressure, pressures_by_rule, rule_counts
from packing.layouts import random_discs


def _two_pores(diagonal_linked=True):
    """Rhombus of four wall discs: two triangular pores sharing the short diagonal (a gap link)."""
    xz = np.array([[-1.2, 0.0], [1.2, 0.0], [0.0, 1.0], [0.0, -1.0]])
    r = np.full(4, 0.5)
    l_m = 1.5 if diagonal_linked else 0.7
    net = pg.build_pores(xz, r, l_m=l_m, walls=np.full(4, pg.WALL_LEFT))
    return xz, r, net


def test_two_pores_equalise_in_one_step_at_k_dt_1():
    xz, r, net = _two_pores()
    assert net.n_pores == 2 and len(net.throat_conns) == 1
    m = pg.measure(net, xz, r)
    assert not m.link_contact[net.throat_link[0]]  # gap: k = k1
    s = WaterSettings(E_w=1000.0, k1=50.0, k2=0.5)
    w = PoreWater(net, m.void_area, s, W=m.void_area * np.array([1.1, 0.95]))
    total = w.total_water()
    w.advance(1.0 / s.k1, m.void_area, m.link_contact)  # k dt = 1: eq 38 exactly
    U = w.pressure(m.void_area)
    assert abs(U[0] - U[1]) < 1e-12 * s.E_w
    assert abs(w.total_water() - total) < 1e-15 * total


def test_stability_limit_pair_is_two_over_k():
    xz, r, net = _two_pores()
    m = pg.measure(net, xz, r)
    s = WaterSettings(E_w=1000.0, k1=50.0, k2=0.5, substep=False)
    w = PoreWater(net, m.void_area, s)
    # equal areas by symmetry, W = A: the pair's exact limit is 2/k
    np.testing.assert_allclose(w.darcy_limit(m.void_area, m.link_contact), 2.0 / s.k1, rtol=1e-12)
    with pytest.raises(DarcyStabilityError, match="Darcy limit"):
        w.advance(2.01 / s.k1, m.void_area, m.link_contact)
    # asked to sub-step, it does, and stays bounded
    w2 = PoreWater(net, m.void_area, WaterSettings(E_w=1000.0, k1=50.0, k2=0.5, substep=True),
                   W=m.void_area * np.array([1.1, 0.95]))
    for _ in range(20):
        w2.advance(10.0 / s.k1, m.void_area, m.link_contact)
    U = w2.pressure(m.void_area)
    assert abs(U[0] - U[1]) < 1e-6


def _random_network(seed=5, n=400, walls=None):
    rng = np.random.default_rng(seed)
    xz, r = random_discs(n, rng)
    return xz, r, pg.build_pores(xz, r, l_m=0.7 * r.mean(), walls=walls)


def test_water_conserved_without_boundaries():
    xz, r, net = _random_network()
    net.pore_surface[:] = False  # a closed network: no boundary exchange
    m = pg.measure(net, xz, r)
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0)
    rng = np.random.default_rng(0)
    w = PoreWater(net, m.void_area, s, W=m.void_area * (1 + 0.2 * rng.random(net.n_pores)))
    total = w.total_water()
    for _ in range(500):
        w.advance(1e-4, m.void_area, m.link_contact)
    assert abs(w.total_water() - total) <= 1e-12 * total
    U = w.pressure(m.void_area)
    assert U.std() < 0.5 * (s.E_w * 0.2)  # pressures have spread out


def test_boundary_fluxes_balance_the_water():
    """Inflow at the bottom, outflow at the free surface and drained sides: the budget closes."""
    rng = np.random.default_rng(6)
    xz, r = random_discs(400, rng)
    walls = np.zeros(len(r), int)
    walls[xz[:, 1] < xz[:, 1].min() + 1.0] = pg.WALL_BOTTOM
    walls[xz[:, 0] < xz[:, 0].min() + 1.0] = pg.WALL_LEFT
    walls[xz[:, 0] > xz[:, 0].max() - 1.0] = pg.WALL_RIGHT
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean(), walls=walls)
    m = pg.measure(net, xz, r)
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=100.0, q_w=0.05, sides="drained")
    w = PoreWater(net, m.void_area, s)
    for _ in range(300):
        w.advance(1e-4, m.void_area, m.link_contact)
    b = w.balance
    assert b.inflow > 0 and b.surface_outflow > 0 and b.side_outflow > 0
    assert w.balance_error() < 1e-12
    # bottom pressure rises first and stays below E_w (eq 32)
    U = w.pressure(m.void_area)
    assert U[net.pore_touches["bottom"]].mean() > U[net.pore_surface].mean() > 0
    assert U.max() < s.E_w


def test_pinched_pore_exchanges_nothing():
    xz, r, net = _two_pores()
    m = pg.measure(net, xz, r)
    w = PoreWater(net, m.void_area, WaterSettings(E_w=1000.0, k1=50.0, k2=0.5),
                  W=m.void_area * np.array([1.1, 0.95]))
    A = m.void_area.copy()
    A[0] = 0.5 * net.a_min  # squeezed shut
    W0 = w.W.copy()
    w.advance(1e-3, A, m.link_contact)
    np.testing.assert_array_equal(w.W, W0)
    assert np.all(np.isfinite(w.pressure(A)))


def test_remesh_rule_a_same_network_keeps_pressures():
    xz, r, net = _random_network()
    m = pg.measure(net, xz, r)
    w = PoreWater(net, m.void_area, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, transfer="paper"),
                  W=m.void_area * (1 + 0.1 * np.random.default_rng(1).random(net.n_pores)))
    U0 = w.pressure(m.void_area)
    net2 = pg.build_pores(xz, r, l_m=0.7 * r.mean())
    counts = w.remesh(net2, m.void_area, m.void_area)
    assert counts == {"a": net.n_pores, "b": 0, "c": 0, "d": 0}
    np.testing.assert_allclose(w.pressure(m.void_area), U0, rtol=1e-12)
    assert w.balance_error() < 1e-12


def test_remesh_rule_b_split_and_merge():
    xz, r, one = _two_pores(diagonal_linked=False)
    _, _, two = _two_pores(diagonal_linked=True)
    assert one.n_pores == 1 and two.n_pores == 2
    U, rule = pressures_by_rule(one, np.array([40.0]), np.array([True]), two)  # split
    assert rule_counts(rule)["b"] == 2
    np.testing.assert_allclose(U, [40.0, 40.0])
    U, rule = pressures_by_rule(two, np.array([10.0, 30.0]), np.array([True, True]), one)  # merge
    assert rule_counts(rule)["b"] == 1
    np.testing.assert_allclose(U, [20.0])


def test_remesh_rules_c_and_d():
    xz, r, net = _random_network(n=100)
    n = net.n_pores
    U_old = np.linspace(1.0, 2.0, n)
    valid = np.ones(n, bool)
    p = int(np.flatnonzero(~net.pore_surface)[0])
    valid[p] = False  # its old pressure is not usable (pinched): rule (c) from its neighbours
    U, rule = pressures_by_rule(net, U_old, valid, net)
    counts = rule_counts(rule)
    assert counts["c"] == 1 and counts["a"] == n - 1
    i, j = net.throat_conns.T
    nb = np.concatenate([j[i == p], i[j == p]])
    np.testing.assert_allclose(U[p], U_old[nb].mean())
    # no usable old pore at all and nothing assigned around: (d) U = 0 everywhere
    U, rule = pressures_by_rule(net, U_old, np.zeros(n, bool), net)
    counts = rule_counts(rule)
    assert counts["d"] == n and np.all(U == 0)


@pytest.mark.parametrize("kw,field", [(dict(E_w=0.0), "E_w"), (dict(k1=-1.0), "k1"), (dict(k2=np.nan), "k2"),
                                      (dict(q_w=-1.0), "q_w"), (dict(sides="leaky"), "sides"),
                                      (dict(transfer="swap"), "transfer")])
def test_bad_settings_name_the_field(kw, field):
    args = dict(E_w=240.0, k1=200.0, k2=2.0)
    args.update(kw)
    with pytest.raises(ValueError, match=field):
        WaterSettings(**args)


def test_pressure_eq32():
    assert pressure(2.0, 1.0, 240.0) == 120.0
    assert pressure(1.0, 1.0, 240.0) == 0.0


def test_smoothing_eq46_is_a_running_average_of_used_flows():
    xz, r, net = _two_pores()
    m = pg.measure(net, xz, r)
    s = WaterSettings(E_w=1000.0, k1=50.0, k2=0.5, smoothing=True)
    w = PoreWater(net, m.void_area, s, W=m.void_area * np.array([1.1, 0.95]))
    q1 = w.advance(1e-3, m.void_area, m.link_contact).throat_q.copy()  # first step: nothing to average
    q2_new = w.flows(m.void_area, m.link_contact).throat_q
    q2 = w.advance(1e-3, m.void_area, m.link_contact).throat_q
    np.testing.assert_allclose(q2, 0.5 * (q1 + q2_new), rtol=1e-14)
    assert w.balance_error() < 1e-14


# -- analytic cases --------------------------------------------------------------------------------
def test_drained_side_drains_exponentially_with_k3():
    """Two equal pores against a drained side wall (every vertex a side-wall disc: no free surface),
    both at the same excess W - A: no throat flow, and each loses q = k3 W U / E_w = k3 (W - A), so
    one explicit step of h multiplies W - A by exactly (1 - k3 h). Undrained: nothing leaves."""
    xz, r, net = _two_pores()
    assert net.pore_touches["left"].all() and not net.pore_surface.any()
    m = pg.measure(net, xz, r)
    A = m.void_area
    np.testing.assert_allclose(A[0], A[1], rtol=1e-12)
    k1, k3, h, n = 50.0, 7.0, 1e-3, 40
    W0 = A * 1.05
    w = PoreWater(net, A, WaterSettings(E_w=1000.0, k1=k1, k2=0.5, k3=k3, sides="drained"), W=W0)
    for _ in range(n):
        w.advance(h, A, m.link_contact)
    np.testing.assert_allclose(w.W - A, (W0 - A) * (1 - k3 * h) ** n, rtol=1e-10)
    assert w.balance.side_outflow == pytest.approx(np.sum(W0 - w.W), rel=1e-12)
    assert w.balance.surface_outflow == 0 and w.balance_error() < 1e-13
    shut = PoreWater(net, A, WaterSettings(E_w=1000.0, k1=k1, k2=0.5, k3=k3, sides="undrained"), W=W0)
    for _ in range(n):
        shut.advance(h, A, m.link_contact)
    np.testing.assert_array_equal(shut.W, W0)


def test_eq45_46_running_averages_with_changing_areas():
    """Smoothing on, the void areas change every step: the area used is [A]_t = ([A]_{t-dt} + A'_t)/2
    from the build-time area on, and the throat flow used is [q]_t = ([q]_{t-dt} + q'_t)/2 with q' of
    eq 39-41 at the area used; W follows eq 42. Written out here for the two pores."""
    xz, r, net = _two_pores()
    m = pg.measure(net, xz, r)
    A0 = m.void_area.copy()
    s = WaterSettings(E_w=1000.0, k1=50.0, k2=0.5, smoothing=True)
    W = A0 * np.array([1.1, 0.95])
    w = PoreWater(net, A0, s, W=W)
    a, b = net.throat_conns[0]
    k = s.k1 if not m.link_contact[net.throat_link[0]] else s.k2
    A_used, q_used, h = A0.copy(), None, 1e-3
    for step in range(6):
        A_new = A0 * (1 + 0.2 * np.array([np.sin(step + 1.0), np.cos(2.0 * step)]))
        A_used = (A_used + A_new) / 2                                          # eq 45
        U = s.E_w * (W - A_used) / W                                          # eq 32
        q_new = k * W[a] * W[b] / (A_used[a] + A_used[b]) * (U[a] - U[b]) / s.E_w  # eq 39-41
        q_used = q_new if q_used is None else (q_used + q_new) / 2            # eq 46
        W = W + np.where(np.arange(2) == a, -q_used, q_used) * h               # eq 42
        w.advance(h, A_new, m.link_contact)
        np.testing.assert_allclose(w.W, W, rtol=1e-13)
    np.testing.assert_allclose(w.A_prev, A_used, rtol=1e-14)


def test_rule_c_for_a_surface_pore():
    """§3.4(2)(c): "その間隙と境界をともにするまわりのすべての図形の水圧の平均値" - the mean over the
    surrounding figures (pores) sharing a boundary. The outside is not a figure: a surface pore
    without (a) or (b) gets the plain mean of its neighbouring pores, as an inner pore does
    (docs/READINGS.md D2), not sum / (n + 1) with the outside at U = 0."""
    xz, r, net = _random_network(n=100)
    n = net.n_pores
    U_old = np.linspace(10.0, 30.0, n)
    i, j = net.throat_conns.T
    for p in (int(np.flatnonzero(net.pore_surface)[0]), int(np.flatnonzero(~net.pore_surface)[0])):
        valid = np.ones(n, bool)
        valid[p] = False
        U, rule = pressures_by_rule(net, U_old, valid, net)
        counts = rule_counts(rule)
        assert counts["c"] == 1 and counts["a"] == n - 1
        nb = np.unique(np.concatenate([j[i == p], i[j == p]]))
        assert len(nb) >= 1
        np.testing.assert_allclose(U[p], U_old[nb].mean(), rtol=1e-14)
        assert U[p] > U_old.min()      # all neighbours > 0: an outside at U = 0 would pull it lower


def test_remesh_recomputes_water_from_eq32_and_books_the_change():
    """After a rebuild W = A_new E_w / (E_w - U) with the inherited U (§3.4(2)); the change of total
    water is booked in the budget (balance error stays at round-off); the eq 45-46 running averages
    restart from the new areas."""
    xz, r, one = _two_pores(diagonal_linked=False)
    _, _, two = _two_pores(diagonal_linked=True)
    A1 = pg.measure(one, xz, r).void_area
    m2 = pg.measure(two, xz, r)
    s = WaterSettings(E_w=1000.0, k1=50.0, k2=0.5, smoothing=True, transfer="paper")
    w = PoreWater(one, A1, s, W=A1 * 1.2)
    w.advance(1e-3, A1 * 0.9, np.zeros(len(one.links), bool))
    U = w.pressure(A1)
    counts = w.remesh(two, m2.void_area, A1)
    assert counts == {"a": 0, "b": 2, "c": 0, "d": 0} and w.remesh_counts == counts and w.net is two
    np.testing.assert_allclose(w.W, m2.void_area * s.E_w / (s.E_w - U[0]), rtol=1e-14)
    np.testing.assert_allclose(w.pressure(m2.void_area), U[0], rtol=1e-12)
    assert w.balance.remesh_change == pytest.approx(w.W.sum() - A1.sum() * 1.2, rel=1e-12)
    assert w.balance_error() < 1e-14
    np.testing.assert_array_equal(w.A_prev, m2.void_area)
    assert w.q_prev is None


def test_split_and_merge_need_only_containment_one_way():
    """Rule (b): a new pore inherits from every valid old pore whose vertex set contains it (a
    split) or that it contains (a merge); a pinched old pore passes nothing on (then (d))."""
    xz, r, one = _two_pores(diagonal_linked=False)
    _, _, two = _two_pores(diagonal_linked=True)
    U, rule = pressures_by_rule(one, np.array([40.0]), np.array([False]), two)
    counts = rule_counts(rule)
    assert counts["d"] == 2 and np.all(U == 0)
    U, rule = pressures_by_rule(two, np.array([10.0, 30.0]), np.array([True, False]), one)
    counts = rule_counts(rule)
    assert counts["b"] == 1 and U[0] == 10.0


def test_stability_limit_is_the_gershgorin_bound_with_boundaries():
    """darcy_limit = 2 / max_i (2 sum_j g_ij + g_b,i) / c_i with g_ij = k A_ij / E_w, the boundary
    conductance g_b = (k1 [surface] + k3 [drained side]) W / E_w and c = W^2 / (E_w A), written out
    here on a network with throats, a free surface and drained sides; a step exactly at the limit
    is allowed."""
    rng = np.random.default_rng(8)
    xz, r = random_discs(150, rng)
    walls = np.where(xz[:, 0] < xz[:, 0].min() + 1.0, pg.WALL_LEFT, 0)
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean(), walls=walls)
    m = pg.measure(net, xz, r)
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=50.0, sides="drained")
    W = m.void_area * (1 + 0.3 * rng.random(net.n_pores))
    w = PoreWater(net, m.void_area, s, W=W)
    A = m.void_area
    i, j = net.throat_conns.T
    k = np.where(m.link_contact[net.throat_link], s.k2, s.k1)
    g = k * W[i] * W[j] / (A[i] + A[j]) / s.E_w
    gsum = np.zeros(net.n_pores)
    np.add.at(gsum, i, g)
    np.add.at(gsum, j, g)
    side = net.pore_touches["left"] | net.pore_touches["right"]
    assert net.pore_surface.any() and side.any()
    g_b = (s.k1 * net.pore_surface + s.k3 * side) * W / s.E_w
    expected = 2 / np.max((2 * gsum + g_b) * s.E_w * A / W**2)
    limit = w.darcy_limit(A, m.link_contact)
    assert limit == pytest.approx(expected, rel=1e-12)
    w.advance(limit, A, m.link_contact)       # at the limit: allowed
    with pytest.raises(ValueError, match="dt"):
        w.advance(0.0, A, m.link_contact)


def test_a_step_that_would_empty_a_pore_is_refused():
    """At its stability limit 2 W / (k1 A) a surface pore at W = 3 A would overshoot to
    W = 3A - k1 (W - A) h = -9 A: the step is refused naming the pore, the water is unchanged."""
    xz = np.array([[0.0, 0.0], [3.0, 0.0], [1.5, 2.6]])
    r = np.ones(3)
    net = pg.build_pores(xz, r, l_m=2.0)
    assert net.n_pores == 1 and net.pore_surface[0]
    A = pg.measure(net, xz, r).void_area
    w = PoreWater(net, A, WaterSettings(E_w=240.0, k1=200.0, k2=2.0), W=3 * A)
    h = w.darcy_limit(A, np.zeros(3, bool))
    assert h == pytest.approx(6 / 200.0, rel=1e-12)
    with pytest.raises(DarcyStabilityError, match="water area of pore 0 fell to -"):
        w.advance(h, A, np.zeros(3, bool))
    np.testing.assert_array_equal(w.W, 3 * A)


def test_balance_error_is_relative_to_the_initial_water():
    xz, r, net = _two_pores()
    A = pg.measure(net, xz, r).void_area
    w = PoreWater(net, A, WaterSettings(E_w=1000.0, k1=50.0, k2=0.5))
    w.W = w.W + np.array([3e-3 * A.sum(), 0.0])    # water appearing from nowhere
    assert w.balance_error() == pytest.approx(3e-3, rel=1e-9)


def test_rule_c_rounds_and_a_single_neighbour():
    """Rule (c) in rounds: of two adjacent pores without (a)/(b), the one next to assigned pores
    is set first, the other from it in the next round; a pore with a single assigned neighbour
    (and no free surface) takes its value."""
    xz, r, net = _random_network(n=100)
    n = net.n_pores
    U_old = np.linspace(10.0, 30.0, n)
    inner = ~net.pore_surface
    conns = np.unique(np.sort(net.throat_conns, axis=1), axis=0)
    p, q = next((a, b) for a, b in conns if inner[a] and inner[b])
    valid = np.ones(n, bool)
    valid[[p, q]] = False
    U, rule = pressures_by_rule(net, U_old, valid, net)
    counts = rule_counts(rule)
    assert counts["c"] == 2

    def nbs(x):
        return np.unique(np.concatenate([conns[conns[:, 0] == x, 1], conns[conns[:, 1] == x, 0]]))
    for a, b in ((p, q), (q, p)):
        others = [x for x in nbs(a) if x != b]
        if others:   # set in the first round from its assigned neighbours only
            np.testing.assert_allclose(U[a], U_old[others].mean(), rtol=1e-14)
        else:        # its only neighbour is the other one: set in the second round from it
            np.testing.assert_allclose(U[a], U[b], rtol=1e-14)
    one = [x for x in range(n) if inner[x] and len(nbs(x)) == 1]
    if one:
        valid = np.ones(n, bool)
        valid[one[0]] = False
        U, _ = pressures_by_rule(net, U_old, valid, net)
        assert U[one[0]] == U_old[nbs(one[0])[0]]


def test_two_rebuilds_add_up_in_the_budget():
    xz, r, one = _two_pores(diagonal_linked=False)
    _, _, two = _two_pores(diagonal_linked=True)
    A1, A2 = pg.measure(one, xz, r).void_area, pg.measure(two, xz, r).void_area
    w = PoreWater(one, A1, WaterSettings(E_w=1000.0, k1=50.0, k2=0.5, transfer="paper"), W=A1 * 1.2)
    w.remesh(two, A2, A1)
    w.remesh(one, A1, A2)
    assert w.balance.remesh_change == pytest.approx(w.W.sum() - 1.2 * A1.sum(), rel=1e-12)
    assert w.balance_error() < 1e-14


def _surface_pore_at_a_side_wall():
    """One triangular pore of a left-wall disc and two particles: on the free surface (its
    particle-particle and wall-particle edges face the outside) and touching a side wall."""
    xz = np.array([[0.0, 0.0], [3.0, 0.0], [1.5, 2.6]])
    net = pg.build_pores(xz, np.ones(3), l_m=2.0, walls=np.array([pg.WALL_LEFT, 0, 0]))
    assert net.n_pores == 1 and net.pore_surface[0] and net.pore_touches["left"][0]
    return net


def test_stability_limit_of_a_pore_drained_to_both_surface_and_side():
    """Both boundary conductances add: lambda = (k1 + k3) W / E_w / c with c = W^2 / (E_w A), so
    the limit is 2 W / ((k1 + k3) A); undrained it is 2 W / (k1 A)."""
    net = _surface_pore_at_a_side_wall()
    A, W = np.array([0.25]), np.array([0.5])
    drained = PoreWater(net, A, WaterSettings(E_w=1.0, k1=4.0, k2=1.0, k3=3.0, sides="drained"), W=W)
    assert drained.darcy_limit(A, np.zeros(3, bool)) == pytest.approx(2 * 0.5 / (7.0 * 0.25), rel=1e-14)
    shut = PoreWater(net, A, WaterSettings(E_w=1.0, k1=4.0, k2=1.0, k3=3.0), W=W)
    assert shut.darcy_limit(A, np.zeros(3, bool)) == pytest.approx(2 * 0.5 / (4.0 * 0.25), rel=1e-14)


def test_a_step_that_would_empty_a_pore_exactly_is_refused():
    """W = 0 has no pressure (eq 32 divides by W): a surface pore with W = 0.5, A = 0.25, E_w = 1,
    k1 = 4 loses q = k1 (W - A) = 1 m^2/s, and a step of h = 0.5 s (half its stability limit)
    would leave exactly W = 0: refused, the water unchanged."""
    net = _surface_pore_at_a_side_wall()
    A = np.array([0.25])
    w = PoreWater(net, A, WaterSettings(E_w=1.0, k1=4.0, k2=1.0), W=[0.5])
    assert w.darcy_limit(A, np.zeros(3, bool)) == 1.0
    with pytest.raises(DarcyStabilityError, match="fell to 0.000e"):
        w.advance(0.5, A, np.zeros(3, bool))
    np.testing.assert_array_equal(w.W, [0.5])


def test_the_refused_step_names_the_pore_that_would_empty():
    """Of two pores against a drained side wall, the second (W = 3 A) would overshoot below zero at
    the stability limit while the first (U = 0) stays full: the error names pore 1."""
    xz, r, net = _two_pores()
    A = pg.measure(net, xz, r).void_area
    w = PoreWater(net, A, WaterSettings(E_w=1000.0, k1=1e-3, k2=1e-3, k3=50.0, sides="drained"), W=A * [1.0, 3.0])
    h = w.darcy_limit(A, np.zeros(len(net.links), bool))
    with pytest.raises(DarcyStabilityError, match="water area of pore 1 fell to -"):
        w.advance(h, A, np.zeros(len(net.links), bool))


def test_balance_error_is_relative_for_pores_of_square_millimetres():
    """The balance error is relative to the initial water also when that is far below 1 m^2 (every
    real packing): 3e-9 m^2 appearing in 1e-6 m^2 of water is an error of 3e-3."""
    net = _surface_pore_at_a_side_wall()
    w = PoreWater(net, np.array([1e-6]), WaterSettings(E_w=1.0, k1=4.0, k2=1.0))
    w.W = w.W + 3e-9
    assert w.balance_error() == pytest.approx(3e-3, rel=1e-9)


def test_rule_codes_per_pore_are_small_integers():
    """pressures_by_rule gives each new pore the code 1-4 of the rule (a)-(d) that set it, as
    integers (postproc.vtk and the snapshots take integer codes); here rule (c) for one pore whose
    old pressure is unusable, (a) for the rest."""
    from engines.model.pore_water import pressures_by_rule
    xz, r, net = _random_network(n=100)
    valid = np.ones(net.n_pores, bool)
    p = int(np.flatnonzero(~net.pore_surface)[0])
    valid[p] = False
    _, rule = pressures_by_rule(net, np.linspace(1.0, 2.0, net.n_pores), valid, net)
    assert rule.dtype.kind == "i"
    expected = np.ones(net.n_pores, int)
    expected[p] = 3
    np.testing.assert_array_equal(rule, expected)


def test_rule_c_averages_neighbours_on_both_sides_of_the_index_order():
    """Rule (c) takes the mean over all assigned neighbours, those listed before it and after it."""
    from engines.model.pore_water import pressures_by_rule
    xz, r, net = _random_network(n=100)
    i, j = net.throat_conns.T
    nbs = {p: np.unique(np.concatenate([j[i == p], i[j == p]])) for p in range(net.n_pores)}
    p = next(p for p in range(net.n_pores) if nbs[p].min() < p < nbs[p].max())
    U_old = np.linspace(1.0, 2.0, net.n_pores) ** 2
    valid = np.ones(net.n_pores, bool)
    valid[p] = False
    U, rule = pressures_by_rule(net, U_old, valid, net)
    assert rule[p] == 3 and U[p] == pytest.approx(U_old[nbs[p]].mean(), rel=1e-14)


def test_pores_without_throats_fall_to_rule_d():
    """Two separate triangles (two pores, no throat between them) without usable old pressures:
    rule (c) has no neighbour to average, so both get U = 0 by rule (d)."""
    from engines.model.pore_water import pressures_by_rule
    tri = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, np.sqrt(3)]])
    xz = np.vstack([tri, tri + 10.0])
    net = pg.build_pores(xz, np.ones(6))
    assert net.n_pores == 2 and len(net.throat_conns) == 0
    U, rule = pressures_by_rule(net, np.array([5.0, 7.0]), np.zeros(2, bool), net)
    np.testing.assert_array_equal(U, [0.0, 0.0])
    np.testing.assert_array_equal(rule, [4, 4])


def test_initial_water_is_checked_and_the_state_starts_clean():
    """W must match the pores and be positive (W = 0 has no pressure, eq 32); a new state has rule
    code 0 (built with the network) for every pore and no re-meshing counts yet."""
    net = _surface_pore_at_a_side_wall()
    A = np.array([0.25])
    for W in ([0.5, 0.5], [0.0], [-0.1]):
        with pytest.raises(ValueError, match="positive water areas"):
            PoreWater(net, A, WaterSettings(E_w=1.0, k1=4.0, k2=1.0), W=W)
    w = PoreWater(net, A, WaterSettings(E_w=1.0, k1=4.0, k2=1.0), W=[1])      # integers are areas too
    assert w.W.dtype == float and w.remesh_counts == {}
    assert w.rule.dtype.kind == "i" and w.rule.shape == (1,) and w.rule[0] == 0


def test_buoyancy_is_the_weight_of_the_displaced_water():
    """Eq 34b: rho_w pi r^2 g per unit thickness [N/m], for one radius or an array of them."""
    assert buoyancy(2e-3, 1000.0, 9.81) == pytest.approx(1000.0 * np.pi * 4e-6 * 9.81, rel=1e-15)
    np.testing.assert_allclose(buoyancy([1e-3, 3e-3], 1000.0, 9.81), 1000.0 * np.pi * np.array([1e-6, 9e-6]) * 9.81,
                               rtol=1e-15)


def test_a_restored_network_gets_its_inflow_weights_again():
    """checkpoint_restored: the inflow weights follow the network a checkpoint set (here one whose
    pore sits on the bottom row, in place of a network without inflow)."""
    xz, r = np.array([[0.0, 0.0], [3.0, 0.0], [1.5, 2.6]]), np.ones(3)
    walls = np.array([pg.WALL_BOTTOM, pg.WALL_BOTTOM, 0])
    fed = pg.build_pores(xz, r, l_m=2.0, walls=walls)
    A = pg.measure(fed, xz, r).void_area
    w = PoreWater(pg.build_pores(xz, r, l_m=2.0), A, WaterSettings(q_w=1e-4), walls=np.zeros(3, np.int64))
    assert w.inflow[1].tolist() == [0.0]
    w.net, w.walls = fed, walls
    w.checkpoint_restored()
    assert w.inflow[0] == 1e-4 and w.inflow[1].tolist() == [1.0]
