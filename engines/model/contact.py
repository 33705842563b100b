"""The paper's contact law between discs (seed 000 §2, eq 1-13, 18-27), vectorised. No YADE.

Per unit thickness: forces in N, stiffnesses in N/m, dashpots in N s/m. Sign conventions are the
paper's: for a pair (i, j) the normal n points from i to j (cos a = (x_j - x_i)/R, eq 2), the
tangent t = (-sin a, cos a); normal forces are positive in compression, Delta u_n is positive
on approach (eq 3a), Delta u_s counter-clockwise (eq 3b, rolling included).

Normal spring variants (Fig. 5): the elastic force follows
  a, b  e_n = kn u_n                      linear (b is a with eps_m > 0, eq 26)
  c     e_n = min(kn u_n, f_max)          nonlinear elastic: same path on unloading
  d     e_n <- min(e_n + kn du_n, f_max)  hysteretic: unloads along kn from the cap (eq 27)
where u_n is the overlap accumulated by the increments of eq 3a from the moment the pair
touched (it starts at the overlap reached in that step). Then eq 4-12: d_n = eta_n du_n/dt;
e_n < 0 -> e_n = d_n = e_s = d_s = 0 (eq 6, 10); |e_s| > mu e_n -> e_s = mu e_n sign(e_s),
d_s = 0 (eq 11). Forces on i (eq 13): F = -f_n n - f_s t, moment -r_i f_s; j gets the opposite
force and moment -r_j f_s.

Velocity adjustment at separation (eq 18-24) is in ``separation_adjustment``.
"""
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from engines.model.fields import NONNEG, POS, Field, settings_class

# columns of the per-pair contact state (ContactLaw.state; the compiled kernels read the same columns)
TOUCHING, U_N, E_N, E_S, VN_COLL, F_N = range(6)


CONTACT_FIELDS = {  # the scene file's [contact] table holds these and the engine's own choices
    "spring": Field(str, "c", ("a", "b", "c", "d"), "normal spring of Fig. 5: a/b linear, c nonlinear elastic, d hysteretic"),
    "kn": Field(float, 1.4e6, POS, "normal stiffness [N/m]"),
    "eta_n": Field(float, 5.2, NONNEG, "normal dashpot [N s/m]"),
    "ks": Field(float, 3.5e5, NONNEG, "tangential stiffness [N/m]"),
    "eta_s": Field(float, 1.3, NONNEG, "tangential dashpot [N s/m]"),
    "mu": Field(float, 1.0, NONNEG, "friction coefficient"),
    "restitution": Field(float, 0.001, (0.0, 1.0), "e of the velocity adjustment at separation (eq 19)"),
    "f_max": Field(float, 2.5, POS, "cap of the elastic normal force for springs c, d [N] (eq 27)"),
    "eps_m": Field(float, 0.0, NONNEG, "force range beyond touching [m] (eq 26)"),
    "separation_adjustment": Field(bool, True, None, "apply eq 18-24 when a particle becomes free"),
}
ContactSettings = settings_class("ContactSettings", CONTACT_FIELDS, "contact", __name__,
                                 "Constants of the contact law (CONTACT_FIELDS; the scene file's [contact] table).")


@dataclass
class SeparationEvent:
    """A pair that touched at the previous step and does not now."""

    i: int
    j: int
    normal: np.ndarray   # unit vector from i to j at separation
    vn_collision: float  # approach velocity at first touch [m/s] (eq 21, positive)


class ContactLaw:
    """State and forces of all disc pairs. Pairs come from a Verlet list (cKDTree) rebuilt when
    a disc has moved by more than half the skin; state is carried over by pair key.

    ``state`` (m, 6) holds per pair the columns TOUCHING, U_N, E_N, E_S, VN_COLL, F_N: touching flag,
    accumulated overlap u_n [m] (kept as it was while the pair is apart), elastic forces e_n, e_s [N],
    approach velocity at first touch [m/s], last normal force [N]. Its compiled twin
    engines.compiled.contact.ContactLaw runs the per-step loop in a kernel (the same arithmetic as
    the NumPy code here, which stays the readable path).
    """

    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("i", "j", "state", "xz_list", "list_builds")
    CHECKPOINT_RESIZED = ("i", "j", "state")  # the pair list
    CHECKPOINT_DERIVED = {name: "the scene's contact settings and the packing's discs" for name in
                          ("s", "r", "mobile", "n", "skin", "pair_filter", "reach")}

    def __init__(self, settings, r, mobile, skin=None, pair_filter=None):
        self.s = settings
        self.r = np.ascontiguousarray(r, float)
        self.mobile = np.asarray(mobile, bool)
        self.n = len(self.r)
        self.skin = 0.25 * self.r.min() if skin is None else skin
        self.pair_filter = pair_filter  # (i, j) -> mask of the candidate pairs that may touch (flat walls)
        self.reach = 2 * self.r.max() + settings.eps_m
        self.i = self.j = np.zeros(0, np.int64)
        self.xz_list = None
        self.state = np.zeros((0, 6))
        self.list_builds = 0

    def checkpoint_restored(self):
        """Refuse a stored pair list whose arrays do not fit together or index no disc."""
        m = len(self.i)
        if self.xz_list is not None and self.xz_list.shape != (self.n, 2):
            raise ValueError(f"pair list: xz_list has shape {self.xz_list.shape}, expected {(self.n, 2)}")
        if self.j.shape != (m,) or self.state.shape != (m, 6):
            raise ValueError(f"pair list: i {self.i.shape}, j {self.j.shape}, state {self.state.shape} do not fit")
        if m and (min(self.i.min(), self.j.min()) < 0 or max(self.i.max(), self.j.max()) >= self.n):
            raise ValueError(f"pair list: disc indices outside [0, {self.n})")

    @property
    def half_skin2(self):
        """(skin / 2)^2 [m^2]: the list is rebuilt once a disc has moved that far (squared)."""
        return (0.5 * self.skin) ** 2

    @property
    def touching(self):
        return self.state[:, TOUCHING] != 0

    @property
    def f_n(self):
        """Normal force of each pair at the last step [N] (0 when not touching)."""
        return self.state[:, F_N]

    def _stale(self, xz):
        """Has a disc moved by half the skin since the pair list was built (or is there none)?"""
        if self.xz_list is None:
            return True
        return self._max_sq_moved(xz) >= self.half_skin2

    def _max_sq_moved(self, xz):
        """The largest squared displacement of a disc since the list was built [m^2]."""
        return np.max(np.sum((xz - self.xz_list) ** 2, axis=1), initial=0.0)

    def _update_list(self, xz):
        """Rebuild the pair list at xz if it is stale (``_stale``); True if it was rebuilt."""
        if not self._stale(xz):
            return False
        self.i, self.j, self.state = self._pairs_near(xz)
        self.xz_list = xz.copy()
        self.list_builds += 1
        return True

    def _pairs_near(self, xz):
        """(i, j, state) of a pair list built at xz: the pairs with a mobile disc and
        R <= r_i + r_j + eps_m + skin, so that no other pair can touch before the next build,
        sorted by (i, j), with the state of the pairs already listed."""
        pairs = cKDTree(xz).query_pairs(self.reach + self.skin, output_type="ndarray").astype(np.int64)
        d = xz[pairs[:, 1]] - xz[pairs[:, 0]]
        near = np.hypot(d[:, 0], d[:, 1]) <= self.r[pairs[:, 0]] + self.r[pairs[:, 1]] + self.s.eps_m + self.skin
        pairs = pairs[near & (self.mobile[pairs[:, 0]] | self.mobile[pairs[:, 1]])]
        pairs.sort(axis=1)
        if self.pair_filter is not None:
            pairs = pairs[self.pair_filter(pairs[:, 0], pairs[:, 1])]
        key_new = pairs[:, 0] * self.n + pairs[:, 1]
        order = np.argsort(key_new)
        pairs, key_new = pairs[order], key_new[order]
        key_old = self.i * self.n + self.j  # sorted by construction
        state = np.zeros((len(pairs), 6))
        if len(key_old):
            pos = np.minimum(np.searchsorted(key_old, key_new), len(key_old) - 1)
            hit = key_old[pos] == key_new
            state[hit] = self.state[pos[hit]]
        return np.ascontiguousarray(pairs[:, 0]), np.ascontiguousarray(pairs[:, 1]), state

    def forces(self, xz, du, dpsi, dt):
        """Contact forces (N, 2) [N] and moments (N,) [N m, counter-clockwise] at positions xz.

        du (N, 2): displacement increments of the last step [m] (eq 17); dpsi (N,): rotation
        increments [rad, counter-clockwise]. Returns (F, M, separations).
        """
        self._update_list(xz)
        F, M, self.state, lost = self._forces_numpy(xz, du, dpsi, dt, self.i, self.j, self.state)
        return F, M, self._separations(xz, lost)

    def _forces_numpy(self, xz, du, dpsi, dt, i, j, state):
        """(F, M, new state, indices of the pairs that stopped touching) of the pairs (i, j) with
        ``state`` of the last step (eq 1-13)."""
        s, r = self.s, self.r
        touching, u_n_old, e_n_old, e_s_old, vn_coll, _ = state.T
        touching = touching != 0
        d = xz[j] - xz[i]
        R = np.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2)
        nx, nz = d[:, 0] / R, d[:, 1] / R  # cos a, sin a (eq 2)
        delta = r[i] + r[j] + s.eps_m - R
        now = delta >= 0  # eq 1, 26
        new = now & ~touching
        dux, duz = du[i, 0] - du[j, 0], du[i, 1] - du[j, 1]
        dun = dux * nx + duz * nz  # eq 3a
        dus = -dux * nz + duz * nx + r[i] * dpsi[i] + r[j] * dpsi[j]  # eq 3b
        u_n = np.where(new, delta, u_n_old + dun)
        if s.spring in ("a", "b"):
            e_n = s.kn * u_n  # eq 4a, 5a
        elif s.spring == "c":
            e_n = np.minimum(s.kn * u_n, s.f_max)  # eq 27, elastic
        else:
            e_n = np.minimum(np.where(new, s.kn * delta, e_n_old + s.kn * dun), s.f_max)  # eq 27
        d_n = s.eta_n * dun / dt  # eq 4b, 5b
        cut = (e_n < 0) | ~now  # eq 6 (and no force out of reach)
        e_n = np.where(cut, 0.0, e_n)
        d_n = np.where(cut, 0.0, d_n)
        e_s = np.where(new, 0.0, e_s_old) + s.ks * dus  # eq 8a, 9a
        d_s = s.eta_s * dus / dt  # eq 8b, 9b
        e_s = np.where(cut, 0.0, e_s)  # eq 10
        d_s = np.where(cut, 0.0, d_s)
        slip = np.abs(e_s) > s.mu * e_n
        e_s = np.where(slip, s.mu * e_n * np.sign(e_s), e_s)  # eq 11a
        d_s = np.where(slip, 0.0, d_s)  # eq 11b
        f_n, f_s = e_n + d_n, e_s + d_s  # eq 7, 12
        fx = -f_n * nx + f_s * nz  # eq 13a, on i
        fz = -f_n * nz - f_s * nx  # eq 13b, on i
        n = self.n
        F = np.column_stack([np.bincount(i, fx, minlength=n) - np.bincount(j, fx, minlength=n),
                             np.bincount(i, fz, minlength=n) - np.bincount(j, fz, minlength=n)])
        M = -(np.bincount(i, r[i] * f_s, minlength=n) + np.bincount(j, r[j] * f_s, minlength=n))  # eq 13c
        new_state = np.column_stack([now, np.where(now | touching, u_n, u_n_old),  # apart: u_n kept, unread
                                     e_n, np.where(now, e_s, 0.0), np.where(new, dun / dt, vn_coll),
                                     np.where(now, f_n, 0.0)])
        return F, M, new_state, np.flatnonzero(touching & ~now)

    def touching_at(self, xz, du, dpsi, dt, keep=None):
        """(pairs (K, 2), f_n (K,), e_s (K,) [N]) of the pairs touching at centres xz after the
        increments du, dpsi of a step of dt [s] (eq 1-13): what ``forces`` would give there, from
        the pair list it would use, the law's state left as it is. ``keep(i, j)``: a mask of the
        listed pairs to evaluate (default all); the compiled twin steps a copy of their state."""
        i, j, state = self._pairs_near(xz) if self._stale(xz) else (self.i, self.j, self.state)
        if keep is not None:
            sel = keep(i, j)
            i, j, state = i[sel], j[sel], state[sel]
        new = self._stepped_state(xz, du, dpsi, dt, i, j, state)
        t = new[:, TOUCHING] != 0
        return np.column_stack([i[t], j[t]]), new[t, F_N], new[t, E_S]

    def _stepped_state(self, xz, du, dpsi, dt, i, j, state):
        """The state of the pairs (i, j) after a step from ``state`` (left as it is)."""
        return self._forces_numpy(xz, du, dpsi, dt, i, j, state)[2]

    def _separations(self, xz, lost):
        """SeparationEvents of the pairs ``lost`` (their vn_coll is that of their first touch)."""
        out = []
        for k in lost.tolist():
            a, b = self.i[k], self.j[k]
            d = xz[b] - xz[a]
            R = np.sqrt(d[0] ** 2 + d[1] ** 2)
            out.append(SeparationEvent(int(a), int(b), np.array([d[0] / R, d[1] / R]),
                                       float(self.state[k, VN_COLL])))
        return out

    def touch_count(self):
        """Number of touching partners of each disc."""
        t = self.touching
        return np.bincount(self.i[t], minlength=self.n) + np.bincount(self.j[t], minlength=self.n)

    def contact_pairs(self):
        """(pairs (K, 2), normal force f_n (K,), elastic shear force e_s (K,) [N]) of the touching
        pairs, for plots and VTK (e_s along t of eq 3b; the dashpot part d_s is not kept)."""
        t = self.touching
        return np.column_stack([self.i[t], self.j[t]]), self.f_n[t].copy(), self.state[t, E_S].copy()


def separation_adjustment(events, touch_count, vel, mass, mobile, e):
    """New velocities of discs that became free this step (eq 18-24, Fig. 3). Returns {disc: v}.

    A disc is free when it touches nothing now. For a free disc i that left j:
      Vn_i = v_i . n, Vn_j = -v_j . n (eq 20), approach positive; the collision value Vn_ij is
      the approach velocity recorded when the pair first touched (eq 21).
      Only a separation faster than restitution allows (-Vn'_ij > e Vn_ij, eq 18) is adjusted.
      (a) j still touches others or is a wall: scale i's normal velocity so -Vn''_ij/Vn_ij = e
          (eq 22-23). (b) i left several discs: the smallest factor Rk_i, along that pair's normal.
      (c) j is free too but had other partners: j is adjusted first, then i against the new j.
      (d) i and j touched only each other: both, conserving their normal momentum (eq 24).
    Eq 24b's left side is read with the separation velocities (the momentum the adjustment keeps).
    """
    by_disc = {}
    for ev in events:
        by_disc.setdefault(ev.i, []).append(ev)
        by_disc.setdefault(ev.j, []).append(ev)
    free = {k for k in by_disc if mobile[k] and touch_count[k] == 0}
    v = {k: np.asarray(vel[k], float).copy() for k in by_disc}
    # (d) isolated pairs first, then (a)/(b) against discs that are not free, then (c)
    done = _isolated_pairs(by_disc, free, v, mass, e)
    pending = sorted(free - done)
    for a in pending:  # (a), (b): every partner is a wall or still touches others
        if all(_partner(ev, a) not in free for ev in by_disc[a]):
            _adjust_against(v, a, by_disc[a], e)
            done.add(a)
    for a in sorted(free - done):  # (c) first the partner j, against the discs that are not free
        fixed = [ev for ev in by_disc[a] if _partner(ev, a) not in free]
        if fixed:
            _adjust_against(v, a, fixed, e)
            done.add(a)
    for a in sorted(free - done):  # (c) then i, against the adjusted j
        _adjust_against(v, a, by_disc[a], e)
        done.add(a)
    return {k: v[k] for k in done if mobile[k]}


def _normal_parts(v, ev, a):
    """(Vn_a, Vn_b, b, n from a to b) for disc a of the event at velocities v, eq 20."""
    b, n = (ev.j, ev.normal) if ev.i == a else (ev.i, -ev.normal)
    return float(v[a][0] * n[0] + v[a][1] * n[1]), float(-(v[b][0] * n[0] + v[b][1] * n[1])), b, n


def _partner(ev, a):
    """The other element of the event than disc a."""
    return ev.j if ev.i == a else ev.i


def _isolated_pairs(by_disc, free, v, mass, e):
    """Pattern (d) of separation_adjustment: free discs a, b that touched only each other, both
    adjusted conserving their normal momentum (eq 24), v in place. Returns the discs settled."""
    done = set()
    for a in sorted(free):
        evs = by_disc[a]
        if a in done or len(evs) != 1:
            continue
        vn_a, vn_b, b, n = _normal_parts(v, evs[0], a)
        if b in free and len(by_disc[b]) == 1:
            target = -e * evs[0].vn_collision
            if -(vn_a + vn_b) > e * evs[0].vn_collision > 0:
                P = mass[a] * vn_a - mass[b] * vn_b  # eq 24b
                new_a = (P + mass[b] * target) / (mass[a] + mass[b])  # Rk_a Vn_a
                new_b = target - new_a  # eq 24a
                v[a] -= (vn_a - new_a) * n
                v[b] += (vn_b - new_b) * n
            done |= {a, b}
    return done


def _adjust_against(v, a, evs, e):
    """Eq 22-23 for disc a against the separations ``evs`` (pattern (b): the smallest Rk_a), v in place."""
    best = None
    for ev in evs:
        vn_a, vn_b, b, n = _normal_parts(v, ev, a)
        if vn_a == 0 or not -(vn_a + vn_b) > e * ev.vn_collision > 0:
            continue
        rk = (-e * ev.vn_collision - vn_b) / vn_a  # eq 22
        if best is None or rk < best[0]:
            best = (rk, vn_a, n)
    if best is not None:
        rk, vn_a, n = best
        v[a] -= (1 - rk) * vn_a * n  # eq 23
