"""Compiled (numba) per-step kernels: the paper's contact law, the pore measure, the Darcy step and
the eq 33 pressure forces. No YADE.

Each kernel repeats, loop by loop, the arithmetic of a readable NumPy function, which stays the
reference path and is tested against it (tests/compiled/test_kernels.py, 1e-12 relative):

  contact_forces    engines.model.contact.ContactLaw.forces          (eq 1-13, 26-27)
  measure           engines.model.pores.measure              (eq 29, 43b; ``turn`` below)
  darcy_flows       engines.model.pore_water.PoreWater.flows, _limit (eq 32, 38-43, boundaries, stability)
  darcy_update      engines.model.pore_water.PoreWater._step         (eq 42, the new U; eq 46 in water_step)
  pressure_forces   engines.model.pores.pressure_forces      (eq 33, telescoped over links)
  tie_forces        engines.model.side_walls.SideWallTies.forces    (Fig. 27, the side-wall springs)
  separation_velocities  engines.model.contact.separation_adjustment   (eq 18-24, bit for bit)
  near_pairs        engines.model.contact.ContactLaw._pairs_near    (the pair list, on a grid of cells:
                    ``_grid``, which engines.compiled.pores uses too)
  gershgorin_limit, substep_count   engines.model.limits (the Darcy check of a water step)

and per-step kernels chain them, so that a step costs one call from Python (each array passed to
a numba function costs ~0.1-0.3 us to unbox, each call ~0.5 us):

  law_step          engines.model.paper_law.PaperLaw.step    (eq 17, contact_forces, spin)
  water_step        engines.model.water_model.WaterModel.advance  (measure, flows, update, eq 32, 33)
  base_step         engines.model.ground_motion.BaseMotion.step (a Cosine, or a Sampled record by
                    ``sampled_acceleration``, np.interp's arithmetic)
  dem_drive_bulk_io engines.model.pore_dem.PoreDEM.step in YADE, its parts in its order (law_step,
                    water_step when due, forces_to_write with the side-wall ties, separation_velocities,
                    base_step), between the bridge's reads and writes: n steps, one step being n = 1
  water_forces_step engines.yade.water_engine.WaterEngine: water_step and the forces to write

Arguments by name (engines.compiled.layout): each kernel called from Python has the layout of its
parameters (``LAW = Layout.of(law_step, 1)``), and its callers build its arguments by name
(``LAW_OWN.values(xz_prev=..., ...) + CONTACT.values(...)``); a kernel that spells out the
arguments of those it calls has its list checked to be theirs one after the other (DEM_DRIVE is
rows, held, LAW, WATER, TIES), and passes them on under their own names (tested). The
network's arrays of water_step are the parts of two buffers (WATER_INTS, WATER_FLOATS), read by
name as a WaterNet of views that hold no reference count (``water_net``, ``_view``). These lists
stay in this file: numba's cache is renewed when this file changes (not when a module it imports
does: the contact state's columns, engines.model.contact.TOUCHING ..., are read as constants;
after changing them, delete engines/compiled/__pycache__; likewise after changing ``_groups``,
``_grid``, ``_within``, ``_beyond`` or ``_grown``, which engines.compiled.pores and
engines.compiled.regular call).

The drives call the C functions of engines.yade.yadebulk, passed as addresses (BRIDGE; so that
this module stays cacheable and free of YADE): read, step, write and YADE's O.step() (the bridge's
steps()), many DEM steps in one call (``dem_drive_bulk_io``; ``water_drive_bulk_io`` with its water
steps between; one water step of the WaterEngine's PyRunner is a call of n = 1).

The pore measure takes each link's turn since the build with ``turn`` (a short series for the
small turns between rebuilds, else atan2) where engines.model.pores.measure calls arctan2: the same
angles to round-off, the measure 30 % cheaper. It sums each link's terms over the pores on its left
and on its right apart, as NumPy does. ``darcy_flows`` divides by E_w once per call and by
W once per pore where the NumPy flows divide each conductance, pressure and capacity: the same
values to round-off.

Sums over pairs are accumulated in the same order as np.bincount, into the same partial sums
(the i side and the j side apart), so most results are bit for bit those of NumPy. Outputs are
written into arrays the caller owns (allocated once per network or contact list). numba compiles on
first use and caches the machine code beside this file (``cache=True``); fastmath is off.
"""
import math
from collections import namedtuple

import numba as nb
import numpy as np
from llvmlite import ir
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array

from engines.compiled.layout import Layout
from engines.compiled.params import BALANCE, CONTACT_PRM, LAM, TIE_PRM, WATER_PRM
from engines.model.contact import E_N, E_S, F_N, TOUCHING, U_N, VN_COLL  # the state columns, numba constants

jit = nb.njit(cache=True, nogil=True)

SPRING_CODE = {"a": 0, "b": 0, "c": 1, "d": 2}  # linear, capped elastic, capped hysteretic


@jit
def _at(i):
    """Index i >= 0 as an unsigned integer: numba indexes with it without the wraparound of
    negative indices it adds for a signed one (measured on the seismic case: the pore measure
    28 % cheaper, the Darcy flows 15 %, the law and the eq 33 forces 8 %)."""
    return np.uint64(i)


@jit
def _beyond(d2, s):
    """Does a squared distance d2 exceed s^2 by more than its round-off (relative 1e-12 where it is
    a few 1e-16), so that sqrt(d2) > s without the square root?"""
    return d2 > s * s * (1.0 + 1e-12)


def contact_params(s, dt):
    """The float parameters of ``contact_forces`` (CONTACT_PRM) from ContactSettings ``s`` and dt [s]."""
    return CONTACT_PRM.vector(s, dt=dt)


# The arguments of contact_forces after (xz, du, dpsi), one tuple by name: the radii r (N,), the pair
# list (pi, pj, its state (m, 6), lost (m,)), the parameters prm (CONTACT_PRM), spring (SPRING_CODE),
# the forces F (N, 2), moments M (N,) and scratch acc_j (N, 3)
ContactArgs = namedtuple("ContactArgs", ("r", "pi", "pj", "state", "prm", "spring", "F", "M", "acc_j", "lost"))
CONTACT = Layout("CONTACT", ContactArgs._fields)


@jit
def with_pairs(c, pi, pj, state, lost):
    """The ContactArgs c on another pair list (pi, pj, state, lost)."""
    return ContactArgs(c.r, pi, pj, state, c.prm, c.spring, c.F, c.M, c.acc_j, lost)


@jit
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
        if spring == 0:
            e_n = kn * u_n                                      # eq 4a, 5a
        elif spring == 1:
            e_n = min(kn * u_n, f_max)                          # eq 27, elastic
        else:
            e_n = min(kn * delta if new else state[k, E_N] + kn * dun, f_max)  # eq 27, hysteretic
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
        F[i, 0] += fx
        F[i, 1] += fz
        M[i] += r[i] * f_s
        acc_j[j, 0] += fx
        acc_j[j, 1] += fz
        acc_j[j, 2] += r[j] * f_s
        if was and not now:
            lost[n_lost] = k
            n_lost += 1
        if new:
            state[k, VN_COLL] = dun / dt
        state[k, TOUCHING] = 1.0 if now else 0.0
        state[k, U_N] = u_n
        state[k, E_N] = e_n
        state[k, E_S] = e_s if now else 0.0
        state[k, F_N] = f_n if now else 0.0
    for a in range(len(F)):
        F[a, 0] -= acc_j[a, 0]
        F[a, 1] -= acc_j[a, 1]
        M[a] = -(M[a] + acc_j[a, 2])                            # eq 13c: -r f_s on both
    return n_lost


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


@jit
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


@jit
def _groups(key, n_groups):
    """Counting sort: (ptr (n_groups + 1,), order) with order[ptr[g]:ptr[g + 1]] the indices of the
    entries of key == g, increasing."""
    ptr = np.zeros(n_groups + 1, np.int64)
    for g in key:
        ptr[g + 1] += 1
    for g in range(n_groups):
        ptr[g + 1] += ptr[g]
    fill = ptr[:-1].copy()
    order = np.empty(len(key), np.int64)
    for e in range(len(key)):
        order[fill[key[e]]] = e
        fill[key[e]] += 1
    return ptr, order


@jit
def _grid(x, z, cell):
    """Square cells of side >= cell over the points (x, z): (x0, z0, cell, nx, nz, start, members),
    the points of cell (gx, gz) being members[start[g]:start[g + 1]], g = gx nz + gz, where
    gx = floor((x - x0) / cell)."""
    x0, z0 = x.min(), z.min()
    nx = int((x.max() - x0) / cell) + 1
    nz = int((z.max() - z0) / cell) + 1
    while nx * nz > 4 * len(x) + 16:  # scattered points: fewer, larger cells
        cell *= 2.0
        nx = int((x.max() - x0) / cell) + 1
        nz = int((z.max() - z0) / cell) + 1
    start, members = _groups(((x - x0) / cell).astype(np.int64) * nz + ((z - z0) / cell).astype(np.int64), nx * nz)
    return x0, z0, cell, nx, nz, start, members


@jit
def _within(dx, dz, s):
    """np.hypot(dx, dz) <= s, the hypot (~20 ns) computed only where dx^2 + dz^2 is not ``_beyond`` s."""
    if _beyond(dx * dx + dz * dz, s):
        return False
    return np.hypot(dx, dz) <= s


@jit
def _grown(x, m):
    """x with room for twice its m entries."""
    out = np.empty(2 * m, x.dtype)
    out[:m] = x[:m]
    return out


@jit
def near_pairs(xz, r, mobile, eps_m, skin, old_i, old_j, old_state):
    """engines.model.contact.ContactLaw._pairs_near before its pair filter: the pairs (i, j), i < j,
    with a mobile disc and R_ij <= r_i + r_j + eps_m + skin [m], sorted by (i, j), and their
    state (m, 6): the row of the same pair in (old_i, old_j, old_state) (sorted by (i, j)), else
    zeros. A grid of cells of side 2 max(r) + eps_m + skin finds them."""
    n = len(r)
    x0, z0, cell, nx, nz, start, in_cell = _grid(xz[:, 0], xz[:, 1], 2.0 * r.max() + eps_m + skin)
    pi = np.empty(8 * n + 16, np.int64)
    pj = np.empty(8 * n + 16, np.int64)
    partners = np.empty(n, np.int64)  # those j > i of disc i
    m = 0
    for i in range(n):
        cx, cz = int((xz[i, 0] - x0) / cell), int((xz[i, 1] - z0) / cell)
        k = 0
        for gx in range(max(cx - 1, 0), min(cx + 2, nx)):
            for gz in range(max(cz - 1, 0), min(cz + 2, nz)):
                g = gx * nz + gz
                for s in range(start[g], start[g + 1]):
                    j = in_cell[s]
                    if j > i and (mobile[i] or mobile[j]) and \
                            _within(xz[j, 0] - xz[i, 0], xz[j, 1] - xz[i, 1], r[i] + r[j] + eps_m + skin):
                        partners[k] = j
                        k += 1
        partners[:k].sort()
        while m + k > len(pi):
            pi, pj = _grown(pi, m), _grown(pj, m)
        pi[m:m + k] = i
        pj[m:m + k] = partners[:k]
        m += k
    state = np.zeros((m, old_state.shape[1]))
    o = 0
    for p in range(m):  # both lists sorted by (i, j): one merge
        while o < len(old_i) and (old_i[o] < pi[p] or (old_i[o] == pi[p] and old_j[o] < pj[p])):
            o += 1
        if o < len(old_i) and old_i[o] == pi[p] and old_j[o] == pj[p]:
            state[p] = old_state[o]
    return pi[:m].copy(), pj[:m].copy(), state


# atan(t) = t (1 - t^2/3 + t^4/5 - ...) for |t| <= SMALL_TURN: 5 terms leave < 6e-17 relative
# (half an ulp), and each of them moves turn(s, c) by more than 2 ulp somewhere in that range
SMALL_TURN = 0.03
_A0, _A1, _A2, _A3, _A4 = ((-1.0) ** k / (2 * k + 1) for k in range(5))  # numba constants


@jit
def turn(s, c):
    """atan2(s, c) [rad]: the angle whose sine and cosine are proportional to s and c. A link
    turns little between rebuilds (s small against c > 0): then the series of atan(s / c), about
    a quarter of the cost of atan2, equal to it to round-off; else atan2."""
    if c > 0.0 and abs(s) <= SMALL_TURN * c:
        t = s / c
        t2 = t * t
        t4 = t2 * t2  # Estrin's scheme: the pairs of terms side by side, not one chain
        return t * ((_A0 + t2 * _A1) + t4 * ((_A2 + t2 * _A3) + t4 * _A4))
    return math.atan2(s, c)


# The network's links as ``measure`` reads them (PoreNetwork: links (L, 2), link_pores (L, 2),
# link_vec0 (L, 2), link_turn_weight (L,), sector_area0 (Np,)), and the measures it writes (Np,)
# and (L,) (``contact`` a bool or 0/1 array; right (Np, 2) scratch)
LinkGeometry = namedtuple("LinkGeometry", ("links", "link_pores", "vec0", "turn_weight", "sector0"))
Measures = namedtuple("Measures", ("poly", "sect", "void", "length", "contact", "vec", "right"))


def link_geometry(net):
    """The LinkGeometry of the PoreNetwork ``net``."""
    return LinkGeometry(net.links, net.link_pores, net.link_vec0, net.link_turn_weight, net.sector_area0)


def new_measures(n_pores, n_links):
    """Measures of zeros for n_pores pores and n_links links (``contact`` bool)."""
    return Measures(np.zeros(n_pores), np.zeros(n_pores), np.zeros(n_pores), np.zeros(n_links),
                    np.zeros(n_links, bool), np.zeros((n_links, 2)), np.zeros((n_pores, 2)))


@jit
def measure(xz, r, eps_m, geometry, out):
    """Pore areas and link states at xz of discs (and wall vertices) of radii r (eq 29, 43b) into
    the Measures ``out``, as engines.model.pores.PoreMeasures (no corner angles): one pass over the
    links of the LinkGeometry ``geometry``, each adding its shoelace term and its turn since the
    build (vec0) times turn_weight to the pore on its left (link_pores[l, 0]) and taking them from
    the pore on its right; sector0: PoreNetwork.sector_area0. out.right (Np, 2) is scratch: the
    sums of the right sides, kept apart as NumPy's (the same sums to the bit where the turns are)."""
    links, link_pores, vec0, turn_weight, sector0 = (geometry.links, geometry.link_pores, geometry.vec0,
                                                     geometry.turn_weight, geometry.sector0)
    poly, sect, void, length, contact, vec, right = out.poly, out.sect, out.void, out.length, out.contact, out.vec, out.right
    for p in range(len(poly)):
        poly[p] = sect[p] = right[p, 0] = right[p, 1] = 0.0
    for l in range(len(links)):
        i, j = _at(links[l, 0]), _at(links[l, 1])
        xi, zi = xz[i, 0], xz[i, 1]
        dx, dz = xz[j, 0] - xi, xz[j, 1] - zi
        length[l] = math.sqrt(dx * dx + dz * dz)
        vec[l, 0], vec[l, 1] = dx, dz
        contact[l] = r[i] + r[j] + eps_m >= length[l]          # eq 43b
        cross = xi * dz - dx * zi
        sector = turn_weight[l] * turn(vec0[l, 0] * dz - vec0[l, 1] * dx, vec0[l, 0] * dx + vec0[l, 1] * dz)  # eq 29
        p0, p1 = link_pores[l, 0], link_pores[l, 1]
        if p0 >= 0:
            poly[_at(p0)] += cross
            sect[_at(p0)] += sector
        if p1 >= 0:
            right[_at(p1), 0] += cross
            right[_at(p1), 1] += sector
    for p in range(len(poly)):
        poly[p] = 0.5 * (poly[p] - right[p, 0])
        sect[p] = sector0[p] + (sect[p] - right[p, 1])
        void[p] = poly[p] - sect[p]


@jit
def darcy_flows(W, A, net):
    """Throat flows net.q (Nt,) and per pore outflow to the surface q_s, to drained sides q_d and
    inflow q_in [m^2/s] (eq 32, 38-43, §5.1) at water W and areas A (Np,) [m^2] of the WaterNet
    ``net`` (its throats throat_i, throat_j, throat_link, link states ``contact``, boundary weights
    surface, drained, bottom, a_min); conductances g, g_b and pressures U are filled too, and the
    sums of q over the throats of each pore as their first (out_i) and second (out_j) pore, in
    throat order (``darcy_update``'s, as PoreWater._step's np.bincount).

    wp: WATER_PRM (E_w, k1, k2, k3, inflow rate), q_in = rate x bottom (PoreWater.inflow_weights: q_w and 1
    per inflow pore, or inflow_velocity and each pore's inflow length). Pores with A <= a_min
    exchange nothing. Returns the Gershgorin
    bound lambda = max_p (2 sum_j g_pj + g_b,p) / c_p, c_p = W^2 / (E_w A) [1/s] of the linearised
    exchange (PoreWater._limit; 0 without open pores); acc_i, acc_j and rate (1 / c_p) (Np,) are
    scratch. Two divisions fewer per pore and one per throat than PoreWater.flows, the same values
    to round-off: 1 / W once per pore (for U and 1 / c_p = E_w A / W^2), and 1 / E_w once per call
    (for W / E_w and g = (k / E_w) A_ij).
    """
    link_contact, ti, tj, t_link, a_min = net.contact, net.throat_i, net.throat_j, net.throat_link, net.a_min
    surface, drained, bottom, wp = net.surface, net.drained, net.bottom, net.wp
    q, q_s, q_d, q_in, g, g_b, U = net.q, net.q_s, net.q_d, net.q_in, net.g, net.g_b, net.U
    acc_i, acc_j, rate, out_i, out_j = net.acc_i, net.acc_j, net.rate, net.out_i, net.out_j
    E_w, k1, k2, k3 = wp[WATER_PRM.E_w], wp[WATER_PRM.k1], wp[WATER_PRM.k2], wp[WATER_PRM.k3]
    q_w = wp[WATER_PRM.inflow]
    per_E = 1.0 / E_w
    for p in range(len(W)):
        per_W = 1.0 / W[p]
        U[p] = E_w * (W[p] - A[p]) * per_W                      # eq 32
        per_k = W[p] * per_E if A[p] > a_min else 0.0           # outside at U = 0: A_ij -> W_i
        g_s = k1 * surface[p] * per_k
        g_d = k3 * drained[p] * per_k
        q_s[p] = g_s * U[p]
        q_d[p] = g_d * U[p]
        q_in[p] = q_w * bottom[p]
        g_b[p] = g_s + g_d
        rate[p] = E_w * A[p] * per_W * per_W
        acc_i[p] = acc_j[p] = out_i[p] = out_j[p] = 0.0
    k1_E, k2_E = k1 * per_E, k2 * per_E
    for t in range(len(ti)):
        i, j = _at(ti[t]), _at(tj[t])
        if A[i] > a_min and A[j] > a_min:
            k_E = k2_E if link_contact[_at(t_link[t])] else k1_E  # eq 43, over E_w
            g[t] = k_E * (W[i] * W[j] / (A[i] + A[j]))            # eq 40
        else:
            g[t] = 0.0
        q[t] = g[t] * (U[i] - U[j])                             # eq 39, 41
        acc_i[i] += g[t]
        acc_j[j] += g[t]
        out_i[i] += q[t]
        out_j[j] += q[t]
    lam = 0.0
    for p in range(len(W)):
        if A[p] > a_min:
            lam = max(lam, (2 * (acc_i[p] + acc_j[p]) + g_b[p]) * rate[p])
    return lam


@jit
def throat_sums(ti, tj, q, out_i, out_j):
    """The sums of q (Nt,) over the throats of each pore as their first (out_i) and second (out_j)
    pore, in throat order (as np.bincount)."""
    out_i[:] = 0.0
    out_j[:] = 0.0
    for t in range(len(ti)):
        out_i[_at(ti[t])] += q[t]
        out_j[_at(tj[t])] += q[t]


@jit
def darcy_update(W, h, out_i, out_j, q_s, q_d, q_in, balance, A, E_w, U):
    """W <- W - ((out_i - out_j) + q_s + q_d - q_in) h (eq 42), out_i, out_j the throat flows'
    sums (``throat_sums``), and U = E_w (W - A) / W [N/m] at the new W (eq 32); balance (BALANCE)
    += the inflow, surface and side outflow volumes [m^2]. Returns the first pore whose W would fall to <= 0
    (nothing changed), or -1."""
    for p in range(len(W)):
        if W[p] - ((out_i[p] - out_j[p]) + q_s[p] + q_d[p] - q_in[p]) * h <= 0:
            return p
    s_in = s_s = s_d = 0.0
    for p in range(len(W)):
        W[p] = W[p] - ((out_i[p] - out_j[p]) + q_s[p] + q_d[p] - q_in[p]) * h
        U[p] = E_w * (W[p] - A[p]) / W[p]                      # eq 32
        s_in += q_in[p]
        s_s += q_s[p]
        s_d += q_d[p]
    balance[BALANCE.inflow] += s_in * h
    balance[BALANCE.surface_outflow] += s_s * h
    balance[BALANCE.side_outflow] += s_d * h
    return -1


# The per-network arrays of water_step, in two buffers (one int64, one float64: a numba call
# unboxes each array argument, ~0.2 us each), each array a part by name (Layout.pack). A water step
# reads them as a WaterNet of views that take no reference count (``water_net``, ``_view``): a
# slice would cost an atomic add (~20 ns) for each of its ~40 parts at every step.
WATER_INTS = Layout("WATER_INTS", ("links", "link_pores", "throat_i", "throat_j", "throat_link", "wall_axis",
                                   "wall_edge", "wall_edge_wall"))
WATER_FLOATS = Layout("WATER_FLOATS", (
    "vec0", "turn_weight", "sector0", "surface", "drained", "bottom", "wp", "eps_m", "a_min", "r",  # inputs
    "poly", "sect", "void", "length", "contact", "vec", "right",                                # measure
    "q", "q_s", "q_d", "q_in", "g", "g_b", "U", "acc_i", "acc_j", "rate", "out_i", "out_j",     # flows
    "balance", "Fj", "lam", "has_q_prev", "check_areas",              # update, forces, eq 46, rebuild trigger
    "wall_position", "vertices", "F_walls"))                                          # flat walls
WaterNet = namedtuple("WaterNet", WATER_INTS.names + WATER_FLOATS.names)


@intrinsic
def _view(typingctx, buf, start, stop):
    """buf[start:stop] of a contiguous 1-d array without a reference to buf's memory: no reference
    count (an atomic add, ~20 ns, where buf[start:stop] makes one), so it is valid only while the
    call that made it holds buf, and must not leave compiled code."""
    def codegen(context, builder, signature, args):
        src = context.make_array(signature.args[0])(context, builder, args[0])
        out = context.make_array(signature.return_type)(context, builder)
        populate_array(out, data=builder.gep(src.data, [args[1]]), shape=[builder.sub(args[2], args[1])],
                       strides=[src.itemsize], itemsize=src.itemsize, meminfo=None)
        return out._getvalue()
    return buf.copy(layout="C")(buf, start, stop), codegen


@jit
def _part(buf, at, k):
    """Part k of a buffer made by Layout.pack, a ``_view`` (only while the call holds buf)."""
    return _view(buf, at[k], at[k + 1])


@intrinsic
def _view2(typingctx, buf, start, stop):
    """``_view`` of buf[start:stop] as an (n, 2) array (row after row)."""
    def codegen(context, builder, signature, args):
        src = context.make_array(signature.args[0])(context, builder, args[0])
        out = context.make_array(signature.return_type)(context, builder)
        two = context.get_constant(nb.types.intp, 2)
        populate_array(out, data=builder.gep(src.data, [args[1]]),
                       shape=[builder.sdiv(builder.sub(args[2], args[1]), two), two],
                       strides=[builder.mul(src.itemsize, two), src.itemsize], itemsize=src.itemsize, meminfo=None)
        return out._getvalue()
    return nb.types.Array(buf.dtype, 2, "C")(buf, start, stop), codegen


@jit
def _part2(buf, at, k):
    """Part k as an (n, 2) array (``_view2``, only while the call holds buf)."""
    return _view2(buf, at[k], at[k + 1])


@jit
def gershgorin_limit(lam):
    """Twin of engines.model.limits.gershgorin_limit: 2 / lambda [s], inf when lambda is 0."""
    return 2.0 / lam if lam > 0 else np.inf


@jit
def substep_count(h, limit):
    """Twin of engines.model.limits.substep_count: 1, or ceil(h / limit) sub-steps when h > limit."""
    return 1 if h <= limit else int(math.ceil(h / limit))


AREAS_OUT_OF_RANGE = -(1 << 62)  # water_step's answer when a void area left its range (a rebuild is due)


@jit
def areas_in_range(void, poly):
    """Twin of engines.model.schedule.areas_in_range: 0 <= A <= polygon area in every pore."""
    for p in range(len(void)):
        if not 0.0 <= void[p] <= poly[p]:
            return False
    return True


@jit
def place_wall_vertices(xz, vertices, wall_axis, wall_position):
    """Twin of engines.model.flat_walls.WallVertices.positions: vertices (V, 2) [m] gets the discs'
    centres xz (N, 2) and the feet of the discs on each flat wall (the face's coordinate along the
    wall's axis); its last rows, the walls' corners, are fixed and left as they are."""
    n = len(xz)
    for i in range(n):
        vertices[i, 0], vertices[i, 1] = xz[i, 0], xz[i, 1]
    for w in range(len(wall_axis)):
        a, at = wall_axis[w], n + w * n
        for i in range(n):
            vertices[at + i, 0], vertices[at + i, 1] = xz[i, 0], xz[i, 1]
            vertices[at + i, a] = wall_position[w]


@jit
def flat_wall_forces(wall_edge, wall_edge_wall, link_pores, U, length, F_walls):
    """Twin of engines.model.pores.flat_wall_forces: F_walls (W,) [N/m] = sum over each wall's edges
    (links wall_edge, of wall wall_edge_wall) of U x edge length, both sides' U (the outer one is 0)."""
    F_walls[:] = 0.0
    for e in range(len(wall_edge)):
        l = wall_edge[e]
        p0, p1 = link_pores[l, 0], link_pores[l, 1]
        F_walls[wall_edge_wall[e]] += ((U[p0] if p0 >= 0 else 0.0) + (U[p1] if p1 >= 0 else 0.0)) * length[l]


@jit
def water_net(ints, i_at, floats, f_at):
    """The parts WATER_INTS of (ints, i_at) and WATER_FLOATS of (floats, f_at) (Layout.pack) as a
    WaterNet, in the layouts' order (a call of more than a few keywords is not compiled): views,
    (n, 2) where the network's array is, and eps_m, a_min and check_areas as numbers (fixed for a
    network)."""
    return WaterNet(
        _part2(ints, i_at, WATER_INTS.links), _part2(ints, i_at, WATER_INTS.link_pores),
        _part(ints, i_at, WATER_INTS.throat_i), _part(ints, i_at, WATER_INTS.throat_j),
        _part(ints, i_at, WATER_INTS.throat_link), _part(ints, i_at, WATER_INTS.wall_axis),
        _part(ints, i_at, WATER_INTS.wall_edge), _part(ints, i_at, WATER_INTS.wall_edge_wall),
        _part2(floats, f_at, WATER_FLOATS.vec0), _part(floats, f_at, WATER_FLOATS.turn_weight),
        _part(floats, f_at, WATER_FLOATS.sector0), _part(floats, f_at, WATER_FLOATS.surface),
        _part(floats, f_at, WATER_FLOATS.drained), _part(floats, f_at, WATER_FLOATS.bottom),
        _part(floats, f_at, WATER_FLOATS.wp), floats[f_at[WATER_FLOATS.eps_m]], floats[f_at[WATER_FLOATS.a_min]],
        _part(floats, f_at, WATER_FLOATS.r),
        _part(floats, f_at, WATER_FLOATS.poly), _part(floats, f_at, WATER_FLOATS.sect),
        _part(floats, f_at, WATER_FLOATS.void), _part(floats, f_at, WATER_FLOATS.length),
        _part(floats, f_at, WATER_FLOATS.contact), _part2(floats, f_at, WATER_FLOATS.vec),
        _part2(floats, f_at, WATER_FLOATS.right),
        _part(floats, f_at, WATER_FLOATS.q), _part(floats, f_at, WATER_FLOATS.q_s),
        _part(floats, f_at, WATER_FLOATS.q_d), _part(floats, f_at, WATER_FLOATS.q_in),
        _part(floats, f_at, WATER_FLOATS.g), _part(floats, f_at, WATER_FLOATS.g_b),
        _part(floats, f_at, WATER_FLOATS.U), _part(floats, f_at, WATER_FLOATS.acc_i),
        _part(floats, f_at, WATER_FLOATS.acc_j), _part(floats, f_at, WATER_FLOATS.rate),
        _part(floats, f_at, WATER_FLOATS.out_i), _part(floats, f_at, WATER_FLOATS.out_j),
        _part(floats, f_at, WATER_FLOATS.balance), _part2(floats, f_at, WATER_FLOATS.Fj),
        _part(floats, f_at, WATER_FLOATS.lam), _part(floats, f_at, WATER_FLOATS.has_q_prev),
        floats[f_at[WATER_FLOATS.check_areas]],
        _part(floats, f_at, WATER_FLOATS.wall_position), _part2(floats, f_at, WATER_FLOATS.vertices),
        _part(floats, f_at, WATER_FLOATS.F_walls))


@jit
def water_step(xz, h, W, A_prev, q_prev, smoothing, substep, F_water, ints, i_at, floats, f_at):
    """Advance the water by h [s] at centres xz and recompute the pressure forces F_water (N, 2) [N]
    (WaterModel.advance): ``measure``, eq 45 smoothing of the areas into A_prev, ``darcy_flows``,
    n = 1 or ceil(h / Darcy limit) sub-steps of ``darcy_update`` by h / n (eq 46 smoothing of the
    throat flows into q_prev) with U at the areas used (eq 32, 45), ``pressure_forces``. The network's
    arrays are the parts WATER_INTS of (ints, i_at) and WATER_FLOATS of (floats, f_at)
    (Layout.pack), read as the WaterNet ``net`` (``water_net``). Flat walls (wall_axis not empty):
    the pores' vertices are the discs and the walls' (vertices, ``place_wall_vertices``; r holds 0
    for the wall vertices) and F_walls gets the water's force on each wall (``flat_wall_forces``).
    lam gets the Gershgorin bound of the first and of the last flows, balance the water of this
    step, has_q_prev is 1 once q_prev holds the flows of an earlier water step.
    Returns n >= 1; 0 when h exceeds the Darcy limit without ``substep`` (W unchanged); -1 - p
    when pore p would fall dry (W as after the previous sub-step); AREAS_OUT_OF_RANGE, nothing
    changed, when check_areas is 1 and a measured void area is out of range (``areas_in_range``)."""
    net = water_net(ints, i_at, floats, f_at)
    points = xz
    if len(net.wall_axis):
        place_wall_vertices(xz, net.vertices, net.wall_axis, net.wall_position)
        points = net.vertices
    measure(points, net.r, net.eps_m, LinkGeometry(net.links, net.link_pores, net.vec0, net.turn_weight, net.sector0),
            Measures(net.poly, net.sect, net.void, net.length, net.contact, net.vec, net.right))
    if net.check_areas != 0.0 and not areas_in_range(net.void, net.poly):
        return AREAS_OUT_OF_RANGE
    A = net.void
    if smoothing:  # eq 45
        for p in range(len(A_prev)):
            A_prev[p] = 0.5 * (A_prev[p] + net.void[p])
        A = A_prev
    lam = net.lam
    lam[LAM.first] = lam[LAM.last] = darcy_flows(W, A, net)
    n_sub = substep_count(h, gershgorin_limit(lam[LAM.first]))
    if n_sub > 1 and not substep:
        return 0
    q = net.q
    net.balance[:] = 0.0
    for sub in range(n_sub):
        if sub > 0:
            lam[LAM.last] = darcy_flows(W, A, net)
        if smoothing:  # eq 46: the flows' sums are those of the smoothed flows
            running = net.has_q_prev[0] != 0.0
            for t in range(len(q)):
                if running:
                    q[t] = 0.5 * (q_prev[t] + q[t])
                q_prev[t] = q[t]
            net.has_q_prev[0] = 1.0
            throat_sums(net.throat_i, net.throat_j, q, net.out_i, net.out_j)
        bad = darcy_update(W, h / n_sub, net.out_i, net.out_j, net.q_s, net.q_d, net.q_in, net.balance, A,
                           net.wp[WATER_PRM.E_w], net.U)  # U at the area used (eq 45)
        if bad >= 0:
            return -1 - bad
    pressure_forces(net.links, net.link_pores, net.r, net.U, net.length, net.vec, F_water, net.Fj)
    if len(net.wall_axis):
        flat_wall_forces(net.wall_edge, net.wall_edge_wall, net.link_pores, net.U, net.length, net.F_walls)
    return n_sub


WATER = Layout.of(water_step, 1)  # the arguments of water_step after xz


LIST_STALE = -1  # law_step's answer when the pair list must be rebuilt first


@jit
def tie_forces(xz, du, dt, tie_pairs, tie_rest, tie_prm, T):
    """x-forces T[0] (N,) [N] of the side-wall ties (engines.model.side_walls) at centres xz (N, 2) with
    velocities du / dt: tie t pulls its upper disc tie_pairs[t, 1] by f = -k's [(x_u - x_l) - tie_rest[t]]
    - eta's (v_u - v_l) and its lower disc tie_pairs[t, 0] by -f; tie_prm: TIE_PRM (k's, eta's); T (2, N),
    T[1] is scratch."""
    ks, eta = tie_prm[TIE_PRM.ks_wall], tie_prm[TIE_PRM.eta_s_wall]
    T[:] = 0.0
    for t in range(len(tie_rest)):
        lo, up = tie_pairs[t, 0], tie_pairs[t, 1]
        f = -ks * ((xz[up, 0] - xz[lo, 0]) - tie_rest[t]) - eta * (du[up, 0] / dt - du[lo, 0] / dt)
        T[0, up] += f
        T[1, lo] += f
    for a in range(T.shape[1]):
        T[0, a] -= T[1, a]


TIES = Layout.of(tie_forces, 3)  # the arguments of tie_forces after (xz, du, dt)


@jit
def forces_to_write(xz, F_out, rows, held, du, dt, F, F_water, tie_pairs, tie_rest, tie_prm, T):
    """The forces of a step to write, F_out = (F + T + F_water)[rows] + held (n, 2) [N]: the law's
    F, the x-forces T of the side-wall ties (``tie_forces`` at xz, du / dt; none when tie_rest
    is empty) and the water's F_water (none when it is empty: a dry scene)."""
    tied = len(tie_rest) > 0
    if tied:
        tie_forces(xz, du, dt, tie_pairs, tie_rest, tie_prm, T)
    wet = len(F_water) > 0
    for k in range(len(rows)):
        a = rows[k]
        fx, fz = F[a, 0], F[a, 1]
        if tied:
            fx = fx + T[0, a]
        if wet:
            fx, fz = fx + F_water[a, 0], fz + F_water[a, 1]
        F_out[k, 0], F_out[k, 1] = fx + held[k, 0], fz + held[k, 1]


@jit
def water_forces_step(xz, F_out, rows, held, water):
    """``water_step`` (``water``: the tuple of its arguments after xz, WATER), then F_out = held +
    F_water[rows] (n, 2) [N], the forces to write (WaterEngine). Returns (n, n) with water_step's
    answer n, or (-1, n) when it failed."""
    n_sub = water_step(xz, *water)
    F_water = water[WATER.F_water]
    for k in range(len(rows)):
        F_out[k, 0] = held[k, 0] + F_water[rows[k], 0]
        F_out[k, 1] = held[k, 1] + F_water[rows[k], 1]
    return (n_sub if n_sub > 0 else -1), n_sub


WATER_FORCES_STEP = Layout.of(water_forces_step, 2).check(("rows", "held", "water"))


def water_forces_step_args(rows, held, water):
    """The arguments of water_forces_step after (xz, F_out) (WATER_FORCES_STEP): the forces to
    write F_water[rows] + held, then the tuple WATER."""
    return WATER_FORCES_STEP.values(rows=rows, held=held, water=water)

# The addresses of the C functions of engines.yade.yadebulk a kernel calls: the position read, the
# force write (set_perm_force_xz, or add_force_unsynced_xz in a scene that resets the forces after
# NewtonIntegrator: engines.yade.yade_io.forces_reset_after_newton), the velocity write and YADE's
# steps (yadebulk.c_steps).
BRIDGE = Layout("BRIDGE", ("get_pos", "write_forces", "set_vel", "steps"))


@intrinsic
def _c_bulk_call(typingctx, address, ids, n, data):
    """(*address)(ids, n, data) for the C function int64 f(const int64 *ids, int64 n, double *data)
    at the integer ``address`` (engines.yade.yadebulk's bulk functions), ids and data addresses too."""
    def codegen(context, builder, signature, args):
        i64, ptr = ir.IntType(64), ir.IntType(8).as_pointer()
        fn = builder.inttoptr(args[0], ir.FunctionType(i64, [ptr, i64, ptr]).as_pointer())
        return builder.call(fn, [builder.inttoptr(args[1], ptr), args[2], builder.inttoptr(args[3], ptr)])
    return nb.types.int64(address, ids, n, data), codegen


@jit
def _read_positions(get_pos, ids, xz):
    return _c_bulk_call(get_pos, ids.ctypes.data, ids.size, xz.ctypes.data)


@jit
def _write_forces(status, write, ids, F):
    """write(ids <- F) when status >= 0; the bridge's error code (0 when nothing was written)."""
    return _c_bulk_call(write, ids.ctypes.data, ids.size, F.ctypes.data) if status >= 0 else 0


@jit
def water_drive_bulk_io(bridge, n, step_last, water_in, water_interval, totals, xz_built, moved2, ids_in, xz, ids_out,
                        F_out, rows, held, water):
    """WaterEngine's step without Python (engines.model.water_model.WaterModel.step in YADE): n DEM
    steps (one water step of the PyRunner is n = 1, water_in = 0, not ``step_last``), the water
    steps among them (step water_in of the call, then every water_interval:
    engines.model.schedule.Schedule) each get_pos(ids_in -> xz), ``water_forces_step`` (``water``:
    the tuple WATER) and write_forces(ids_out <- F_out), each step made by bridge's steps()
    (YADE's O.step()) but for the last when not ``step_last``. totals (3,) [m^2] gets the water
    balance (inflow, surface, side) of every water step that needed no sub-steps. Stops before
    stepping after a water step that did not answer 1 (sub-steps or a failure: its bookkeeping is
    the caller's) or at an error code; with moved2 > 0 [m^2], also before a water step at which a
    disc is farther than sqrt(moved2) from its centre in xz_built (N, 2) [m] or a void area is out
    of range (water_step's AREAS_OUT_OF_RANGE): a rebuild is due, that water step is the
    caller's, nothing done of it. Returns (DEM steps done, water steps done, the last water step's
    answer or 1, the bridge's error code)."""
    balance = _part(water[WATER.floats], water[WATER.f_at], WATER_FLOATS.balance)
    n_water, next_water = 0, water_in
    for s in range(n):
        if s == next_water:  # the rebuild triggers, then the water and the forces to write
            next_water += water_interval
            rc = _read_positions(bridge[BRIDGE.get_pos], ids_in, xz)
            if rc != 0:
                return s, n_water, 1, rc
            if moved2 > 0.0 and max_sq_displacement(xz, xz_built) > moved2:
                return s, n_water, 1, 0  # a rebuild is due: that water step is the caller's
            status, n_sub = water_forces_step(xz, F_out, rows, held, water)
            if n_sub == AREAS_OUT_OF_RANGE:
                return s, n_water, 1, 0
            rc = _write_forces(status, bridge[BRIDGE.write_forces], ids_out, F_out)
            if rc != 0:
                return s, n_water, n_sub, rc
            n_water += 1
            if n_sub != 1:
                return s, n_water, n_sub, 0
            for a in range(3):
                totals[a] += balance[a]
        if s == n - 1 and not step_last:
            return s, n_water, 1, 0
        rc = _c_bulk_call(bridge[BRIDGE.steps], 0, 1, 0)
        if rc != 0:
            return s, n_water, 1, rc
    return n, n_water, 1, 0


Layout.of(water_drive_bulk_io, 12).check(WATER_FORCES_STEP)


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


@jit
def _write_step_velocities(set_vel, ids, discs, V):
    """set_vel(ids[discs] <- V[discs]) for the discs where ``discs`` (N,) is true; the bridge's
    error code."""
    at = np.flatnonzero(discs)
    W = np.empty((len(at), 2))
    for m in range(len(at)):
        W[m, 0], W[m, 1] = V[at[m], 0], V[at[m], 1]
    chosen = ids[at]
    return _c_bulk_call(set_vel, chosen.ctypes.data, chosen.size, W.ctypes.data)


# The base motion of the drive (engines.model.ground_motion.BaseMotion): its numbers, and for a
# sampled input (Sampled) its record (t_s, a_s) passed beside them; a cosine passes empty records.
MOTION = Layout("MOTION", ("amplitude", "w", "left", "right", "dt", "acc", "vel", "disp", "wall_velocity"))


@jit
def sampled_acceleration(t, t_s, a_s, left, right):
    """Twin of engines.model.ground_motion.Sampled at a time t [s]: np.interp(t, t_s, a_s, left,
    right) in NumPy's arithmetic (the interval's slope times the distance from its start, plus its
    start value; a sample's own value at a sample time) [m/s^2]."""
    last = len(t_s) - 1
    if t > t_s[last]:
        return right
    if t < t_s[0]:
        return left
    if t == t_s[last]:
        return a_s[last]
    j = np.searchsorted(t_s, t, side="right") - 1  # t_s[j] <= t < t_s[j + 1]
    if t == t_s[j]:
        return a_s[j]
    slope = (a_s[j + 1] - a_s[j]) / (t_s[j + 1] - t_s[j])
    return slope * (t - t_s[j]) + a_s[j]


@jit
def base_step(motion, t_s, a_s, k):
    """Twin of engines.model.ground_motion.BaseMotion.step: motion (MOTION: amplitude [m/s^2] and
    2 pi frequency [rad/s] of a Cosine, left and right [m/s^2] of a Sampled record (t_s, a_s) (s,
    m/s^2; empty for a Cosine), dt [s], acc, vel, disp, wall velocity) advanced in place from
    step k to k + 1; the wall velocity of that step is (u_k+1 - u_k) / dt [m/s]."""
    dt = motion[MOTION.dt]
    t = (k + 1) * dt
    if len(t_s):
        a_next = sampled_acceleration(t, t_s, a_s, motion[MOTION.left], motion[MOTION.right])
    else:
        a_next = motion[MOTION.amplitude] * math.cos(motion[MOTION.w] * t)
    a_bar = 0.5 * (motion[MOTION.acc] + a_next)
    du = motion[MOTION.vel] * dt + 0.5 * a_bar * dt * dt
    motion[MOTION.vel] += a_bar * dt
    motion[MOTION.disp] += du
    motion[MOTION.acc] = a_next
    motion[MOTION.wall_velocity] = du / dt


@jit
def dem_drive_bulk_io(bridge, n, k, step_last, water_in, water_interval, adjust, e, mass, skin, totals, motion, t_s,
                      a_s, wall_ids, wall_vel, ids_in, xz, ids_out, F_out, rows, held,
                      xz_prev, xz_list, half_skin2, omega, dpsi, du, inertia, mobile, dt, contact,
                      h, W, A_prev, q_prev, smoothing, substep, F_water, ints, i_at, floats, f_at,
                      tie_pairs, tie_rest, tie_prm, T):
    """PoreDEM's step (engines.model.pore_dem.PoreDEM.step, its order a-f) in YADE without Python,
    up to n steps from step index k (one step is n = 1), each: get_pos(ids_in -> xz); a ``law_step``
    (LAW: the arguments from xz_prev to the ContactArgs ``contact``; a stale pair list rebuilt at
    the step's centres by ``near_pairs`` with the list's skin [m]: its pi, pj, state and lost
    become new arrays, xz_list is overwritten); ``water_step`` (WATER: from h to f_at) at step water_in of the call, then every
    water_interval (engines.model.schedule.Schedule), when the scene is wet; ``forces_to_write``
    (the side-wall ties, TIES: from tie_pairs on); write_forces(ids_out <- F_out); with ``adjust``
    (the eq 18-24 velocity adjustment, restitution e, the discs' masses ``mass`` (N,) [kg/m]) the
    discs that pairs stopped touching set free (``free_discs``) get their ``separation_velocities``
    by set_vel; the water's balance of the step added to totals (3,) [m^2] (not that of a step
    that needed sub-steps: its books are the caller's); the base motion advanced (``base_step``
    when motion is not empty: MOTION and the record t_s, a_s) and the walls wall_ids given its wall
    velocity (v, 0) by set_vel (wall_vel (m, 2) is scratch); then bridge's steps() (O.step()),
    but for the last step when not ``step_last``. Each part's arguments are spelled out but the
    contact's (a tuple): numba leaves a reference count of each array around a call of more than
    30 arrays, two atomic adds each. It stops after a step whose water answered other than 1 (sub-steps or a failure) before
    its O.step(), at the start of a step whose list is still stale once rebuilt (skin 0: nothing
    done of it), or at an error code.
    Returns (steps made, of them stepped by O.step(), the list was stale, the last water step's
    answer or 1, the error code, the pair lists built, the ContactArgs on the last pair list)."""
    wet = len(W) > 0
    V = np.empty_like(du) if adjust else du  # the adjusted velocities [m/s]
    balance = _part(floats, f_at, WATER_FLOATS.balance) if wet else totals  # a dry scene has no buffer: not read
    builds, next_water = 0, water_in
    for s in range(n):
        rc = _read_positions(bridge[BRIDGE.get_pos], ids_in, xz)
        if rc != 0:
            return s, s, False, 1, rc, builds, contact
        water_due = wet and s == next_water
        if s == next_water:
            next_water += water_interval
        for attempt in range(2):  # a stale list rebuilt once
            n_lost = law_step(xz, xz_prev, xz_list, half_skin2, omega, dpsi, du, inertia, mobile, dt, contact)
            if n_lost != LIST_STALE or attempt == 1:
                break
            pi, pj, state = near_pairs(xz, contact.r, mobile, contact.prm[CONTACT_PRM.eps_m], skin, contact.pi,
                                       contact.pj, contact.state)
            contact = with_pairs(contact, pi, pj, state, np.zeros(len(pi), np.int64))
            xz_list[:] = xz
            builds += 1
        if n_lost == LIST_STALE:
            return s, s, True, 1, 0, builds, contact
        n_sub = 1
        if water_due:
            n_sub = water_step(xz, h, W, A_prev, q_prev, smoothing, substep, F_water, ints, i_at, floats, f_at)
        forces_to_write(xz, F_out, rows, held, du, dt, contact.F, F_water, tie_pairs, tie_rest, tie_prm, T)
        rc = _write_forces(0, bridge[BRIDGE.write_forces], ids_out, F_out)
        if rc != 0:
            return s, s, False, n_sub, rc, builds, contact
        if adjust and n_lost > 0:
            lost, pi, pj, state = contact.lost, contact.pi, contact.pj, contact.state
            free = free_discs(lost, n_lost, pi, pj, state, mobile)
            if free.any():
                separation_velocities(lost, n_lost, pi, pj, state, xz, du, dt, mass, free, e, V)
                rc = _write_step_velocities(bridge[BRIDGE.set_vel], ids_in, free, V)
                if rc != 0:
                    return s, s, False, n_sub, rc, builds, contact
        if water_due and n_sub == 1:
            for a in range(3):
                totals[a] += balance[a]
        if len(motion):
            base_step(motion, t_s, a_s, k + s)
            for b in range(len(wall_ids)):
                wall_vel[b, 0], wall_vel[b, 1] = motion[MOTION.wall_velocity], 0.0
            rc = _c_bulk_call(bridge[BRIDGE.set_vel], wall_ids.ctypes.data, wall_ids.size, wall_vel.ctypes.data)
            if rc != 0:
                return s + 1, s, False, n_sub, rc, builds, contact
        if n_sub != 1 or (s == n - 1 and not step_last):
            return s + 1, s, False, n_sub, 0, builds, contact
        rc = _c_bulk_call(bridge[BRIDGE.steps], 0, 1, 0)
        if rc != 0:
            return s + 1, s, False, 1, rc, builds, contact
    return n, n, False, 1, 0, builds, contact


DEM_DRIVE = Layout.of(dem_drive_bulk_io, 20).check(("rows", "held"), LAW, WATER, TIES)


@jit
def read_bulk_io(get_pos, ids, xz):
    """get_pos(ids -> xz): the bridge's position read; returns its error code."""
    return _read_positions(get_pos, ids, xz)


@jit
def write_rows_bulk_io(write, ids, F, rows, add, out):
    """out = F[rows] + add, then write(ids <- out): the bridge's force write (BRIDGE.write_forces)
    of some rows of F plus held forces; returns its error code."""
    for k in range(len(rows)):
        out[k, 0] = F[rows[k], 0] + add[k, 0]
        out[k, 1] = F[rows[k], 1] + add[k, 1]
    return _write_forces(0, write, ids, out)


def dry_water_args():
    """The arguments of dem_drive_bulk_io from h to f_at (WATER) for a scene without water."""
    no_i, no_f = np.zeros(0, np.int64), np.zeros(0)
    return WATER.values(h=0.0, W=no_f, A_prev=no_f, q_prev=no_f, smoothing=False, substep=False,
                        F_water=np.zeros((0, 2)), ints=no_i, i_at=np.zeros(1, np.int64), floats=no_f,
                        f_at=np.zeros(1, np.int64))


def no_tie_args():
    """The arguments of dem_drive_bulk_io from tie_pairs on (TIES) for a scene without side-wall ties."""
    return TIES.values(tie_pairs=np.zeros((0, 2), np.int64), tie_rest=np.zeros(0),
                       tie_prm=np.zeros(len(TIE_PRM.names)), T=np.zeros((2, 0)))


def tie_args(ties):
    """The arguments of tie_forces after (xz, du, dt) (TIES) of engines.model.side_walls.SideWallTies
    ``ties``: (lower, upper) pairs (M, 2), rest (M,), TIE_PRM and the (2, N) force buffer."""
    return TIES.values(tie_pairs=np.stack([ties.lower, ties.upper], axis=1), tie_rest=ties.rest,
                       tie_prm=TIE_PRM.vector(ks_wall=ties.ks, eta_s_wall=ties.eta), T=np.zeros((2, ties.n)))


@jit
def pressure_forces(links, link_pores, r, U, length, vec, F, Fj):
    """Force of the pore pressures U on every disc, F (N, 2) [N] (eq 33); Fj (N, 2) is scratch.
    The outer face and closed faces (link_pores = -1) have U = 0. Vertices past the N discs (the
    flat walls', radius 0) take nothing. The links come sorted by i: disc i's sum is kept in
    registers while its links follow one another (the same sums in the same order)."""
    F[:] = 0.0
    Fj[:] = 0.0
    n = len(F)
    a_sum, fx, fz = _at(0), 0.0, 0.0  # the disc summed in (fx, fz), F[a_sum] not yet written
    for l in range(len(links)):
        p0, p1 = link_pores[l, 0], link_pores[l, 1]
        s = ((U[_at(p1)] if p1 >= 0 else 0.0) - (U[_at(p0)] if p0 >= 0 else 0.0)) / length[l]
        px, pz = -vec[l, 1] * s, vec[l, 0] * s
        i, j = links[l, 0], links[l, 1]
        if i < n:
            a = _at(i)
            if a != a_sum:
                F[a_sum, 0], F[a_sum, 1] = fx, fz
                a_sum, fx, fz = a, F[a, 0], F[a, 1]
            fx += r[a] * px
            fz += r[a] * pz
        if j < n:
            b = _at(j)
            Fj[b, 0] += r[b] * px
            Fj[b, 1] += r[b] * pz
    if n:
        F[a_sum, 0], F[a_sum, 1] = fx, fz
    for a in range(len(F)):
        F[a, 0] += Fj[a, 0]
        F[a, 1] += Fj[a, 1]
