"""The paper's contact law as an engine (seed 000 §2: springs a-d, eps_m, eq 1-13, 18-27, spin).

No YADE law has the f_max plateau of springs (c) and (d), the eq 18-24 velocity adjustment at
separation or the paper's incremental tangential spring with rolling, so this law runs as its own
engine: ``PaperLaw`` is the per-step work without YADE (engines.contact's ContactLaw, compiled
by default), ``PaperLawEngine`` the YADE object that reads the centres in bulk, calls it and adds
the forces. The discs' spin about y is integrated here (eq 14c, 16c); YADE only translates them.
The side-wall springs of the seismic box (Fig. 27) are added by engines.pore_dem.PoreDEM.
"""
import numpy as np

from engines import kernels
from engines.contact import ContactLaw, separation_adjustment


class PaperLaw:
    """State and per-step work of the paper's law for N discs (SI, per unit thickness).

    r, mass, inertia (N,) [m, kg/m, kg m]; mobile (N,) bool; dt [s]. ``omega`` (N,) spin [rad/s]
    and ``du`` (N, 2) the last displacement increments [m] are plain arrays (saved in checkpoints).
    """

    def __init__(self, settings, r, mobile, mass, inertia, dt, compiled=True):
        self.settings, self.dt, self.compiled = settings, float(dt), compiled
        self.mobile = np.asarray(mobile, bool)
        self.mass, self.inertia = np.asarray(mass, float), np.ascontiguousarray(inertia, float)
        self.contact = ContactLaw(settings, r, self.mobile, compiled=compiled)
        n = len(self.mobile)
        self.omega = np.zeros(n)
        self.du = np.zeros((n, 2))
        self.xz_prev = None
        self._dpsi = np.zeros(n)  # omega dt, scratch of the compiled step

    def step(self, xz, vel=None):
        """Forces (N, 2) [N] at centres xz (N, 2) of this step and {disc: new velocity (2,)} of the
        discs that became free (eq 18-24); ``vel`` (N, 2) the velocities if known, else du/dt.
        Compiled, the forces are a buffer that the next step overwrites."""
        if self.compiled:
            F, separations = self._step_compiled(xz)
        else:
            F, separations = self._step_numpy(xz)
        return F, self._fixes(separations, vel)

    def _fixes(self, separations, vel):
        s = self.settings
        if not (separations and s.separation_adjustment):
            return {}
        v = self.du / self.dt if vel is None else vel
        return separation_adjustment(separations, self.contact.touch_count(), v, self.mass, self.mobile, s.restitution)

    def _step_numpy(self, xz):
        dt = self.dt
        self.du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev  # eq 17
        F, M, separations = self.contact.forces(xz, self.du, self.omega * dt, dt)
        mob = self.mobile
        self.omega[mob] += M[mob] / self.inertia[mob] * dt  # eq 14c, 16c
        self.xz_prev = xz
        return F, separations

    def _step_compiled(self, xz):
        """kernels.law_step: the same arithmetic as _step_numpy; du and xz_prev are updated in place."""
        if self.xz_prev is None:  # du = 0 at the first step
            self.xz_prev = np.array(xz, float)
            self.contact._update_list(xz)
        while True:
            n_lost = kernels.law_step(xz, *self.kernel_args())
            if n_lost >= 0:
                return self.contact._F, self.finish_kernel_step(xz, n_lost)
            self.contact._update_list(xz)

    def kernel_args(self):
        """The arguments of kernels.law_step after xz (compiled, after the first step)."""
        c = self.contact
        return (self.xz_prev, c.xz_list, c.half_skin2, self.omega, self._dpsi, self.du, self.inertia, self.mobile,
                self.dt) + c.kernel_args(self.dt)

    def finish_kernel_step(self, xz, n_lost):
        """The SeparationEvents of a law_step at xz that returned n_lost."""
        c = self.contact
        return c._separations(xz, c._lost[:n_lost]) if n_lost else []


class PaperLawEngine:
    """The paper's law in a YADE scene, as a PyRunner every step after ForceResetter and before
    NewtonIntegrator (no collider or InteractionLoop needed for these discs)::

        law = PaperLawEngine(disc_ids, ContactSettings(spring="d", kn=1.4e5, ...))
        O.engines = [ForceResetter(), law.runner(), NewtonIntegrator(gravity=(0, 0, -9.81))]

    or without a PyRunner, driven from Python: ``law.drive(n)`` does the same work before each of n
    O.step() calls and holds the forces as permanent forces (with ``held`` added, e.g. buoyancy);
    this saves the PyRunner's dispatch (~50 us a call).

    disc_ids: spheres in the x-z plane; the dynamic ones get blockedDOFs 'yXYZ' (this engine
    integrates their spin). Masses and inertias are read from the bodies: set them per unit
    thickness (m = rho pi r^2, I = m r^2 / 2, SPEC §1). ``core``: an object with
    ``step(xz) -> (F, fixes)`` over the same discs to run instead of a plain PaperLaw (e.g.
    engines.pore_dem.PoreDEM, which adds the water in the paper's order). ``hooks``: callables
    run after each step's forces are written.
    """

    def __init__(self, disc_ids, settings=None, core=None, compiled=True):
        from yade import O
        from engines import yade_io

        self.io = yade_io.Bodies(disc_ids)
        bodies = [O.bodies[i] for i in self.io.id_list]
        dynamic = np.array([b.dynamic for b in bodies])
        for b in bodies:
            if b.dynamic:
                b.state.blockedDOFs = "yXYZ"
        if core is None:
            if not O.dt > 0:
                raise ValueError("set O.dt before creating the PaperLawEngine")
            core = PaperLaw(settings, [b.shape.radius for b in bodies], dynamic, [b.state.mass for b in bodies],
                            [b.state.inertia[1] for b in bodies], O.dt, compiled)
        self.core = core
        self._dynamic = np.flatnonzero(dynamic)
        self.forced = yade_io.Bodies(self.io.ids[dynamic])
        self.held = np.zeros((len(self._dynamic), 2))  # forces added in drive mode [N]
        self._xz = np.zeros((self.io.n, 2))  # positions read and forces written by _kernel_work
        self._F_out = np.zeros((len(self._dynamic), 2))
        self.hooks = []
        self._set_velocities, self._run_kernel = yade_io.set_velocities, yade_io.run_kernel

    def runner(self, label="paperLaw"):
        from engines import yade_io
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
        call with the bridge; engines.yade_io.run_kernel). False when the step needs ``_work``."""
        core = self.core
        while True:
            args = core.kernel_step_args()
            if args is None:
                return False
            due, law_args, water_args, tie_args = args
            n_lost, n_sub = self._run_kernel(kernels.dem_step, self.io, self._xz, self.forced, self._F_out,
                                             self._dynamic, self.held, due, *law_args, *water_args, *tie_args)
            if n_lost != kernels.LIST_STALE:
                break
            core.law.contact._update_list(self._xz)
        fixes = core.finish_kernel_step(self._xz, n_lost, n_sub, args)
        self._after(fixes)
        return True

    def _write_held(self, F):
        self.forced.set_permanent_forces(F, self._dynamic, self.held)
