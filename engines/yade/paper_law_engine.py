"""The paper's contact law as a YADE engine (seed 000 §2); the per-step work is
engines.model.paper_law.PaperLaw's (by its compiled twin engines.compiled.paper_law.PaperLaw unless
``compiled=False``), this module reads the centres in bulk, calls it and adds the forces.
"""
import numpy as np

from engines.compiled import paper_law as compiled_paper_law
from engines.compiled import pore_dem as compiled_pore_dem
from engines.model.paper_law import PaperLaw
from engines.yade.contract import follow_dt


class PaperLawEngine:
    """The paper's law in a YADE scene, as a PyRunner every step after ForceResetter and before
    NewtonIntegrator (no collider or InteractionLoop needed for these discs)::

        law = PaperLawEngine(disc_ids, ContactSettings(spring="d", kn=1.4e5, ...))
        O.engines = [ForceResetter(), law.runner(), NewtonIntegrator(gravity=(0, 0, -9.81))]

    or without a PyRunner, driven from Python: ``law.drive(n)`` does the same work before each of n
    O.step() calls and writes the forces (with ``held`` added, e.g. buoyancy) for the step: as
    permanent forces, or, when the engine list resets the forces after NewtonIntegrator::

        O.engines = [NewtonIntegrator(gravity=(0, 0, -9.81), warnNoForceReset=False), ForceResetter()]

    (engines.yade.yade_io.forces_reset_after_newton), added to the reset forces, which spares YADE
    the sync pass that permanent forces cost at every step (engines.yade.coupling does this). This
    saves the PyRunner's dispatch at every step, and with the compiled PoreDEM as core and the
    bridge runs the steps between pore rebuilds in one compiled call (kernels.dem_drive_bulk_io;
    ``step_path`` chooses), back in Python only for the steps that need it.

    disc_ids: spheres in the x-z plane; the dynamic ones get blockedDOFs 'yXYZ' (this engine
    integrates their spin). Masses and inertias are read from the bodies: set them per unit
    thickness (m = rho pi r^2, I = m r^2 / 2, SPEC §1). ``core``: an object with
    ``step(xz) -> (F, fixes)`` over the same discs to run instead of a plain PaperLaw (e.g.
    engines.compiled.pore_dem.PoreDEM, which adds the water in the paper's order). ``hooks``: callables
    run after each step's forces are written, before its O.step() (with hooks, drive makes one
    compiled step a call).
    ``drive_walls(ids)``: the bodies ids move in x at the core's ``wall_velocity`` of each step
    (their velocity set before O.step()). A script may change O.dt between steps: the core follows
    it before its next step (engines.yade.contract.follow_dt: ``set_dt``, its limits checked again).
    """

    # what a checkpoint stores (engines.model.state): nothing of its own; the core is a part of its owner
    CHECKPOINT_FIELDS = ()
    CHECKPOINT_DERIVED = {
        **{name: "the bodies, built from the scene" for name in ("io", "_dynamic", "forced", "walls")},
        "core": "its owner's part (YadeCoupling.core), stored there",
        "held": "buoyancy, from the scene", "hooks": "set by its owner",
        **{name: "scratch of each step" for name in ("_xz", "_F_out", "_wall_vel")},
        **{name: "functions of engines.yade.yade_io" for name in ("_set_velocities", "_check",
                                                                  "_drive_dem")},
        "_reset_last": "read from O.engines by each drive"}

    def __init__(self, disc_ids, settings=None, core=None, compiled=True):
        from yade import O

        from engines.yade import yade_io

        self.io = yade_io.Bodies(disc_ids)
        bodies = [O.bodies[i] for i in self.io.id_list]
        dynamic = np.array([b.dynamic for b in bodies])
        for b in bodies:
            if b.dynamic:
                b.state.blockedDOFs = "yXYZ"
        if core is None:
            if not O.dt > 0:
                raise ValueError("set O.dt before creating the PaperLawEngine")
            law = compiled_paper_law.PaperLaw if compiled else PaperLaw
            core = law(settings, [b.shape.radius for b in bodies], dynamic, [b.state.mass for b in bodies],
                       [b.state.inertia[1] for b in bodies], O.dt)
        self.core = core
        self._dynamic = np.flatnonzero(dynamic)
        self.forced = yade_io.Bodies(self.io.ids[dynamic])
        self.held = np.zeros((len(self._dynamic), 2))  # forces added in drive mode [N]
        self._xz = np.zeros((self.io.n, 2))  # positions read and forces written by the compiled drive
        self._F_out = np.zeros((len(self._dynamic), 2))
        self.hooks = []
        self._set_velocities, self._check = yade_io.set_velocities, yade_io.check
        self._drive_dem = yade_io.drive_dem if yade_io.BACKEND == "yadebulk" else None
        self._reset_last = False  # how drive writes the forces (set by drive from the engine list)
        self.drive_walls([])

    def drive_walls(self, ids):
        """Move the bodies ``ids`` (fixed walls) in x at the core's ``wall_velocity`` of each step."""
        from engines.yade import yade_io
        self.walls = yade_io.Bodies(np.asarray(ids, np.int64))
        self._wall_vel = np.zeros((self.walls.n, 2))  # (v, 0) rows

    def runner(self, label="paperLaw"):
        from engines.yade import yade_io
        return yade_io.py_runner(self.__call__, 1, label)

    def _work(self, write):
        F, fixes = self.core.step(self.io.positions())
        write(F)
        self._after(fixes)

    def _after(self, fixes):
        if fixes:
            disc = np.fromiter(fixes, np.int64)
            self._set_velocities(self.io.ids[disc], np.array([fixes[d] for d in disc.tolist()]))
        if self.walls.n:
            self._wall_vel[:, 0] = self.core.wall_velocity
            self._set_velocities(self.walls.ids, self._wall_vel)
        for hook in self.hooks:
            hook()

    def __call__(self):
        follow_dt(self.core)
        self._work(self._add)

    def _add(self, F):
        self.forced.add_forces(F[self._dynamic])

    def drive(self, n, stop=None):
        """n steps: this engine's work, then O.step(); ``stop()`` true ends early (asked after each
        step made from Python and after each compiled run of steps). The steps are made the way
        ``step_path`` chooses: by compiled runs of steps (``_kernel_steps``; one step a call with
        hooks), or by ``_work``, which also makes a step a compiled run cannot make."""
        from yade import O

        from engines.yade import yade_io
        self._reset_last = yade_io.forces_reset_after_newton(O.engines)
        path = step_path(self.core, self._drive_dem is not None)
        done, n = 0, int(n)
        while done < n:
            follow_dt(self.core)
            m = self._kernel_steps(1 if self.hooks else n - done) if path == "drive" else 0
            if m == 0:
                self._work(self._write_held)
                O.step()
                m = 1
            done += m
            if stop is not None and stop():
                break

    def _kernel_steps(self, n):
        """Up to n steps by kernels.dem_drive_bulk_io (engines.yade.yade_io.drive_dem); a step it
        leaves before its O.step() (water sub-steps, or the hooks') is finished here: the water's
        books, the hooks, O.step(). Returns the steps done (0: the next step needs ``_work``)."""
        from yade import O
        core = self.core
        while True:
            drive = core.kernel_drive_args(self._dynamic, self.held, n)
            if drive is None:
                if not self._rebuild_pores():
                    return 0
                continue
            made, stepped, stale, n_sub, rc, builds, *pairs = self._drive_dem(
                core.k, not self.hooks, drive, self.walls, self._wall_vel, self.io, self._xz, self.forced,
                self._F_out, self._reset_last)
            if builds:
                core.law.contact.take_list(builds, *pairs)
            core.finish_kernel_drive(made, drive.totals, drive.motion)
            self._check(rc)
            if stepped < made:  # its water's books, hooks and O.step() here
                if n_sub != 1:
                    core.finish_substeps(n_sub)
                for hook in self.hooks:
                    hook()
                O.step()
            if not stale:
                return made
            core.law.contact._update_list(self._xz)
            if made:
                return made

    def _rebuild_pores(self):
        """The core's pore rebuild of this step at the positions read now, when that is all that
        keeps the step from a compiled call (``pores_due``); True if it was made."""
        if not self.core.pores_due():
            return False
        self.core.rebuild_pores(self.io.positions())
        return True

    def _write_held(self, F):
        self.forced.write_forces(F, self._dynamic, self.held, self._reset_last)


def step_path(core, bridge):
    """How PaperLawEngine.drive makes the steps of ``core`` (the one choice of a path): "drive",
    by kernels.dem_drive_bulk_io (a compiled PoreDEM and the bulk ``bridge``; with hooks one step
    a call, the hooks run before its O.step()); "python", core.step between the reads and writes
    of engines.yade.yade_io (a PaperLaw, the NumPy PoreDEM, or no bridge)."""
    return "drive" if bridge and isinstance(core, compiled_pore_dem.PoreDEM) else "python"
