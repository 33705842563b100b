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

The schedule (water steps, rebuilds by interval, displacement and areas) is
engines.model.schedule.Schedule's: ``step`` asks it, ``schedule.k_built`` is the step of the last
build.
"""
import numpy as np

from engines.model import flat_walls as fw
from engines.model import pores as pg
from engines.model.pore_water import NUMPY_REMESH, PoreWater
from engines.model.schedule import Schedule


class WaterModel:
    """Pores and water of N discs (no YADE). Units: SI per unit thickness (engines.model.pore_water).

    r (N,) radii [m] (the true ones: pores use them even where a contact law enlarges them by
    eps_m/2); walls (N,) wall codes of engines.model.pores; xz (N, 2) initial centres [m], those
    of DEM step k0. ``F`` (N, 2) [N] holds the pressure forces of the last water step; ``schedule``
    (engines.model.schedule.Schedule of water_interval, rebuild_interval, rebuild_distance, k0;
    default Schedule()) says when the water steps and the pores are rebuilt, ``xz_built`` the
    centres of the last build. rebuild_distance [m]: > 0 also rebuilds when a disc has moved more
    than this since the last build or a void area is out of range (0: off, the interval only). flat_walls:
    engines.model.flat_walls.FlatWall, ... (SPEC §2.6); ``F_walls`` (W,) [N/m] holds the pore
    water's normal force on each of them (pores.flat_wall_forces) of the last water step.
    """

    build_steps, remesh_steps = pg.NUMPY_BUILD, NUMPY_REMESH  # of build_pores and PoreWater.remesh
    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("wall_vertices", "F", "F_walls", "n_rebuilds", "schedule", "substeps_max",
                         "substeps_total", "last_limit", "xz_built", "water")
    CHECKPOINT_DERIVED = {name: "the scene's [water] and [numerics], the packing's discs and flat walls" for name in
                          ("settings", "eps_m", "l_m", "flat_walls", "r", "walls", "dt")} | {
        "log": "the print function", "on_change": "set by the engine that steps the model (its limit checks)",
        "watch": "set by the engine that steps the model (engines.model.limits.AccuracyWatch): it watches "
                 "again from the restored step"}

    def __init__(self, settings, r, walls, xz, eps_m, l_m, dt, schedule=None, log=print, flat_walls=()):
        self.settings, self.eps_m, self.l_m = settings, float(eps_m), float(l_m)
        self.flat_walls = tuple(flat_walls)
        self.r = np.ascontiguousarray(r, float)
        # one WallVertices for every build, so that the walls' shift (move_walls) holds across rebuilds
        self.wall_vertices = fw.WallVertices(self.flat_walls, len(self.r)) if self.flat_walls else None
        self.walls = np.asarray(walls, np.int64)
        self.dt = float(dt)
        self.schedule = Schedule() if schedule is None else schedule
        self.log = log
        self.on_change = None  # called after each rebuild and change of dt: the stepping engine's limit checks
        self.watch = None  # limits.AccuracyWatch of the water steps made from Python, or None
        self.F = np.zeros((len(self.r), 2))
        self.F_walls = np.zeros(len(self.flat_walls))
        self.n_rebuilds = 0
        self.substeps_max = self.substeps_total = 0
        self.last_limit = np.inf  # Darcy limit of the last water step [s]
        self.xz_built = np.array(xz, float)
        net = self._build(xz)
        self.water = PoreWater(net, pg.measure(net, xz, self.r).void_area, settings, walls=self.walls)

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

    def set_dt(self, dt):
        """Step with dt [s] from now on: water steps of water_interval dt (each checked against its
        Darcy limit, engines.model.limits)."""
        if not dt > 0:
            raise ValueError(f"dt must be > 0 [s], got {dt}")
        self.dt = float(dt)
        if self.on_change is not None:
            self.on_change()

    def move_walls(self, shift):
        """Translate the flat walls to the displacements ``shift`` (W, 2) [m] from their FlatWall
        positions (flat_walls.WallVertices.move): the faces of the next measure and build."""
        self.wall_vertices.move(shift)

    # -- per step ---------------------------------------------------------------------------------
    def rebuild_due(self, k, xz=None):
        """Is a pore rebuild due at step k (Schedule.rebuild_due: by interval, or by displacement
        at the centres xz (N, 2) [m] of step k when given)?"""
        sch = self.schedule
        if sch.interval_due(k):
            return True
        return xz is not None and sch.by_displacement and sch.moved_too_far(self.max_sq_moved(xz))

    def max_sq_moved(self, xz):
        """max over the discs of |xz - xz_built|^2 [m^2]."""
        return float(np.max(np.sum((xz - self.xz_built) ** 2, axis=1)))

    def step(self, k, xz):
        """Step k of the DEM at centres xz (N, 2) [m]: rebuild when due, advance the water by
        water_interval dt at its steps (``schedule``). Returns True when ``F`` was recomputed."""
        if self.rebuild_due(k, xz):
            self.rebuild(xz, k)
        if not self.schedule.water_due(k):
            return False
        self.advance(self.schedule.water_interval * self.dt, xz, k)
        return True

    def rebuild(self, xz, k=None):
        """Rebuild the pores at xz, those of step k (None: the schedule is left as it was), and move
        the water onto them (§3.4(2))."""
        old, new = self.water.net, self._build(xz)
        self.water.remesh(new, self._void_area(new, xz), self._void_area(old, xz), xz=xz, steps=self.remesh_steps)
        self.n_rebuilds += 1
        self.xz_built = np.array(xz, float)
        if k is not None:
            self.schedule.built(k)
        if self.watch is not None:
            self.watch.rebuilt()
        if self.on_change is not None:
            self.on_change()

    def _void_area(self, net, xz):
        """Void areas (Np,) [m^2] of ``net`` at xz (eq 29)."""
        return pg.measure(net, xz, self.r).void_area

    def advance(self, h, xz, k=None):
        """Advance the water by h [s] at centres xz and recompute the pressure forces ``F``. With
        rebuild_distance > 0, a void area out of range (Schedule.areas_due) rebuilds the pores at xz
        first (those of step k; None: the schedule is left as it was)."""
        m = pg.measure(self.water.net, xz, self.r)
        if self.schedule.areas_due(m.void_area, m.polygon_area):
            self.rebuild(xz, k)
            m = pg.measure(self.water.net, xz, self.r)
        self.last_limit = self.water._limit(self.water.advance(h, m.void_area, m.link_contact))
        A = self.water.A_prev if self.settings.smoothing else m.void_area  # eq 45: the area used
        U = self.water.pressure(A)
        self.F = pg.pressure_forces(self.water.net, self.r, U, m)
        self.F_walls = pg.flat_wall_forces(self.water.net, U, m)
        if self.watch is not None:
            self.watch(m.void_area, U, self.settings.E_w, self.water.net.a_min, h)

    # -- observations ------------------------------------------------------------------------------
    def void_area(self, xz):
        """Void areas (Np,) [m^2] of the pores at centres xz (eq 29)."""
        return self._void_area(self.water.net, xz)

    def pressures(self, xz):
        """U (Np,) [N/m] at centres xz (eq 32)."""
        return self.water.pressure(self.void_area(xz))
