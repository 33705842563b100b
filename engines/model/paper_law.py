"""The paper's contact law per step, without YADE (seed 000 §2: springs a-d, eps_m, eq 1-13, 18-27, spin).

No YADE law has the f_max plateau of springs (c) and (d), the eq 18-24 velocity adjustment at
separation or the paper's incremental tangential spring with rolling, so this law runs as its own
engine: ``PaperLaw`` is the per-step work without YADE (engines.model.contact's ContactLaw, compiled
by default), engines.yade.paper_law_engine.PaperLawEngine the YADE object that reads the centres in bulk,
calls it and adds the forces. The discs' spin about y is integrated here (eq 14c, 16c); YADE only translates them.
The side-wall springs of the seismic box (Fig. 27) are added by engines.model.pore_dem.PoreDEM.
"""
import numpy as np

from engines.compiled import kernels
from engines.model.contact import ContactLaw, separation_adjustment


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
        """The arguments of kernels.law_step after xz (kernels.LAW: LAW_OWN, then the contact's
        CONTACT; compiled, after the first step)."""
        c = self.contact
        return kernels.LAW_OWN.values(xz_prev=self.xz_prev, xz_list=c.xz_list, half_skin2=c.half_skin2,
                                      omega=self.omega, dpsi=self._dpsi, du=self.du, inertia=self.inertia,
                                      mobile=self.mobile, dt=self.dt) + c.kernel_args(self.dt)

    def contact_pairs(self, xz, keep=None):
        """(pairs (K, 2), f_n (K,), e_s (K,) [N]) of the pairs touching at centres xz, as this law's
        step at xz would find them (eq 17: du = xz - xz_prev, dpsi = omega dt), its state left as it
        is (ContactLaw.touching_at; ``keep`` as there)."""
        du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev
        return self.contact.touching_at(xz, du, self.omega * self.dt, self.dt, keep)

    def finish_kernel_step(self, xz, n_lost):
        """The SeparationEvents of a law_step at xz that returned n_lost."""
        c = self.contact
        return c._separations(xz, c._lost[:n_lost]) if n_lost else []
