"""One DEM step of the seed-000 model without YADE: contact law, spin, pores and pore water, loading.

With the paper's law, the YADE engine (engines.paper_law.PaperLawEngine, set up by
engines/yade_coupling.py) reads the disc centres in bulk, calls ``PoreDEM.step`` and writes the
forces back; YADE's NewtonIntegrator then integrates the translations
(v += F/m dt, x += v dt: eq 14-17) with gravity. The order within step k (t = k dt) is the
contract shared with the reference (engines/reference.py):

  a. du = x_t - x_{t-dt}, dpsi = omega dt (zero at k = 0)
  b. contact forces (engines.contact, eq 1-13)
  c. velocity adjustment of discs that became free (eq 18-24)
  d. water: pores rebuilt when k > 0 and k % rebuild_interval == 0; water advanced when
     k % water_interval == 0 by water_interval dt at the areas of x_t; pressure forces (eq 33)
     recomputed then and held in between
  e. spin: omega += M/I dt (the one rotational degree of freedom of a disc in the x-z plane;
     it lives in the law, computed in b's call and independent of d)
  f. moving walls: v_w += a(t) dt
Gravity -m g and buoyancy +rho_w pi r^2 g (water scenes: the buoyant weight of eq 34b) are
constant and applied by the caller (YADE: NewtonIntegrator gravity and permanent forces).
"""
import numpy as np

from engines import pore_geometry as pg
from engines.contact import critical_time_step
from engines.ground_motion import Cosine, Sampled
from engines.paper_law import PaperLaw
from engines.trajectory import block_means
from engines.water_engine import WaterModel

G0 = 9.80665  # standard gravity for records given in g [m/s^2]


def disc_masses(scene, packing):
    """Mass rho f pi r^2 [kg per m thickness] and moment of inertia m r^2/2 (SPEC §1, eq 15)."""
    m = scene.material.rho * packing.density_factor * np.pi * packing.r**2
    return m, 0.5 * m * packing.r**2


def check_time_step(scene, mobile_mass):
    """Refuse dt above dt_safety x 2 sqrt(m_min / kn) (eq 52)."""
    dt = scene.numerics.dt
    limit = scene.numerics.dt_safety * critical_time_step(mobile_mass, scene.contact.kn)
    if dt > limit:
        raise ValueError(f"[numerics] dt = {dt:.3e} s exceeds the stability limit {limit:.3e} s "
                         f"(dt_safety x 2 sqrt(m_min/kn), eq 52)")


def moving_walls(scene, packing):
    """(N,) bool: the wall discs that follow the input acceleration ([loading] moves)."""
    if scene.loading.type == "none":
        return np.zeros(len(packing.r), bool)
    groups = {"bottom": [pg.WALL_BOTTOM], "box": [pg.WALL_BOTTOM, pg.WALL_LEFT, pg.WALL_RIGHT]}[scene.loading.moves]
    return np.isin(packing.group, groups)


def water_model(scene, packing, compiled=True):
    """The scene's WaterModel on the packing's discs (true radii), or None for a dry scene."""
    settings = scene.water_settings()
    if settings is None:
        return None
    num = scene.numerics
    return WaterModel(settings, packing.r, packing.group, packing.xz, scene.contact.eps_m, scene.water.l_m,
                      num.dt, num.rebuild_interval, num.water_interval, compiled)


def pore_state(water, xz, r):
    """(network, measures, U) of PoreWater ``water`` at xz, or None for a dry scene."""
    if water is None:
        return None
    m = pg.measure(water.net, xz, r)
    return water.net, m, water.pressure(m.void_area)


def block_pressures(water, xz, r, bounds):
    """Mean excess pore pressure of each output block [N/m] (nan where no pore or dry)."""
    state = pore_state(water, xz, r)
    if state is None:
        return np.full(len(bounds), np.nan)
    net, _, U = state
    return block_means(pg.pore_centroids(net, xz)[:, 1], U, bounds)


def porosity(scene, packing, xz):
    """Void / polygon area of the pores of a freshly built network at xz (the same for dry and
    wet scenes; eq 28 with the scene's l_m)."""
    net = pg.build_pores(xz, packing.r, eps_m=scene.contact.eps_m, l_m=scene.water.l_m, walls=packing.group)
    m = pg.measure(net, xz, packing.r)
    total = m.polygon_area.sum()
    return float(m.void_area.sum() / total) if total > 0 else np.nan


def kinetic_energy(mass, inertia, mobile, vel, omega):
    """Translational + rotational kinetic energy of the mobile discs [J per m]."""
    v2 = np.sum(vel**2, axis=1)
    return float(0.5 * np.sum(mass[mobile] * v2[mobile]) + 0.5 * np.sum(inertia[mobile] * omega[mobile] ** 2))


def input_acceleration(scene):
    """Horizontal acceleration a(t) [m/s^2] of the moving walls, or None without loading."""
    ld = scene.loading
    if ld.type == "none":
        return None
    if ld.type == "cosine":
        return Cosine(ld.amplitude, ld.frequency)
    try:
        rec = np.loadtxt(ld.record, comments="#", ndmin=2)
    except OSError as e:
        raise ValueError(f"[loading] record: cannot read {ld.record}: {e}") from None
    t_rec, a_rec = rec[:, 0] * ld.time_scale, rec[:, 1] * G0 * ld.amplitude_scale
    return Sampled(t_rec, a_rec, left=None)


class PoreDEM:
    """State and per-step work of one scene (see the module docstring for the order).

    ``law``: the paper's contact law (engines.paper_law.PaperLaw); ``water_model``: the pores and
    water (engines.water_engine.WaterModel) or None for a dry scene. ``compiled=False`` runs the
    readable NumPy path of both (the compiled kernels are tested against it)."""

    def __init__(self, scene, packing, compiled=True):
        self.scene, self.packing = scene, packing
        self.r = packing.r
        self.mobile = packing.mobile
        self.mass, self.inertia = disc_masses(scene, packing)
        self.dt = scene.numerics.dt
        check_time_step(scene, self.mass[self.mobile])
        if scene.numerics.damping_eq44:
            raise ValueError("[numerics] damping_eq44: not available in the YADE path (NewtonIntegrator "
                             "moves x by v dt); the reference implements it")
        self.law = PaperLaw(scene.contact_settings(), self.r, self.mobile, self.mass, self.inertia, self.dt, compiled)
        self.k = 0
        self.accel = input_acceleration(scene)
        self.wall_velocity = 0.0
        self.water_model = water_model(scene, packing, compiled)

    @property
    def water(self):
        """The PoreWater state (W, network, balance), or None for a dry scene."""
        return None if self.water_model is None else self.water_model.water

    @property
    def contact(self):
        return self.law.contact

    @property
    def omega(self):
        return self.law.omega

    @property
    def du(self):
        return self.law.du

    # -- per step -------------------------------------------------------------------------------
    def step(self, xz, vel=None):
        """Forces (N, 2) [N] at positions xz (N, 2) of step k, and {disc: new velocity} (eq 18-24).

        ``vel`` (N, 2): current velocities if the caller has them; else du/dt is used.
        """
        F, fixes = self.law.step(xz, vel)                               # a, b, c, e
        if self.water_model is not None:                                # d
            self.water_model.step(self.k, xz)
            F = F + self.water_model.F
        if self.accel is not None:                                      # f
            self.wall_velocity += self.accel(self.k * self.dt) * self.dt
        self.k += 1
        return F, fixes
