"""The paper's contact law compiled (engines.model.contact.ContactLaw.forces, engines.model.paper_law.
PaperLaw.step): ``contact_forces`` (eq 1-13: overlap, normal and tangential springs and dashpots,
Coulomb's cap eq 11; eq 25-27: the force range eps_m and the capped springs c, d) and ``law_step``
(eq 17 increments, the forces, the spin eq 14c, 16c). The parameters by name: ContactArgs, and its
vector prm (engines.compiled.params.CONTACT_PRM). No YADE."""
import math
from collections import namedtuple

import numpy as np

from engines.compiled.kernels.common import _at, _beyond, jit, jit_inline
from engines.compiled.layout import Layout
from engines.compiled.params import CONTACT_PRM
from engines.model.contact import E_N, E_S, F_N, TOUCHING, U_N, VN_COLL  # the state columns, numba constants


SPRING_CODE = {"a": 0, "b": 0, "c": 1, "d": 2}  # linear, capped elastic, capped hysteretic


def contact_params(s, dt):
    """The float parameters of ``contact_forces`` (CONTACT_PRM) from ContactSettings ``s`` and dt [s]."""
    return CONTACT_PRM.vector(s, dt=dt)


# The arguments of contact_forces after (xz, du, dpsi), one tuple by name: the radii r (N,), the pair
# list (pi, pj, its state (m, 6), lost (m,)), the parameters prm (CONTACT_PRM), spring (SPRING_CODE),
# the forces F (N, 2), moments M (N,) and scratch acc_j (N, 3)
ContactArgs = namedtuple("ContactArgs", ("r", "pi", "pj", "state", "prm", "spring", "F", "M", "acc_j", "lost"))
CONTACT = Layout("CONTACT", ContactArgs._fields)


@jit_inline
def with_pairs(c, pi, pj, state, lost):
    """The ContactArgs c on another pair list (pi, pj, state, lost)."""
    return ContactArgs(c.r, pi, pj, state, c.prm, c.spring, c.F, c.M, c.acc_j, lost)


@jit_inline
def contact_forces(xz, du, dpsi, c):
    """Forces c.F (N, 2) and moments c.M (N,) of all pairs (c.pi, c.pj) of the ContactArgs c;
    updates c.state (m, 6) in place.

    c.prm: CONTACT_PRM (kn, eta_n, ks, eta_s, mu, f_max, eps_m, dt); c.spring = SPRING_CODE; c.acc_j
    (N, 3) is scratch. Writes the indices of the pairs that stopped touching into c.lost; returns
    their number.
    """
    r, pi, pj, state, prm, spring, F, M, acc_j, lost = c.r, c.pi, c.pj, c.state, c.prm, c.spring, c.F, c.M, c.acc_j, c.lost
    kn, eta_n, ks, eta_s = prm[CONTACT_PRM.kn], prm[CONTACT_PRM.eta_n], prm[CONTACT_PRM.ks], prm[CONTACT_PRM.eta_s]
    mu, f_max, eps_m, dt = prm[CONTACT_PRM.mu], prm[CONTACT_PRM.f_max], prm[CONTACT_PRM.eps_m], prm[CONTACT_PRM.dt]
    F[:] = 0.0
    M[:] = 0.0
    acc_j[:] = 0.0
    n_lost = 0
    for k in range(len(pi)):
        i, j = _at(pi[k]), _at(pj[k])
        dx, dz = xz[j, 0] - xz[i, 0], xz[j, 1] - xz[i, 1]
        reach = r[i] + r[j] + eps_m
        was = state[k, TOUCHING] != 0.0
        d2 = dx * dx + dz * dz
        if not was and _beyond(d2, reach):  # apart before and now (no force; its state stays): no sqrt
            continue
        R = math.sqrt(d2)
        delta = reach - R
        now = delta >= 0                                        # eq 1, 26
        if not (now or was):  # apart before and now: no force; its state stays (forces 0 since it parted)
            continue
        nx, nz = dx / R, dz / R                                 # eq 2
        new = now and not was
        dux, duz = du[i, 0] - du[j, 0], du[i, 1] - du[j, 1]
        dun = dux * nx + duz * nz                               # eq 3a
        dus = -dux * nz + duz * nx + r[i] * dpsi[i] + r[j] * dpsi[j]   # eq 3b
        u_n = delta if new else state[k, U_N] + dun
        e_n = _elastic_normal(spring, kn, f_max, u_n, delta, dun, state[k, E_N], new)
        d_n = eta_n * dun / dt                                  # eq 4b, 5b
        e_s = (0.0 if new else state[k, E_S]) + ks * dus        # eq 8a, 9a
        d_s = eta_s * dus / dt                                  # eq 8b, 9b
        if e_n < 0 or not now:                                  # eq 6, 10
            e_n = d_n = e_s = d_s = 0.0
        if abs(e_s) > mu * e_n:                                 # eq 11
            e_s = mu * e_n * (1.0 if e_s > 0 else -1.0)
            d_s = 0.0
        f_n, f_s = e_n + d_n, e_s + d_s                         # eq 7, 12
        fx = -f_n * nx + f_s * nz                               # eq 13a, on i
        fz = -f_n * nz - f_s * nx                               # eq 13b
        _add_pair(F, M, acc_j, i, j, r, fx, fz, f_s)
        if was and not now:
            lost[n_lost] = k
            n_lost += 1
        _store_state(state, k, now, new, dun / dt, u_n, e_n, e_s, f_n)
    _add_j_sides(F, M, acc_j)
    return n_lost


@jit
def stepped_state(xz, du, dpsi, r, pi, pj, state, prm, spring):
    """``contact_forces`` of the pairs (pi, pj) on forces made here: their state (m, 6) after the
    step, updated in place. From Python, arrays spelled out take numba's fast argument check, where
    a ContactArgs is typed in Python at every call (~50 us)."""
    n = len(r)
    contact_forces(xz, du, dpsi, ContactArgs(r, pi, pj, state, prm, spring, np.empty((n, 2)), np.empty(n),
                                             np.empty((n, 3)), np.empty(len(pi), np.int64)))


@jit
def _add_pair(F, M, acc_j, i, j, r, fx, fz, f_s):
    """The force (fx, fz) [N] of a pair on disc i, and its tangential force f_s [N], added to F, M
    (the i side) and acc_j (the j side, (N, 3): force and moment), as np.bincount sums them."""
    F[i, 0] += fx
    F[i, 1] += fz
    M[i] += r[i] * f_s
    acc_j[j, 0] += fx
    acc_j[j, 1] += fz
    acc_j[j, 2] += r[j] * f_s


@jit
def _store_state(state, k, now, new, vn, u_n, e_n, e_s, f_n):
    """Row k of the contact state after the step: touching ``now``, u_n, e_n, e_s, f_n (0 apart),
    and the normal velocity vn [m/s] at the collision of a ``new`` contact (eq 19)."""
    if new:
        state[k, VN_COLL] = vn
    state[k, TOUCHING] = 1.0 if now else 0.0
    state[k, U_N] = u_n
    state[k, E_N] = e_n
    state[k, E_S] = e_s if now else 0.0
    state[k, F_N] = f_n if now else 0.0


@jit
def _elastic_normal(spring, kn, f_max, u_n, delta, dun, e_n_before, new):
    """The elastic normal force e_n [N] of the spring SPRING_CODE ``spring`` at the normal
    displacement u_n [m] (new contact: the overlap delta; else e_n_before + kn dun for spring d)."""
    if spring == 0:
        return kn * u_n                                         # eq 4a, 5a
    if spring == 1:
        return min(kn * u_n, f_max)                             # eq 27, elastic
    return min(kn * delta if new else e_n_before + kn * dun, f_max)  # eq 27, hysteretic


@jit
def _add_j_sides(F, M, acc_j):
    """F, M of the i sides less the j sides' sums acc_j (N, 3): the force on j is minus that on i
    (eq 13a, b); the moment -r f_s on both (eq 13c)."""
    for a in range(len(F)):
        F[a, 0] -= acc_j[a, 0]
        F[a, 1] -= acc_j[a, 1]
        M[a] = -(M[a] + acc_j[a, 2])                            # eq 13c: -r f_s on both


@jit
def max_sq_displacement(xz, xz_ref):
    """max_a |xz_a - xz_ref_a|^2 [m^2] (the Verlet-list check)."""
    out = 0.0
    for a in range(len(xz)):
        dx, dz = xz[a, 0] - xz_ref[a, 0], xz[a, 1] - xz_ref[a, 1]
        out = max(out, dx * dx + dz * dz)
    return out


@jit
def spin_update(omega, M, inertia, mobile, dt):
    """omega += M / I dt for mobile discs (eq 14c, 16c)."""
    for a in range(len(omega)):
        if mobile[a]:
            omega[a] += M[a] / inertia[a] * dt


@jit_inline
def law_step(xz, xz_prev, xz_list, half_skin2, omega, dpsi, du, inertia, mobile, dt, contact):
    """One step of PaperLaw: du = xz - xz_prev (eq 17), dpsi = omega dt, the contact forces F, M
    (``contact_forces`` of the ContactArgs ``contact``), omega += M / I dt (eq 14c, 16c), xz_prev <- xz.
    Returns the number of pairs that stopped touching (indices in ``lost``), or -1, having changed
    nothing, when a disc has moved by half the skin since the pair list was built at xz_list."""
    if max_sq_displacement(xz, xz_list) >= half_skin2:
        return -1
    for a in range(len(xz)):  # du, dpsi and xz_prev <- xz in one pass
        x, z = xz[a, 0], xz[a, 1]
        du[a, 0], du[a, 1] = x - xz_prev[a, 0], z - xz_prev[a, 1]
        xz_prev[a, 0], xz_prev[a, 1] = x, z
        dpsi[a] = omega[a] * dt
    n_lost = contact_forces(xz, du, dpsi, contact)
    spin_update(omega, contact.M, inertia, mobile, dt)
    return n_lost


LAW = Layout.of(law_step, 1)  # the arguments of law_step after xz: LAW_OWN, then the ContactArgs


LAW_OWN = Layout("LAW_OWN", LAW.names[:-1])


LAW.check(LAW_OWN, ("contact",))


LIST_STALE = -1  # law_step's answer when the pair list must be rebuilt first
