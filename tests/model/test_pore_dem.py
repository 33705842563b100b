"""One model step without YADE (engines/model/pore_dem.py): masses, input motion, the order of a step
(rebuilds, water steps, held pressure forces, eq 45 in the forces), observations. No YADE.
Runs the compiled twin (engines.compiled.pore_dem.PoreDEM), and the readable NumPy path too where the
water is involved."""
import numpy as np
import pytest

from engines.compiled.pore_dem import PoreDEM
from engines.model import pore_dem
from engines.model import pores as pg
from engines.model.flat_walls import FlatWall, as_tables
from engines.model.pore_dem import disc_masses, moving_walls, weight_carried
from packing.layouts import hex_lattice
from packing.packing import Packing
from tests.scene_helpers import make_scene as scene

R = 0.45e-3
PORE_DEM = {True: PoreDEM, False: pore_dem.PoreDEM}  # compiled: the class


def wet_box(seed=2, jitter=0.0):
    """Particles on a hexagonal lattice (centres moved by up to ``jitter`` R) with random radii
    0.85-0.95 R in a box of wall discs, open at the top."""
    rng = np.random.default_rng(seed)
    xz = hex_lattice(7, 6, 2 * R)
    col, row = np.arange(len(xz)) % 7, np.arange(len(xz)) // 7
    group = np.where(row == 0, pg.WALL_BOTTOM, np.where(col == 0, pg.WALL_LEFT, np.where(col == 6, pg.WALL_RIGHT, 0)))
    r = np.where(group == 0, R * (0.85 + 0.1 * rng.random(len(xz))), R)
    xz[group == 0] += jitter * R * rng.uniform(-1, 1, (int(np.sum(group == 0)), 2))
    return Packing(xz, r, group, np.where(row == 5, 5.0, 1.0))


def test_masses_per_unit_thickness():
    """SPEC §1 (eq 15a's r^3 is a typo): m = rho f pi r^2, I = m r^2 / 2."""
    pk = Packing(np.array([[0.0, 0.0], [1e-3, 0.0]]), [0.4e-3, 0.5e-3], [0, 1], [5.0, 1.0])
    m, inertia = disc_masses(scene(material={"rho": 2000.0}).settings, pk)
    np.testing.assert_allclose(m, 2000.0 * np.array([5.0, 1.0]) * np.pi * np.array([0.4e-3, 0.5e-3]) ** 2, rtol=1e-15)
    np.testing.assert_allclose(inertia, m * np.array([0.4e-3, 0.5e-3]) ** 2 / 2, rtol=1e-15)


def test_wall_velocity_lands_the_walls_on_the_cosine_displacement():
    """The driven walls, moved by x += wall_velocity dt each step, follow the exact displacement of
    a = A cos(w t) from rest, u = A/w^2 (1 - cos w t), to the second-order error of the
    constant-average-acceleration method (a first-order integration would be off by ~1/n)."""
    s = scene(loading={"type": "cosine", "amplitude": 15.0, "frequency": 50.0, "moves": "box"},
              numerics={"dt": 1e-6})
    pk = wet_box()
    core = PoreDEM(s.settings, pk)
    np.testing.assert_array_equal(moving_walls(s.settings, pk), pk.group != 0)
    u, w = 0.0, 2 * np.pi * 50.0
    for k in range(1, 31):
        core.step(pk.xz)
        u += core.wall_velocity * 1e-6
        assert u == pytest.approx(15.0 / w**2 * (1 - np.cos(w * k * 1e-6)), rel=1e-6)
    np.testing.assert_array_equal(moving_walls(scene(loading={"type": "cosine"}).settings, pk), pk.group == pg.WALL_BOTTOM)
    assert moving_walls(scene().settings, pk).shape == (len(pk.r),) and not moving_walls(scene().settings, pk).any()
    still = PoreDEM(scene().settings, pk)
    still.step(pk.xz)
    assert still.base is None and still.wall_velocity == 0.0


def test_bad_numerics_are_refused():
    pk = wet_box()
    with pytest.raises(ValueError, match=r"\[numerics\] dt"):
        PoreDEM(scene(numerics={"dt": 1e-3}).settings, pk)


def wet_scene(rebuild_interval=4, **water):
    return scene(water={"enabled": True, "E_w": 240.0, "k1": 200.0, "k2": 2.0, **water},
                 numerics={"dt": 1e-6, "rebuild_interval": rebuild_interval, "water_interval": 3})


def moving_positions(pk, k):
    """A smooth made-up motion of the particles (walls fixed), the same for every run."""
    xz = pk.xz.copy()
    mob = pk.mobile
    phase = np.arange(len(xz))[mob]
    xz[mob, 0] += 2e-3 * R * k * np.sin(phase)
    xz[mob, 1] += 2e-3 * R * k * np.cos(1.3 * phase)
    return xz


@pytest.mark.parametrize("compiled", [True, False])
def test_step_order_rebuilds_water_steps_and_held_forces(compiled):
    """Rebuilds at k > 0, k % rebuild_interval == 0; water advanced only at k % water_interval == 0
    and by water_interval dt; the pressure forces of eq 33 recomputed then and held in between."""
    pk = wet_box()
    core = PORE_DEM[compiled](wet_scene(q_w=1e-4).settings, pk)
    dry = PORE_DEM[compiled](scene(numerics={"dt": 1e-6}).settings, pk)
    W_seen, F_seen = [], []
    for k in range(10):
        xz = moving_positions(pk, k)
        F, _ = core.step(xz)
        W_seen.append(core.water.total_water())
        F_seen.append(core.water_model.F.copy())
        np.testing.assert_allclose(F, dry.step(xz)[0] + core.water_model.F, rtol=1e-13, atol=1e-18)  # law + water
        assert core.water_model.n_rebuilds == k // 4
    water_steps = [k for k in range(10) if k % 3 == 0]
    for k in range(1, 10):
        if k in water_steps or k % 4 != 0:    # (a rebuild may recompute W by eq 32: either way)
            assert (W_seen[k] != W_seen[k - 1]) == (k in water_steps), k
        assert np.array_equal(F_seen[k], F_seen[k - 1]) == (k not in water_steps), k
    n_bottom = int(np.sum(core.water.net.pore_touches["bottom"]))
    assert core.water.balance.inflow == pytest.approx(len(water_steps) * 3 * 1e-6 * 1e-4 * n_bottom, rel=1e-12)


@pytest.mark.parametrize("compiled", [True, False])
def test_pressure_forces_use_the_area_of_eq45(compiled):
    """With smoothing the forces of eq 33 come from U of eq 32 at the area actually used
    ([A]_t = ([A]_{t-dt} + A'_t)/2), the same U that drives the flows."""
    pk = wet_box()
    s = wet_scene(rebuild_interval=1000, smoothing=True)
    core = PORE_DEM[compiled](s.settings, pk)
    A_used = pg.measure(core.water.net, pk.xz, core.r).void_area
    for k in range(3):
        xz = moving_positions(pk, 3 * k)
        core.step(xz)
        m = pg.measure(core.water.net, xz, core.r)
        A_used = (A_used + m.void_area) / 2
        expected = pg.pressure_forces(core.water.net, core.r, core.water.pressure(A_used), m)
        # to 1e-12 of the largest force: a disc's force is a sum of pressure differences (cancellation)
        np.testing.assert_allclose(core.water_model.F, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
        core.step(xz)
        core.step(xz)   # two steps without a water step: the force is held
    raw = pg.pressure_forces(core.water.net, core.r, core.water.pressure(m.void_area), m)
    assert np.abs(raw - core.water_model.F).max() > 1e-6 * np.abs(raw).max()   # smoothing made a difference


def test_dry_scene_has_no_water_and_nan_pressures():
    pk = wet_box()
    s = scene()
    core = PoreDEM(s.settings, pk)
    assert core.water is None and core.water_model is None and pore_dem.pore_state(core.water_model, pk.xz) is None
    assert pore_dem.water_model(s.settings, pk) is None
    bounds = pk.block_bounds(s.output.block_z)
    dry_blocks = pore_dem.block_pressures(core.water_model, pk.xz, bounds)
    assert dry_blocks.shape == (len(bounds),) and np.all(np.isnan(dry_blocks))
    F, fixes = core.step(pk.xz)
    assert np.all(np.isfinite(F)) and fixes == {}


def test_block_pressures_are_means_of_the_pores_in_each_block():
    pk = wet_box()
    s = wet_scene()
    core = PoreDEM(s.settings, pk)
    rng = np.random.default_rng(0)
    core.water.W = core.water.W * (1 + 0.1 * rng.random(core.water.net.n_pores))
    net, A, U = pore_dem.pore_state(core.water_model, pk.xz)
    np.testing.assert_allclose(A, pg.measure(net, pk.xz, pk.r).void_area, rtol=1e-15)
    np.testing.assert_allclose(U, s.water.E_w * (1 - A / core.water.W), rtol=1e-12)   # eq 32
    cz = pg.pore_centroids(net, pk.xz)[:, 1]
    bounds = pk.block_bounds(s.output.block_z)
    got = pore_dem.block_pressures(core.water_model, pk.xz, bounds)
    assert len(got) == len(bounds)
    for (z0, z1), g in zip(bounds, got):
        sel = (cz >= z0) & (cz < z1)
        assert sel.any() and g == pytest.approx(U[sel].mean(), rel=1e-14)


def test_window_porosity_moves_with_the_base():
    """Void fraction of the window of a box packing around its particles only (walls excluded):
    one particle of radius r wholly inside gives 1 - pi r^2 / |window|; the window shifted with
    the base until the particle's centre is on its edge sees half the disc."""
    xz = np.array([[0.0, 0.0], [4 * R, 0.0], [2 * R, -2 * R], [2 * R, 0.0]])
    pk = Packing(xz, np.full(4, R), [pg.WALL_LEFT, pg.WALL_RIGHT, pg.WALL_BOTTOM, 0], np.ones(4))
    window = pore_dem.porosity_window(scene(output={"porosity_window": [0.0, 1.0]}).settings, pk)
    assert (window.x0, window.x1) == pytest.approx((R, 3 * R), rel=1e-12)
    area = (window.x1 - window.x0) * (window.z1 - window.z0)
    big = type(window)(-5 * R, 5 * R, -R, R)
    assert pore_dem.window_porosity(pk, big, xz) == pytest.approx(1 - np.pi * R**2 / (20 * R**2), rel=1e-12)
    assert pore_dem.window_porosity(pk, big, xz, base_disp=-3 * R) == pytest.approx(1 - np.pi * R**2 / 2 / (20 * R**2), rel=1e-12)
    assert 0 < area and np.isnan(pore_dem.window_porosity(pk, None, xz))
    for keep in ([2, 3], [0, 2, 3], [1, 2, 3]):        # no side column, only the left, only the right
        part = Packing(xz[keep], np.full(len(keep), R), np.array(pk.group)[keep], np.ones(len(keep)))
        assert pore_dem.porosity_window(scene().settings, part) is None


def test_kinetic_energy_with_spin_of_the_mobile_discs():
    """1/2 m v^2 + 1/2 I omega^2 summed over the particles only (walls excluded)."""
    mass, inertia = np.array([1.0, 2.0, 3.0]), np.array([0.1, 0.2, 0.3])
    mobile = np.array([False, True, True])
    vel = np.array([[9.0, 9.0], [3.0, 4.0], [0.0, -2.0]])
    omega = np.array([5.0, 7.0, -1.0])
    expected = 0.5 * (2.0 * 25.0 + 3.0 * 4.0) + 0.5 * (0.2 * 49.0 + 0.3 * 1.0)
    assert pore_dem.kinetic_energy(mass, inertia, mobile, vel, omega) == pytest.approx(expected, rel=1e-15)


def test_a_disc_pressed_into_a_wall_feels_the_spring():
    """A free disc overlapping a bottom wall disc by 1e-7 m: the step's force is kn x overlap
    upwards (spring a, no dashpot at rest), the pair is listed with that normal force, the one the
    law reported for these positions before the step (PaperLaw.contact_pairs)."""
    s = scene(contact={"spring": "a", "eta_n": 0.0}, numerics={"dt": 1e-7})
    pk = Packing(np.array([[0.0, 0.0], [0.0, 2 * R - 1e-7]]), np.full(2, R), [pg.WALL_BOTTOM, 0], [1.0, 1.0])
    core = PoreDEM(s.settings, pk)
    ahead = core.law.contact_pairs(pk.xz)
    F, _ = core.step(pk.xz)
    for got, expected in zip(ahead, core.contact.contact_pairs()):
        assert np.array_equal(got, expected)
    assert F[1, 1] == pytest.approx(s.contact.kn * 1e-7, rel=1e-9) and F[1, 0] == pytest.approx(0.0, abs=1e-15)
    pairs, fn, es = core.contact.contact_pairs()
    assert sorted(pairs.ravel().tolist()) == [0, 1] and fn == pytest.approx([s.contact.kn * 1e-7], rel=1e-9)
    assert es == pytest.approx([0.0], abs=1e-15)                 # no tangential motion: no shear spring
    moved = pk.xz.copy()
    moved[1, 1] += 3e-9
    ahead = core.law.contact_pairs(moved)
    core.step(moved)
    np.testing.assert_allclose(core.du, [[0.0, 0.0], [0.0, 3e-9]], atol=1e-20)   # eq 17: du of the step
    assert ahead[1] == pytest.approx([s.contact.kn * (1e-7 - 3e-9)], rel=1e-9)
    for got, expected in zip(ahead, core.contact.contact_pairs()):
        assert np.array_equal(got, expected)


def test_a_disc_leaving_a_wall_gets_the_separation_adjustment():
    """Eq 18-23 through the step: a disc that hit a wall disc at 0.1 m/s and leaves it at 0.1 m/s
    comes back with -Vn''/Vn = e."""
    s = scene(contact={"spring": "a", "eta_n": 0.0, "separation_adjustment": True}, numerics={"dt": 1e-7})
    pk = Packing(np.array([[0.0, 0.0], [0.0, 2 * R + 5e-9]]), np.full(2, R), [pg.WALL_BOTTOM, 0], [1.0, 1.0])
    core = PoreDEM(s.settings, pk)
    xz = pk.xz.copy()
    core.step(xz.copy())
    xz[1, 1] = 2 * R - 5e-9                 # approach at 0.1 m/s: contact
    _, fixes = core.step(xz.copy())
    assert fixes == {}
    xz[1, 1] = 2 * R + 5e-9                 # leave at 0.1 m/s: free again
    _, fixes = core.step(xz.copy())
    assert set(fixes) == {1}
    np.testing.assert_allclose(fixes[1], [0.0, s.contact.restitution * 0.1], rtol=1e-6)
    # the caller's velocities, when given, are the ones adjusted (YADE's state.vel instead of du/dt)
    twin = PoreDEM(s.settings, pk)
    for z in (2 * R + 5e-9, 2 * R - 5e-9):
        twin.step(np.array([[0.0, 0.0], [0.0, z]]))
    _, fixes = twin.step(xz.copy(), vel=np.array([[0.0, 0.0], [0.3, 0.2]]))
    np.testing.assert_allclose(fixes[1], [0.3, s.contact.restitution * 0.1], rtol=1e-6)


def step_beside_the_reference(core, model, s, pk, moving, n=400):
    """n steps of the PoreDEM ``core`` driven by a plain Python stand-in for YADE's NewtonIntegrator
    (v += (F/m + g) dt, x += v dt, the ``moving`` walls at the input velocity, adjusted velocities
    set before) beside those of the reference ``model``: positions equal to 1e-10 R and spins to
    1e-9 at every step. Returns the largest displacement [m]."""
    m, _ = disc_masses(s.settings, pk)
    mob, dt, g = pk.mobile, s.numerics.dt, s.material.g
    up = s.material.rho_w * np.pi * pk.r**2 * g
    x, v = pk.xz.copy(), np.zeros_like(pk.xz)
    moved = 0.0
    for _ in range(n):
        F, fixes = core.step(x.copy())
        for d, vel in fixes.items():
            v[d] = vel
        v[mob, 0] += F[mob, 0] / m[mob] * dt
        v[mob, 1] += ((F[mob, 1] + up[mob]) / m[mob] - g) * dt
        v[moving] = [core.wall_velocity, 0.0]
        step = mob | moving
        x[step] += v[step] * dt
        model.step()
        np.testing.assert_allclose(x, model.x, rtol=0, atol=1e-10 * R)
        np.testing.assert_allclose(core.omega[mob], model.omega[mob], rtol=1e-9, atol=1e-9 * np.abs(model.omega).max())
        moved = max(moved, np.abs(x - pk.xz).max())
    return moved


@pytest.mark.parametrize("variant", ["inflow_smoothing", "shaken_drained_d"])
def test_steps_match_the_reference_without_yade(variant):
    """PoreDEM driven by a plain Python stand-in for YADE's NewtonIntegrator (v += (F/m + g) dt,
    x += v dt, walls at the input velocity, adjusted velocities set before) follows the independent
    reference disc by disc: contact law, spin,
    separation adjustment, pore rebuilds, water steps every water_interval, smoothing, drained
    sides, inflow and input."""
    from engines.reference import model as ref
    water = {"enabled": True, "E_w": 240.0, "k1": 200.0, "k2": 2.0, "l_m": 1.3e-4}
    if variant == "inflow_smoothing":
        tables = dict(water={**water, "q_w": 2e-3, "smoothing": True}, contact={"spring": "c", "separation_adjustment": True})
        loading = {}
    else:
        tables = dict(water={**water, "sides": "drained", "k3": 500.0},
                      contact={"spring": "d", "eps_m": 2e-5, "f_max": 1.5, "separation_adjustment": True})
        loading = {"type": "cosine", "amplitude": 30.0, "frequency": 200.0, "moves": "box"}
    s = scene(material={"g": 1000.0}, loading=loading, numerics={"dt": 1e-6, "rebuild_interval": 25, "water_interval": 2},
              **tables)
    pk = wet_box(seed=5, jitter=0.05)
    core = PoreDEM(s.settings, pk)
    model = ref.ReferenceModel(s.as_dict(), pk)   # the paper's readings, walls included (READINGS D1)
    moved = step_beside_the_reference(core, model, s, pk, moving_walls(s.settings, pk))
    np.testing.assert_allclose(core.water.total_water(), model.water.total(), rtol=1e-12)
    assert core.water_model.n_rebuilds == model.counts["rebuilds"] == 15 and moved > 0.01 * R
    assert np.abs(model.omega).max() > 0 and core.water.balance_error() < 1e-12


def test_rebuild_every_step_when_asked():
    pk = wet_box()
    core = PoreDEM(scene(water={"enabled": True}, numerics={"dt": 1e-6, "rebuild_interval": 1}).settings, pk)
    for k in range(4):
        core.step(moving_positions(pk, k))
    assert core.water_model.n_rebuilds == 3     # at k = 1, 2, 3 (never at k = 0)


@pytest.mark.parametrize("compiled", [True, False])
def test_side_wall_ties_add_their_forces_to_the_step(compiled):
    """[loading] side_walls = "springs" (Fig. 27): a middle disc of the left column moved by dx in
    one step feels -2 k's dx - 2 eta's dx/dt more than with fixed walls (its two ties, the tie
    velocity du/dt of the step), its two neighbours +k's dx + eta's dx/dt each; nothing in z."""
    ks, eta, dx, dt = 1e3, 0.5, 1e-8, 1e-7
    tables = dict(contact={"ks_wall": ks, "eta_s_wall": eta}, numerics={"dt": dt})
    pk = wet_box()
    ties = PORE_DEM[compiled](scene(loading={"type": "cosine", "amplitude": 0.0, "side_walls": "springs"}, **tables).settings, pk)
    fixed = PORE_DEM[compiled](scene(loading={"type": "cosine", "amplitude": 0.0}, **tables).settings, pk)
    left = np.flatnonzero(pk.group == pg.WALL_LEFT)
    left = left[np.argsort(pk.xz[left, 1])]
    d, below, above = left[2], left[1], left[3]
    for k in range(2):
        xz = pk.xz.copy()
        xz[d, 0] += k * dx
        diff = ties.step(xz)[0] - fixed.step(xz)[0]
        tie = k * (ks * dx + eta * dx / dt)
        expected = np.zeros_like(diff)
        expected[[d, below, above], 0] = [-2 * tie, tie, tie]
        np.testing.assert_allclose(diff, expected, rtol=1e-9, atol=1e-9 * eta * dx / dt)
    rows, held = np.arange(len(pk.r)), np.zeros((len(pk.r), 2))
    if compiled:  # the ties run in the one-call step too
        assert ties.kernel_drive_args(rows, held, 1) is not None and fixed.kernel_drive_args(rows, held, 1) is not None


def test_side_wall_ties_refuse_a_step_above_their_limit():
    """dt must stay below sqrt(m_min / k's) of the moving wall discs (engines.model.side_walls)."""
    pk = wet_box()
    m_wall = disc_masses(scene().settings, pk)[0][pk.group == pg.WALL_LEFT].min()
    dt = 1e-7
    for ks, ok in ((0.98 * m_wall / dt**2, True), (1.02 * m_wall / dt**2, False)):
        s = scene(loading={"type": "cosine", "side_walls": "springs"}, contact={"ks_wall": ks}, numerics={"dt": dt})
        if ok:
            PoreDEM(s.settings, pk)
        else:
            with pytest.raises(ValueError, match="side-wall ties"):
                PoreDEM(s.settings, pk)


class PythonBridge:
    """The bridge of kernels.dem_drive_bulk_io (kernels.BRIDGE) as ctypes callbacks, without YADE:
    get_pos reads the rows of ``xz`` (N, 2), write_forces keeps the forces in ``F`` (N, 2), set_vel
    the velocities in ``vel`` {id: (vx, vz)}, steps counts the O.step() calls in ``steps``."""

    def __init__(self):
        import ctypes
        proto = ctypes.CFUNCTYPE(ctypes.c_int64, ctypes.POINTER(ctypes.c_int64), ctypes.c_int64,
                                 ctypes.POINTER(ctypes.c_double))
        self.xz, self.F, self.vel, self.steps = None, None, {}, 0

        def rows(ids, n, data):
            return np.ctypeslib.as_array(ids, (n,)).copy(), np.ctypeslib.as_array(data, (n, 2))

        def get_pos(ids, n, data):
            i, out = rows(ids, n, data)
            out[:] = self.xz[i]
            return 0

        def write_forces(ids, n, data):
            i, F = rows(ids, n, data)
            self.F[i] = F
            return 0

        def set_vel(ids, n, data):
            if n:
                i, V = rows(ids, n, data)
                self.vel.update(zip(i.tolist(), V.tolist()))
            return 0

        def step(ids, n, data):
            self.steps += 1
            return 0
        self._callbacks = [proto(f) for f in (get_pos, write_forces, set_vel, step)]  # kept alive
        self.addresses = tuple(ctypes.cast(f, ctypes.c_void_p).value for f in self._callbacks)


def fused_step(core, xz):
    """One step of ``core`` as PaperLawEngine.drive makes it with hooks: kernels.dem_drive_bulk_io
    with n = 1, its O.step() left to the caller (through a PythonBridge) and the water's books of
    sub-steps (``finish_substeps``), or the general ``step`` where kernel_drive_args says None.
    Returns (F, the velocities set {disc: (vx, vz)}, made in one compiled call)."""
    from engines.compiled import kernels
    n = len(xz)
    rows, held, ids = np.arange(n), np.zeros_like(xz), np.arange(n)
    drive = core.kernel_drive_args(rows, held, 1)
    if drive is None:
        return (*core.step(xz), False)
    bridge = PythonBridge()
    bridge.xz, bridge.F = xz, np.zeros_like(xz)
    steps, water_in, water_interval, adjust, e, mass, skin, totals, motion, record, args = drive
    made, stepped, stale, n_sub, rc, builds, *pairs = kernels.dem_drive_bulk_io(
        bridge.addresses, steps, core.k, False, water_in, water_interval, adjust, e, mass, skin, totals, motion,
        *record, np.zeros(0, np.int64), np.zeros((0, 2)), ids, np.zeros_like(xz), ids, np.zeros_like(xz), *args)
    assert rc == 0 and made == 1 and stepped == 0 and not stale and bridge.steps == 0
    if builds:
        core.law.contact.take_list(builds, *pairs)
    core.finish_kernel_drive(made, totals, motion)
    if n_sub != 1:
        core.finish_substeps(n_sub)
    return bridge.F, bridge.vel, True


@pytest.mark.parametrize("wet", [None, "plain", "smoothing_substeps"])
def test_one_compiled_call_per_step_equals_the_general_step(wet):
    """kernels.dem_drive_bulk_io, one step a call (``fused_step``: what PaperLawEngine.drive does
    with hooks) gives the forces, water and rebuilds of
    PoreDEM.step, step by step; it leaves the first step and the rebuild steps to ``step``. Also
    with smoothing (eq 45-46) and water steps above the Darcy limit taken in sub-steps."""
    if wet is None:
        s = scene(numerics={"dt": 1e-6})
    elif wet == "plain":
        s = wet_scene(q_w=1e-4)
    else:
        s = wet_scene(q_w=1e-4, k1=2e6, smoothing=True, substep=True)
    pk = wet_box(jitter=0.05)
    general, fused = PoreDEM(s.settings, pk), PoreDEM(s.settings, pk)
    n_fused = 0
    for k in range(10):
        xz = moving_positions(pk, k)
        F, fixes = general.step(xz.copy())
        F2, fixes2, one_call = fused_step(fused, xz.copy())
        n_fused += one_call
        assert one_call == (k > 0 and not (wet and k % 4 == 0))
        np.testing.assert_allclose(F2, F, rtol=1e-12, atol=1e-12 * np.abs(F).max())
        assert fused.k == general.k == k + 1
        if wet:
            assert fused.water.total_water() == pytest.approx(general.water.total_water(), rel=1e-13)
            assert fused.water_model.n_rebuilds == general.water_model.n_rebuilds
    if wet:
        assert general.water.balance.inflow > 0
        assert fused.water.balance.inflow == pytest.approx(general.water.balance.inflow, rel=1e-13)
        assert (fused.water_model.last_limit < 3e-6) == (wet == "smoothing_substeps")   # sub-steps taken
    every = PoreDEM(wet_scene(rebuild_interval=1).settings, pk)
    every.step(pk.xz)
    assert every.kernel_drive_args(np.arange(len(pk.r)), np.zeros((len(pk.r), 2)), 1) is None   # k = 1: a rebuild is due


def test_one_compiled_call_adjusts_the_velocities():
    """The separation adjustment of eq 18-23 in the compiled drive: the disc leaving the wall at
    du/dt = 0.1 m/s after coming at 0.1 m/s gets -Vn''/Vn = e, the velocity the general step gives."""
    s = scene(contact={"spring": "a", "eta_n": 0.0, "separation_adjustment": True}, numerics={"dt": 1e-7})
    pk = Packing(np.array([[0.0, 0.0], [0.0, 2 * R + 5e-9]]), np.full(2, R), [pg.WALL_BOTTOM, 0], [1.0, 1.0])
    core, general = PoreDEM(s.settings, pk), PoreDEM(s.settings, pk)
    for z in (2 * R + 5e-9, 2 * R - 5e-9, 2 * R + 5e-9):
        xz = np.array([[0.0, 0.0], [0.0, z]])
        _, fixes, one_call = fused_step(core, xz.copy())
        _, expected = general.step(xz.copy())
    assert one_call and set(fixes) == set(expected) == {1}
    np.testing.assert_array_equal(fixes[1], expected[1])
    np.testing.assert_allclose(fixes[1], [0.0, s.contact.restitution * 0.1], rtol=1e-6, atol=1e-12)


def test_an_isolated_pair_separating_keeps_its_momentum():
    """Eq 24 through the step: two free discs of different masses (m = rho pi r^2) that collided
    and fly apart too fast are slowed to -Vn''/Vn = e, their total momentum unchanged."""
    s = scene(contact={"spring": "a", "eta_n": 0.0, "separation_adjustment": True}, numerics={"dt": 1e-7})
    r = np.array([R, 0.7 * R])
    pk = Packing(np.array([[0.0, 0.0], [r.sum() + 5e-9, 0.0]]), r, [0, 0], [1.0, 1.0])
    core = PoreDEM(s.settings, pk)
    m, _ = disc_masses(s.settings, pk)
    for gap in (5e-9, -5e-9):                              # approach at 0.1 m/s: contact
        core.step(np.array([[0.0, 0.0], [r.sum() + gap, 0.0]]))
    vel = np.array([[-0.3, 0.0], [0.5, 0.0]])
    _, fixes = core.step(np.array([[0.0, 0.0], [r.sum() + 5e-9, 0.0]]), vel=vel)
    assert set(fixes) == {0, 1}
    assert m[0] * fixes[0][0] + m[1] * fixes[1][0] == pytest.approx(m @ vel[:, 0], rel=1e-9)
    assert fixes[1][0] - fixes[0][0] == pytest.approx(s.contact.restitution * 0.1, rel=1e-6)


def test_flat_walls_of_a_scene_stand_at_the_wall_discs_inner_faces():
    """[walls] kind = "flat": the bottom at max(z + r) of the bottom discs, the sides at max(x + r)
    and min(x - r) of theirs; the boundaries from [water] q_w and sides; the porosity window in
    their box."""
    grid = np.array([(i, j) for j in range(6) for i in range(7)], float) * 2 * R  # a square box, particles of 0.9 R
    col, row = np.arange(len(grid)) % 7, np.arange(len(grid)) // 7
    group = np.where(row == 0, pg.WALL_BOTTOM, np.where(col == 0, pg.WALL_LEFT, np.where(col == 6, pg.WALL_RIGHT, 0)))
    pk = Packing(grid, np.where(group == 0, 0.9 * R, R), group, np.ones(len(grid)))
    flat = {"walls": {"kind": "flat"}, "contact": {"law": "yade", "spring": "a"}}
    walls = pore_dem.scene_flat_walls(scene(**flat, water={"enabled": True, "q_w": 1e-4, "sides": "drained"}).settings, pk)
    left, right, bottom = (pk.group == g for g in (pg.WALL_LEFT, pg.WALL_RIGHT, pg.WALL_BOTTOM))
    assert walls == {pg.WALL_BOTTOM: FlatWall(1, float(np.max(pk.xz[bottom, 1] + R)), 1, "inflow"),
                     pg.WALL_LEFT: FlatWall(0, float(np.max(pk.xz[left, 0] + R)), 1, "drained"),
                     pg.WALL_RIGHT: FlatWall(0, float(np.min(pk.xz[right, 0] - R)), -1, "drained")}
    closed = pore_dem.scene_flat_walls(scene(**flat, water={"enabled": True, "q_w": 0.0}).settings, pk)
    assert [w.boundary for w in closed.values()] == ["undrained"] * 3
    slow = pore_dem.scene_flat_walls(scene(**flat, water={"enabled": True, "inflow_velocity": 1e-3}).settings, pk)
    assert slow[pg.WALL_BOTTOM].boundary == "inflow"  # a Darcy velocity of 1 mm/s
    assert pore_dem.scene_flat_walls(scene().settings, pk) == {}  # kind = "discs"
    faces = {code: w.position for code, w in walls.items()}
    window = pore_dem.porosity_window(scene(output={"porosity_window": [0.0, 0.5]}).settings, pk.particles(), faces)
    h = pk.bed_top - faces[pg.WALL_BOTTOM]
    assert (window.x0, window.x1, window.z0, window.z1) == (faces[pg.WALL_LEFT], faces[pg.WALL_RIGHT],
                                                            faces[pg.WALL_BOTTOM], faces[pg.WALL_BOTTOM] + 0.5 * h)


def test_a_flat_wall_moves_back_to_a_particle_that_reaches_past_the_inner_face():
    """A particle resting in the dip between two bottom wall discs (its bottom below their tops)
    puts the flat bottom at its own bottom, so that it starts touching the wall, not overlapping it."""
    rw, r = R, 0.6 * R
    dz = np.sqrt((rw + r) ** 2 - rw**2)  # the particle on the two discs at x = 0, 2 rw
    xz = np.array([[0.0, 0.0], [2 * rw, 0.0], [rw, dz]])
    pk = Packing(xz, [rw, rw, r], [pg.WALL_BOTTOM, pg.WALL_BOTTOM, 0], np.ones(3))
    walls = pore_dem.scene_flat_walls(scene(walls={"kind": "flat"}, contact={"law": "yade", "spring": "a"}).settings, pk)
    assert dz - r < rw and walls == {pg.WALL_BOTTOM: FlatWall(1, dz - r, 1, "undrained")}  # dry: q_w = 0


@pytest.mark.parametrize("pressed", [0.0, 0.5, 0.99, 1.01])
def test_a_flat_wall_stays_at_its_face_under_a_particle_pressed_into_it_at_rest(pressed):
    """A particle past the face by less than rest_overlap (the whole weight over kn: one at rest on
    the wall, settled on it) leaves the wall at the face, so that the contact starts loaded; past it
    by more, the wall moves back to the particle (the dip's rule above)."""
    rw, r = R, 0.6 * R
    sc = scene(walls={"kind": "flat"}, contact={"law": "yade", "spring": "a"})
    pk = Packing(np.array([[0.0, 0.0], [2 * rw, 0.0], [rw, rw + r]]), [rw, rw, r], [pg.WALL_BOTTOM, pg.WALL_BOTTOM, 0],
                 np.ones(3))
    tol = pore_dem.rest_overlap(sc.settings, pk)
    assert tol == pytest.approx(sc.material.rho * np.pi * r**2 * sc.material.g / sc.contact.kn)
    pk.xz[2, 1] -= pressed * tol
    bottom = pore_dem.scene_flat_walls(sc.settings, pk)[pg.WALL_BOTTOM].position
    assert bottom == pytest.approx(rw if pressed < 1 else rw - pressed * tol, rel=1e-12, abs=0)


def test_the_flat_walls_that_follow_the_input_are_a_boolean_mask():
    """moving_flat_walls: (W,) bool, none without a ground motion, the bottom face with moves =
    "bottom", every wall with "box"; no walls, no entries."""
    walls = (FlatWall(1, 0.0, +1), FlatWall(0, 0.0, +1), FlatWall(1, 1.0, -1))
    for loading, want in (({}, [False] * 3), ({"type": "cosine"}, [True, False, False]),
                          ({"type": "cosine", "moves": "box"}, [True] * 3)):
        for w, expect in ((walls, want), ((), [])):
            moving = pore_dem.moving_flat_walls(scene(loading=loading).settings, w)
            assert moving.dtype == bool and moving.tolist() == expect


SHAKEN = {"type": "cosine", "amplitude": 150.0, "frequency": 500.0}  # 15 um of base displacement in 400 steps


@pytest.mark.parametrize("moves", [None, "bottom", "box"])
def test_flat_walls_steps_match_the_reference_without_yade(moves):
    """The NumPy PoreDEM with flat walls (the law's wall contacts, the pores they close, the inflow
    and drained walls) follows the reference (step_beside_the_reference), written independently
    from SPEC §2.6, disc by disc: the wet box's particles settling under 1000 m/s^2 on an inflow
    bottom face, between an undrained left and a drained right face; fixed, or shaken by a cosine:
    the bottom sliding under the bed (moves = bottom), or the whole box, its side faces moving
    (moves = box). Were the feet of a moving wall at rest in either, or a face left behind, the
    positions would part."""
    from engines.model.pore_dem import PoreDEM as NumpyPoreDEM
    from engines.reference import model as ref
    water = {"enabled": True, "E_w": 240.0, "k1": 200.0, "k2": 2.0, "l_m": 1.3e-4, "q_w": 2e-3, "k3": 500.0}
    loading = {"loading": {**SHAKEN, "moves": moves}} if moves else {}
    s = scene(material={"g": 1000.0}, numerics={"dt": 1e-6, "rebuild_interval": 25},
              water=water, contact={"spring": "d", "eps_m": 2e-5, "f_max": 1.5, "separation_adjustment": True},
              **loading)
    pk = wet_box(seed=5, jitter=0.05).particles()
    lo, hi = pk.xz.min(axis=0) - pk.r.max() - 1e-5, pk.xz.max(axis=0) + pk.r.max() + 1e-5  # 10 um off the discs
    x0, x1, z0 = lo[0], hi[0], lo[1]
    walls = (FlatWall(1, z0, +1, "inflow"), FlatWall(0, x0, +1, "undrained"), FlatWall(0, x1, -1, "drained"))
    core = NumpyPoreDEM(s.settings, pk, walls)
    tables = s.as_dict()
    moving = pore_dem.moving_flat_walls(s.settings, walls)
    assert moving.tolist() == {None: [False] * 3, "bottom": [True, False, False], "box": [True] * 3}[moves]
    tables["walls"] = {"flat": as_tables(walls, moving)}
    model = ref.ReferenceModel(tables, pk)
    moved = step_beside_the_reference(core, model, s, pk, np.zeros(len(pk.r), bool))
    if moves:
        assert core.base.disp > 1e-5  # the walls moved by more than 10 um
        np.testing.assert_allclose(core.law.walls.shift[moving, 0], core.base.disp, rtol=1e-15)
        np.testing.assert_allclose([w.position for w in model.flat], core.water_model.wall_vertices.faces(),
                                   rtol=1e-12)
    np.testing.assert_allclose(core.water.total_water(), model.water.total(), rtol=1e-12)
    assert core.water_model.n_rebuilds == model.counts["rebuilds"] == 15 and moved > 0.01 * R
    normal, water_push = model.wall_reactions()
    np.testing.assert_allclose(core.water_model.F_walls, water_push, rtol=1e-9)
    contact = core.law.wall_forces()
    np.testing.assert_allclose(contact, normal - water_push, rtol=1e-9, atol=1e-12)
    assert contact[0] > 0 and water_push[0] > 0  # the bed rests on the bottom face, the water pushes it
    assert core.water.balance.inflow > 0 and core.water.balance.side_outflow > 0


def test_the_compiled_pore_dem_with_flat_walls_is_the_numpy_one():
    """engines.compiled.pore_dem.PoreDEM with flat walls (its law's contact loop and its water steps
    compiled, the builds NumPy) gives the NumPy PoreDEM's forces to round-off at every one of 400
    steps of the settling box of test_flat_walls_steps_match_the_reference_without_yade."""
    from engines.model.pore_dem import PoreDEM as NumpyPoreDEM
    water = {"enabled": True, "E_w": 240.0, "k1": 200.0, "k2": 2.0, "l_m": 1.3e-4, "q_w": 2e-3, "k3": 500.0}
    s = scene(material={"g": 1000.0}, numerics={"dt": 1e-6, "rebuild_interval": 25},
              water=water, contact={"spring": "d", "eps_m": 2e-5, "f_max": 1.5, "separation_adjustment": True})
    pk = wet_box(seed=5, jitter=0.05).particles()
    lo, hi = pk.xz.min(axis=0) - pk.r.max() - 1e-5, pk.xz.max(axis=0) + pk.r.max() + 1e-5
    walls = (FlatWall(1, lo[1], +1, "inflow"), FlatWall(0, lo[0], +1, "undrained"), FlatWall(0, hi[0], -1, "drained"))
    cores = [cls(s.settings, pk, walls) for cls in (NumpyPoreDEM, PoreDEM)]
    m, _ = disc_masses(s.settings, pk)
    x, v = pk.xz.copy(), np.zeros_like(pk.xz)
    for _ in range(400):
        (Fa, fa), (Fb, fb) = (core.step(x.copy()) for core in cores)
        np.testing.assert_allclose(Fb, Fa, rtol=1e-9, atol=1e-12 * np.abs(Fa).max())
        assert fa.keys() == fb.keys()
        for d, vel in fa.items():
            v[d] = vel
        v += (Fa / m[:, None] + [0.0, -s.material.g]) * s.numerics.dt
        x += v * s.numerics.dt
    assert cores[1].law.walls is not None and cores[1].kernel_drive_args(np.arange(3), np.zeros((3, 2)), 1) is None
    np.testing.assert_allclose(cores[1].law.wall_forces(), cores[0].law.wall_forces(), rtol=1e-9)
    np.testing.assert_allclose(cores[1].water.W, cores[0].water.W, rtol=1e-12)


@pytest.mark.parametrize("kind", ["discs", "flat"])
def test_weight_carried_by_wall_discs_or_flat_walls(kind):
    """A disc resting at its spring-a equilibrium (eq 26: kn (eps_m - gap) = m g) is carried whole;
    lifted out of the force range, by nothing. On wall discs it rests on top of one; on flat walls
    above the dip between two, out of the wall discs' reach, where only the flat face at their
    tops (which replaces them) carries it, meeting it at its foot. A second disc beside it, out of
    every reach, is carried by nothing: ``which`` picks the discs, the default takes both. The
    disc is heavy enough (f x its own density) to load its spring above f_max: the packing law is
    spring a, uncapped, whatever the scene's spring."""
    eps_m, kn, rho, g, f = 1e-4, 7e5, 2700.0, 9.81, 200.0
    sc = scene(contact={"spring": "c", "kn": kn, "eps_m": eps_m, "f_max": 1.0}, material={"rho": rho, "g": g},
               walls={"kind": kind})
    r, wall_r = 0.5e-3, 0.45e-3
    x = 0.0 if kind == "discs" else wall_r
    walls = np.column_stack([np.arange(-5, 6) * 2 * wall_r, np.zeros(11)])
    m = f * rho * np.pi * r ** 2
    assert kn * eps_m > m * g > sc.contact.f_max
    for gap, carried in ((eps_m - m * g / kn, 1.0), (2 * eps_m, 0.0)):
        xz = np.vstack([[x, wall_r + r + gap], [x + 4 * wall_r, wall_r + r + 3 * eps_m], walls])
        pk = Packing(xz, np.r_[r, r, np.full(11, wall_r)], np.r_[pg.WALL_NONE, pg.WALL_NONE, np.full(11, pg.WALL_BOTTOM)],
                     np.r_[f, 1.0, np.ones(11)])
        first, second = np.arange(13) == 0, np.arange(13) == 1
        assert weight_carried(sc.settings, pk, first) == pytest.approx(carried, abs=1e-9)
        assert weight_carried(sc.settings, pk, second) == 0.0
        assert weight_carried(sc.settings, pk) == pytest.approx(carried * f / (f + 1), abs=1e-9)


@pytest.mark.parametrize("compiled", [True, False])
def test_a_new_dt_reaches_the_law_and_the_water_and_is_checked_as_at_the_start(compiled):
    """set_dt (a script changing O.dt): the core, its law and its water step with the new dt; a dt
    above eq 52's limit or above the side-wall ties' limit (tests/model/test_limits.py) is refused,
    the old dt kept; with a ground motion, sampled at the scene's dt, any change is refused."""
    pk = wet_box()
    m_wall = disc_masses(scene().settings, pk)[0][pk.group == pg.WALL_LEFT].min()
    ks = m_wall / 2e-7**2   # the ties' limit: 2e-7 s
    core = PORE_DEM[compiled](scene(water={"enabled": True}, loading={"side_walls": "springs"}, contact={"ks_wall": ks},
                                    numerics={"dt": 1e-7}).settings, pk)
    core.set_dt(1.9e-7)
    assert core.dt == core.law.dt == core.water_model.dt == 1.9e-7
    for dt, limit in ((2.1e-7, "side-wall ties"), (1e-3, "eq 52")):
        with pytest.raises(ValueError, match=limit):
            core.set_dt(dt)
        assert core.dt == core.law.dt == core.water_model.dt == 1.9e-7
    shaken = PORE_DEM[compiled](scene(loading={"type": "cosine"}, numerics={"dt": 1e-7}).settings, pk)
    with pytest.raises(ValueError, match=r"dt cannot change during a run with a ground motion .* set \[numerics\] dt"):
        shaken.set_dt(0.5e-7)
    assert shaken.dt == shaken.law.dt == 1e-7
