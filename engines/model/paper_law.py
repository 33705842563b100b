"""The paper's contact law per step, without YADE (seed 000 §2: springs a-d, eps_m, eq 1-13, 18-27, spin).

No YADE law has the f_max plateau of springs (c) and (d), the eq 18-24 velocity adjustment at
separation or the paper's incremental tangential spring with rolling, so this law runs as its own
engine: ``PaperLaw`` is the per-step work without YADE (engines.model.contact's ContactLaw; its
compiled twin is engines.compiled.paper_law.PaperLaw), engines.yade.paper_law_engine.PaperLawEngine
the YADE object that reads the centres in bulk, calls it and adds the forces. The discs' spin about y is integrated here (eq 14c, 16c); YADE only translates them.
The side-wall springs of the seismic box (Fig. 27) are added by engines.model.pore_dem.PoreDEM.

Flat walls (SPEC §2.6, READINGS F7): a particle touches a flat wall as it would a wall disc of
radius 0 at its foot on the face (engines.model.flat_walls.WallVertices), the foot moving with its
wall (at rest for a fixed wall; with a translated wall, ``move_walls``, its du is the wall's
displacement in the step, as a driven wall disc's): R is the distance to the face, the normal the
wall's, eq 1-13 and 25-27 as for any pair, and for eq 18-24 the wall is an element that is not
free (pattern (a)) moving at its velocity.
"""
import numpy as np

from engines.model.contact import ContactLaw, separation_adjustment
from engines.model.effective_stress import pair_contacts
from engines.model.flat_walls import WallVertices


class PaperLaw:
    """State and per-step work of the paper's law for N discs (SI, per unit thickness).

    r, mass, inertia (N,) [m, kg/m, kg m]; mobile (N,) bool; dt [s]. ``omega`` (N,) spin [rad/s]
    and ``du`` (N, 2) the last displacement increments [m] are plain arrays (saved in checkpoints).
    flat_walls: engines.model.flat_walls.FlatWall, ... (module docstring); the contact law then runs
    over the discs and their feet (``walls``: the WallVertices), and its pairs index those.
    """

    contact_class = ContactLaw  # of ``contact``
    # what a checkpoint stores (engines.model.state); shift_prev and wall_du with flat walls only
    CHECKPOINT_FIELDS = ("contact", "walls", "omega", "du", "xz_prev", "shift_prev", "wall_du")
    CHECKPOINT_DERIVED = {name: "the scene's settings and the packing's discs" for name in
                          ("settings", "dt", "mobile", "mass", "inertia")}

    def __init__(self, settings, r, mobile, mass, inertia, dt, flat_walls=()):
        self.settings, self.dt = settings, float(dt)
        self.mobile = np.asarray(mobile, bool)
        self.mass, self.inertia = np.ascontiguousarray(mass, float), np.ascontiguousarray(inertia, float)
        n = len(self.mobile)
        self.walls = WallVertices(flat_walls, n) if flat_walls else None
        if self.walls is None:
            self.contact = self.contact_class(settings, r, self.mobile)
        else:  # pairs of two discs or a disc and its own foot (WallVertices.may_touch)
            wv, r = self.walls, np.asarray(r, float)
            mobile = np.concatenate([self.mobile, np.zeros(wv.n_vertices - n, bool)])
            self.contact = self.contact_class(settings, wv.radii(r), mobile, skin=0.25 * r.min(),
                                              pair_filter=wv.may_touch)
        self.omega = np.zeros(n)
        self.du = np.zeros((n, 2))
        self.xz_prev = None
        if self.walls is not None:  # the walls' shift at the last step and its increment (eq 17 of a wall)
            self.shift_prev, self.wall_du = self.walls.shift.copy(), np.zeros_like(self.walls.shift)

    def checkpoint_restored(self):
        """Refuse stored positions of the last step of another shape than the discs'."""
        if self.xz_prev is not None and self.xz_prev.shape != (len(self.mobile), 2):
            raise ValueError(f"xz_prev has shape {self.xz_prev.shape}, expected {(len(self.mobile), 2)}")

    def move_walls(self, shift):
        """Translate the flat walls to ``shift`` (W, 2) [m] from their FlatWall positions
        (flat_walls.WallVertices.move): their positions at the next step."""
        self.walls.move(shift)

    def set_dt(self, dt):
        """Step with dt [s] from now on (eq 17: du / dt, the dashpots and the spin read it at each step)."""
        if not dt > 0:
            raise ValueError(f"dt must be > 0 [s], got {dt}")
        self.dt = float(dt)

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
        mass, mobile = self.mass, self.mobile
        if self.walls is not None:  # the feet: not free, at their wall's velocity
            v = self._at_vertices(v, self.wall_du / self.dt)
            mass, mobile = self._at_vertices(mass), self._at_vertices(mobile)
        return separation_adjustment(separations, self.contact.touch_count(), v, mass, mobile, s.restitution)

    def _at_vertices(self, a, per_wall=None):
        """The disc array a (N, ...) over the contact law's vertices: zeros for the feet, or
        per_wall[w] (W, ...) for the feet on wall w."""
        wv, n = self.walls, len(self.mobile)
        out = np.zeros((wv.n_vertices,) + np.shape(a)[1:], np.asarray(a).dtype)
        out[:n] = a
        if per_wall is not None:
            out[n:wv.foot(len(wv.walls), 0)] = np.repeat(per_wall, n, axis=0)
        return out

    def _on_vertices(self, xz, du, wall_du):
        """(positions, increments du, dpsi) of the contact law's vertices at disc centres xz with
        increments du: the discs', then their feet, which move by their wall's increment wall_du
        (W, 2) [m] and do not turn."""
        return (self.walls.positions(xz), self._at_vertices(du, wall_du),
                self._at_vertices(self.omega * self.dt))

    def _forces(self, xz):
        """(F (N, 2) [N], SeparationEvents) of the step at xz: eq 17, the contact forces, the spin."""
        dt = self.dt
        self.du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev  # eq 17
        if self.walls is None:
            F, M, separations = self.contact.forces(xz, self.du, self.omega * dt, dt)
        else:
            self.wall_du = self.walls.shift - self.shift_prev  # eq 17 of the walls
            self.shift_prev = self.walls.shift.copy()
            F, M, separations = self.contact.forces(*self._on_vertices(xz, self.du, self.wall_du), dt)
            F, M = F[:len(xz)], M[:len(xz)]
        mob = self.mobile
        self.omega[mob] += M[mob] / self.inertia[mob] * dt  # eq 14c, 16c
        self.xz_prev = xz
        return F, separations

    def contact_pairs(self, xz, keep=None):
        """(pairs (K, 2), f_n (K,), e_s (K,) [N]) of the pairs touching at centres xz, as this law's
        step at xz would find them (eq 17: du = xz - xz_prev, dpsi = omega dt), its state left as it
        is (ContactLaw.touching_at; ``keep`` as there); with flat walls the pairs of two discs only."""
        du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev
        if self.walls is None:
            return self.contact.touching_at(xz, du, self.omega * self.dt, self.dt, keep)
        n = len(xz)

        def discs(i, j):  # the pairs of two discs (the walls' contacts: wall_forces), those ``keep`` takes
            sel = j < n
            if keep is not None:
                sel[sel] = keep(i[sel], j[sel])
            return sel
        # the feet's increments do not matter: only pairs of two discs are evaluated
        return self.contact.touching_at(*self._on_vertices(xz, du, self.wall_du), self.dt, discs)

    def stress_contacts(self, xz):
        """The contacts of the particles at centres xz as this law's step at xz would find them
        (``contact_pairs``, its state left as it is), with the flat walls' feet: Contacts of
        engines.model.effective_stress (a contact with a wall disc or a foot counts for its particle)."""
        du = np.zeros_like(xz) if self.xz_prev is None else xz - self.xz_prev
        if self.walls is None:
            at = (xz, du, self.omega * self.dt)
        else:
            at = self._on_vertices(xz, du, self.wall_du)
        pairs, f_n, f_s = self.contact.touching_at(*at, self.dt)
        return pair_contacts(at[0], self.contact.r, pairs, f_n, f_s, self.contact.mobile)

    def wall_forces(self):
        """Normal force (W,) [N per m thickness] of the particles' contacts on each flat wall at the
        last step, positive pushing the wall outward (pores.wall_reactions takes it)."""
        c, wv = self.contact, self.walls
        foot = c.j >= wv.n  # pairs are sorted (i < j): a foot is j
        k, w = wv.split_bits(wv.bits[c.j[foot]])
        return np.bincount(w, c.f_n[foot][k], minlength=len(wv.walls))
