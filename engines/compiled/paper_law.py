"""The paper's law per step compiled: engines.model.paper_law.PaperLaw stepped by kernels.law_step
(eq 17, the contact forces, the spin in one call) on engines.compiled.contact.ContactLaw. With flat
walls the step is the NumPy law's (the feet placed, the increments extended) around the compiled
contact loop (kernels.contact_forces). No YADE."""
import numpy as np

from engines.compiled import kernels
from engines.compiled.contact import ContactLaw
from engines.model import paper_law


class PaperLaw(paper_law.PaperLaw):
    """engines.model.paper_law.PaperLaw by kernels.law_step: the forces ``step`` returns are a buffer
    that the next step overwrites; du and xz_prev are updated in place."""

    contact_class = ContactLaw
    CHECKPOINT_DERIVED = paper_law.PaperLaw.CHECKPOINT_DERIVED | {"_dpsi": "scratch of the kernel: omega dt"}

    def __init__(self, settings, r, mobile, mass, inertia, dt, flat_walls=()):
        super().__init__(settings, r, mobile, mass, inertia, dt, flat_walls)
        self._dpsi = np.zeros(len(self.mobile))  # omega dt, scratch of the kernel

    def _forces(self, xz):
        """kernels.law_step: the same arithmetic as engines.model.paper_law.PaperLaw._forces."""
        if self.walls is not None:
            return super()._forces(xz)
        if self.xz_prev is None:  # du = 0 at the first step
            self.xz_prev = np.array(xz, float)
            self.contact._update_list(xz)
        while True:
            n_lost = kernels.law_step(xz, *self.kernel_args())
            if n_lost >= 0:
                return self.contact._F, self.finish_kernel_step(xz, n_lost)
            self.contact._update_list(xz)

    def kernel_args(self, flat=False):
        """The arguments of kernels.law_step after xz (kernels.LAW: LAW_OWN, then the contact's
        kernels.ContactArgs; after the first step); ``flat``: with the ContactArgs' arrays in its
        place (LAW_OWN, then CONTACT: those of kernels.dem_drive_bulk_io)."""
        c = self.contact
        return kernels.LAW_OWN.values(xz_prev=self.xz_prev, xz_list=c.xz_list, half_skin2=c.half_skin2,
                                      omega=self.omega, dpsi=self._dpsi, du=self.du, inertia=self.inertia,
                                      mobile=self.mobile, dt=self.dt) + (
            tuple(c.kernel_args(self.dt)) if flat else (c.kernel_args(self.dt),))

    def finish_kernel_step(self, xz, n_lost):
        """The SeparationEvents of a law_step at xz that returned n_lost."""
        c = self.contact
        return c._separations(xz, c._lost[:n_lost]) if n_lost else []
