"""Water at re-meshing: the paper's rule against the conserving transfer; and the
drained side-wall flux against the analytic solution of eq 32 with the k3 outflow."""
import numpy as np
import pytest

from engines.model import pores as pg
from engines.model.pores import overlaps, triangulation
from engines.model.pore_water import PoreWater, WaterSettings, pressure, water_from_pressure
from packing.layouts import random_discs
from packing.psd import sample_diameters
from tests.layouts import random_sequential

E_W = 2400.0


def _closed_box(seed, k=13, rw=0.45e-3):
    """Particles inside a closed ring of touching wall discs around [0, L]^2, L = 2 k rw, none
    overlapping the ring: the pores always fill the ring, so old and new networks cover the same
    region (no free surface)."""
    rng = np.random.default_rng(seed)
    L = 2 * k * rw
    d = sample_diameters(140, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, rng)
    xz, r = random_sequential(d, L - 2e-3, L - 2e-3, rng)
    xz = xz + 1e-3  # the largest radius is 1 mm
    s = (np.arange(k + 2) - 0.5) * 2 * rw
    side = rw + np.arange(k) * 2 * rw
    ring = np.vstack([np.column_stack([s, np.full(k + 2, -rw)]), np.column_stack([s, np.full(k + 2, L + rw)]),
                      np.column_stack([np.full(k, -rw), side]), np.column_stack([np.full(k, L + rw), side])])
    walls = np.concatenate([np.zeros(len(r), int), np.full(len(ring), pg.WALL_LEFT)])
    return np.vstack([xz, ring]), np.concatenate([r, np.full(len(ring), rw)]), walls, rng


def _remesh(transfer, seed=0, W_of=None):
    xz, r, walls, rng = _closed_box(seed)
    old = pg.build_pores(xz, r, eps_m=0.0, l_m=1.3e-4, walls=walls)
    xz2 = xz.copy()
    inner = walls == 0
    xz2[inner] += 1e-5 * rng.standard_normal((inner.sum(), 2))
    new = pg.build_pores(xz2, r, eps_m=2e-4, l_m=3.5e-4, walls=walls)
    A_old = pg.measure(old, xz2, r).void_area
    A_new = pg.measure(new, xz2, r).void_area
    W0 = W_of(A_old) if W_of else A_old * (1 + 0.1 * rng.random(old.n_pores))
    w = PoreWater(old, A_old, WaterSettings(E_w=E_W, k1=1e3, k2=1e2, transfer=transfer), W=W0)
    before = w.total_water()
    counts = w.remesh(new, A_new, A_old, xz=xz2)
    return w, before, counts, old, new, A_new


def test_conserving_transfer_conserves_water_to_round_off():
    w, before, counts, old, new, _ = _remesh("conserving")
    assert new.n_pores > 2 * old.n_pores  # merges and splits everywhere
    assert counts["unmatched"] == 0 and counts["a"] < new.n_pores  # many pores changed
    assert abs(w.total_water() - before) < 1e-13 * before
    assert abs(w.balance.remesh_change) < 1e-13 * before
    assert abs(w.balance.remesh_excess_change) < 1e-13 * before and w.balance.remesh_excess_edge == 0
    assert w.balance_error() < 1e-13
    assert np.all(w.W > 0)


def test_paper_rule_creates_or_destroys_water_and_reports_it_exactly():
    w, before, counts, *_ = _remesh("paper")
    change = w.total_water() - before
    assert abs(change) > 1e-6 * before
    assert w.balance.remesh_change == pytest.approx(change, rel=1e-12)
    assert w.balance_error() < 1e-13


def test_remesh_excess_change_is_the_change_without_the_void_change():
    """remesh_excess_change = change of sum(W - A): the total change less the change of the void."""
    seen = []

    def W_of(A):
        seen.append(A.copy())
        return A * (1 + 0.1 * np.random.default_rng(9).random(len(A)))

    w, before, counts, old, new, A_new = _remesh("paper", W_of=W_of)
    void_change = A_new.sum() - seen[0].sum()
    assert abs(w.balance.remesh_excess_change) > 1e-6 * before
    assert w.balance.remesh_excess_edge == 0  # closed box: all of it is the rule's own
    assert w.balance.remesh_excess_change == pytest.approx(w.total_water() - before - void_change, rel=1e-9)


def test_conserving_transfer_keeps_a_uniform_pressure():
    U0 = 300.0
    w, before, counts, old, new, A_new = _remesh("conserving", W_of=lambda A: water_from_pressure(U0, A, E_W))
    np.testing.assert_allclose(w.pressure(A_new), U0, rtol=1e-9)
    assert abs(w.total_water() - before) < 1e-13 * before


def test_unchanged_pores_keep_their_water():
    xz, r, walls, rng = _closed_box(1)
    net = pg.build_pores(xz, r, l_m=3.5e-4, eps_m=2e-4, walls=walls)
    A = pg.measure(net, xz, r).void_area
    w = PoreWater(net, A, WaterSettings(E_w=E_W, k1=1e3, k2=1e2, transfer="conserving"),
                  W=A * (1 + 0.2 * rng.random(net.n_pores)))
    W0 = w.W.copy()
    again = pg.build_pores(xz, r, l_m=3.5e-4, eps_m=2e-4, walls=walls)
    w.remesh(again, pg.measure(again, xz, r).void_area, A, xz=xz)
    np.testing.assert_allclose(w.W, W0, rtol=1e-12)


def test_open_surface_exchange_is_recorded():
    """With a free surface the covered region changes: new pores that overlap no old pore take the
    paper's pressure, the rest is split; the balance still closes exactly."""
    rng = np.random.default_rng(4)
    xz, r = random_discs(300, rng)
    old = pg.build_pores(xz, r, l_m=0.3 * r.mean())
    new = pg.build_pores(xz, r, l_m=0.7 * r.mean())
    A_old, A_new = pg.measure(old, xz, r).void_area, pg.measure(new, xz, r).void_area
    w = PoreWater(old, A_old, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, transfer="conserving"),
                  W=A_old * (1 + 0.1 * rng.random(old.n_pores)))
    before = w.total_water()
    counts = w.remesh(new, A_new, A_old, xz=xz)
    assert counts["unmatched"] > 0
    assert w.balance.remesh_change == pytest.approx(w.total_water() - before, rel=1e-12)
    b = w.balance  # the excess water changes at the edges only
    assert b.remesh_excess_edge != 0 and b.remesh_excess_change == pytest.approx(b.remesh_excess_edge, abs=1e-13 * before)
    assert w.balance_error() < 1e-13 and np.all(w.W > 0)


def test_conserving_needs_positions():
    w, *_ = _remesh("paper")
    w.settings.transfer = "conserving"
    with pytest.raises(ValueError, match="needs the positions"):
        w.remesh(w.net, np.ones(w.net.n_pores), np.ones(w.net.n_pores))


def test_clip_areas_star_of_david():
    """Two concentric equilateral triangles, one turned by 180 degrees: the overlap is the hexagon,
    2/3 of either; identical triangles overlap fully; distant ones not at all."""
    t1 = np.array([[[0.0, 1.0], [-np.sqrt(3) / 2, -0.5], [np.sqrt(3) / 2, -0.5]]])
    t2 = -t1  # also counter-clockwise
    area = 3 * np.sqrt(3) / 4
    np.testing.assert_allclose(overlaps._clip_areas(t1, t2), [2 / 3 * area], rtol=1e-14)
    np.testing.assert_allclose(overlaps._clip_areas(t1, t1), [area], rtol=1e-14)
    assert overlaps._clip_areas(t1, t1 + 10.0)[0] == 0.0


def test_pore_overlaps_partition_the_old_pores():
    xz, r, walls, rng = _closed_box(2)
    old = pg.build_pores(xz, r, l_m=1.3e-4, walls=walls)
    new = pg.build_pores(xz, r, eps_m=2e-4, l_m=3.5e-4, walls=walls)
    p, q, o = pg.pore_overlaps(old, new, xz)
    np.testing.assert_allclose(np.bincount(p, o, old.n_pores), pg.measure(old, xz, r).polygon_area, rtol=1e-10)
    np.testing.assert_allclose(np.bincount(q, o, new.n_pores), pg.measure(new, xz, r).polygon_area, rtol=1e-10)


# -- drained side wall: one pore losing water through k3 ------------------------------------------------
def _drained_pore(k3):
    xz = np.array([[0.0, 0.0], [2.2e-3, 0.0], [1.1e-3, 1.9e-3]])
    r = np.full(3, 0.9e-3)
    net = pg.build_pores(xz, r, l_m=0.5e-3, walls=np.full(3, pg.WALL_LEFT))
    assert net.n_pores == 1 and net.pore_touches["left"][0] and not net.pore_surface[0]
    A = pg.measure(net, xz, r).void_area
    return net, A, WaterSettings(E_w=E_W, k1=1e3, k2=1e2, k3=k3, sides="drained")


def _drain(dt, t_end, k3=1e3, W0_over_A=1.3):
    net, A, s = _drained_pore(k3)
    w = PoreWater(net, A, s, W=A * W0_over_A)
    for _ in range(int(round(t_end / dt))):
        w.advance(dt, A, np.zeros(0, bool))
    return w, A


def test_drained_pore_decays_exponentially():
    """dW/dt = -k3 W U / E_w = -k3 (W - A) (eq 32): W - A = (W0 - A) exp(-k3 t). The explicit step
    gives (1 - k3 dt)^n exactly, first order in dt; the outflow is booked as side outflow."""
    k3, t_end = 1e3, 2e-3
    errors = []
    for dt in (2e-5, 1e-5, 5e-6):
        w, A = _drain(dt, t_end, k3)
        n = int(round(t_end / dt))
        np.testing.assert_allclose(w.W - A, 0.3 * A * (1 - k3 * dt) ** n, rtol=1e-10)
        exact = A * (1 + 0.3 * np.exp(-k3 * t_end))
        errors.append(abs(w.W[0] - exact[0]))
        U_exact = E_W * (1 - A / exact)
        assert abs(w.pressure(A)[0] - U_exact[0]) < 0.02 * U_exact[0]
        assert w.balance.side_outflow == pytest.approx(0.3 * A[0] - (w.W[0] - A[0]), rel=1e-10)
        assert w.balance_error() < 1e-13
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 2.0, rtol=0.02)


def test_undrained_pore_keeps_its_water():
    net, A, s = _drained_pore(1e3)
    s.sides = "undrained"
    w = PoreWater(net, A, s, W=A * 1.3)
    for _ in range(100):
        w.advance(1e-5, A, np.zeros(0, bool))
    np.testing.assert_allclose(w.W, A * 1.3, rtol=1e-15)
    assert pressure(w.W, A, E_W)[0] == pytest.approx(E_W * 0.3 / 1.3)


def test_clip_areas_of_a_batch_with_different_vertex_counts():
    """One call over pairs whose overlaps have 6, 3, 3, 0 and 4 vertices (padded rows of
    different lengths): each area is the analytic one; an empty batch gives no areas."""
    star = np.array([[0.0, 1.0], [-np.sqrt(3) / 2, -0.5], [np.sqrt(3) / 2, -0.5]])
    unit = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    subj = np.array([star, unit, unit, unit, unit])
    clip = np.array([-star, 0.5 * unit + 0.1, unit + [0.5, 0.0], unit + 5.0, np.array([[0.5, -1.0], [0.5, 2.0], [-1.0, 0.5]])])
    # hexagon 2/3 of the triangle; a half-size copy inside; the corner triangle (0.5, 0)-(1, 0)-(0.5, 0.5);
    # nothing; the unit triangle cut by x <= 0.5: a trapezoid of area 0.5 - 0.125
    expected = [2 / 3 * 3 * np.sqrt(3) / 4, 0.125, 0.125, 0.0, 0.375]
    np.testing.assert_allclose(overlaps._clip_areas(subj, clip), expected, rtol=1e-13, atol=1e-15)
    assert overlaps._clip_areas(np.zeros((0, 3, 2)), np.zeros((0, 3, 2))).shape == (0,)


def _tri_area(a, b, c):
    return 0.5 * abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def test_conserving_transfer_across_a_flipped_diagonal():
    """Four discs, two pores split by one diagonal before and by the other after: each old pore
    overlaps both new ones in a triangle cut by the crossing point M of the diagonals
    (pore_overlaps against these areas). Such overlaps have rank one (|ABM| |CDM| = |BCM| |DAM|),
    so the void shares are V = a b^T / sum(a) and X = W - A of each old pore is split in the
    proportions b of the new voids."""
    from engines.model.pore_water import conserving_water
    r = np.ones(4)
    old = pg.build_pores(np.array([[0.0, 0.0], [3.0, 0.0], [3.4, 2.2], [0.0, 2.0]]), r, l_m=2.0)
    new = pg.build_pores(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [-0.4, 2.2]]), r, l_m=2.0)
    assert [1, 3] in old.links.tolist() and [0, 2] in new.links.tolist()
    xz = np.array([[0.0, 0.0], [3.0, 0.0], [3.2, 2.1], [-0.2, 2.1]])      # both triangulations valid here
    A, B, C, D = xz
    t = np.linalg.solve(np.column_stack([C - A, B - D]), B - A)[0]        # A + t (C - A) = M on BD
    M = A + t * (C - A)
    piece = {frozenset(k): _tri_area(*(xz[list(k)]), M) for k in ((0, 1), (1, 2), (2, 3), (3, 0))}
    p, q, o = pg.pore_overlaps(old, new, xz)
    assert len(o) == 4
    for pp, qq, oo in zip(p, q, o):   # the two triangles share two corners (a side); M is the third
        common = frozenset(old.vertices_of(pp).tolist()) & frozenset(new.vertices_of(qq).tolist())
        assert oo == pytest.approx(piece[common], rel=1e-12)
    a, b = np.array([1.0, 3.0]), np.array([2.5, 1.5])                    # void areas (same total)
    W_old = a + np.array([0.5, 0.3])
    W_new, matched = conserving_water(old, W_old, a, new, b, xz)
    assert matched.all()
    np.testing.assert_allclose(W_new, b + (W_old - a).sum() * b / b.sum(), rtol=1e-12)


class _Pores:
    """A stand-in network for conserving_water: only its pore count and a_min are read."""

    def __init__(self, n_pores):
        self.n_pores, self.a_min = n_pores, 0.0


def test_conserving_shares_solve_the_matrix_scaling(monkeypatch):
    """The void shares V = diag(alpha) O diag(beta) of a 2x2 group of overlaps O (given here, not
    of rank one) with rows summing to the old voids a and columns to the new voids b rescaled to
    the same total: V = [[x, a0 - x], [b0 - x, a1 - b0 + x]] with the cross ratio
    V00 V11 / (V01 V10) = O00 O11 / (O01 O10), a quadratic in x. Each old pore's excess water goes
    in the shares V_pq / a_p. An old pore (the last) and a new pore overlapping nothing: the new
    one is unmatched, the old one's excess is not passed on; a 1x1 group takes all its water."""
    from engines.model import pore_water as pw
    O = np.array([[1.0, 2.0], [3.0, 1.5]])
    # old pores 0, 1 (the 2x2 group), 2 (alone with new pore 2), 3 (overlapping nothing)
    p, q = np.array([0, 0, 1, 1, 2]), np.array([0, 1, 0, 1, 2])
    monkeypatch.setattr(pw.pg, "pore_overlaps", lambda old, new, xz: (p, q, np.r_[O.ravel(), 0.7]))
    a = np.array([1.0, 3.0, 2.0, 0.5])
    b = np.array([2.5, 2.5, 1.0, 0.4])                  # the group's new voids total 5, its old ones 4
    X = np.array([0.5, 0.3, 0.2, 0.1])
    W_new, matched = pw.conserving_water(_Pores(4), a + X, a, _Pores(4), b, np.zeros((0, 2)))
    np.testing.assert_array_equal(matched, [True, True, True, False])
    bs = b[:2] * a[:2].sum() / b[:2].sum()
    rho = O[0, 0] * O[1, 1] / (O[0, 1] * O[1, 0])
    roots = np.roots([1 - rho, a[1] - bs[0] + rho * (a[0] + bs[0]), -rho * a[0] * bs[0]])
    x = [v.real for v in roots if max(0.0, bs[0] - a[1]) < v.real < min(a[0], bs[0])][0]
    V = np.array([[x, a[0] - x], [bs[0] - x, a[1] - bs[0] + x]])
    np.testing.assert_allclose(W_new[:2], b[:2] + X[:2] @ (V / a[:2, None]), rtol=1e-11)
    assert W_new[2] == pytest.approx(b[2] + X[2], rel=1e-14) and np.isnan(W_new[3])


def test_conserving_transfer_refuses_a_new_pore_left_without_water(monkeypatch):
    """Suction (W < A) handed on whole: old pore 1 (A = 2, W = 1.5) onto new pore 1 (A = 0.5)
    leaves it exactly W = 0.5 - 0.5 = 0, no water: refused, naming new pore 1 (pore 0, at W/A = 0.6
    into as much void, is fine), the cause (W/A = 0.75 over it handed into a quarter of the void)
    and the remedies."""
    from engines.model import pore_water as pw
    monkeypatch.setattr(pw.pg, "pore_overlaps", lambda old, new, xz: (np.array([0, 1]), np.array([0, 1]), np.ones(2)))
    a, b = np.array([1.0, 2.0]), np.array([1.0, 0.5])
    with pytest.raises(ValueError, match=r"new pore 1 would hold no water \(W = 0.000e\+00 m\^2\): .*W/A down to 0.75\b.*"
                                         r"their void is 4.00 x .* rebuild_interval= or rebuild_distance=.*"
                                         r"transfer='paper'"):
        pw.conserving_water(_Pores(2), np.array([0.6, 1.5]), a, _Pores(2), b, np.zeros((0, 2)))


def test_pore_overlaps_of_an_old_triangle_turned_over():
    """An old pore (triangle ABC) whose corner C has moved across AB, so that it is turned over at
    the current positions, with a disc D now inside it: the new network splits ABC' into ABD, BC'D
    and C'AD (area 2 each), and the old pore overlaps each of them wholly."""
    r = np.ones(4)
    old = pg.build_pores(np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 3.0], [20.0, 20.0]]), r, l_m=3.0)
    xz = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, -3.0], [2.0, -1.0]])
    new = pg.build_pores(xz, r, l_m=3.0)
    assert old.n_pores == 1 and new.n_pores == 3 and triangulation._signed_area(xz[old.tri])[0] < 0
    p, q, o = pg.pore_overlaps(old, new, xz)
    np.testing.assert_array_equal(p, [0, 0, 0])
    np.testing.assert_array_equal(q, [0, 1, 2])
    np.testing.assert_allclose(o, [_tri_area(*xz[new.vertices_of(k)]) for k in range(3)], rtol=1e-12)
    np.testing.assert_allclose(o, 2.0, rtol=1e-12)


def test_pore_overlaps_onto_a_single_new_pore():
    """Two old pores (a quadrilateral split by its diagonal) onto one new pore (the diagonal no
    longer a link): pairs (0, 0) and (1, 0) with the areas of the two triangles."""
    r = np.ones(4)
    xz = np.array([[0.0, 0.0], [3.0, 0.0], [3.2, 2.1], [-0.2, 2.1]])
    old = pg.build_pores(np.array([[0.0, 0.0], [3.0, 0.0], [3.4, 2.2], [0.0, 2.0]]), r, l_m=2.0)
    new = pg.build_pores(xz, r, l_m=1.5)
    assert old.n_pores == 2 and new.n_pores == 1
    p, q, o = pg.pore_overlaps(old, new, xz)
    np.testing.assert_array_equal(p, [0, 1])
    np.testing.assert_array_equal(q, [0, 0])
    np.testing.assert_allclose(o, [_tri_area(*xz[old.vertices_of(k)]) for k in range(2)], rtol=1e-12)


def test_pores_that_only_share_an_edge_do_not_overlap():
    """The old pore ABD and the new pore BCD (the radii decide which sides are links) meet along
    BD only: no overlapping pair, so the new pore is unmatched in the conserving transfer."""
    from engines.model.pore_water import conserving_water
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [2.4, 2.4], [0.0, 2.0]])
    old = pg.build_pores(xz, np.array([0.6, 1.42, 0.5, 1.42]))
    new = pg.build_pores(xz, np.array([0.2, 1.42, 1.1, 1.42]))
    assert sorted(old.vertices_of(0).tolist()) == [0, 1, 3] and sorted(new.vertices_of(0).tolist()) == [1, 2, 3]
    p, q, o = pg.pore_overlaps(old, new, xz)
    assert len(p) == len(q) == len(o) == 0
    W_new, matched = conserving_water(old, np.array([0.2]), np.array([0.1]), new, np.array([0.3]), xz)
    assert not matched.any() and np.isnan(W_new).all()


def test_the_books_of_the_excess_water_add_up_over_re_meshings():
    """Two pores re-meshed onto themselves twice, the overlaps given: new pore 0 over old pore 0
    only, the last pores of both overlapping nothing (rule (a) hands old pore 1's pressure to new
    pore 1). Each re-meshing adds to remesh_excess_change the change of the excess W - A of all
    pores and to remesh_excess_edge that of the pores outside the overlaps; both add up."""
    from engines.model.pore_water import NUMPY_REMESH
    xz = np.array([[-1.2, 0.0], [1.2, 0.0], [0.0, 1.0], [0.0, -1.0]])
    r = np.full(4, 0.5)
    net = pg.build_pores(xz, r, l_m=1.5, walls=np.full(4, pg.WALL_LEFT))
    A = pg.measure(net, xz, r).void_area
    w = PoreWater(net, A, WaterSettings(E_w=10.0, transfer="conserving"), W=A * [1.1, 1.3])
    steps = NUMPY_REMESH._replace(pore_overlaps=lambda old, new, at: (np.array([0]), np.array([0]), np.array([0.4])))
    change = edge = 0.0
    for A_old, A_new in ((A, 0.9 * A), (0.9 * A, 0.8 * A)):
        X_old = w.W - A_old
        counts = w.remesh(net, A_new, A_old, xz=xz, steps=steps)
        X_new = w.W - A_new
        assert counts["unmatched"] == 1 and w.W[0] == pytest.approx(A_new[0] + X_old[0], rel=1e-14)
        change, edge = change + X_new.sum() - X_old.sum(), edge + X_new[1] - X_old[1]
        assert X_new[1] != X_old[1]
    assert w.balance.remesh_excess_change == pytest.approx(change, rel=1e-14)
    assert w.balance.remesh_excess_edge == pytest.approx(edge, rel=1e-14)
    with pytest.raises(ValueError, match=r"^transfer = 'conserving' needs the positions xz at re-meshing$"):
        w.remesh(net, A, A)


def test_slivers_are_judged_against_the_overlaps_of_their_pores_at_any_scale():
    """without_slivers: at pores of 1e-8 m^2, an overlap of 1e-12 m^2 (1e-4 of its pores) is kept and
    one of 1e-19 m^2 (1e-11) dropped, in either pore's column; the areas' own scale, not 1 m^2."""
    p, q = np.array([0, 0, 1, 1]), np.array([0, 1, 1, 0])
    area = np.array([1e-8, 1e-12, 1e-8, 1e-19])
    kept = overlaps.without_slivers(p, q, area)
    assert [a.tolist() for a in kept] == [[0, 0, 1], [0, 1, 1], [1e-8, 1e-12, 1e-8]]
