"""One DEM step of the seed-000 model without YADE: contact law, spin, pores and pore water, loading.

With the paper's law, the YADE engine (engines.yade.paper_law_engine.PaperLawEngine, set up by
engines/yade/coupling.py) reads the disc centres in bulk, calls ``PoreDEM.step`` and writes the
forces back; YADE's NewtonIntegrator then integrates the translations
(v += F/m dt, x += v dt: eq 14-17) with gravity. The order within step k (t = k dt) is the
contract shared with the reference (engines/reference/model.py):

  a. du = x_t - x_{t-dt}, dpsi = omega dt (zero at k = 0)
  b. contact forces (engines.model.contact, eq 1-13)
  c. velocity adjustment of discs that became free (eq 18-24)
  d. water, when engines.model.schedule.Schedule says (``PoreDEM.schedule``): pores rebuilt at
     k = n rebuild_interval (n >= 1), or with [numerics] rebuild_distance > 0 when a disc has moved
     that far since the last build; water advanced at k = j water_interval by water_interval dt at
     the areas of x_t; pressure forces (eq 33) recomputed then and held in between
  e. spin: omega += M/I dt (the one rotational degree of freedom of a disc in the x-z plane;
     it lives in the law, computed in b's call and independent of d)
  f. moving walls: the base motion (engines.model.ground_motion.BaseMotion, constant average
     acceleration) is advanced from t to t + dt; ``wall_velocity`` = (u(t + dt) - u(t)) / dt is the
     velocity the caller gives the driven walls for this step, so x += v dt lands them on u(t + dt).
     Flat walls that follow the input (``moving_flat_walls``) are translated to u(t + dt) in x
     (the law's and the pores' walls: PaperLaw.move_walls, WaterModel.move_walls), where the
     caller's driven walls land
Side walls on springs ([loading] side_walls = "springs", Fig. 27): the side-wall discs move in x
under the contact forces, the pore pressure forces of eq 33 (they bound pores like any disc) and
the ties of engines.model.side_walls (added to the law's forces in b, with the tie velocities du/dt of
this step); the caller integrates them in x only.
The settings are engines.model.settings.Settings (a validated scene's ``settings``), typed by table.
Gravity -m g and buoyancy +rho_w pi r^2 g (water scenes: the buoyant weight of eq 34b) are
constant and applied by the caller (YADE: NewtonIntegrator gravity and permanent forces).
"""
import numpy as np

from engines.model import groups, ground_motion, limits
from engines.model import pores as pg
from engines.model.contact import ContactLaw, ContactSettings
from engines.model.flat_walls import FlatWall
from engines.model.observe import block_means, box_window, porosity
from engines.model.paper_law import PaperLaw
from engines.model.schedule import Schedule
from engines.model.side_walls import SideWallTies
from engines.model.water_model import WaterModel


def disc_masses(settings, packing):
    """Mass rho f pi r^2 [kg per m thickness] and moment of inertia m r^2/2 (SPEC §1, eq 15)."""
    m = settings.material.rho * packing.density_factor * np.pi * packing.r**2
    return m, 0.5 * m * packing.r**2


def weight_carried(settings, packing, which=None):
    """The vertical force of the normal springs (the packing law: spring a, eps_m of the settings) on
    the discs ``which`` (a mask; default: every mobile disc) at the packing's positions, over their
    weight: ~1 when they rest on the others and the walls. Of every mobile disc: the overburden the
    walls carry; of the discs above a depth: the overburden the discs below carry; of the denser top:
    ~1 when the packing starts at rest under it ([packing] settle_loaded), ~1/dense_top_factor when
    it was settled before the top was marked. With [walls] kind = "flat" the flat walls replace the
    wall discs, each meeting a disc as a wall disc of radius 0 at the disc's foot (engines.model.paper_law)."""
    which = packing.mobile if which is None else which
    weight = float((disc_masses(settings, packing)[0][which] * settings.material.g).sum())
    c = settings.contact
    xz, r, mobile = packing.xz, packing.r, packing.mobile
    walls = scene_flat_walls(settings, packing)
    if walls:
        m = np.flatnonzero(mobile)
        feet = []
        for w in walls.values():
            f = xz[m[w.gap(xz[m], r[m]) <= c.eps_m]].copy()
            f[:, w.axis] = w.position
            feet.append(f)
        xz = np.vstack([xz[m]] + feet)
        r = np.concatenate([r[m], np.zeros(len(xz) - len(m))])
        mobile = np.arange(len(xz)) < len(m)
        which = np.concatenate([which[m], np.zeros(len(xz) - len(m), bool)])
    # at rest (du = 0): no dashpot and no shear force, the normal springs alone
    law = ContactLaw(ContactSettings(spring="a", kn=c.kn, eps_m=c.eps_m), r, mobile)
    F, _, _ = law.forces(xz, np.zeros_like(xz), np.zeros(len(r)), settings.numerics.dt)
    return float(F[which, 1].sum()) / weight


def side_wall_ties(settings, packing):
    """The Fig. 27 ties of the side-wall columns (engines.model.side_walls.SideWallTies) when
    [loading] side_walls = "springs", else None."""
    if settings.loading.side_walls != "springs":
        return None
    c = settings.contact
    return SideWallTies(packing.xz, packing.group, c.ks_wall, c.eta_s_wall)


def moving_walls(settings, packing):
    """(N,) bool: the wall discs that follow the input acceleration ([loading] moves)."""
    if settings.loading.type == "none":
        return np.zeros(len(packing.r), bool)
    groups = {"bottom": [pg.WALL_BOTTOM], "box": list(pg.WALL_NAMES)}[settings.loading.moves]
    return np.isin(packing.group, groups)


def moving_flat_walls(settings, flat_walls):
    """(W,) bool: the flat walls (FlatWall, ...) that follow the input acceleration ([loading]
    moves = "bottom": the bottom face, z = const below the discs; "box": every wall)."""
    if settings.loading.type == "none":
        return np.zeros(len(flat_walls), bool)
    if settings.loading.moves == "box":
        return np.ones(len(flat_walls), bool)
    return np.array([w.axis == 1 and w.inward == 1 for w in flat_walls], bool)


def scene_flat_walls(settings, packing):
    """{wall code: FlatWall} of [walls] kind = "flat", {} for kind = "discs": each wall-disc group of
    the packing replaced by a flat wall at its inner face (Packing.inner_faces), moved back to the
    outermost particle where one reaches past it by more than ``rest_overlap`` (a particle resting in
    the dip between two wall discs would start overlapping the face; one pressed into the face by
    the bed's weight rests on it: deposition.settle_on_flat_walls leaves its packing so); the bottom
    is an inflow wall when [water] q_w or inflow_velocity is > 0, the sides
    drain when [water] sides = "drained", else undrained."""
    if settings.walls.kind != "flat":
        return {}
    w = settings.water
    inflow = w.q_w > 0 or w.inflow_velocity > 0
    m = packing.mobile
    tolerance = rest_overlap(settings, packing)
    walls = {}
    for code, face in sorted(packing.inner_faces().items()):
        name = pg.WALL_NAMES[code]  # its face and its word: engines.model.groups
        (axis, inward), boundary = groups.kind(name).face, groups.flat_word(name, w.sides, inflow)
        reach = float(np.min(inward * packing.xz[m, axis] - packing.r[m]))  # the outermost particle, inward * its edge
        at = inward * face if reach > inward * face - tolerance else reach
        walls[code] = FlatWall(axis, inward * at, inward, boundary)
    return walls


def rest_overlap(settings, packing):
    """The overlap [m] of a contact carrying the whole weight of the packing's particles, W / kn: no
    contact at rest overlaps a wall more."""
    weight = float(disc_masses(settings, packing)[0][packing.mobile].sum()) * settings.material.g
    return weight / settings.contact.kn


def water_model(settings, packing, cls=WaterModel, flat_walls=()):
    """The WaterModel of ``settings`` (``cls``: engines.model.water_model.WaterModel or its compiled twin) on
    the packing's discs (true radii) and the flat walls, or None for a dry scene."""
    water = settings.water_settings()
    if water is None:
        return None
    num = settings.numerics
    return cls(water, packing.r, packing.group, packing.xz, settings.contact.eps_m, settings.water.l_m,
               num.dt, Schedule(num.water_interval, num.rebuild_interval, num.rebuild_distance),
               flat_walls=flat_walls)


def pore_state(water_model, xz):
    """(network, void areas (Np,) [m^2], U (Np,) [N/m]) of the pores of ``water_model`` (WaterModel)
    at centres xz (eq 29, 32: one measure of these positions), or None for a dry scene."""
    if water_model is None:
        return None
    A = water_model.void_area(xz)
    return water_model.water.net, A, water_model.water.pressure(A)


def block_pressures(water_model, xz, bounds):
    """Mean excess pore pressure of each output block [N/m] at centres xz (nan where no pore or dry)."""
    state = pore_state(water_model, xz)
    if state is None:
        return np.full(len(bounds), np.nan)
    net, _, U = state
    return block_means(pg.pore_centroids(net, xz)[:, 1], U, bounds)


def porosity_window(settings, packing, faces=None):
    """The fixed rectangle whose void fraction is the reported porosity ([output] porosity_window,
    engines.model.observe.box_window) in the box of ``faces`` {wall code: position [m]} (default: the
    wall discs' inner faces, Packing.inner_faces), or None for a box without both side walls."""
    faces = packing.inner_faces() if faces is None else faces
    if not (pg.WALL_LEFT in faces and pg.WALL_RIGHT in faces):
        return None
    return box_window(packing, settings.output.porosity_window, faces)


def window_porosity(packing, window, xz, base_disp=0.0):
    """Void fraction of ``window`` moved with the base by ``base_disp`` [m] around the particles
    at xz (exact disc-rectangle areas; independent of the pore mesh); nan without a window."""
    if window is None:
        return np.nan
    mob = packing.mobile
    return porosity(xz[mob], packing.r[mob], window.shifted(base_disp))


def kinetic_energy(mass, inertia, mobile, vel, omega):
    """Translational + rotational kinetic energy of the mobile discs [J per m]."""
    v2 = np.sum(vel**2, axis=1)
    return float(0.5 * np.sum(mass[mobile] * v2[mobile]) + 0.5 * np.sum(inertia[mobile] * omega[mobile] ** 2))


class PoreDEM:
    """State and per-step work of one run of ``settings`` (engines.model.settings.Settings) on
    ``packing`` (see the module docstring for the order).

    ``law``: the paper's contact law (engines.model.paper_law.PaperLaw); ``water_model``: the pores and
    water (engines.model.water_model.WaterModel) or None for a dry scene: the readable NumPy path of
    both. Its compiled twin engines.compiled.pore_dem.PoreDEM (tested against it) runs the compiled
    law and water and offers the whole step as one kernel call. ``flat_walls``:
    engines.model.flat_walls.FlatWall, ... (SPEC §2.6): the law's contacts with them and the pores
    they close (the compiled twin runs them too, each step by ``step``, not one kernel call); those
    that follow the input move with the base (f)."""

    law_class, water_class = PaperLaw, WaterModel  # of ``law`` and ``water_model``
    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("law", "k", "base", "wall_velocity", "water_model", "ties")
    CHECKPOINT_DERIVED = {**{name: "the scene and the packing" for name in
                             ("settings", "packing", "r", "mobile", "mass", "inertia", "dt", "moving_flat")},
                          "schedule": "its water model's (stored there), or a dry scene's, which holds no state"}

    def __init__(self, settings, packing, flat_walls=()):
        self.settings, self.packing = settings, packing
        self.r = packing.r
        self.mobile = packing.mobile
        self.mass, self.inertia = disc_masses(settings, packing)
        self.dt = settings.numerics.dt
        num = settings.numerics
        limits.check_contact(self.dt, num.dt_safety, self.mass[self.mobile], settings.contact.kn)
        self.law = self.law_class(settings.contact_settings(), self.r, self.mobile, self.mass, self.inertia, self.dt,
                                  flat_walls)
        self.k = 0
        accel = ground_motion.input_acceleration(settings)
        self.base = None if accel is None else ground_motion.BaseMotion(accel, self.dt)
        self.wall_velocity = 0.0
        self.moving_flat = moving_flat_walls(settings, tuple(flat_walls)) if self.base is not None else None
        self.ties = side_wall_ties(settings, packing)
        limits.check_ties(self.dt, self.ties, self.mass)
        self.water_model = water_model(settings, packing, self.water_class, flat_walls)
        # what happens at step k: the water model's schedule, or a dry scene's (output events only)
        self.schedule = Schedule(rebuild_interval=None) if self.water_model is None else self.water_model.schedule

    def set_dt(self, dt):
        """Step with dt [s] from now on: the limits of the start (eq 52, the side-wall ties) checked
        again, the law and the water follow; refused with a ground motion, whose input is sampled
        at the scene's dt from step 0."""
        if self.base is not None:
            raise ValueError(f"dt cannot change during a run with a ground motion ([loading] type = "
                             f"{self.settings.loading.type!r} is sampled at dt = {self.dt:g} s from step 0): "
                             f"set [numerics] dt in the scene instead")
        limits.check_contact(dt, self.settings.numerics.dt_safety, self.mass[self.mobile], self.settings.contact.kn)
        limits.check_ties(dt, self.ties, self.mass)
        self.law.set_dt(dt)
        self.dt = self.law.dt
        if self.water_model is not None:
            self.water_model.set_dt(dt)

    def _tie_forces(self, xz, du):
        """(N, 2) x-forces [N] of the side-wall ties at centres xz, velocities du / dt."""
        F = np.zeros_like(xz)
        F[:, 0] = self.ties.forces(xz[:, 0], du[:, 0] / self.dt)
        return F

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
        if self.ties is not None:                                       # b: side-wall ties
            F = F + self._tie_forces(xz, self.law.du)
        if self.water_model is not None:                                # d
            self.water_model.step(self.k, xz)
            F = F + self.water_model.F
        self._move_walls()
        return F, fixes

    def _shift_flat_walls(self):
        """Translate the flat walls that follow the input to the base displacement in x."""
        if self.moving_flat is None or not self.moving_flat.any():
            return
        shift = np.zeros((len(self.moving_flat), 2))
        shift[self.moving_flat, 0] = self.base.disp
        self.law.move_walls(shift)
        if self.water_model is not None:
            self.water_model.move_walls(shift)

    def _move_walls(self):
        if self.base is not None:                                       # f
            self.wall_velocity = self.base.step()
            self._shift_flat_walls()
        self.k += 1
