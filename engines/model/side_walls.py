"""Side walls of the seismic box (seed 000 §6.1, Fig. 26-27). Pure NumPy, no YADE.

The bottom wall follows the input motion (engines.model.ground_motion) and takes no force ("the bottom
wall elements receive no force from the other elements"). Each side wall is a column of wall
discs that moves only in x, under the sum of the forces of the particles (the contact law, added
by the caller) and of the ties of Fig. 27: vertical neighbours of a column are joined by a
tangential spring k'_s and a dashpot eta'_s, the lowest disc to the corner disc of the bottom
wall. For a vertical tie, tangential is horizontal, so a tie (l, u) pulls on the relative x motion:

    f_u = -k'_s [(x_u - x_l) - (x_u0 - x_l0)] - eta'_s (v_u - v_l),    f_l = -f_u

(x0: positions when the ties are made). A column displaced rigidly with the base feels nothing;
the forces of a tie are equal and opposite, and the dashpots only dissipate:
dE/dt = -eta'_s sum (v_u - v_l)^2.

Stability (explicit update): each disc has at most two ties, so the column's highest frequency
obeys w^2 <= 4 k'_s / m_min (Gershgorin), and symplectic Euler needs dt < 2 / w = sqrt(m_min / k'_s) (engines.model.limits.tie_limit).
"""
import numpy as np

from engines.model.pores import WALL_BOTTOM, WALL_LEFT, WALL_RIGHT


class SideWallTies:
    """The ties of Fig. 27 between the discs of both side columns and the bottom corners.

    Attributes: ``lower``, ``upper`` (M,) disc indices of each tie (upper above lower);
    ``rest`` (M,) x_u0 - x_l0 [m]; ``columns`` {"left"/"right": disc indices bottom to top, the
    corner disc of the bottom wall first}; ``moving`` (N,) bool: the side-wall discs (x only).
    """

    # a checkpoint stores nothing of it (engines.model.state): the ties are constant for a run
    CHECKPOINT_FIELDS = ()
    CHECKPOINT_DERIVED = {name: "the packing's side columns and the scene's springs" for name in
                          ("ks", "eta", "n", "columns", "lower", "upper", "rest", "moving")}

    def __init__(self, xz, group, ks, eta):
        xz, group = np.asarray(xz, float), np.asarray(group)
        if not (np.isfinite(ks) and ks >= 0 and np.isfinite(eta) and eta >= 0):
            raise ValueError(f"ks_wall and eta_s_wall must be >= 0, got {ks}, {eta}")
        self.ks, self.eta, self.n = float(ks), float(eta), len(xz)
        bottom = np.flatnonzero(group == WALL_BOTTOM)
        if not len(bottom):
            raise ValueError("side-wall ties need a bottom wall to anchor the columns")
        self.columns = {}
        lower, upper = [], []
        for code, name in ((WALL_LEFT, "left"), (WALL_RIGHT, "right")):
            col = np.flatnonzero(group == code)
            if not len(col):
                continue
            col = col[np.argsort(xz[col, 1])]
            corner = bottom[np.argmin(np.abs(xz[bottom, 0] - xz[col[0], 0]) + 1e-9 * xz[bottom, 1])]
            chain = np.concatenate([[corner], col])
            self.columns[name] = chain
            lower.extend(chain[:-1])
            upper.extend(chain[1:])
        self.lower, self.upper = np.array(lower, np.int64), np.array(upper, np.int64)
        self.rest = xz[self.upper, 0] - xz[self.lower, 0]
        self.moving = np.isin(np.arange(self.n), np.concatenate([c[1:] for c in self.columns.values()] or [[]]))

    def tie_forces(self, x, vx):
        """Per tie the force f_u on the upper disc [N] (the lower disc gets -f_u)."""
        return -self.ks * ((x[self.upper] - x[self.lower]) - self.rest) - self.eta * (vx[self.upper] - vx[self.lower])

    def forces(self, x, vx):
        """x-forces (N,) [N per m thickness] of the ties on every disc, for x positions (N,) [m]
        and x velocities (N,) [m/s]. The corner discs get the reactions (the driven base ignores them)."""
        f = self.tie_forces(np.asarray(x, float), np.asarray(vx, float))
        return np.bincount(self.upper, f, minlength=self.n) - np.bincount(self.lower, f, minlength=self.n)

