"""The paper's contact law as a YADE engine (seed 000 §2); the per-step work is
engines.model.paper_law.PaperLaw's (by its compiled twin engines.compiled.paper_law.PaperLaw unless
``compiled=False``), this module reads the centres in bulk, calls it and adds the forces.
"""
import numpy as np

from engines.compiled import kernels
from engines.compiled import paper_law as compiled_paper_law
from engines.model.paper_law import PaperLaw


class PaperLawEngine:
    """The paper's law in a YADE scene, as a PyRunner every step after ForceResetter and before
    NewtonIntegrator (no collider or InteractionLoop needed for these discs)::

        law = PaperLawEngine(disc_ids, ContactSettings(spring="d", kn=1.4e5, ...))
        O.engines = [ForceResetter(), law.runner(), NewtonIntegrator(gravity=(0, 0, -9.81))]

    or without a PyRunner, driven from Python: ``law.drive(n)`` does the same work before each of n
    O.step() calls and holds the forces as permanent forces (with ``held`` added, e.g. buoyancy);
    this saves the PyRunner's dispatch at every step.

    disc_ids: spheres in the x-z plane; the dynamic ones get blockedDOFs 'yXYZ' (this engine
    integrates their spin). Masses and inertias are read from the bodies: set them per unit
    thickness (m = rho pi r^2, I = m r^2 / 2, SPEC §1). ``core``: an object with
    ``step(xz) -> (F, fixes)`` over the same discs to run instead of a plain PaperLaw (e.g.
    engines.compiled.pore_dem.PoreDEM, which adds the water in the paper's order). ``hooks``: callables
    run after each step's forces are written.
    """

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
        self._xz = np.zeros((self.io.n, 2))  # positions read and forces written by _kernel_work
        self._F_out = np.zeros((len(self._dynamic), 2))
        self.hooks = []
        self._set_velocities, self._run_kernel = yade_io.set_velocities, yade_io.run_kernel

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
        for hook in self.hooks:
            hook()

    def __call__(self):
        self._work(self._add)

    def _add(self, F):
        self.forced.add_forces(F[self._dynamic])

    def drive(self, n, stop=None):
        """n steps: this engine's work, then O.step(); ``stop()`` true ends early. A core that
        offers ``kernel_step_args`` (PoreDEM) does the step in one compiled call where it can."""
        from yade import O
        write = self._write_held
        fused = self._kernel_work if hasattr(self.core, "kernel_step_args") else None
        for _ in range(int(n)):
            if fused is None or not fused():
                self._work(write)
            O.step()
            if stop is not None and stop():
                break

    def _kernel_work(self):
        """This step as kernels.dem_step between a position read and the force write (one compiled
        call with the bridge; engines.yade.yade_io.run_kernel). False when the step needs ``_work``."""
        core = self.core
        while True:
            args = core.kernel_step_args(self._dynamic, self.held)
            if args is None:
                return False
            n_lost, n_sub = self._run_kernel(kernels.dem_step, self.io, self._xz, self.forced, self._F_out, args)
            if n_lost != kernels.LIST_STALE:
                break
            core.law.contact._update_list(self._xz)
        fixes = core.finish_kernel_step(self._xz, n_lost, n_sub, args)
        self._after(fixes)
        return True

    def _write_held(self, F):
        self.forced.set_permanent_forces(F, self._dynamic, self.held)
