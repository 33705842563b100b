"""The pore water as a YADE engine: pores between discs, Darcy exchange, pressure forces (seed 000 §3).

``WaterEngine`` is the public YADE object: a YADE script with its own spheres (kept in the x-z
plane), its own collider and contact law adds the water in a few lines::

    from engines.model.pore_water import WaterSettings
    from engines.yade import yade_io
    from engines.yade.water_engine import WaterEngine
    water = WaterEngine(disc_ids, walls={"bottom": bottom_ids, "left": left_ids, "right": right_ids},
                        settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), l_m=1.3e-4)
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]   # before NewtonIntegrator
    O.run(3000, True)
    yade_io.raise_pending()   # optional: raise an engine error here (else the script exits with status 1)

The bodies are checked at construction (engines.yade.contract: spheres in one x-z plane, masses
per metre of thickness, pores built, an inflow boundary when q_w > 0) and refused in one line naming
the body; bodies added later are refused at the next rebuild.

Every ``water_interval`` steps from its creation its PyRunner reads the centres in bulk
(engines.yade.yade_io), rebuilds the pores when due (the model's engines.model.schedule.Schedule,
started at the engine's creation: a disc farther than ``rebuild_distance`` from its centre at the
last build or a void area out of range, or the first water step at or after each multiple of
``rebuild_interval`` steps from the engine's creation), measures the void areas (eq 29), advances
the water by water_interval x O.dt (eq 32-43, 45-46; the model follows a change of O.dt) and
writes the pressure forces (eq 33) plus buoyancy (eq 34b) as permanent forces: between water
steps no Python runs. The work itself is engines.model.water_model.WaterModel's, by its compiled
twin engines.compiled.water_model.WaterModel unless ``compiled=False`` (no YADE there).

With ``settings.substep`` a water step above the Darcy limit is split into sub-steps; the engine
prints the count when it first sub-steps and whenever the count doubles, and keeps
``substeps_max``/``substeps_total``.
"""
import time

import numpy as np

from engines.compiled import kernels, params
from engines.compiled import water_model as compiled_water_model
from engines.model import limits, pore_water
from engines.model import pores as pg
from engines.model.schedule import Schedule
from engines.model.water_model import WaterModel
from engines.yade import contract, scene_save
from engines.yade.scene_save import RestoreError, call  # noqa: F401  (call: the runners' command, scene_save.RUNNER_MODULE)

CHUNK_SECONDS = 0.1  # wall time of one compiled call of WaterEngine.drive (signals wait that long)
# The default rebuild_distance, a fraction of l_m. Links join discs closer than l_m beyond touching
# (eq 28) and a pore's void area is measured on the links of its build (eq 29): with every disc
# within l_m / 4 of its centre at the build, a link's length has changed by less than l_m / 2, so
# the built links stay those the discs would be given now to within half the link range, and the
# measured areas stay close to the true ones (frictmat_box: every U <= E_w).
REBUILD_FRACTION = 0.25
# A disc farther than this fraction of its radius (plus twice what its velocity covers in the steps
# between) from its centre at the engine's last water step, with no water step missed in between,
# was put there by something else than the steps: a scene loaded or its bodies moved by hand
# (``check_same_scene``).
JUMP_FRACTION = 0.5


class WaterEngine:
    """The pore water of a YADE scene as a PyRunner (see the module docstring for the usage).

    disc_ids: the spheres that bound the pores (particles and wall discs), kept in the x-z plane.
    walls: {"bottom"|"left"|"right": ids} among disc_ids (inflow enters bottom pores; drained
    sides drain through left/right). radii: the true disc radii [m] (default: read from the
    bodies; give them when the contact law enlarges the spheres by eps_m/2). eps_m: contact range
    of the links (eq 43b); l_m: link range (eq 28), within 0.01-2 x the median radius and >= eps_m
    (engines.model.pores.check_lengths). buoyancy: add -rho_w pi r^2 g to the dynamic discs (eq 34b),
    rho_w from ``rho_w``; g the gravity of the NewtonIntegrator in O.engines, read at every water
    step (a ramp is followed), or ``gravity`` [m/s^2] along -z when given (needed without an
    integrator). Pressure forces act on dynamic bodies only.
    flat_walls: {body id: "undrained" | "drained" (needs settings.k3 > 0) | "inflow"} of YADE Box or Wall bodies (not in
    disc_ids) that close the pores (SPEC §2.6; engines.yade.walls takes the face the discs lie
    against); the water's push on them is ``wall_forces``. A flat wall may translate (a
    TranslationEngine or a velocity of its body): each water step reads where it is.
    rebuild_distance [m]: the pores are rebuilt at the first water step at which a disc is
    farther than this from its centre at the last build or a void area is out of range
    (engines.model.schedule.areas_in_range) (default None: REBUILD_FRACTION x l_m, see there;
    0: off); rebuild_interval [steps] bounds the time between rebuilds. A script may change O.dt
    between steps: the model follows it at the next water step (engines.yade.contract.follow_dt).
    The water step water_interval x O.dt is checked (``check_limits``) at construction, after each
    rebuild, each change of O.dt and of the settable ``water_interval``: above the water-stiffness limit it is refused, naming the
    largest stable water_interval; above the Darcy limit it is sub-stepped (refused without
    settings.substep). The accuracy watch (engines.model.limits.AccuracyWatch, ``model.watch``)
    compares the void areas of every water step with the last one (on every path; the compiled
    drive's, kernels.watch_areas, reported at the end of each call): above
    WATCH_WARN it warns once, above WATCH_STOP it stops the run unless ``accept_inaccurate``.
    """

    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("model", "k", "wall_motion")
    CHECKPOINT_DERIVED = {
        **{name: "the bodies, built from the scene" for name in ("io", "wall_ids", "_n_bodies", "forced", "_dynamic")},
        "compiled": "the caller's choice", "F_const": "buoyancy, from the scene",
        **{name: "the bodies and the caller's arguments" for name in ("_mass", "_lift", "_newton")},
        "g": "the NewtonIntegrator's gravity, read at each water step (or the caller's)",
        "_xz": "scratch of each water step", "_F_out": "scratch of each water step",
        "_seen": "(O.iter, centres) at the last water step or drive's end: a restored engine starts afresh",
        "arguments": "the constructor's arguments: the recipe of a saved scene's tag (engines.yade.scene_save)",
        "_chunk": "the steps of drive's next compiled call, adapted to the wall time: how steps are grouped, not "
                  "what they compute"}

    def __init__(self, disc_ids, walls, settings, l_m, eps_m=0.0, radii=None, rebuild_interval=1000,
                 water_interval=1, buoyancy=True, rho_w=1000.0, gravity=None, compiled=True,
                 rebuild_distance=None, flat_walls=None, accept_inaccurate=False):
        self.arguments = {k: v for k, v in locals().items() if k != "self"}  # saved with the scene (scene_save)
        from yade import O  # YADE only here and below

        from engines.yade import yade_io
        from engines.yade.walls import WallMotion
        from engines.yade.walls import flat_walls as faces

        contract.check_scene(O)
        disc_ids = [int(i) for i in disc_ids]
        radii = contract.check_discs(O.bodies, disc_ids, radii)
        self.io = yade_io.Bodies(disc_ids)
        ids = self.io.ids
        pg.check_lengths(l_m, eps_m, radii)
        contract.check_flat_boundaries(flat_walls or {}, settings)
        self.wall_ids = [int(i) for i in (flat_walls or {})]
        walls_xz = faces(O.bodies, flat_walls or {}, self.io.positions())
        self.wall_motion = WallMotion(self.wall_ids) if self.wall_ids else None
        code = np.zeros(len(ids), np.int64)
        pos = {i: k for k, i in enumerate(ids.tolist())}
        for name, group in (walls or {}).items():
            if name not in pg.WALL_CODES:
                raise ValueError(f"walls: unknown group {name!r}; known: {sorted(pg.WALL_CODES)}")
            missing = [i for i in group if i not in pos]
            if missing:
                raise ValueError(f"walls[{name!r}]: ids {missing[:5]} are not among disc_ids")
            code[[pos[i] for i in group]] = pg.WALL_CODES[name]
        if not O.dt > 0:
            raise ValueError("set O.dt before creating the WaterEngine (the water step is water_interval x O.dt)")
        self.compiled = compiled  # engines.compiled.water_model.WaterModel, else the NumPy one
        model = compiled_water_model.WaterModel if compiled else WaterModel
        if rebuild_distance is None:
            rebuild_distance = REBUILD_FRACTION * l_m
        self.model = model(settings, radii, code, self.io.positions(), eps_m, l_m, O.dt,
                           Schedule(water_interval, rebuild_interval, rebuild_distance, O.iter), flat_walls=walls_xz)
        contract.check_pores(self.model.water.net, settings, len(ids), l_m)
        self._n_bodies = len(O.bodies)  # bodies added later are refused at the next rebuild
        dynamic = np.array([O.bodies[i].dynamic for i in ids.tolist()])
        self._mass = np.array([O.bodies[i].state.mass for i in ids.tolist()])
        self.forced = yade_io.Bodies(ids[dynamic])
        self._dynamic = np.flatnonzero(dynamic)
        self.F_const = np.zeros((len(self._dynamic), 2))
        # buoyancy -rho_w pi r^2 g (eq 34b) per unit g; gravity: given along -z, else the NewtonIntegrator's
        self._lift = (pore_water.buoyancy(np.asarray(radii, float)[self._dynamic], rho_w, 1.0) if buoyancy
                      else np.zeros(len(self._dynamic)))
        self._newton = None if gravity is not None else contract.newton_of(O.engines)
        self.g = contract.gravity_of(O.engines, gravity)
        self.F_const[:] = -self._lift[:, None] * self.g
        self.forced.set_permanent_forces(self.F_const)
        self._xz, self._F_out = np.zeros((len(ids), 2)), np.zeros((len(self._dynamic), 2))  # buffers of __call__
        self.k = O.iter  # DEM step of the last call (the model's k0 is that of creation)
        self._chunk = 100  # steps of drive's next compiled call, adapted to CHUNK_SECONDS
        self.model.watch = limits.AccuracyWatch(accept=accept_inaccurate)
        self.check_limits("at construction")
        self.model.on_change = self.check_limits  # at each rebuild and change of dt
        self._seen = (O.iter, self.io.positions())

    def checkpoint_restored(self):
        """Restored with its scene (engines.model.state): the next water step starts the comparison
        of ``check_same_scene`` afresh."""
        self._seen = None

    def check_same_scene(self, xz):
        """Stop (scene_save.RestoreError, one line naming what to do) when the scene is not the one
        the water belongs to: O.iter before that of the engine's last water step (an earlier scene
        loaded without the engine's saved water), or, no water step missed since, a disc farther than
        JUMP_FRACTION of its radius plus twice its velocity x the steps' time from its centre then
        (a scene loaded, bodies moved by hand); xz (N, 2) [m] the centres now."""
        from yade import O
        if self._seen is None:
            return
        k, seen = self._seen
        remedy = ("the engine's water is not this scene's: restore it with the scene (water.runner() in O.engines "
                  "when O.save/O.saveTmp is called: O.load/O.loadTmp then restore it, engines.yade.scene_save), or "
                  "make the WaterEngine again after the load (its water starts afresh)")
        if O.iter < k:
            raise RestoreError(f"the scene went back from step {k} to step {O.iter} (O.load or O.loadTmp of an earlier "
                               f"scene?): {remedy}")
        if O.iter > k + self.water_interval:
            return
        d = np.hypot(*(np.asarray(xz) - seen).T)
        r = self.model.r
        far = np.flatnonzero(d > JUMP_FRACTION * r)
        if len(far):
            v = np.array([O.bodies[int(self.io.ids[i])].state.vel.norm() for i in far.tolist()])
            far = far[d[far] > JUMP_FRACTION * r[far] + 2 * v * (O.iter - k) * O.dt]
        if len(far):
            i = int(far[np.argmax(d[far] / r[far])])
            raise RestoreError(f"body {int(self.io.ids[i])}: moved {d[i]:.3g} m ({d[i] / r[i]:.2g} of its radius) since "
                               f"the water step at step {k} in {O.iter - k} steps, more than its velocity allows (a "
                               f"scene loaded, or bodies moved by hand): {remedy}")

    @property
    def water_interval(self):
        """Steps between water steps (settable between steps: ``water.water_interval = M`` is checked
        like a change of O.dt, ``check_limits``, and takes effect at the next water step,
        engines.model.schedule.Schedule.set_water_interval; the runner follows)."""
        return self.model.schedule.water_interval

    @water_interval.setter
    def water_interval(self, value):
        from yade import O
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"water_interval = {value!r}: the steps between water steps, an integer >= 1")
        value = int(value)
        self.check_limits(f"when water_interval was set at step {O.iter}", value)
        first = self.model.schedule.set_water_interval(value, O.iter)
        self.arguments["water_interval"] = value  # a saved scene's engine is made again with it
        scene_save.set_period(self, value, first)

    def check_limits(self, when=None, water_interval=None):
        """Refuse the water step h = water_interval x O.dt (default the schedule's water_interval)
        above the water-stiffness limit of the pores now (no sub-steps: the message names the
        largest stable water_interval), or above the Darcy limit without settings.substep
        (engines.model.limits); at construction, after each pore rebuild, each change of O.dt and
        of ``water_interval``."""
        from yade import O
        m, s = self.model, self.model.settings
        xz = self.io.positions()
        meas = pg.measure(m.water.net, xz, m.r)
        M = water_interval or m.schedule.water_interval
        when = when or f"at step {O.iter} (the pores rebuilt or O.dt changed)"
        stiff = limits.water_stiffness_limit(m.water.net, meas.void_area, m.r, s.E_w, self._mass, self._mobile())
        limits.check_water_stiffness(m.dt, stiff, s.E_w, M, limits.ENGINE_NAMES, when)
        limits.substeps(M * m.dt, m.water.darcy_limit(meas.void_area, meas.link_contact), s.substep, s.E_w)

    def _mobile(self):
        """(N,) bool: the discs YADE moves (dynamic)."""
        mobile = np.zeros(len(self._mass), bool)
        mobile[self._dynamic] = True
        return mobile

    def _follow_gravity(self):
        """Buoyancy -rho_w pi r^2 g of the NewtonIntegrator's gravity now (a ramp is followed), when
        the gravity was not given."""
        if self._newton is None:
            return
        g = contract.plane_gravity(self._newton.gravity)
        if not np.array_equal(g, self.g):
            self.g = g
            self.F_const[:] = -self._lift[:, None] * g

    def due(self, k):
        """True when step k is a water step (every water_interval steps from the engine's creation)."""
        return self.model.schedule.water_due(k)

    def runner(self, label="water"):
        """The PyRunner to put after the InteractionLoop and before NewtonIntegrator. YADE's
        PyRunner adds its dispatch to every call (``drive`` does not pay it). O.save and O.saveTmp
        save the engine's water with the scene, O.load and O.loadTmp restore it, in a new process
        too (engines.yade.scene_save)."""
        return scene_save.runner(self, label)

    def drive(self, n, stop=None):
        """Instead of the runner and O.run(n): n O.step() calls, this engine's work before each of
        them that is a water step (the same work: nothing moves the bodies between NewtonIntegrator
        and the next step's PyRunner). ``stop()`` true (asked after each step made from Python and
        after each compiled call), or an error kept by an engine callback (yade_io.ERRORS), ends
        early. Without a PyRunner among O.engines, with the bulk bridge, the steps between two
        rebuilds run in compiled calls of about CHUNK_SECONDS (``_drive_compiled``, which stops
        before a water step due for a rebuild by displacement: that step is made here): the same
        run without Python per step."""
        from yade import O
        from yade.wrapper import PyRunner

        from engines.yade import yade_io
        self.check_same_scene(self.io.positions())
        n, done = int(n), 0
        alone = not any(isinstance(e, PyRunner) for e in O.engines) and not self._walls_may_move()
        fast = alone and water_path(self.compiled, yade_io.BACKEND == "yadebulk") == "drive"
        due, errors = self.due, yade_io.ERRORS
        while done < n:
            contract.follow_dt(self.model)
            self._follow_gravity()
            to_event = self.model.schedule.steps_to_event(O.iter, water_steps_only=True)
            m = min(n - done, to_event, self._chunk) if fast else 0
            if m > 0:
                t0 = time.perf_counter()
                got = self._drive_compiled(m)
                done += got
                if got == m == self._chunk:
                    self._chunk = int(min(max(m * CHUNK_SECONDS / max(time.perf_counter() - t0, 1e-6), 10), 1e6))
                if stop is not None and stop():
                    break
                if got == m or done >= n:
                    continue
            if due(O.iter):
                self()
            O.step()
            done += 1
            if errors or (stop is not None and stop()):
                break
        self._seen = (O.iter, self.io.positions())

    def _walls_may_move(self):
        """Can a flat wall move in the next steps: its body has a velocity, or a kinematic engine
        (a TranslationEngine) drives it? Then each water step is made here, where it reads the walls."""
        from yade import O
        from yade.wrapper import KinematicEngine
        if self.wall_motion is None:
            return False
        ids = set(self.wall_ids)
        return (any(O.bodies[i].state.vel.norm() > 0 for i in ids)
                or any(isinstance(e, KinematicEngine) and ids & set(e.ids) for e in O.engines))

    def _follow_walls(self):
        """Move the model's flat walls to where their bodies are now (engines.yade.walls.WallMotion)."""
        if self.wall_motion is not None:
            shift = self.wall_motion.shift()
            if not np.array_equal(shift, self.model.wall_vertices.shift):
                self.model.move_walls(shift)

    def _drive_compiled(self, n):
        """Up to n steps by kernels.water_drive_bulk_io, no rebuild among them; returns the steps
        done (fewer after a water step that needed sub-steps: its bookkeeping and its step follow
        here; fewer before a water step due for a rebuild by displacement; an error is raised)."""
        from yade import O

        from engines.yade import yade_io
        m = self.model
        sch = m.schedule
        h = sch.water_interval * m.dt
        args = m.kernel_args(h)
        b = m.water.balance
        totals = params.balance_of(b)
        k = O.iter
        done, n_water, n_sub, rc = yade_io.drive_water(n, True, sch.steps_to_water(k), sch.water_interval, totals,
                                                       m.xz_built, sch.moved2, self.io, self._xz, self.forced,
                                                       self._F_out, self._forces_step_args(args))
        params.book_balance(b, totals)
        if n_water:
            self.k = sch.last_water(k + done - (1 if n_sub == 1 else 0))  # the last water step
            m.after_kernel_steps()
            m.report_watch(h)  # every water step of the call watched (kernels.watch_areas)
        yade_io.check(rc, self.io.ids)  # an error code names the disc read (positions first)
        if n_sub != 1:  # that water step's sub-steps or failure, then its DEM step
            m.finish_kernel_step(h, n_sub)
            O.step()
            done += 1
        return done

    def __call__(self):
        """One water step: rebuild when due (a disc farther than rebuild_distance from its centre
        at the last build or a void area out of range, or the first call at or after each multiple
        of rebuild_interval steps from the engine's creation), advance by water_interval x O.dt,
        write the forces. With the bridge it is one call of the compiled drive (n = 1, no O.step())."""
        from yade import O

        from engines.yade import yade_io
        m = self.model
        xz = self.io.positions()
        self.check_same_scene(xz)
        self._seen = (O.iter, xz)
        self.k = O.iter
        contract.follow_dt(m)
        self._follow_gravity()
        sch = m.schedule
        h = sch.water_interval * m.dt
        self._follow_walls()
        path = water_path(self.compiled, yade_io.BACKEND == "yadebulk")
        if path == "drive" and not sch.interval_due(self.k):  # read, triggers, water, write: one call
            _, n_water, n_sub, rc = yade_io.drive_water(1, False, 0, sch.water_interval, np.zeros(3), m.xz_built,
                                                        sch.moved2, self.io, self._xz, self.forced, self._F_out,
                                                        self._forces_step_args(m.kernel_args(h)))
            yade_io.check(rc, self.io.ids)  # an error code names the disc read (positions first)
            if n_water:
                m.finish_kernel_step(h, n_sub)
                return
            rebuild = True  # due by displacement or areas: nothing done, rebuilt and made below
        else:
            rebuild = m.rebuild_due(self.k, xz if sch.by_displacement else None)
        if path == "kernel" and not rebuild:  # the positions read, water, write
            n_sub = kernels.water_step(xz, *m.kernel_args(h))
            if n_sub > 0:
                self.write_forces()
            if n_sub != kernels.AREAS_OUT_OF_RANGE:
                m.finish_kernel_step(h, n_sub)
                return
            rebuild = True  # nothing done: rebuilt and made below
        if rebuild:
            contract.check_added(O.bodies, self._n_bodies)
            m.rebuild(xz, self.k)
        m.advance(h, xz, self.k)
        self.write_forces()

    def _forces_step_args(self, water):
        """The arguments of kernels.water_forces_step after (xz, F_out) for the water step arguments ``water``."""
        return kernels.water_forces_step_args(self._dynamic, self.F_const, water)

    def write_forces(self):
        """The permanent forces: the last water step's pressure forces plus buoyancy."""
        self.forced.set_permanent_forces(self.model.F, self._dynamic, self.F_const)

    def pressures(self):
        """U (Np,) [N/m] of the pores at the current positions."""
        return self.model.pressures(self.io.positions())

    def network(self):
        """The pores now as a pore network in OpenPNM's vocabulary (engines.model.network_view:
        pore.coords, pore.pressure, polygons, boundaries, throat.conns, throat.flux, the balance)."""
        from engines.model.network_view import pore_network
        return pore_network(self.model, self.io.positions())

    def wall_forces(self):
        """{body id of flat_walls: (F_x, F_z)} [N per m thickness]: the push of the pore water on
        each flat wall at the last water step (U x wetted length along the outward normal; the
        discs' contacts on it are YADE's, in O.forces)."""
        return {i: tuple(-f * wall.normal()) for i, f, wall in zip(self.wall_ids, self.model.F_walls,
                                                                    self.model.flat_walls)}


def water_path(compiled, bridge=False):
    """How WaterEngine makes its water steps (the one choice of a path): "drive", by the compiled
    kernels.water_drive_bulk_io (the compiled model and the bulk ``bridge``): runs of DEM steps with
    their water steps (``drive`` without stop, no PyRunner among O.engines, no flat wall that may
    move), else one water step a call; "kernel", kernels.water_step between the reads and
    writes of engines.yade.yade_io (the compiled model, no bridge); "python", the NumPy model's."""
    if not compiled:
        return "python"
    return "drive" if bridge else "kernel"


scene_save.ENGINE_CLASS = WaterEngine  # the class a saved scene's recipe makes again (scene_save.restore)
