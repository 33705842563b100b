"""The Darcy step compiled (engines.model.pore_water.PoreWater.flows, _step, _limit): the pore pressure
U = E_w (W - A) / W (eq 32), the throat conductance g = k A_ij / E_w (eq 40), the permeability law k
(eq 43: k1 across a gap, k2 across a contact; k3 for drained flat walls), the flows (eq 38, 39, 41;
boundaries §5.1), the update of W (eq 42), and the explicit step's Gershgorin bound and sub-steps
(engines.model.limits). No YADE."""
import math

import numpy as np

from engines.compiled.kernels.common import _at, jit
from engines.compiled.params import BALANCE, WATER_PRM


@jit
def permeability(contact, wp):
    """Twin of engines.model.pore_water.permeability, the permeability law [1/s] (eq 43, §5.1,
    §6.1): (k of a link across a contact (``contact`` true): k2, else across a gap: k1; k of a
    free-surface edge: k1; k of a drained wall: k3), from WATER_PRM ``wp``. ``darcy_flows`` asks
    it once for a gap and once for a contact."""
    return (wp[WATER_PRM.k2] if contact else wp[WATER_PRM.k1]), wp[WATER_PRM.k1], wp[WATER_PRM.k3]


@jit
def darcy_flows(W, A, net):
    """Throat flows net.q (Nt,) and per pore outflow to the surface q_s, to drained sides q_d and
    inflow q_in [m^2/s] (eq 32, 38-43, §5.1) at water W and areas A (Np,) [m^2] of the WaterNet
    ``net`` (its throats throat_i, throat_j, throat_link, link states ``contact``, boundary weights
    surface, drained, bottom, a_min); conductances g, g_b and pressures U are filled too, and the
    sums of q over the throats of each pore as their first (out_i) and second (out_j) pore, in
    throat order (``darcy_update``'s, as PoreWater._step's np.bincount).

    wp: WATER_PRM (E_w, the permeabilities of ``permeability``, inflow rate), q_in = rate x bottom (PoreWater.inflow_weights: q_w and 1
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
    E_w, q_w = wp[WATER_PRM.E_w], wp[WATER_PRM.inflow]
    k_gap, k_surface, k_drained = permeability(False, wp)  # eq 43
    k_contact = permeability(True, wp)[0]
    per_E = 1.0 / E_w
    for p in range(len(W)):
        per_W = 1.0 / W[p]
        U[p] = E_w * (W[p] - A[p]) * per_W                      # eq 32
        per_k = W[p] * per_E if A[p] > a_min else 0.0           # outside at U = 0: A_ij -> W_i
        g_s = k_surface * surface[p] * per_k
        g_d = k_drained * drained[p] * per_k
        q_s[p] = g_s * U[p]
        q_d[p] = g_d * U[p]
        q_in[p] = q_w * bottom[p]
        g_b[p] = g_s + g_d
        rate[p] = E_w * A[p] * per_W * per_W
        acc_i[p] = acc_j[p] = out_i[p] = out_j[p] = 0.0
    k_gap_E, k_contact_E = k_gap * per_E, k_contact * per_E
    for t in range(len(ti)):
        i, j = _at(ti[t]), _at(tj[t])
        if A[i] > a_min and A[j] > a_min:
            k_E = k_contact_E if link_contact[_at(t_link[t])] else k_gap_E  # eq 43, over E_w
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


@jit
def gershgorin_limit(lam):
    """Twin of engines.model.limits.gershgorin_limit: 2 / lambda [s], inf when lambda is 0."""
    return 2.0 / lam if lam > 0 else np.inf


@jit
def substep_count(h, limit):
    """Twin of engines.model.limits.substep_count: 1, or ceil(h / limit) sub-steps when h > limit."""
    return 1 if h <= limit else int(math.ceil(h / limit))
