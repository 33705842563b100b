"""The velocity adjustment at separation compiled (engines.model.contact.separation_adjustment,
eq 18-24, Fig. 3): the discs a separation set free (``free_discs``), and their new velocities
(eq 20 normal parts, eq 22 Rk, eq 23 the adjustment, eq 24 a pair that touched only each other).
No YADE."""
import math

import numpy as np

from engines.compiled.kernels.common import jit
from engines.model.contact import TOUCHING, VN_COLL  # the state columns, numba constants


@jit
def free_discs(lost, n_lost, pi, pj, state, mobile):
    """(N,) bool: the mobile discs of the pairs lost[:n_lost] that stopped touching which touch
    nothing now: the free discs of engines.model.contact.separation_adjustment (eq 18-24)."""
    free = np.zeros(len(mobile), np.bool_)
    for m in range(n_lost):
        for a in (pi[lost[m]], pj[lost[m]]):
            free[a] = mobile[a]
    for k in range(len(pi)):
        if state[k, TOUCHING] != 0.0:
            free[pi[k]] = free[pj[k]] = False
    return free


@jit
def _normal_parts(V, ea, eb, en, m, a):
    """(Vn_a, Vn_b, b, n_x, n_z) of disc a in separation m (eq 20): n from a to its partner b."""
    if ea[m] == a:
        b, n0, n1 = eb[m], en[m, 0], en[m, 1]
    else:
        b, n0, n1 = ea[m], -en[m, 0], -en[m, 1]
    return V[a, 0] * n0 + V[a, 1] * n1, -(V[b, 0] * n0 + V[b, 1] * n1), b, n0, n1


@jit
def _separations_of(ea, eb, a):
    """How many of the separations (ea, eb) disc a is in."""
    c = 0
    for m in range(len(ea)):
        c += (ea[m] == a) + (eb[m] == a)
    return c


@jit
def _has_partner(ea, eb, free, a, partner_free):
    """Has disc a a partner in the separations (ea, eb) whose ``free`` flag is partner_free?"""
    for m in range(len(ea)):
        if (ea[m] == a and free[eb[m]] == partner_free) or (eb[m] == a and free[ea[m]] == partner_free):
            return True
    return False


@jit
def _adjust_one(V, ea, eb, en, vnc, free, only_fixed, a, e):
    """Eq 22-23 for free disc a against its separations (``only_fixed``: those whose partner is not
    free): the smallest Rk_a, along that pair's normal (separation_adjustment's ``adjust``)."""
    best, vn_best, n0_best, n1_best = np.inf, 0.0, 0.0, 0.0
    found = False
    for m in range(len(ea)):
        if ea[m] != a and eb[m] != a:
            continue
        vn_a, vn_b, b, n0, n1 = _normal_parts(V, ea, eb, en, m, a)
        if only_fixed and free[b]:
            continue
        if vn_a == 0 or not -(vn_a + vn_b) > e * vnc[m] > 0:
            continue
        rk = (-e * vnc[m] - vn_b) / vn_a                        # eq 22
        if not found or rk < best:
            best, vn_best, n0_best, n1_best, found = rk, vn_a, n0, n1, True
    if found:
        c = (1 - best) * vn_best                                # eq 23
        V[a, 0] -= c * n0_best
        V[a, 1] -= c * n1_best


@jit
def separation_velocities(lost, n_lost, pi, pj, state, xz, du, dt, mass, free, e, V):
    """Twin of engines.model.contact.separation_adjustment (eq 18-24, Fig. 3) for the pairs
    lost[:n_lost] that stopped touching at centres xz, at the velocities du / dt: V (N, 2) [m/s]
    gets the new velocity of each disc ``free`` (``free_discs``); its other rows are not set."""
    ea, eb = pi[lost[:n_lost]], pj[lost[:n_lost]]
    vnc = state[lost[:n_lost], VN_COLL]
    en = np.empty((n_lost, 2))
    for m in range(n_lost):
        d0, d1 = xz[eb[m], 0] - xz[ea[m], 0], xz[eb[m], 1] - xz[ea[m], 1]
        R = math.sqrt(d0 * d0 + d1 * d1)
        en[m, 0], en[m, 1] = d0 / R, d1 / R
    discs = np.unique(np.concatenate((ea, eb)))  # ascending, as separation_adjustment's sorted()
    for a in discs:
        V[a, 0], V[a, 1] = du[a, 0] / dt, du[a, 1] / dt
    done = np.zeros(len(free), np.bool_)
    for a in discs:  # (d) pairs that touched only each other (eq 24)
        if not free[a] or done[a] or _separations_of(ea, eb, a) != 1:
            continue
        m = 0
        while ea[m] != a and eb[m] != a:
            m += 1
        vn_a, vn_b, b, n0, n1 = _normal_parts(V, ea, eb, en, m, a)
        if free[b] and _separations_of(ea, eb, b) == 1:
            target = -e * vnc[m]
            if -(vn_a + vn_b) > e * vnc[m] > 0:
                P = mass[a] * vn_a - mass[b] * vn_b             # eq 24b
                new_a = (P + mass[b] * target) / (mass[a] + mass[b])
                new_b = target - new_a                          # eq 24a
                V[a, 0] -= (vn_a - new_a) * n0
                V[a, 1] -= (vn_a - new_a) * n1
                V[b, 0] += (vn_b - new_b) * n0
                V[b, 1] += (vn_b - new_b) * n1
            done[a] = done[b] = True
    for a in discs:  # (a), (b): every partner is a wall or still touches others
        if free[a] and not done[a] and not _has_partner(ea, eb, free, a, True):
            _adjust_one(V, ea, eb, en, vnc, free, False, a, e)
            done[a] = True
    for a in discs:  # (c) first the partner j, against the discs that are not free
        if free[a] and not done[a] and _has_partner(ea, eb, free, a, False):
            _adjust_one(V, ea, eb, en, vnc, free, True, a, e)
            done[a] = True
    for a in discs:  # (c) then i, against the adjusted j
        if free[a] and not done[a]:
            _adjust_one(V, ea, eb, en, vnc, free, False, a, e)
