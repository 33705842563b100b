"""Pore water between discs (seed 000 §3.2-3.4, SPEC §2.3). Pure NumPy, no YADE.

Per unit thickness: water areas W and void areas A in m^2, excess pressures U and the water
modulus E_w in N/m, permeabilities k in 1/s, flows q in m^2/s.

* U = E_w (W - A) / W                                   (eq 32)
* between pores i, j sharing a link: i_ij = (U_i - U_j)/E_w, A_ij = W_i W_j / (A_i + A_j),
  q_ij = k A_ij i_ij with k = k1 across a gap, k2 across a contact        (eq 38-41, 43)
* W_i <- W_i - sum_j q_ij dt - boundary outflow dt + inflow dt           (eq 42)
* free surface (a pore with a non-wall edge on the outer face): q = k1 W U / E_w to U = 0 outside
* drained side walls: q = k3 W U / E_w for pores touching a side wall; undrained: nothing
* quick-sand inflow: q_w [m^2/s per pore] into every pore that has a bottom-wall disc as a vertex
  (§5.1); or, with ``inflow_velocity`` v [m/s] (SPEC §2.7), v x the length of each inflow edge (a
  link between two bottom-wall discs, centre to centre, or an inflow flat wall's edge) into the pore
  on its inner side (``inflow_lengths``): the total is v x the row's span whatever the grain size
* flat walls (engines.model.flat_walls, SPEC §2.6), by their boundary: a pore with a drained one as a
  vertex drains as a side-wall pore (booked as side outflow), one with an inflow one receives q_w
  as a bottom pore (once per pore, however many such walls or wall discs it has); undrained: nothing
* optional smoothing (eq 45-46): the areas and the pore-to-pore flows used are the running
  averages [A]_t = ([A]_{t-dt} + A'_t)/2 and [q]_t = ([q]_{t-dt} + q'_t)/2 of the values used at the
  previous step and the new ones; boundary outflows are not smoothed

Pinched pores: a pore whose current void area is <= ``net.a_min`` keeps its water but exchanges
none (its throats and boundary outflow are shut) until it reopens; its U follows eq 32.

Re-meshing (§3.4(2), ``PoreWater.remesh``): the paper's rule (``transfer = "paper"``) gives each new
pore the pressure of the old pores by rules (a)-(d) and its water from eq 32, so water is created
or destroyed (the balance records it as ``remesh_change``). ``transfer = "conserving"`` moves the
water itself (``conserving_water``): the void A of a new pore holds water at U = 0, and the excess
water X = W - A of the old pores (X = W U / E_w: the part that carries the pressure) is split over
the new pores by overlap. Total water is then conserved to round-off wherever old and new pores
cover the same region; where they do not (the free surface moved, a closed face reopened) the
difference is exchanged with the outside at U = 0 and recorded in ``remesh_change`` too.

Stability: the update is explicit. Linearising eq 32 (dU/dW = E_w A / W^2) gives
dU/dt = -M U with M = C^-1 G, conductances g = k A_ij / E_w and capacities c = W^2 / (E_w A).
Gershgorin bounds its eigenvalues by lambda = max_i (2 sum_j g_ij + g_boundary,i) / c_i, and
forward Euler is stable for dt <= 2 / lambda (engines.model.limits). For two equal pores this is
exact: dt <= 2 / k.
"""
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from engines.model import groups, limits
from engines.model import pores as pg
from engines.model.fields import NONNEG, POS, Field, settings_class
from engines.model.limits import DarcyStabilityError


WATER_FIELDS = {  # the scene file's [water] table holds these and the engine's own choices
    "E_w": Field(float, 240.0, POS, "water modulus per unit thickness [N/m] (eq 32)"),
    "k1": Field(float, 200.0, NONNEG, "permeability across a gap link [1/s] (eq 43a)"),
    "k2": Field(float, 2.0, NONNEG, "permeability across a contact link [1/s] (eq 43b)"),
    "k3": Field(float, 0.0, NONNEG, "permeability of drained side walls [1/s]"),
    "q_w": Field(float, 0.0, NONNEG, "inflow into every pore with a bottom-wall disc or an inflow flat wall as a "
                 "vertex [m^2/s per inflow pore] (§5.1, the paper's: the total grows with the number of such pores)"),
    "sides": Field(str, "undrained", groups.SIDE_WORDS, "side-wall drainage"),
    "smoothing": Field(bool, False, None, "eq 45-46"),
    "substep": Field(bool, True, None, "sub-step the water where a water step exceeds the explicit Darcy limit (the "
                     "engine prints the count and its cost); false: refuse such a step (preflight at the start, the "
                     "engine mid-run)"),
    "transfer": Field(str, "conserving", ("paper", "conserving"), "water at re-meshing: paper = W from the inherited U "
                      "(§3.4(2)); conserving = excess water W - A of the old pores split over the new ones by overlap "
                      "(engines.model.pore_water.conserving_water)"),
    "inflow_velocity": Field(float, 0.0, NONNEG, "inflow as a Darcy flux per unit width [m/s] (SPEC §2.7): each link "
                             "between two bottom-wall discs and each inflow flat-wall edge passes v x its length into "
                             "the pore on its inner side, so the total is v x the row's span; exclusive with q_w"),
}
WaterSettings = settings_class("WaterSettings", WATER_FIELDS, "water", __name__,
                               "Constants of the pore water (WATER_FIELDS; the scene file's [water] table).")


@dataclass
class WaterBalance:
    """Cumulative water budget [m^2] since the start."""

    initial: float = 0.0
    inflow: float = 0.0
    surface_outflow: float = 0.0
    side_outflow: float = 0.0
    remesh_change: float = 0.0   # W recomputed from inherited U and new A at re-meshing (eq 32)
    # the part of remesh_change that is excess water X = W - A = W U / E_w (the water that carries
    # the pressure), without the void gained or lost where the covered region changes (a free
    # surface moving), which holds water at U = 0
    remesh_excess_change: float = 0.0
    # of which at the edges: X of the new pores that overlap no old pore less X of the old pores
    # that overlap no new one (known when remesh gets the positions); the rest, where old and new
    # pores cover the same ground, is what the transfer rule itself creates (conserving: none)
    remesh_excess_edge: float = 0.0

    def expected(self):
        return self.initial + self.inflow - self.surface_outflow - self.side_outflow + self.remesh_change


@dataclass
class FlowState:
    """Flows of one water step: throat q (Nt,), and per pore (Np,) the surface and side outflow
    and the inflow [m^2/s]; the conductances behind them (g = k A_ij / E_w per throat, g_b per pore
    to the outside) and the capacities c = dW/dU = W^2 / (E_w A) [m^2 per N/m] of open pores."""

    throat_q: np.ndarray
    surface_q: np.ndarray
    side_q: np.ndarray
    inflow_q: np.ndarray
    g: np.ndarray
    g_b: np.ndarray
    capacity: np.ndarray
    net_out: np.ndarray = None


def pressure(W, A, E_w):
    """Excess pore pressure U = E_w (W - A) / W [N/m] (eq 32)."""
    return E_w * (W - A) / W


def permeability(contact, s):
    """The permeability law [1/s] (eq 43, §5.1, §6.1): (k of each link of the states ``contact``
    (bool array): k2 across a contact, k1 across a gap; k of a free-surface edge to the outside:
    k1; k of a drained wall: k3), from the WaterSettings s. The flows' conductance is
    g = k A_ij / E_w (eq 40, 41). Its twins: engines.compiled.kernels.darcy.permeability and
    engines.reference.model.permeability (a new law replaces these three functions)."""
    return np.where(contact, s.k2, s.k1), s.k1, s.k3


def buoyancy(r, rho_w, g):
    """Upward force rho_w pi r^2 g [N per m thickness] on discs of radius r [m] in water (eq 34b:
    the buoyant weight is the weight less this)."""
    return rho_w * np.pi * np.asarray(r) ** 2 * g


def water_from_pressure(U, A, E_w):
    """Water area W = A E_w / (E_w - U) [m^2] that gives pressure U in area A (eq 32 inverted)."""
    return A * E_w / (E_w - U)


class PoreWater:
    """Water state of a pore network: W per pore, advanced by Darcy exchange (eq 32-46)."""

    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("net", "W", "A_prev", "q_prev", "balance", "remesh_counts", "rule")
    CHECKPOINT_RESIZED = ("W", "A_prev", "rule")  # per pore
    CHECKPOINT_DERIVED = {"settings": "the scene's [water]", "walls": "the packing's wall codes",
                          "inflow": "of the network (checkpoint_restored)"}

    def __init__(self, net, A, settings, W=None, walls=None):
        """Water on ``net`` with void areas A [m^2]; W defaults to A (after packing, U = 0); walls
        (N,) the discs' wall codes (engines.model.pores; None: no wall discs), for the inflow by
        velocity (``inflow_lengths``)."""
        if settings.q_w > 0 and settings.inflow_velocity > 0:
            raise ValueError(f"q_w = {settings.q_w:g} m^2/s per inflow pore and inflow_velocity = "
                             f"{settings.inflow_velocity:g} m/s are two ways of one inflow; set one of them to 0")
        self.settings = settings
        self.walls = np.zeros(net.n_discs, np.int64) if walls is None else np.asarray(walls, np.int64)
        self.net = net
        A = np.asarray(A, float)
        self.W = A.copy() if W is None else np.array(W, float)
        if self.W.shape != A.shape or np.any(self.W <= 0):
            raise ValueError(f"W must be {A.shape} positive water areas, got shape {self.W.shape}")
        self.A_prev = A.copy()
        self.q_prev = None
        self.balance = WaterBalance(initial=float(self.W.sum()))
        self.remesh_counts = {}
        self.rule = np.zeros(net.n_pores, np.int8)  # per pore: 0 built with the network, 1-4 inherited by rule (a)-(d)
        self.inflow = self.inflow_weights()

    def checkpoint_restored(self):
        """After a checkpoint set the network: its inflow weights again."""
        self.inflow = self.inflow_weights()

    def inflow_weights(self):
        """(rate, weights (Np,)): the inflow into pore p is rate x weights[p] [m^2/s]: q_w [m^2/s] and 1
        per inflow pore (§5.1), or inflow_velocity [m/s] and the pore's inflow length [m]
        (``inflow_lengths``, SPEC §2.7)."""
        s = self.settings
        if s.inflow_velocity > 0:
            return s.inflow_velocity, inflow_lengths(self.net, self.walls)
        return s.q_w, self._boundary_masks()[2].astype(float)

    # -- state -----------------------------------------------------------------------------------
    def pressure(self, A):
        return pressure(self.W, A, self.settings.E_w)

    def total_water(self):
        return float(self.W.sum())

    def balance_error(self):
        """Relative water balance error |sum W - expected| / initial water."""
        return abs(self.total_water() - self.balance.expected()) / max(self.balance.initial, 1e-300)

    # -- flows -------------------------------------------------------------------------------------
    def _boundary_masks(self):
        m = boundary_masks(self.net, self.settings.sides)
        return m["surface"], m["drained"], m["inflow"]

    def flows(self, A, link_contact):
        """Throat and boundary flows [m^2/s] for void areas A and link states (eq 38-43)."""
        s, net = self.settings, self.net
        W = self.W
        U = pressure(W, A, s.E_w)
        open_ = A > net.a_min
        i, j = net.throat_conns[:, 0], net.throat_conns[:, 1]
        both = open_[i] & open_[j]
        k, k_surface, k_drained = permeability(link_contact[net.throat_link], s)  # eq 43
        A_ij = W[i] * W[j] / np.where(both, A[i] + A[j], 1.0)  # eq 40 (the OCR's W' is W_i)
        g = np.where(both, k * A_ij / s.E_w, 0.0)
        q = g * (U[i] - U[j])  # eq 41 with i_ij = (U_i - U_j)/E_w (eq 39)
        surface, drained, _ = self._boundary_masks()
        per_k = open_ * W / s.E_w  # outside at U = 0: A_ij -> W_i
        g_s, g_d = k_surface * surface * per_k, k_drained * drained * per_k
        q_s, q_d = g_s * U, g_d * U
        rate, weight = self.inflow
        q_in = rate * weight
        capacity = np.where(open_, W**2 / (s.E_w * np.where(open_, A, 1.0)), np.inf)
        return FlowState(q, q_s, q_d, q_in, g, g_s + g_d, capacity)

    def _limit(self, fl):
        n = self.net.n_pores
        i, j = self.net.throat_conns[:, 0], self.net.throat_conns[:, 1]
        g_sum = np.bincount(i, fl.g, minlength=n) + np.bincount(j, fl.g, minlength=n)
        return limits.gershgorin_limit(np.max((2 * g_sum + fl.g_b) / fl.capacity, initial=0.0))

    def darcy_limit(self, A, link_contact):
        """Largest stable explicit water step [s] for the current state (Gershgorin bound)."""
        return self._limit(self.flows(A, link_contact))

    def advance(self, dt, A, link_contact):
        """Advance the water by dt [s] at void areas A (Np,) and link states (L,) (eq 42).

        A step above the explicit limit is sub-stepped with settings.substep, else refused
        (engines.model.limits.substeps: DarcyStabilityError).
        Returns the FlowState used.
        """
        if not dt > 0:
            raise ValueError(f"dt must be > 0, got {dt}")
        A = np.asarray(A, float)
        if self.settings.smoothing:  # eq 45
            A = 0.5 * (self.A_prev + A)
            self.A_prev = A
        fl = self.flows(A, link_contact)
        n_sub = limits.substeps(dt, self._limit(fl), self.settings.substep, self.settings.E_w)
        h = dt / n_sub
        for sub in range(n_sub):
            fl = self._step(h, fl if sub == 0 else self.flows(A, link_contact))
        return fl

    def _step(self, h, fl):
        if self.settings.smoothing:  # eq 46
            q_new = fl.throat_q
            if self.q_prev is not None:
                fl.throat_q = 0.5 * (self.q_prev + q_new)
            self.q_prev = fl.throat_q
        net = self.net
        n = net.n_pores
        i, j = net.throat_conns[:, 0], net.throat_conns[:, 1]
        out = np.bincount(i, fl.throat_q, minlength=n) - np.bincount(j, fl.throat_q, minlength=n)
        fl.net_out = out + fl.surface_q + fl.side_q - fl.inflow_q
        W_new = self.W - fl.net_out * h  # eq 42
        if np.any(W_new <= 0):
            p = int(np.flatnonzero(W_new <= 0)[0])
            raise DarcyStabilityError(f"water area of pore {p} fell to {W_new[p]:.3e} m^2 in a step of {h:.3e} s; "
                                      f"{limits.DRY_HINT}")
        self.W = W_new
        b = self.balance
        b.inflow += fl.inflow_q.sum() * h
        b.surface_outflow += fl.surface_q.sum() * h
        b.side_outflow += fl.side_q.sum() * h
        return fl

    # -- re-meshing --------------------------------------------------------------------------------
    def remesh(self, new_net, A_new, A_old, xz=None, steps=None):
        """Move the water onto a rebuilt network (§3.4(2)); A_new, A_old: void areas of the new and
        the old network at the current positions xz (N, 2) [m].

        A new pore takes (a) the U of the old pore with the same vertex set; else (b) the mean U
        of the old pores whose vertex set contains or is contained in its own (a split or merge);
        else (c) the mean U of its already assigned neighbouring pores (the outside is not a pore
        and does not count), repeated until nothing changes; else (d) U = 0. Old pores
        pinched at A <= a_min do not pass on their pressure.
        transfer = "paper": W is recomputed from U and the new A (eq 32).
        transfer = "conserving": W from ``conserving_water`` (needs xz); new pores that overlap no
        old pore take the water of the pressure of rules (a)-(d) (counted as "unmatched").
        ``steps``: RemeshSteps, by default NUMPY_REMESH; engines.compiled.pores.REMESH: rules (b), (c)
        and the overlaps by compiled kernels (the same results). Returns the counts per rule.
        """
        steps = steps or NUMPY_REMESH
        U_old = pressure(self.W, A_old, self.settings.E_w)
        U_new, rule = pressures_by_rule(self.net, U_old, A_old > self.net.a_min, new_net, steps)
        counts = rule_counts(rule)
        A_new, A_old = np.asarray(A_new, float), np.asarray(A_old, float)
        overlaps = None if xz is None else steps.pore_overlaps(self.net, new_net, xz)
        if self.settings.transfer == "conserving":
            if xz is None:
                raise ValueError("transfer = 'conserving' needs the positions xz at re-meshing")
            W_new, matched = conserving_water(self.net, self.W, A_old, new_net, A_new, xz, overlaps)
            W_new[~matched] = water_from_pressure(U_new[~matched], A_new[~matched], self.settings.E_w)
            counts["unmatched"] = int((~matched).sum())
        else:
            W_new = water_from_pressure(U_new, A_new, self.settings.E_w)
        self.balance.remesh_change += float(W_new.sum() - self.W.sum())
        X_old, X_new = self.W - A_old, W_new - A_new
        self.balance.remesh_excess_change += float(X_new.sum() - X_old.sum())
        if overlaps is not None:
            new_on = np.bincount(overlaps[1], minlength=new_net.n_pores) > 0
            old_on = np.bincount(overlaps[0], minlength=self.net.n_pores) > 0
            self.balance.remesh_excess_edge += float(X_new[~new_on].sum() - X_old[~old_on].sum())
        self.net, self.W, self.A_prev, self.q_prev = new_net, W_new, A_new.copy(), None
        self.remesh_counts, self.rule = counts, rule
        self.inflow = self.inflow_weights()
        return counts


def boundary_masks(net, sides):
    """{water: (Np,) bool} for each of engines.model.groups.WATER: the pores of network ``net`` on
    which a boundary kind does that to the water (groups.BOUNDARY_KINDS): the open top's pores,
    those with a disc of a wall group as a vertex, those with a flat wall of a word as a vertex;
    [water] sides = ``sides``."""
    masks = {water: np.zeros(net.n_pores, bool) for water in groups.WATER}
    for k in groups.BOUNDARY_KINDS:
        if k.group:
            masks[groups.water_of(k.name, sides)] |= net.pore_touches[k.name]
        elif k.word:
            if net.flat_walls:
                masks[k.water] |= net.flat_wall_pores(k.name)
        else:  # the network's open top
            masks[k.water] |= net.pore_surface
    return masks


def inflow_lengths(net, walls):
    """(Np,) [m]: each pore's length of inflow boundary at the build (SPEC §2.7): every link between
    two discs of an inflow wall group (the bottom, engines.model.groups; codes ``walls`` (N,), engines.model.pores) counts its length centre to
    centre for the pore above it, every edge of an inflow flat wall its length for the pore on the
    wall's inward side; a pore on the row at a vertex only gets none, the outer face none."""
    n_p = net.n_pores
    if n_p == 0:
        return np.zeros(0)
    codes = np.asarray(walls, np.int64)
    links, vec = net.links, net.link_vec0
    v = len(codes) if net.wall_vertices is None else net.wall_vertices.n_vertices
    codes = np.concatenate([codes, np.full(v - len(codes), -1)])
    row, inward = np.zeros(len(links), bool), np.zeros((len(links), 2))
    for k in groups.disc_groups():
        if k.water == "inflow":  # a link between two discs of an inflow group; its inner side: the face's normal
            on = (codes[links[:, 0]] == k.group) & (codes[links[:, 1]] == k.group)
            row |= on
            inward[on, k.face[0]] = k.face[1]
    for e, w in zip(*pg.wall_edges(net)):  # an edge of an inflow flat wall; its inner side: the wall's normal
        if groups.kind(net.flat_walls[w].boundary).water == "inflow":
            inward[e] = net.flat_walls[w].normal()
            row[e] = True
    # the pore on the left of i -> j lies along (-dz, dx)
    left = inward[:, 0] * -vec[:, 1] + inward[:, 1] * vec[:, 0] > 0
    pore = np.where(left, net.link_pores[:, 0], net.link_pores[:, 1])
    keep = row & (pore != pg.OUTER)
    return np.bincount(pore[keep], np.hypot(vec[keep, 0], vec[keep, 1]), minlength=n_p)


RULES = "abcd"  # PoreWater.rule codes 1-4; 0: built with the network


def rule_counts(rule):
    """{"a": n, ..., "d": n} of rule codes 1-4."""
    return {name: int(np.sum(rule == k)) for k, name in enumerate(RULES, 1)}


def pressures_by_rule(old_net, U_old, old_valid, new_net, steps=None):
    """Pressures for the pores of ``new_net`` from those U_old of ``old_net`` (only where ``old_valid``)
    by rules (a)-(d) of §3.4(2) (``PoreWater.remesh``): (U_new (Np_new,), rule code 1-4 of (a)-(d)
    (Np_new,) int8). ``steps``: RemeshSteps for rules (b) and (c) (default NUMPY_REMESH)."""
    steps = steps or NUMPY_REMESH
    n_new = new_net.n_pores
    U = np.full(n_new, np.nan)
    rule = np.zeros(n_new, np.int8)
    # (a) the same vertex set: equal signatures (pores._mix64)
    valid = np.flatnonzero(old_valid)
    order = valid[np.argsort(old_net.pore_signature[valid], kind="stable")]
    sorted_sig = old_net.pore_signature[order]
    pos = np.minimum(np.searchsorted(sorted_sig, new_net.pore_signature), max(len(order) - 1, 0))
    if len(order):
        same = sorted_sig[pos] == new_net.pore_signature
        U[same], rule[same] = U_old[order[pos[same]]], 1
    todo = np.flatnonzero(np.isnan(U))
    if len(todo):  # (b) split or merge: old vertex set contains or is contained in the new one
        U_b = steps.near_vertex_sets(old_net, U_old, old_valid, new_net, todo)
        U[todo] = U_b
        rule[todo[~np.isnan(U_b)]] = 2
    # (c) mean over the assigned neighbouring pores ("まわりのすべての図形"); the outside is not a pore
    steps.spread_to_neighbours(U, rule, new_net.throat_conns)
    left = np.isnan(U)  # (d)
    U[left], rule[left] = 0.0, 4
    return U, rule


def near_vertex_sets(old_net, U_old, old_valid, new_net, todo):
    """Rule (b) for the new pores ``todo``: the mean U_old of the old pores (where ``old_valid``)
    whose vertex set contains or is contained in theirs, nan where there is none (len(todo),)."""
    by_vertex = {}
    for q in np.flatnonzero(old_valid):
        for v in old_net.vertices_of(q).tolist():
            by_vertex.setdefault(v, []).append(q)
    U_b = np.full(len(todo), np.nan)
    for k, p in enumerate(todo):
        mine = set(new_net.vertices_of(p).tolist())
        cands = {q for v in mine for q in by_vertex.get(v, ())}
        near = [q for q in cands if _subset_or_superset(set(old_net.vertices_of(q).tolist()), mine)]
        if near:
            U_b[k] = float(np.mean(U_old[near]))
    return U_b


def spread_to_neighbours(U, rule, conns):
    """Rule (c), in place: in rounds, each pore with U nan takes the mean U of its distinct
    neighbours (the pore pairs conns (Nt, 2)) that had one at the round's start; rule code 3."""
    n = len(U)
    i, j = np.unique(np.sort(conns, axis=1), axis=0).T  # distinct neighbours
    while True:
        unset = np.isnan(U)
        if not unset.any():
            return
        known = np.where(unset, 0.0, U)
        has = (~unset).astype(float)
        s = np.bincount(i, known[j], n) + np.bincount(j, known[i], n)
        c = np.bincount(i, has[j], n) + np.bincount(j, has[i], n)
        assign = unset & (c > 0)
        if not assign.any():
            return
        U[assign] = s[assign] / c[assign]
        rule[assign] = 3


def _subset_or_superset(a, b):
    return a <= b or b <= a


class RemeshSteps(NamedTuple):
    """The parts of ``PoreWater.remesh`` that have compiled twins (engines.compiled.pores.REMESH)."""

    pore_overlaps: Callable         # as engines.model.pores.pore_overlaps
    near_vertex_sets: Callable      # as near_vertex_sets
    spread_to_neighbours: Callable  # as spread_to_neighbours


NUMPY_REMESH = RemeshSteps(pg.pore_overlaps, near_vertex_sets, spread_to_neighbours)


SINKHORN_TOL, SINKHORN_MAX_ITER = 1e-13, 500


def conserving_water(old_net, W_old, A_old, new_net, A_new, xz, overlaps=None):
    """Water of the new pores from the water of the old ones, conserved (module docstring).

    O_pq: polygon overlap of old pore p and new pore q (pores.pore_overlaps). The void of
    the overlap is not known exactly (the discs cut it), so V_pq = alpha_p O_pq beta_q is scaled
    (Sinkhorn iterations) until its rows sum to the old voids A_p and its columns to the new voids
    A_q (times the ratio of the two totals in each connected group of overlapping pores, which is 1
    up to round-off where old and new cover the same region). The excess water X_p = W_p - A_p of
    old pore p goes to the new pores in the shares V_pq / sum_q V_pq (exactly all of it), and
    W_q = A_q + sum_p X_p V_pq / sum_q V_pq. So a uniform pressure stays uniform, and the total
    water changes only by the void gained or lost at the edges of the covered region (at U = 0)
    and by the water of old pores that no new pore overlaps.
    ``overlaps``: pore_overlaps(old_net, new_net, xz) when the caller has it.
    Returns (W_new (Np_new,), matched (Np_new,) bool: the pore overlaps some old pore; W_new is
    nan where it does not). Raises ValueError if a new pore would get no water (W <= 0).
    """
    p, q, o = pg.pore_overlaps(old_net, new_net, xz) if overlaps is None else overlaps
    n_old, n_new = old_net.n_pores, new_net.n_pores
    W_new = np.full(n_new, np.nan)
    matched = np.zeros(n_new, bool)
    if not len(o):
        return W_new, matched
    matched[q] = True
    a = np.maximum(A_old, old_net.a_min)  # a pinched old pore still hands on its water
    b = np.asarray(A_new, float).copy()
    _, group = connected_components(coo_matrix((o, (p, n_old + q)), shape=(n_old + n_new,) * 2), directed=False)
    ga, gb = group[:n_old], group[n_old:]
    has_old = np.zeros(n_old, bool)
    has_old[p] = True
    tot_a = np.bincount(ga[has_old], a[has_old], minlength=group.max() + 1)
    tot_b = np.bincount(gb[matched], b[matched], minlength=group.max() + 1)
    b[matched] *= tot_a[gb[matched]] / tot_b[gb[matched]]
    alpha, beta = np.ones(n_old), np.ones(n_new)
    for _ in range(SINKHORN_MAX_ITER):
        alpha[has_old] = a[has_old] / np.bincount(p, o * beta[q], minlength=n_old)[has_old]
        col = np.bincount(q, o * alpha[p], minlength=n_new)
        beta[matched] = b[matched] / col[matched]
        row = np.bincount(p, o * alpha[p] * beta[q], minlength=n_old)
        if np.max(np.abs(row[has_old] / a[has_old] - 1)) < SINKHORN_TOL:
            break
    v = o * alpha[p] * beta[q]
    share = v / np.bincount(p, v, minlength=n_old)[p]
    X = np.asarray(W_old, float) - np.asarray(A_old, float)
    W_new[matched] = np.asarray(A_new, float)[matched] + np.bincount(q, X[p] * share, minlength=n_new)[matched]
    if np.any(W_new[matched] <= 0):
        k = int(np.flatnonzero(matched & ~(W_new > 0))[0])
        over = p[q == k]
        raise ValueError(f"conserving transfer: new pore {k} would hold no water (W = {W_new[k]:.3e} m^2): the old "
                         f"pores over it, at suction (W/A down to {np.min(np.asarray(W_old, float)[over] / np.asarray(A_old, float)[over]):.2f}), hand on "
                         f"their water missing whole, and their void is {tot_a[gb[k]] / tot_b[gb[k]]:.2f} x that of "
                         f"the new pores it goes to (the discs moved far on one mesh); rebuild more often "
                         f"(WaterEngine rebuild_interval= or rebuild_distance=; [numerics] rebuild_interval or "
                         f"rebuild_distance) or use the paper's transfer (WaterSettings transfer='paper'; [water] "
                         f"transfer = \"paper\" in a scene file)")
    return W_new, matched
