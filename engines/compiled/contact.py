"""The paper's contact law with its per-step loop compiled: engines.model.contact.ContactLaw, whose
NumPy arithmetic kernels.contact_forces repeats (tests/compiled/test_kernels.py). No YADE."""
import numpy as np

from engines.compiled import kernels
from engines.compiled.params import CONTACT_PRM
from engines.model import contact


class ContactLaw(contact.ContactLaw):
    """engines.model.contact.ContactLaw, stepped by kernels.contact_forces; the F, M that ``forces``
    returns are buffers reused by the next call."""

    CHECKPOINT_DERIVED = contact.ContactLaw.CHECKPOINT_DERIVED | {
        "_F": "scratch: the forces of a call", "_M": "scratch: the moments of a call", "_acc": "scratch of the kernel",
        "_lost": "scratch of the kernel, one per listed pair (checkpoint_restored)",
        "_spring": "the scene's spring", "_prm": "the scene's contact parameters for dt", "_args": "a cache of kernel_args"}

    def __init__(self, settings, r, mobile, skin=None, pair_filter=None):
        super().__init__(settings, r, mobile, skin, pair_filter)
        self._F, self._M, self._acc = np.zeros((self.n, 2)), np.zeros(self.n), np.zeros((self.n, 3))
        self._spring = kernels.SPRING_CODE[settings.spring]
        self._prm = kernels.contact_params(settings, np.nan)  # refreshed when dt changes
        self._args = None

    def kernel_args(self, dt):
        """The argument of kernels.contact_forces after (xz, du, dpsi) (kernels.ContactArgs) for a
        step of dt [s]."""
        if self._prm[CONTACT_PRM.dt] != dt:
            self._prm = kernels.contact_params(self.s, dt)
            self._args = None
        if self._args is None:
            self._args = kernels.ContactArgs(r=self.r, pi=self.i, pj=self.j, state=self.state, prm=self._prm,
                                             spring=self._spring, F=self._F, M=self._M, acc_j=self._acc,
                                             lost=self._lost)
        return self._args

    def _pairs_near(self, xz):
        """As engines.model.contact.ContactLaw._pairs_near, by kernels.near_pairs."""
        i, j, state = kernels.near_pairs(np.ascontiguousarray(xz, float), self.r, self.mobile, self.s.eps_m,
                                         self.skin, self.i, self.j, self.state)
        if self.pair_filter is not None:
            keep = self.pair_filter(i, j)
            i, j, state = i[keep], j[keep], state[keep]
        return i, j, state

    def _max_sq_moved(self, xz):
        return kernels.max_sq_displacement(xz, self.xz_list)

    def _update_list(self, xz):
        if not super()._update_list(xz):
            return False
        self._lost = np.zeros(len(self.i), np.int64)
        self._args = None
        return True

    def checkpoint_restored(self):
        """After a checkpoint set the pair list: its scratch and the kernel's arguments again."""
        super().checkpoint_restored()
        self._lost = np.zeros(len(self.i), np.int64)
        self._args = None

    def take_list(self, builds, i, j, state, lost):
        """The pair list that a kernel rebuilt ``builds`` times (kernels.dem_drive_bulk_io:
        near_pairs, with xz_list overwritten in place), and its ``lost`` buffer."""
        self.i, self.j, self.state, self._lost = i, j, state, lost
        self.list_builds += builds
        self._args = None

    def forces(self, xz, du, dpsi, dt):
        self._update_list(xz)
        n_lost = kernels.contact_forces(xz, du, dpsi, self.kernel_args(dt))
        return self._F, self._M, self._separations(xz, self._lost[:n_lost])

    def _stepped_state(self, xz, du, dpsi, dt, i, j, state):
        new = state.copy()
        kernels.stepped_state(xz, du, dpsi, self.r, i, j, new, kernels.contact_params(self.s, dt), self._spring)
        return new
