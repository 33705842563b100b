"""One DEM step of the seed-000 model without YADE: contact law, spin, pores and pore water, loading.

The YADE engine (engines/yade_coupling.py) reads the disc centres in bulk, calls ``PoreDEM.step``
and writes the forces back; YADE's NewtonIntegrator then integrates the translations
(v += F/m dt, x += v dt: eq 14-17) with gravity. The order within step k (t = k dt) is the
contract shared with the reference (engines/reference.py):

  a. du = x_t - x_{t-dt}, dpsi = omega dt (zero at k = 0)
  b. contact forces (engines.contact, eq 1-13)
  c. velocity adjustment of discs that became free (eq 18-24)
  d. water: pores rebuilt when k > 0 and k % rebuild_interval == 0; water advanced when
     k % water_interval == 0 by water_interval dt at the areas of x_t; pressure forces (eq 33)
     recomputed then and held in between
  e. spin: omega += M/I dt (the one rotational degree of freedom of a disc in the x-z plane;
     YADE offers no bulk read of angular velocities, so the spin lives here)
  f. moving walls: v_w += a(t) dt
Gravity -m g and buoyancy +rho_w pi r^2 g (water scenes: the buoyant weight of eq 34b) are
constant and applied by the caller (YADE: NewtonIntegrator gravity and permanent forces).
"""
import numpy as np

from engines import pore_geometry as pg
from engines.contact import ContactLaw, critical_time_step, separation_adjustment
from engines.pore_water import PoreWater
from engines.trajectory import block_means

G0 = 9.80665  # standard gravity for records given in g [m/s^2]


def disc_masses(scene, packing):
    """Mass rho f pi r^2 [kg per m thickness] and moment of inertia m r^2/2 (SPEC §1, eq 15)."""
    m = scene.material.rho * packing.density_factor * np.pi * packing.r**2
    return m, 0.5 * m * packing.r**2


def input_acceleration(scene):
    """Horizontal acceleration a(t) [m/s^2] of the moving walls, or None without loading."""
    ld = scene.loading
    if ld.type == "none":
        return None
    if ld.type == "cosine":
        return lambda t: ld.amplitude * np.cos(2 * np.pi * ld.frequency * t)
    try:
        rec = np.loadtxt(ld.record, comments="#", ndmin=2)
    except OSError as e:
        raise ValueError(f"[loading] record: cannot read {ld.record}: {e}") from None
    t_rec, a_rec = rec[:, 0] * ld.time_scale, rec[:, 1] * G0 * ld.amplitude_scale
    return lambda t: float(np.interp(t, t_rec, a_rec, right=0.0))


class PoreDEM:
    """State and per-step work of one scene (see the module docstring for the order)."""

    def __init__(self, scene, packing):
        self.scene, self.packing = scene, packing
        self.r = packing.r
        self.mobile = packing.mobile
        self.mass, self.inertia = disc_masses(scene, packing)
        self.dt = scene.numerics.dt
        limit = scene.numerics.dt_safety * critical_time_step(self.mass[self.mobile], scene.contact.kn)
        if self.dt > limit:
            raise ValueError(f"[numerics] dt = {self.dt:.3e} s exceeds the stability limit {limit:.3e} s "
                             f"(dt_safety x 2 sqrt(m_min/kn), eq 52)")
        if scene.numerics.damping_eq44:
            raise ValueError("[numerics] damping_eq44: not available in the YADE path (NewtonIntegrator "
                             "moves x by v dt); the reference implements it")
        self.contact = ContactLaw(scene.contact_settings(), self.r, self.mobile)
        self.omega = np.zeros(len(self.r))
        self.xz_prev = None
        self.du = np.zeros((len(self.r), 2))
        self.k = 0
        self.accel = input_acceleration(scene)
        moving = {"bottom": [pg.WALL_BOTTOM], "box": [pg.WALL_BOTTOM, pg.WALL_LEFT, pg.WALL_RIGHT]}[scene.loading.moves]
        self.moving = np.isin(packing.group, moving) if self.accel else np.zeros(len(self.r), bool)
        self.wall_velocity = 0.0
        self.block_bounds = packing.block_bounds(scene.output.block_z)
        self.water = None
        self.F_pressure = np.zeros((len(self.r), 2))
        self.n_rebuilds = 0
        settings = scene.water_settings()
        if settings is not None:
            net = self._build(packing.xz)
            self.water = PoreWater(net, pg.measure(net, packing.xz, self.r).void_area, settings)

    # -- per step -------------------------------------------------------------------------------
    def _build(self, xz):
        c, w = self.scene.contact, self.scene.water
        return pg.build_pores(xz, self.r, eps_m=c.eps_m, l_m=w.l_m, walls=self.packing.group)

    def step(self, xz, vel=None):
        """Forces (N, 2) [N] at positions xz (N, 2) of step k, and {disc: new velocity} (eq 18-24).

        ``vel`` (N, 2): current velocities if the caller has them; else du/dt is used.
        """
        dt, num = self.dt, self.scene.numerics
        self.du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev
        F, M, separations = self.contact.forces(xz, self.du, self.omega * dt, dt)
        fixes = {}
        if separations and self.scene.contact.separation_adjustment:
            v = self.du / dt if vel is None else vel
            fixes = separation_adjustment(separations, self.contact.touch_count(), v, self.mass, self.mobile,
                                          self.scene.contact.restitution)
        if self.water is not None:
            if self.k > 0 and self.k % num.rebuild_interval == 0:
                self.rebuild(xz)
            if self.k % num.water_interval == 0:
                m = pg.measure(self.water.net, xz, self.r)
                self.water.advance(num.water_interval * dt, m.void_area, m.link_contact)
                A = self.water.A_prev if self.water.settings.smoothing else m.void_area  # eq 45: the area used
                self.F_pressure = pg.pressure_forces(self.water.net, self.r, self.water.pressure(A), m)
            F = F + self.F_pressure
        self.omega[self.mobile] += M[self.mobile] / self.inertia[self.mobile] * dt  # eq 14c, 16c
        if self.accel is not None:
            self.wall_velocity += self.accel(self.k * dt) * dt
        self.k += 1
        self.xz_prev = xz
        return F, fixes

    def rebuild(self, xz):
        """Rebuild the pores at xz and move the water onto them (§3.4(2))."""
        old = self.water.net
        new = self._build(xz)
        self.water.remesh(new, pg.measure(new, xz, self.r).void_area, pg.measure(old, xz, self.r).void_area)
        self.n_rebuilds += 1

    # -- observations -----------------------------------------------------------------------------
    def pore_state(self, xz):
        """(network, measures, U) of the water at xz, or None for a dry scene."""
        if self.water is None:
            return None
        m = pg.measure(self.water.net, xz, self.r)
        return self.water.net, m, self.water.pressure(m.void_area)

    def block_pressures(self, xz):
        """Mean excess pore pressure of each output block [N/m] (nan where no pore)."""
        state = self.pore_state(xz)
        if state is None:
            return np.full(len(self.block_bounds), np.nan)
        net, _, U = state
        return block_means(pg.pore_centroids(net, xz)[:, 1], U, self.block_bounds)

    def porosity(self, xz):
        """Void / polygon area of the pores of a freshly built network at xz (the same for dry
        and wet scenes; eq 28 with the scene's l_m)."""
        net = self._build(xz)
        m = pg.measure(net, xz, self.r)
        total = m.polygon_area.sum()
        return float(m.void_area.sum() / total) if total > 0 else np.nan

    def kinetic_energy(self):
        """Translational + rotational kinetic energy of the particles [J per m], from du/dt."""
        v2 = np.sum((self.du / self.dt) ** 2, axis=1)
        mob = self.mobile
        return float(0.5 * np.sum(self.mass[mob] * v2[mob]) + 0.5 * np.sum(self.inertia[mob] * self.omega[mob] ** 2))

    def bottom_normal_force(self, xz):
        """Mean normal force [N] of the touching pairs whose midpoint lies in the first block."""
        pairs, fn = self.contact.contact_pairs()
        if len(fn) == 0:
            return 0.0
        zmid = 0.5 * (xz[pairs[:, 0], 1] + xz[pairs[:, 1], 1])
        z0, z1 = self.block_bounds[0]
        sel = (zmid >= z0) & (zmid < z1)
        return float(fn[sel].mean()) if sel.any() else 0.0
