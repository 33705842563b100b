"""The paper's contact law per step, without YADE (seed 000 §2: springs a-d, eps_m, eq 1-13, 18-27, spin).

No YADE law has the f_max plateau of springs (c) and (d), the eq 18-24 velocity adjustment at
separation or the paper's incremental tangential spring with rolling, so this law runs as its own
engine: ``PaperLaw`` is the per-step work without YADE (engines.model.contact's ContactLaw; its
compiled twin is engines.compiled.paper_law.PaperLaw), engines.yade.paper_law_engine.PaperLawEngine
the YADE object that reads the centres in bulk, calls it and adds the forces. The discs' spin about y is integrated here (eq 14c, 16c); YADE only translates them.
The side-wall springs of the seismic box (Fig. 27) are added by engines.model.pore_dem.PoreDEM.
"""
import numpy as np

from engines.model.contact import ContactLaw, separation_adjustment


class PaperLaw:
    """State and per-step work of the paper's law for N discs (SI, per unit thickness).

    r, mass, inertia (N,) [m, kg/m, kg m]; mobile (N,) bool; dt [s]. ``omega`` (N,) spin [rad/s]
    and ``du`` (N, 2) the last displacement increments [m] are plain arrays (saved in checkpoints).
    """

    contact_class = ContactLaw  # of ``contact``

    def __init__(self, settings, r, mobile, mass, inertia, dt):
        self.settings, self.dt = settings, float(dt)
        self.mobile = np.asarray(mobile, bool)
        self.mass, self.inertia = np.asarray(mass, float), np.ascontiguousarray(inertia, float)
        self.contact = self.contact_class(settings, r, self.mobile)
        n = len(self.mobile)
        self.omega = np.zeros(n)
        self.du = np.zeros((n, 2))
        self.xz_prev = None

    def step(self, xz, vel=None):
        """Forces (N, 2) [N] at centres xz (N, 2) of this step and {disc: new velocity (2,)} of the
        discs that became free (eq 18-24); ``vel`` (N, 2) the velocities if known, else du/dt."""
        F, separations = self._forces(xz)
        return F, self._fixes(separations, vel)

    def _fixes(self, separations, vel):
        s = self.settings
        if not (separations and s.separation_adjustment):
            return {}
        v = self.du / self.dt if vel is None else vel
        return separation_adjustment(separations, self.contact.touch_count(), v, self.mass, self.mobile, s.restitution)

    def _forces(self, xz):
        """(F (N, 2) [N], SeparationEvents) of the step at xz: eq 17, the contact forces, the spin."""
        dt = self.dt
        self.du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev  # eq 17
        F, M, separations = self.contact.forces(xz, self.du, self.omega * dt, dt)
        mob = self.mobile
        self.omega[mob] += M[mob] / self.inertia[mob] * dt  # eq 14c, 16c
        self.xz_prev = xz
        return F, separations

    def contact_pairs(self, xz, keep=None):
        """(pairs (K, 2), f_n (K,), e_s (K,) [N]) of the pairs touching at centres xz, as this law's
        step at xz would find them (eq 17: du = xz - xz_prev, dpsi = omega dt), its state left as it
        is (ContactLaw.touching_at; ``keep`` as there)."""
        du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev
        return self.contact.touching_at(xz, du, self.omega * self.dt, self.dt, keep)
