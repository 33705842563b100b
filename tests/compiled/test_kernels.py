"""Compiled kernels (engines.compiled.kernels) against the readable NumPy functions, to 1e-12 relative.

Relative is taken against the largest magnitude of the compared quantity (a disc's net force can
cancel to ~0 from large contact forces; its round-off is relative to those).
"""
import numpy as np
import pytest
from numba import literal_unroll, njit

from engines.compiled import contact, kernels, paper_law, water_model
from engines.model import contact as model_contact
from engines.model import paper_law as model_paper_law
from engines.model import pores as pg
from engines.model import water_model as model_water_model
from engines.model.contact import ContactSettings
from engines.model.limits import DarcyStabilityError
from engines.model.pore_water import WaterSettings
from engines.model.schedule import Schedule
from engines.model.side_walls import SideWallTies
from engines.yade.deposition import wall_box
from packing.layouts import hex_lattice, random_discs

RTOL = 1e-12


def assert_close(a, b, what):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, what
    scale = max(np.max(np.abs(b), initial=0.0), 1e-300)
    err = np.max(np.abs(a - b), initial=0.0) / scale
    assert err <= RTOL, f"{what}: relative difference {err:.2e}"


def _column(seed=3, n=300, gap=-0.02):
    """Random discs squeezed together (overlaps, gaps) with a bottom row, left and right columns."""
    rng = np.random.default_rng(seed)
    xz, r = random_discs(n, rng)
    xz = xz * (1 + gap)  # gap < 0: many overlapping pairs
    walls = np.zeros(len(r), np.int64)
    walls[xz[:, 1] < xz[:, 1].min() + 0.5] = pg.WALL_BOTTOM
    walls[(xz[:, 0] < xz[:, 0].min() + 0.5) & (walls == 0)] = pg.WALL_LEFT
    walls[(xz[:, 0] > xz[:, 0].max() - 0.5) & (walls == 0)] = pg.WALL_RIGHT
    return xz, r, walls, rng


@pytest.mark.parametrize("spring", ["a", "b", "c", "d"])
def test_contact_law_compiled_equals_numpy(spring):
    """Many steps of random motion (loading, unloading, sliding, separations) on both paths."""
    xz, r, walls, rng = _column()
    xz = xz * 1.0  # units of r ~ 1: scale the law to it
    s = ContactSettings(spring=spring, kn=1e3, eta_n=0.5, ks=4e2, eta_s=0.2, mu=0.4, f_max=20.0,
                        eps_m=0.01 if spring == "b" else 0.0)
    mobile = walls == 0
    laws = [law(s, r, mobile) for law in (model_contact.ContactLaw, contact.ContactLaw)]
    x_prev = xz.copy()
    n_sep = 0
    for step in range(60):
        move = 0.01 * rng.standard_normal(xz.shape) * mobile[:, None]
        x = x_prev + move
        du = x - x_prev
        dpsi = 0.01 * rng.standard_normal(len(r))
        out = [law.forces(x, du, dpsi, 1e-3) for law in laws]
        (F0, M0, sep0), (F1, M1, sep1) = out
        assert_close(F1, F0, f"F at step {step}")
        assert_close(M1, M0, f"M at step {step}")
        assert_close(laws[1].state, laws[0].state, f"state at step {step}")
        assert [(e.i, e.j) for e in sep1] == [(e.i, e.j) for e in sep0]
        for e0, e1 in zip(sep0, sep1):
            assert_close(e1.normal, e0.normal, "separation normal")
            assert e1.vn_collision == e0.vn_collision
        n_sep += len(sep0)
        x_prev = x
    assert laws[0].touching.sum() > 50 and n_sep > 10  # the test went through contacts and separations
    if spring in ("c", "d"):
        assert np.any(laws[0].state[:, model_contact.E_N] == s.f_max)  # and the cap


def test_paper_law_step_compiled_equals_numpy():
    """PaperLaw.step (kernels.law_step: du, pair list, forces, spin in one call) against the NumPy
    path over moving discs: forces, spins, increments and the velocity fixes of eq 18-24, through
    rebuilds of the pair list."""
    xz, r, walls, rng = _column(seed=5)
    mobile = walls == 0
    mass = np.pi * r**2
    s = ContactSettings(spring="d", kn=1e3, eta_n=0.5, ks=4e2, eta_s=0.2, mu=0.4, f_max=20.0, eps_m=0.01)
    laws = [law(s, r, mobile, mass, 0.5 * mass * r**2, 1e-3) for law in (model_paper_law.PaperLaw, paper_law.PaperLaw)]
    x = xz.copy()
    n_fixes = 0
    for step in range(40):
        x = x + 0.02 * rng.standard_normal(x.shape) * mobile[:, None]
        (F0, fix0), (F1, fix1) = (law.step(x.copy()) for law in laws)
        assert_close(F1, F0, f"F at step {step}")
        assert_close(laws[1].omega, laws[0].omega, f"omega at step {step}")
        assert_close(laws[1].du, laws[0].du, f"du at step {step}")
        assert sorted(fix1) == sorted(fix0)
        for d in fix0:
            assert_close(fix1[d], fix0[d], f"velocity fix of disc {d}")
        n_fixes += len(fix0)
    assert laws[1].contact.list_builds == laws[0].contact.list_builds > 3 and n_fixes > 0


@pytest.mark.parametrize("spread, shift", [(1.0, 0.0), (40.0, 0.0), (40.0, -3000.0)])
def test_the_pair_list_compiled_equals_numpy(spread, shift):
    """ContactLaw._pairs_near by the grid kernel (kernels.near_pairs) against the
    k-d tree of the NumPy path: the same pairs in the same order, the state of the listed pairs
    carried over row by row, a new pair's zero, pairs of two fixed discs left out, and the pair
    filter. spread: discs packed, or some scattered over 40 times the box (a sparse grid); shift:
    the scene moved to negative coordinates, twice its width away from 0."""
    xz, r, walls, rng = _column(seed=9)
    xz[::7] *= spread
    xz += shift
    mobile = walls == 0
    s = ContactSettings(spring="d", kn=1e3, eta_n=0.5, ks=4e2, eta_s=0.2, mu=0.4, f_max=20.0, eps_m=0.01)
    laws = [law(s, r, mobile) for law in (model_contact.ContactLaw, contact.ContactLaw)]
    for law in laws:
        law._update_list(xz)
        law.state = np.arange(law.state.size, dtype=float).reshape(law.state.shape)  # rows told apart
    moved = xz + 0.3 * r.min() * rng.standard_normal(xz.shape)
    (i0, j0, s0), (i1, j1, s1) = (law._pairs_near(moved) for law in laws)
    assert i1.dtype == j1.dtype == np.int64
    np.testing.assert_array_equal(i1, i0)
    np.testing.assert_array_equal(j1, j0)
    np.testing.assert_array_equal(s1, s0)
    kept = np.isin(i0 * len(r) + j0, laws[0].i * len(r) + laws[0].j)
    assert 0 < kept.sum() < len(i0) and not s0[~kept].any()  # carried over and new pairs both
    assert not (~mobile[i0] & ~mobile[j0]).any() and (~mobile[i0] | ~mobile[j0]).any()
    laws[1].pair_filter = lambda i, j: (i + j) % 3 != 0
    i2, j2, s2 = laws[1]._pairs_near(moved)
    keep = (i0 + j0) % 3 != 0
    np.testing.assert_array_equal(i2, i0[keep])
    np.testing.assert_array_equal(s2, s0[keep])


@pytest.mark.parametrize("law", [model_contact.ContactLaw, contact.ContactLaw])
def test_a_pair_exactly_at_the_lists_reach_is_listed(law):
    """R = r_i + r_j + eps_m + skin is in the list, the next float beyond it is not."""
    r = np.array([1e-3, 1.5e-3])
    c = law(ContactSettings(spring="a", kn=1e3, eps_m=1e-4), r, np.ones(2, bool))
    reach = r[0] + r[1] + 1e-4 + c.skin
    for x, listed in ((reach, 1), (np.nextafter(reach, 1.0), 0)):
        assert len(c._pairs_near(np.array([[0.0, 0.0], [x, 0.0]]))[0]) == listed


@pytest.mark.parametrize("law", [model_contact.ContactLaw, contact.ContactLaw])
def test_a_pair_exactly_touching_feels_its_dashpot(law):
    """delta = 0 exactly (R = r_i + r_j + eps_m), the discs approaching: e_n = kn u_n = 0 is no
    tension (eq 6 cuts e_n < 0 only), so the dashpot's d_n = eta_n dun / dt pushes them apart."""
    r = np.array([1e-3, 1.5e-3])
    c = law(ContactSettings(spring="a", kn=1e3, eta_n=0.5, ks=4e2, eta_s=0.2, mu=0.4, eps_m=1e-4), r, np.ones(2, bool))
    x = np.array([[0.0, 0.0], [r[0] + r[1] + 1e-4, 0.0]])
    F, _, _ = c.forces(x, np.array([[1e-6, 0.0], [-1e-6, 0.0]]), np.zeros(2), 1e-3)
    d_n = 0.5 * 2e-6 / 1e-3  # eq 4b: dun = 2e-6 m of approach in dt = 1e-3 s
    np.testing.assert_allclose(F, [[-d_n, 0.0], [d_n, 0.0]], rtol=1e-12, atol=1e-18)


def _kernel_measure(net, xz, r):
    out = kernels.new_measures(net.n_pores, len(net.links))
    kernels.measure(xz, r, net.eps_m, kernels.link_geometry(net), out)
    return out[:-1]


@pytest.mark.parametrize("layout", ["random", "hex", "moved"])
def test_measure_compiled_equals_numpy(layout):
    if layout == "hex":
        xz = hex_lattice(8, 7, 2.05)
        r = np.ones(len(xz))
        net = pg.build_pores(xz, r, l_m=0.1)
    else:
        xz, r, walls, rng = _column()
        net = pg.build_pores(xz, r, eps_m=0.01, l_m=0.3, walls=walls)
    if layout == "moved":  # links turn after the build (eq 29 relative to the build angles)
        xz = xz + 0.12 * rng.standard_normal(xz.shape)
        v = xz[net.links[:, 1]] - xz[net.links[:, 0]]
        v0 = net.link_vec0
        turns = np.arctan2(v0[:, 0] * v[:, 1] - v0[:, 1] * v[:, 0], np.einsum("ij,ij->i", v0, v))
        # links that turned both less and more than the series' range, with both signs of weight
        assert (np.abs(turns) < 0.5 * kernels.SMALL_TURN).sum() > 50 and (np.abs(turns) > 0.15).sum() > 5
        assert (net.link_turn_weight > 0).sum() > 50 and (net.link_turn_weight < 0).sum() > 50
    m = pg.measure(net, xz, r)
    poly, sect, void, length, contact, vec = _kernel_measure(net, xz, r)
    for a, b, what in ((poly, m.polygon_area, "polygon"), (sect, m.sector_area, "sectors"), (void, m.void_area, "void"),
                       (length, m.link_length, "length"), (vec, m.link_vector, "vectors")):
        assert_close(a, b, what)
    np.testing.assert_array_equal(contact, m.link_contact)
    assert net.n_pores > 40


def test_turn_is_atan2():
    """kernels.turn (a series for small turns, else atan2) against np.arctan2 to 2 ulp, at every quadrant,
    the series' edge and zero."""
    rng = np.random.default_rng(5)
    angles = np.concatenate([rng.uniform(-np.pi, np.pi, 2000), rng.uniform(-0.11, 0.11, 2000),
                             [0.0, np.arctan(kernels.SMALL_TURN), -np.arctan(kernels.SMALL_TURN), np.pi, -np.pi / 2]])
    scale = 10.0 ** rng.uniform(-6, 3, len(angles))
    for a, k in zip(angles, scale):
        s, c = k * np.sin(a), k * np.cos(a)
        assert abs(kernels.turn(s, c) - np.arctan2(s, c)) <= 4.5e-16 * abs(np.arctan2(s, c)), (a, k)  # 2 ulp
    assert kernels.turn(0.0, 1.0) == 0.0


def test_pressure_forces_compiled_equals_numpy():
    xz, r, walls, rng = _column()
    net = pg.build_pores(xz, r, l_m=0.3, walls=walls)
    m = pg.measure(net, xz, r)
    U = 100 * rng.standard_normal(net.n_pores)
    F, scratch = np.zeros((len(r), 2)), np.zeros((len(r), 2))
    kernels.pressure_forces(net.links, net.link_pores, r, U, m.link_length, m.link_vector, F, scratch)
    assert_close(F, pg.pressure_forces(net, r, U, m), "eq 33 forces")
    kernels.pressure_forces(net.links, net.link_pores, r, np.full(net.n_pores, 7.0), m.link_length, m.link_vector, F, scratch)
    assert np.abs(F[walls == 0]).max() > 0  # surface discs feel the outside at U = 0


SETTINGS = {
    "undrained": WaterSettings(E_w=240.0, k1=200.0, k2=2.0),
    "inflow_drained": WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=100.0, q_w=0.05, sides="drained"),
    "smoothing": WaterSettings(E_w=240.0, k1=200.0, k2=20.0, q_w=0.05, smoothing=True),
    "substep": WaterSettings(E_w=240.0, k1=2e5, k2=2e3, q_w=0.05, substep=True),
    # sides 50 times as permeable as the throats: the drained pores set the Darcy limit (g_b in the bound)
    "drained_limit": WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=1e4, q_w=0.05, sides="drained", substep=True),
}


@njit
def _last_of_each_part(ints, i_at, floats, f_at, out):
    """out gets the last value of every field of kernels.water_net, in its order."""
    net, k = kernels.water_net(ints, i_at, floats, f_at), 0
    for v in literal_unroll(net):  # the name itself: numba does not unroll numba.literal_unroll
        out[k] = np.asarray(v).ravel()[-1]
        k += 1


def test_water_net_reads_each_part_of_the_buffers_by_name():
    """Part k of the packed buffers holds k + 1 as its last value: each field of the WaterNet, by
    name, is its own part (views of 1 or 2 columns, numbers)."""
    names = kernels.WATER_INTS.names + kernels.WATER_FLOATS.names
    assert kernels.WaterNet._fields == names
    parts = {name: np.arange(4.0) + k - 2 for k, name in enumerate(names)}  # last value k + 1
    for name in ("eps_m", "a_min", "check_areas"):
        parts[name] = parts[name][-1:]
    ints, i_at = kernels.WATER_INTS.pack({n: parts[n] for n in kernels.WATER_INTS.names}, np.int64)
    floats, f_at = kernels.WATER_FLOATS.pack({n: parts[n] for n in kernels.WATER_FLOATS.names}, float)
    last = np.zeros(len(names))
    _last_of_each_part(ints, i_at, floats, f_at, last)
    assert last.tolist() == list(range(1, len(names) + 1))


@pytest.mark.parametrize("case", sorted(SETTINGS))
def test_water_model_compiled_equals_numpy(case):
    """WaterModel's kernels (measure, flows, update, eq 33) against PoreWater.advance, measure and
    pressure_forces over moving discs, rebuilds included; one pore pinched for a while."""
    xz, r, walls, rng = _column(n=250, gap=0.0)
    s = SETTINGS[case]
    models = [model(s, r, walls, xz, 0.0, 0.3, 1e-4, Schedule(rebuild_interval=7), log=lambda m: None)
              for model in (model_water_model.WaterModel, water_model.WaterModel)]
    pinched = int(np.flatnonzero(~models[0].water.net.pore_surface)[0])
    x = xz.copy()
    for k in range(20):
        x = x + 0.003 * rng.standard_normal(x.shape) * (walls == 0)[:, None]
        xk = x.copy()
        if 3 <= k < 6:  # squeeze one pore shut: its corner discs move to its centroid
            net = models[0].water.net
            v = net.vertices_of(pinched) if k < models[0].schedule.rebuild_interval else []
            xk[v] = xk[v].mean(axis=0) + 0.2 * (xk[v] - xk[v].mean(axis=0))
            assert models[0].void_area(xk)[pinched] <= models[0].water.net.a_min
        for m in models:
            m.step(k, xk)
        W0, W1 = models[0].water.W, models[1].water.W
        assert_close(W1, W0, f"W at step {k}")
        assert_close(models[1].F, models[0].F, f"F at step {k}")
        assert_close(models[1].last_limit, models[0].last_limit, f"Darcy limit at step {k}")
        b0, b1 = models[0].water.balance, models[1].water.balance
        for name in ("inflow", "surface_outflow", "side_outflow"):
            assert abs(getattr(b1, name) - getattr(b0, name)) <= RTOL * max(abs(getattr(b0, name)), 1e-300) + 1e-30
    assert models[1].water.balance_error() < 1e-12
    assert models[0].n_rebuilds == models[1].n_rebuilds == 2
    if case == "substep":
        assert models[1].substeps_max > 1
    if case == "inflow_drained":
        assert models[1].water.balance.side_outflow > 0 and models[1].water.balance.inflow > 0


def test_tie_forces_compiled_equals_numpy():
    """kernels.tie_forces against SideWallTies.forces: the seismic box's columns moved and moving
    at random (a tie's stretch, its dashpot, a disc with two ties, the corners' reactions)."""
    xz, group = wall_box(25, 12, 0.55e-3)
    ties = SideWallTies(xz, group, 1.5e5, 0.6)
    rng = np.random.default_rng(7)
    dt = 1e-6
    args = kernels.tie_args(ties)
    T = args[kernels.TIES.T]
    for _ in range(5):
        x = xz + 1e-5 * rng.standard_normal(xz.shape)
        du = 1e-7 * rng.standard_normal(xz.shape)
        kernels.tie_forces(x, du, dt, *args)
        F = ties.forces(x[:, 0], du[:, 0] / dt)
        assert_close(T[0], F, "tie forces")
        assert np.count_nonzero(F) == np.count_nonzero(ties.moving) + 2  # the columns and their corners


@pytest.mark.parametrize("model", [model_water_model.WaterModel, water_model.WaterModel])
def test_a_water_step_that_would_empty_pore_0_is_refused_naming_it(model):
    """Three discs, one surface pore (pore 0) at W = 3 A: a step just under its stability limit
    would overshoot below zero (tests/model/test_pore_water.py): both paths refuse it naming
    pore 0 and keep the water."""
    xz, r = np.array([[0.0, 0.0], [3.0, 0.0], [1.5, 2.6]]), np.ones(3)
    m = model(WaterSettings(E_w=240.0, k1=200.0, k2=2.0), r, np.zeros(3, np.int64), xz, 0.0, 2.0, 1e-3)
    A = pg.measure(m.water.net, xz, r).void_area
    assert m.water.net.n_pores == 1 and m.water.net.pore_surface[0]
    m.water.W[:] = 3 * A
    with pytest.raises(DarcyStabilityError, match="water area of pore 0 "):
        m.advance(0.999 * m.water.darcy_limit(A, np.zeros(3, bool)), xz)
    np.testing.assert_array_equal(m.water.W, 3 * A)


def test_a_pore_at_the_degenerate_area_exactly_exchanges_nothing():
    """A pore is closed at A <= a_min (eq 32-43 run over the open pores): with a_min set to the
    void area the water step measured for the smallest surface pore, under pressure, that pore
    keeps its water bit for bit (no throat, no outflow to the surface), while the others exchange."""
    xz, r, walls, rng = _column(n=120, gap=0.0)
    m = water_model.WaterModel(WaterSettings(E_w=240.0, k1=200.0, k2=2.0), r, walls, xz, 0.0, 0.3, 1e-3)
    net = m.water.net
    m.water.W[:] = m.water.W * (1 + 0.01 * rng.random(net.n_pores))
    m.advance(1e-6, xz)
    void = m._part("void").copy()   # the water step's own measure (eq 29)
    surface = np.flatnonzero(net.pore_surface)
    p = int(surface[np.argmin(void[surface])])
    m._part("a_min")[:] = void[p]
    W = m.water.W.copy()
    assert W[p] != void[p]   # U != 0: it would flow out
    m.advance(1e-6, xz)
    assert m.water.W[p] == W[p] and np.count_nonzero(m.water.W != W) > net.n_pores // 2


def test_refuses_a_water_step_above_the_darcy_limit():
    xz, r, walls, _ = _column(n=120, gap=0.0)
    m = water_model.WaterModel(WaterSettings(E_w=240.0, k1=2e5, k2=2e3, substep=False), r, walls, xz, 0.0, 0.3, 1e-3)
    with pytest.raises(DarcyStabilityError, match="substep"):
        m.step(0, xz)


def test_the_darcy_check_twins_equal_the_model_limits():
    """kernels.gershgorin_limit and substep_count give what engines.model.limits gives."""
    from engines.model import limits
    for lam in (0.0, 1e-300, 0.5, 4.0, 3e7):
        assert kernels.gershgorin_limit(lam) == limits.gershgorin_limit(lam)
    for h, limit in ((1e-3, 1e-3), (0.5e-3, 1e-3), (2.5e-3, 1e-3), (1.0, np.inf), (3e-6, 1e-6 + 1e-22), (7.0, 0.7)):
        assert kernels.substep_count(h, limit) == limits.substep_count(h, limit)


def _inputs():
    """The ground motions the compiled drive runs: the paper's cosine, the El Centro record as
    liquefaction_case6.toml scales it, and a short record with end values (None) and samples at
    multiples of dt."""
    import os

    from engines.model.ground_motion import Cosine, Sampled, record_acceleration
    from engines import ROOT
    elcentro = os.path.join(ROOT, "yade_scripts", "scenes", "elcentro_ns_1940.txt")
    return {"cosine": Cosine(15.0, 50.0), "elcentro": record_acceleration(elcentro, 0.02, 4.7976, "g"),
            "ends": Sampled(np.array([0.002, 0.004, 0.01, 0.03]), np.array([1.0, -3.0, 2.5, 0.5]), None, None)}


@pytest.mark.parametrize("dt", [1e-6, 3.7e-4, 4e-4])
@pytest.mark.parametrize("name", ["cosine", "elcentro", "ends"])
def test_the_base_motion_twin_equals_base_motion_bit_for_bit(dt, name):
    """kernels.base_step (with engines.compiled.pore_dem.base_motion_args) against
    engines.model.ground_motion.BaseMotion.step for every input: acceleration, velocity,
    displacement and the wall velocity of every step the same floats, over 0.05 s."""
    from engines.compiled.pore_dem import base_motion_args
    from engines.model.ground_motion import BaseMotion
    base = BaseMotion(_inputs()[name], dt)
    motion, t_s, a_s = base_motion_args(base, 0.0)
    for k in range(int(0.05 / dt)):
        v = base.step()
        kernels.base_step(motion, t_s, a_s, k)
        assert motion[kernels.MOTION.acc:].tolist() == [base.acc, base.vel, base.disp, v], k
    assert abs(base.disp) > 1e-7


def test_the_sampled_twin_equals_np_interp_at_and_between_samples():
    """kernels.sampled_acceleration against np.interp (Sampled) before, at, between and after the
    samples of the El Centro record, and at random times."""
    acc = _inputs()["elcentro"]
    t_s, a_s = acc.t_s, acc.a_s
    mid = 0.5 * (t_s[:-1] + t_s[1:])
    times = np.concatenate(([-1.0, 0.0, t_s[-1] * 2], t_s, mid, np.random.default_rng(1).uniform(-0.1, t_s[-1] + 0.1, 2000)))
    for t in times.tolist():
        assert kernels.sampled_acceleration(t, t_s, a_s, 0.0, 0.0) == acc(t), t


def test_an_input_without_a_compiled_twin_is_refused():
    """base_motion_args names an acceleration it cannot compile instead of running it wrongly."""
    from engines.compiled.pore_dem import base_motion_args
    from engines.model.ground_motion import BaseMotion
    with pytest.raises(TypeError, match="no compiled twin"):
        base_motion_args(BaseMotion(lambda t: 1.0, 1e-4), 0.0)


def test_separation_velocities_equal_the_velocity_adjustment_bit_for_bit():
    """kernels.free_discs and separation_velocities against engines.model.contact.separation_adjustment
    (eq 18-24) on random pair lists, lost pairs, masses and velocities: the same discs get the
    same velocities, bit for bit (what dem_drive_bulk_io writes), in each of Fig. 3's cases: a
    pair that touched only each other (d), a disc against partners that still touch (a, b), and
    two free discs with other partners (c)."""
    from engines.model.contact import VN_COLL, SeparationEvent, TOUCHING, separation_adjustment
    rng = np.random.default_rng(5)
    dt, e = 1e-6, 0.5
    changed, cases = 0, set()
    for _ in range(600):
        n, m = 8, 12
        pi, pj = rng.integers(0, n, m), rng.integers(0, n - 1, m)
        pj += pj >= pi  # no pair of a disc with itself
        state = np.zeros((m, 6))
        state[:, TOUCHING] = rng.random(m) < 0.4
        state[:, VN_COLL] = rng.normal(0.1, 0.1, m)
        mobile = rng.random(n) < 0.7
        mass = rng.uniform(0.5, 2.0, n)
        xz, du = rng.random((n, 2)), 1e-7 * rng.standard_normal((n, 2))
        apart = np.flatnonzero(state[:, TOUCHING] == 0)
        lost = rng.choice(apart, min(len(apart), rng.integers(1, 5)), replace=False)
        touching = state[:, TOUCHING] != 0
        touch = np.bincount(pi[touching], minlength=n) + np.bincount(pj[touching], minlength=n)
        events = []
        for k in lost:
            d = xz[pj[k]] - xz[pi[k]]
            normal = np.array([d[0] / np.sqrt(d[0] ** 2 + d[1] ** 2), d[1] / np.sqrt(d[0] ** 2 + d[1] ** 2)])
            events.append(SeparationEvent(int(pi[k]), int(pj[k]), normal, state[k, VN_COLL]))
        v = du / dt
        fixes = separation_adjustment(events, touch, v, mass, mobile, e)
        free = kernels.free_discs(lost, len(lost), pi, pj, state, mobile)
        assert set(fixes) == set(np.flatnonzero(free).tolist())
        V = np.full((n, 2), np.nan)
        kernels.separation_velocities(lost, len(lost), pi, pj, state, xz, du, dt, mass, free, e, V)
        for a, va in fixes.items():
            assert V[a].tolist() == va.tolist(), a
            if np.any(va != v[a]):
                changed += 1
                partners = [ev.j if ev.i == a else ev.i for ev in events if a in (ev.i, ev.j)]
                alone = [len([ev for ev in events if b in (ev.i, ev.j)]) == 1 for b in partners]
                cases.add("d" if len(partners) == 1 and free[partners[0]] and alone[0]
                          else "c" if any(free[partners]) else "a, b")
    assert changed > 100 and cases == {"a, b", "c", "d"}
