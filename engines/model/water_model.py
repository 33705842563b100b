"""The pores and water of N discs stepping, without YADE (seed 000 §3, eq 28-46).

``WaterModel`` builds the pore network (engines.model.pores), holds the water
(engines.model.pore_water) and advances it by water steps through the readable NumPy functions; its
compiled twin engines.compiled.water_model.WaterModel does the same through kernels. The
paper's step order (engines.model.pore_dem) and the YADE water engine (engines.yade.water_engine)
both step it.

Stability: every water step is checked against its Darcy limit (engines.model.limits): the bound
is one more pass over throats and pores inside the flow kernel (measured at a few per cent of a
water step), about what testing whether the areas changed enough to need a new check would cost,
so the check is exact at every step instead. Above it the step is sub-stepped with
``settings.substep`` and refused without.

Rebuilds: one schedule (``WaterModel.rebuild_due``), every ``rebuild_interval`` steps
(``rebuild_due``, the paper's) and, with ``rebuild_distance`` d > 0 (SPEC §2.6), also as soon as a
disc is more than d from its centre at the last build (YADE's collider keeps its Verlet lists so)
or a measured void area leaves its range (``areas_in_range``; eq 32 would put U above E_w); the
interval is then an upper bound.
"""
import numpy as np

from engines.model import flat_walls as fw
from engines.model import pores as pg
from engines.model.pore_water import NUMPY_REMESH, PoreWater


def rebuild_due(k, k_built, k0, interval):
    """Is a pore rebuild due at step k, the pores last built at step k_built (§3.4(2)): has a
    multiple of ``interval`` steps counted from the start k0 been reached since? Asked at every
    step (the paper's law) this rebuilds at exactly k0 + n interval; asked at water steps only
    (the YADE law's engine) at the first water step at or after each of them."""
    return (k - k0) // interval > (k_built - k0) // interval


def steps_to_rebuild(k, k_built, k0, interval, call_interval):
    """Steps from step k to the first step, among those k0 + j call_interval, at which
    ``rebuild_due`` holds."""
    due = k0 + ((k_built - k0) // interval + 1) * interval  # the next multiple after the last build
    t = max(k, due)
    return t + (k0 - t) % call_interval - k


def areas_in_range(void, poly):
    """Are the void areas A (Np,) [m^2] in their range 0 <= A <= polygon area poly (Np,)? Below 0
    the discs cover more than their pore's polygon, above it a sector is negative (a disc has
    crossed a link): the pores no longer describe the discs. Every pore has A > a_min > 0 at its
    build (engines.model.pores), so a rebuild brings the areas back into range."""
    return bool(np.all((void >= 0) & (void <= poly)))


class WaterModel:
    """Pores and water of N discs (no YADE). Units: SI per unit thickness (engines.model.pore_water).

    r (N,) radii [m] (the true ones: pores use them even where a contact law enlarges them by
    eps_m/2); walls (N,) wall codes of engines.model.pores; xz (N, 2) initial centres [m], those
    of DEM step k0. ``F`` (N, 2) [N] holds the pressure forces of the last water step; ``k_built``
    is the step of the last pore build (``rebuild_due``) and ``xz_built`` its centres.
    rebuild_distance [m]: > 0 also rebuilds when a disc has moved more than this since the last
    build or a void area is out of range (0: off, the interval only). flat_walls:
    engines.model.flat_walls.FlatWall, ... (SPEC §2.6); ``F_walls`` (W,) [N/m] holds the pore
    water's normal force on each of them (pores.flat_wall_forces) of the last water step.
    """

    build_steps, remesh_steps = pg.NUMPY_BUILD, NUMPY_REMESH  # of build_pores and PoreWater.remesh
    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("wall_vertices", "F", "F_walls", "n_rebuilds", "k0", "k_built", "substeps_max",
                         "substeps_total", "last_limit", "xz_built", "water")
    CHECKPOINT_DERIVED = {name: "the scene's [water] and [numerics], the packing's discs and flat walls" for name in
                          ("settings", "eps_m", "l_m", "flat_walls", "r", "walls", "dt", "rebuild_interval",
                           "water_interval", "rebuild_distance")} | {"log": "the print function"}

    def __init__(self, settings, r, walls, xz, eps_m, l_m, dt, rebuild_interval=1000, water_interval=1,
                 log=print, k0=0, rebuild_distance=0.0, flat_walls=()):
        self.settings, self.eps_m, self.l_m = settings, float(eps_m), float(l_m)
        self.flat_walls = tuple(flat_walls)
        self.r = np.ascontiguousarray(r, float)
        # one WallVertices for every build, so that the walls' shift (move_walls) holds across rebuilds
        self.wall_vertices = fw.WallVertices(self.flat_walls, len(self.r)) if self.flat_walls else None
        self.walls = np.asarray(walls, np.int64)
        self.dt, self.rebuild_interval, self.water_interval = float(dt), int(rebuild_interval), int(water_interval)
        if self.rebuild_interval < 1 or self.water_interval < 1:
            raise ValueError(f"rebuild_interval and water_interval must be >= 1, got "
                             f"{rebuild_interval}, {water_interval}")
        self.rebuild_distance = float(rebuild_distance)
        if not self.rebuild_distance >= 0:
            raise ValueError(f"rebuild_distance must be >= 0 [m], got {rebuild_distance}")
        self.log = log
        self.F = np.zeros((len(self.r), 2))
        self.F_walls = np.zeros(len(self.flat_walls))
        self.n_rebuilds = 0
        self.k0 = self.k_built = int(k0)
        self.substeps_max = self.substeps_total = 0
        self.last_limit = np.inf  # Darcy limit of the last water step [s]
        self.xz_built = np.array(xz, float)
        net = self._build(xz)
        self.water = PoreWater(net, pg.measure(net, xz, self.r).void_area, settings)

    def checkpoint_restored(self):
        """Refuse stored water that does not fit its network or these discs."""
        w, n_p = self.water, self.water.net.n_pores
        if w.net.n_discs != len(self.r):
            raise ValueError(f"the pore network is of {w.net.n_discs} discs, the run has {len(self.r)}")
        if w.W.shape != (n_p,) or w.A_prev.shape != (n_p,) or w.rule.shape != (n_p,):
            raise ValueError(f"water: W, A_prev and rule must be one per pore ({n_p})")
        if w.q_prev is not None and w.q_prev.shape != (len(w.net.throat_conns),):
            raise ValueError(f"water: q_prev must be one per throat ({len(w.net.throat_conns)})")

    def _build(self, xz):
        return pg.build_pores(xz, self.r, eps_m=self.eps_m, l_m=self.l_m, walls=self.walls, steps=self.build_steps,
                              flat_walls=self.wall_vertices or ())

    def move_walls(self, shift):
        """Translate the flat walls to the displacements ``shift`` (W, 2) [m] from their FlatWall
        positions (flat_walls.WallVertices.move): the faces of the next measure and build."""
        self.wall_vertices.move(shift)

    # -- per step ---------------------------------------------------------------------------------
    def rebuild_due(self, k, xz=None):
        """Is a pore rebuild due at step k (``rebuild_due``), or, with rebuild_distance > 0 and the
        centres xz (N, 2) [m] of step k given, has a disc moved more than rebuild_distance since
        the last build?"""
        if rebuild_due(k, self.k_built, self.k0, self.rebuild_interval):
            return True
        d = self.rebuild_distance
        return xz is not None and d > 0 and self.max_sq_moved(xz) > d * d

    def max_sq_moved(self, xz):
        """max over the discs of |xz - xz_built|^2 [m^2]."""
        return float(np.max(np.sum((xz - self.xz_built) ** 2, axis=1)))

    def step(self, k, xz):
        """Step k of the DEM at centres xz (N, 2) [m]: rebuild when due (at k0 + n rebuild_interval,
        or by displacement or an area out of range), advance when k % water_interval == 0. Returns True when ``F`` was
        recomputed."""
        if self.rebuild_due(k, xz):
            self.rebuild(xz, k)
        if k % self.water_interval != 0:
            return False
        self.advance(self.water_interval * self.dt, xz, k)
        return True

    def rebuild(self, xz, k=None):
        """Rebuild the pores at xz, those of step k (None: the schedule is left as it was), and move
        the water onto them (§3.4(2))."""
        old, new = self.water.net, self._build(xz)
        self.water.remesh(new, self._void_area(new, xz), self._void_area(old, xz), xz=xz, steps=self.remesh_steps)
        self.n_rebuilds += 1
        self.xz_built = np.array(xz, float)
        if k is not None:
            self.k_built = int(k)

    def _void_area(self, net, xz):
        """Void areas (Np,) [m^2] of ``net`` at xz (eq 29)."""
        return pg.measure(net, xz, self.r).void_area

    def advance(self, h, xz, k=None):
        """Advance the water by h [s] at centres xz and recompute the pressure forces ``F``. With
        rebuild_distance > 0, a void area out of range (``areas_in_range``) rebuilds the pores at xz
        first (those of step k; None: the schedule is left as it was)."""
        m = pg.measure(self.water.net, xz, self.r)
        if self.rebuild_distance > 0 and not areas_in_range(m.void_area, m.polygon_area):
            self.rebuild(xz, k)
            m = pg.measure(self.water.net, xz, self.r)
        self.last_limit = self.water._limit(self.water.advance(h, m.void_area, m.link_contact))
        A = self.water.A_prev if self.settings.smoothing else m.void_area  # eq 45: the area used
        U = self.water.pressure(A)
        self.F = pg.pressure_forces(self.water.net, self.r, U, m)
        self.F_walls = pg.flat_wall_forces(self.water.net, U, m)

    # -- observations ------------------------------------------------------------------------------
    def void_area(self, xz):
        """Void areas (Np,) [m^2] of the pores at centres xz (eq 29)."""
        return self._void_area(self.water.net, xz)

    def pressures(self, xz):
        """U (Np,) [N/m] at centres xz (eq 32)."""
        return self.water.pressure(self.void_area(xz))
