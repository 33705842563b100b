"""The stability limits (engines.model.limits) on analytic cases: eq 52, the ties, the water
stiffness, the Darcy bound (eigsh and Gershgorin) and the sub-step count."""
import math
import re

import numpy as np
import pytest

from engines.model import limits as lim
from engines.model import pores as pg
from engines.model.pore_water import PoreWater, WaterSettings
from engines.model.side_walls import SideWallTies
from packing.layouts import random_discs


def _two_pores():
    """Rhombus of four wall discs: two equal triangular pores sharing a gap link."""
    xz = np.array([[-1.2, 0.0], [1.2, 0.0], [0.0, 1.0], [0.0, -1.0]])
    r = np.full(4, 0.5)
    net = pg.build_pores(xz, r, l_m=1.5, walls=np.full(4, pg.WALL_LEFT))
    return xz, r, net


# -- the limits -----------------------------------------------------------------------------------
def test_darcy_limit_of_two_equal_pores_is_two_over_k():
    """Two equal pores at W = A: G = g [[1, -1], [-1, 1]], c equal, lambda_max = 2 g / c = k, so
    2 / lambda_max = 2 / k exactly (the Gershgorin bound is exact here too)."""
    xz, r, net = _two_pores()
    m = pg.measure(net, xz, r)
    w = PoreWater(net, m.void_area, WaterSettings(E_w=1000.0, k1=50.0, k2=0.5))
    assert lim.darcy_eigen_limit(w, m.void_area, m.link_contact) == pytest.approx(2 / 50.0, rel=1e-12)
    assert w.darcy_limit(m.void_area, m.link_contact) == pytest.approx(2 / 50.0, rel=1e-12)


def test_darcy_limit_eigsh_matches_dense_and_bounds_gershgorin():
    rng = np.random.default_rng(3)
    xz, r = random_discs(300, rng)
    walls = np.where(xz[:, 1] < xz[:, 1].min() + 1.0, pg.WALL_BOTTOM, 0)
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean(), walls=walls)
    m = pg.measure(net, xz, r)
    w = PoreWater(net, m.void_area, WaterSettings(E_w=240.0, k1=200.0, k2=2.0), W=m.void_area * (1 + 0.2 * rng.random(net.n_pores)))
    S, open_ = lim.exchange_matrix(w, m.void_area, m.link_contact)
    assert S.shape[0] >= 50  # the eigsh path
    dense = np.linalg.eigvalsh(S.toarray())
    assert dense[0] > -1e-9 * dense[-1]  # positive semi-definite
    assert lim.lambda_max(S) == pytest.approx(dense[-1], rel=1e-7)
    exact = lim.darcy_eigen_limit(w, m.void_area, m.link_contact)
    gersh = w.darcy_limit(m.void_area, m.link_contact)
    assert gersh <= exact * (1 + 1e-12) and gersh > 0.3 * exact
    # forward Euler on the linearised exchange: just below 2 / lambda_max decays, just above grows
    lam = dense[-1]
    for h, grows in ((0.99 * 2 / lam, False), (1.01 * 2 / lam, True)):
        assert (abs(1 - h * lam) > 1) == grows


def test_water_stiffness_by_hand_on_two_pores():
    xz, r, net = _two_pores()
    A = pg.measure(net, xz, r).void_area
    k = lim.water_stiffness(net, A, r, 240.0)
    # discs 0 and 1 (the short diagonal's ends... the rhombus' far corners) bound one pore each or both
    expected = np.zeros(4)
    for p in range(net.n_pores):
        expected[net.vertices_of(p)] += 240.0 * (2 * 0.5) ** 2 / A[p]
    np.testing.assert_allclose(k, expected, rtol=1e-12)
    assert sorted(np.round(k / (240.0 / A[0]), 12).tolist()) == [1.0, 1.0, 2.0, 2.0]  # equal pores: 1 or 2 each
    mass = np.array([1.0, 2.0, 3.0, 4.0])
    mobile = np.array([True, True, False, False])
    limit = lim.water_stiffness_limit(net, A, r, 240.0, mass, mobile)
    assert limit == pytest.approx(min(2 * np.sqrt(mass[mobile] / k[mobile])), rel=1e-12)


def test_critical_time_step_is_eq52_over_the_lightest_disc():
    assert lim.critical_time_step(np.array([4.0, 1.0]), 1e6) == pytest.approx(2 * math.sqrt(1.0 / 1e6))


def test_check_contact_refuses_just_above_dt_safety_times_eq52():
    mass, kn, safety = np.array([4.0, 1.0]), 1e6, 0.5
    limit = safety * 2 * math.sqrt(1.0 / kn)
    lim.check_contact(0.999 * limit, safety, mass, kn)
    with pytest.raises(ValueError, match=r"\[numerics\] dt = .* eq 52 .*m_min = 1 kg/m"):
        lim.check_contact(1.001 * limit, safety, mass, kn)
    lim.check_contact(1.0, safety, np.zeros(0), kn)  # no mobile disc: nothing to bound


def _column(n=6, ks=2e5):
    """One column of n side-wall discs over a bottom wall of three discs."""
    xz = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]] + [[0.0, 1.0 + k] for k in range(n)])
    group = np.array([pg.WALL_BOTTOM] * 3 + [pg.WALL_LEFT] * n)
    return SideWallTies(xz, group, ks, 0.0)


def test_tie_limit_bounds_the_highest_frequency_of_the_column():
    """sqrt(m_min / k's) <= 2 / w_max of the tie chain (stiffness matrix K, masses M), so the
    explicit update is stable below it; without springs it is inf."""
    ties = _column()
    rng = np.random.default_rng(1)
    mass = 1.0 + rng.random(ties.n)
    mov = np.flatnonzero(ties.moving)
    assert lim.tie_limit(ties, mass) == pytest.approx(math.sqrt(mass[mov].min() / ties.ks), rel=1e-15)
    K = np.zeros((ties.n, ties.n))
    for a, b in zip(ties.lower, ties.upper):
        K[np.ix_([a, b], [a, b])] += ties.ks * np.array([[1, -1], [-1, 1]])
    Km = K[np.ix_(mov, mov)] / np.sqrt(np.outer(mass[mov], mass[mov]))
    w_max = math.sqrt(np.linalg.eigvalsh(Km)[-1])
    assert lim.tie_limit(ties, mass) <= 2 / w_max
    assert lim.tie_limit(_column(ks=0.0), mass) == math.inf and lim.tie_limit(None, mass) == math.inf
    with pytest.raises(ValueError, match="side-wall ties .*ks_wall"):
        lim.check_ties(1.001 * lim.tie_limit(ties, mass), ties, mass)
    lim.check_ties(1.0, None, mass)


def test_sub_steps_are_the_ceiling_of_the_step_over_the_limit():
    assert lim.substep_count(1e-3, 1e-3) == 1 and lim.substep_count(0.5e-3, 1e-3) == 1
    assert lim.substep_count(2.5e-3, 1e-3) == 3 and lim.substep_count(1.0, math.inf) == 1
    assert lim.substeps(2.5e-3, 1e-3, True, 240.0) == 3
    with pytest.raises(lim.DarcyStabilityError, match=r"Darcy limit .*substep=True.*\[water\] substep = true"):
        lim.substeps(2.5e-3, 1e-3, False, 240.0)
    assert lim.substeps(0.9e-3, 1e-3, False, 240.0) == 1
    assert lim.gershgorin_limit(0.0) == math.inf and lim.gershgorin_limit(4.0) == 0.5
    assert lim.substep_cost(1) == 1 and lim.substep_cost(5) == 1 + 4 * lim.SUBSTEP_COST


def test_water_stiffness_weighs_each_disc_by_its_width_squared():
    """k_w = E_w sum_p (2 r)^2 / A_p with unequal radii (2 r != 1, so the power of the width
    shows), for an E_w small enough that k_w < 1 N/m; no open pore: no stiffness, no limit."""
    xz, r0, net = _two_pores()
    A = pg.measure(net, xz, r0).void_area
    r = np.array([0.3, 0.45, 0.6, 0.8])
    E_w = 1e-3
    k = lim.water_stiffness(net, A, r, E_w)
    for p in range(net.n_pores):
        v = net.vertices_of(p)
        assert np.all(k[v] >= E_w * 4 * r[v] ** 2 / A[p] * (1 - 1e-12))
    assert k.sum() == pytest.approx(sum(E_w * np.sum(4 * r[net.vertices_of(p)] ** 2) / A[p]
                                        for p in range(net.n_pores)), rel=1e-12)
    assert k.max() < 1
    mass, mobile = np.full(4, 2.0), np.ones(4, bool)
    assert lim.water_stiffness_limit(net, A, r, E_w, mass, mobile) == pytest.approx(
        2 * np.sqrt(2.0 / k.max()), rel=1e-12)
    closed = np.zeros_like(A)  # every pore pinched shut: no stiffness at all
    assert lim.water_stiffness_limit(net, closed, r, E_w, mass, mobile) == math.inf


def test_check_water_stiffness_refuses_just_above_its_limit():
    lim.check_water_stiffness(0.999e-4, 1e-4, 240.0)
    with pytest.raises(ValueError, match=r"water-stiffness limit .*E_w = 240 N/m"):
        lim.check_water_stiffness(1.001e-4, 1e-4, 240.0)


def test_the_refusal_states_its_limit():
    mass, kn = np.array([3.0]), 2e6
    limit = 2 * math.sqrt(3.0 / kn)
    with pytest.raises(ValueError) as err:
        lim.check_contact(2 * limit, 1.0, mass, kn)
    said = float(re.search(r"limit (\S+) s", str(err.value)).group(1))
    assert said == pytest.approx(limit, rel=5e-3)  # printed to 3 digits


def test_darcy_eigen_limit_without_exchange_and_for_a_slow_one():
    """No permeability: no exchange, no limit (inf). k1 = 0.01 1/s: lambda = k < 1, 2 / k."""
    xz, r, net = _two_pores()
    m = pg.measure(net, xz, r)
    dry = PoreWater(net, m.void_area, WaterSettings(E_w=1000.0, k1=0.0, k2=0.0))
    assert lim.darcy_eigen_limit(dry, m.void_area, m.link_contact) == math.inf
    slow = PoreWater(net, m.void_area, WaterSettings(E_w=1000.0, k1=0.01, k2=0.0))
    assert lim.darcy_eigen_limit(slow, m.void_area, m.link_contact) == pytest.approx(2 / 0.01, rel=1e-12)


def test_lambda_max_is_the_largest_eigenvalue_on_the_dense_path():
    import scipy.sparse as sp
    d = np.array([3.0, 1.0, 7.0, 2.0, 5.0])  # 3 <= n < 50: the dense path; the largest is not last
    assert lim.lambda_max(sp.diags(d).tocsr()) == 7.0
    assert lim.lambda_max(sp.csr_matrix((0, 0))) == 0.0


def test_a_tie_of_one_newton_per_metre_still_bounds_the_step():
    ties = _column(ks=1.0)
    mass = np.full(ties.n, 4.0)
    assert lim.tie_limit(ties, mass) == pytest.approx(2.0, rel=1e-15)


def test_the_accuracy_watch_warns_once_then_stops_unless_accepted():
    """max |dA| / A between two water steps on the same pores: quiet below WATCH_WARN, one warning
    above it (or at U < -E_w), an AccuracyError above WATCH_STOP unless accepted; a rebuild
    starts a new comparison."""
    said = []
    w = lim.AccuracyWatch(log=said.append)
    A, U = np.array([1.0, 2.0, 1e-9]), np.zeros(3)
    w(A, U, 240.0, 1e-6, 1e-4)
    w(A * [1 + 0.5 * lim.WATCH_WARN, 1, 50], U, 240.0, 1e-6, 1e-4)  # the pinched pore does not count
    assert said == [] and w.worst == pytest.approx(0.5 * lim.WATCH_WARN)
    w(A * [1 + 2 * lim.WATCH_WARN, 1, 1], U, 240.0, 1e-6, 1e-4)
    w(A * [1 + 0.1 * lim.WATCH_WARN, 1, 1], [-300.0, 0, 0], 240.0, 1e-6, 1e-4)
    assert len(said) == 1 and "void area changed by" in said[0] and w.lowest == pytest.approx(-1.25)
    w.rebuilt()
    w(A * 10, U, 240.0, 1e-6, 1e-4)  # new pores: nothing to compare
    with pytest.raises(lim.AccuracyError, match="shorten the water step .* accept_inaccurate=True"):
        w(A * 10 * (1 + 2 * lim.WATCH_STOP), U, 240.0, 1e-6, 1e-4)
    accepted = lim.AccuracyWatch(accept=True, log=said.append)
    accepted(A, U, 240.0, 1e-6, 1e-4)
    accepted(A * (1 + 2 * lim.WATCH_STOP), U, 240.0, 1e-6, 1e-4)
    assert len(said) == 2


def test_the_water_step_above_the_stiffness_limit_names_the_largest_water_interval():
    lim.check_water_stiffness(1e-6, 1e-5, 240.0, 10)  # at the limit
    with pytest.raises(lim.WaterStiffnessError,
                       match=r"water_interval 11 x .*set \[numerics\] water_interval <= 10 \(5 leaves a margin"):
        lim.check_water_stiffness(1e-6, 1e-5, 240.0, 11)
    with pytest.raises(lim.WaterStiffnessError, match=r"reduce O.dt to <= 1e-05 s with water_interval = 1, or reduce "
                                                      r"WaterSettings E_w$"):
        lim.check_water_stiffness(2e-5, 1e-5, 240.0, 1, lim.ENGINE_NAMES)
