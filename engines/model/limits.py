"""The stability limits of the seed-000 step [s], and the checks that refuse a step above them. No YADE.

Every "is this step stable?" question is answered here: preflight (engines.run.preflight) asks
them of a scene at its start, dt = "auto" (engines.model.start) takes the smallest, the
engines ask the contact and tie limits at construction and the Darcy limit at every water step
(the compiled water step runs the twins of ``substep_count`` and ``gershgorin_limit`` in
engines.compiled.kernels, tested equal).

* contact (eq 52): 2 sqrt(m_min / kn) over the mobile particles; dt is refused above
  [numerics] dt_safety times it;
* ties: sqrt(m_min / k'_s) over the moving side-wall discs (Fig. 27 springs,
  engines.model.side_walls);
* water stiffness: a disc moved by dx changes the void of each pore it bounds by at most its
  width 2 r dx, so the pressure of that pore by E_w 2 r dx / A (eq 32 at W = A), which pushes the
  disc over at most 2 r: the water adds a spring k_w = E_w sum_p (2 r)^2 / A_p (over the open
  pores p the disc bounds) and 2 sqrt(m / k_w) is the eq 52 bound of that spring. The pressure
  forces are recomputed once per water step h = water_interval x dt and held in between, so the
  spring acts with the step h: h is refused above the bound (no sub-steps; the message names the
  largest stable water_interval);
* Darcy: the explicit water update (eq 42) is stable for a water step h <= 2 / lambda_max of the
  linearised exchange dU/dt = -C^-1 G U (engines.model.pore_water: conductances g, boundary g_b,
  capacities c = W^2 / (E_w A)); ``darcy_eigen_limit`` computes it with eigsh. The engines check
  every water step against the Gershgorin bound of the same matrix (``gershgorin_limit`` of the
  lambda the flow pass returns), which is below it (0.74-0.8 of it on the seismic box);
* sub-steps: a water step above the Gershgorin limit is split into ``substep_count`` equal
  sub-steps when the water's settings allow it (``substeps``), each costing about SUBSTEP_COST of
  a water step; otherwise it is refused.
"""
import math

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

SUBSTEP_COST = 0.25  # one sub-step (a flow and an update pass) costs about a quarter of a water step


class DarcyStabilityError(ValueError):
    """A water step exceeds the explicit Darcy limit, or a pore's water would fall to zero."""


# what to change when a pore's water falls to zero, as the engine's arguments and the scene's fields
DRY_HINT = ("reduce the water step (O.dt or WaterEngine water_interval=; [numerics] dt or water_interval in a "
            "scene file)")


def refuse_dt(dt, limit, what):
    """Raise ValueError "[numerics] dt = ... exceeds <what> <limit>" when dt > limit."""
    if dt > limit:
        raise ValueError(f"[numerics] dt = {dt:.3g} s exceeds {what.format(limit=f'{limit:.3g} s')}")


# -- contact (eq 52) --------------------------------------------------------------------------------
def critical_time_step(mass, kn):
    """Cundall's bound dt < 2 sqrt(m / kn) over the lightest disc [s] (eq 52)."""
    return 2.0 * np.sqrt(np.min(mass) / kn)


def check_contact(dt, dt_safety, mobile_mass, kn):
    """Refuse dt above dt_safety x 2 sqrt(m_min / kn) over the mobile discs (eq 52)."""
    if len(mobile_mass):
        refuse_dt(dt, dt_safety * critical_time_step(mobile_mass, kn),
                  f"the stability limit {{limit}} of eq 52 (dt_safety {dt_safety:g} x 2 sqrt(m_min / kn), "
                  f"m_min = {np.min(mobile_mass):.3g} kg/m, kn = {kn:.3g} N/m)")


# -- side-wall ties (Fig. 27) -----------------------------------------------------------------------
def tie_limit(ties, mass):
    """sqrt(m_min / k'_s) over the moving wall discs of SideWallTies ``ties`` [s]; inf without springs."""
    if ties is None or ties.ks == 0 or not ties.moving.any():
        return math.inf
    return float(np.sqrt(np.min(np.asarray(mass)[ties.moving]) / ties.ks))


def check_ties(dt, ties, mass):
    """Refuse dt above ``tie_limit``."""
    if ties is not None:
        refuse_dt(dt, tie_limit(ties, mass), f"the stability limit {{limit}} of the side-wall ties "
                                             f"(sqrt(m_min / k's), k's = [contact] ks_wall = {ties.ks:.3g} N/m)")


# -- the stiffness the water adds -------------------------------------------------------------------
def water_stiffness(net, A, r, E_w):
    """k_w (N,) [N/m]: E_w sum over the open pores p that disc i bounds of (2 r_i)^2 / A_p (flat
    walls, vertices >= N, take none)."""
    ptr, idx = net.pore_vertex_ptr, net.pore_vertex_idx
    pore = np.repeat(np.arange(net.n_pores), np.diff(ptr))
    keep = (idx < net.n_discs) & (np.asarray(A)[pore] > net.a_min)
    v, p = idx[keep], pore[keep]
    return np.bincount(v, E_w * (2 * r[v]) ** 2 / np.asarray(A)[p], minlength=net.n_discs)


def water_stiffness_limit(net, A, r, E_w, mass, mobile):
    """min over the particles of 2 sqrt(m / k_w) [s] (inf where the water adds no stiffness)."""
    k = water_stiffness(net, A, r, E_w)[mobile]
    m = np.asarray(mass)[mobile]
    has = k > 0
    return float(np.min(2 * np.sqrt(m[has] / k[has]))) if has.any() else math.inf


class WaterStiffnessError(ValueError):
    """A water step above the water-stiffness limit (it has no sub-steps)."""


# the names of the water step's parts in a scene file and in a YADE script (WaterEngine)
SCENE_NAMES = {"interval": "[numerics] water_interval", "dt": "[numerics] dt", "E_w": "[water] E_w"}
ENGINE_NAMES = {"interval": "WaterEngine water_interval=", "dt": "O.dt", "E_w": "WaterSettings E_w"}


def largest_water_interval(dt, limit):
    """The largest water_interval whose water step water_interval x dt [s] is within ``limit`` [s] (0: none)."""
    return int(math.floor(limit / dt * (1 + 1e-12))) if math.isfinite(limit) else 2**62


def check_water_stiffness(dt, limit, E_w, water_interval=1, names=SCENE_NAMES, when="at the start"):
    """Refuse a water step water_interval x dt [s] above the water-stiffness limit ``limit`` [s]:
    the pressure forces are held for a water step, the water's spring k_w acts with that step, and
    it has no sub-steps; the message names the largest stable water_interval (or the dt and E_w
    that would do when even water_interval = 1 is above it)."""
    h = water_interval * dt
    if h <= limit:
        return
    largest = largest_water_interval(dt, limit)
    margin = f" ({largest // 2} leaves a margin: the limit moves with the pores)" if largest >= 2 else ""
    fix = (f"set {names['interval']} <= {largest}{margin}" if largest >= 1 else
           f"reduce {names['dt']} to <= {limit:.3g} s with water_interval = 1, or reduce {names['E_w']}")
    raise WaterStiffnessError(
        f"water step {h:.3g} s ({names['interval']} {water_interval} x {names['dt']} {dt:.3g} s) exceeds the "
        f"water-stiffness limit {limit:.3g} s {when} (2 sqrt(m / k_w), k_w = E_w sum (2 r)^2 / A over the pores a "
        f"disc bounds, E_w = {E_w:g} N/m): the pressure forces, held for a water step, would throw the discs about, "
        f"and this limit has no sub-steps; {fix}")


# -- the accuracy of a water step -------------------------------------------------------------------
# max |dA| / A of the pores between two water steps: warned once above WATCH_WARN, refused above
# WATCH_STOP unless accepted (docs/ENGINE.md, "The accuracy watch": how they were chosen)
WATCH_WARN, WATCH_STOP = 0.05, 0.5


class AccuracyError(ValueError):
    """A water step too long for the discs' motion (the accuracy watch)."""


def area_change(A_prev, A, a_min):
    """max |A - A_prev| / A_prev over the pores open (> a_min [m^2]) in both void areas (Np,) [m^2]; 0 when none."""
    open_ = (A_prev > a_min) & (A > a_min)
    return float(np.max(np.abs(A[open_] - A_prev[open_]) / A_prev[open_])) if open_.any() else 0.0


class AccuracyWatch:
    """The accuracy of the water steps (docs/ENGINE.md): at each water step, max |dA| / A of the
    open pores since the last water step on the same pores, and min U / E_w. Warns once (``log``)
    above ``warn`` or at U < -E_w; above ``stop`` raises AccuracyError unless ``accept``. ``worst``
    keeps the largest ratio seen, ``lowest`` the lowest U / E_w."""

    # what a checkpoint stores (engines.model.state): nothing; a restored run watches again from its step
    CHECKPOINT_FIELDS = ()
    CHECKPOINT_DERIVED = {**{name: "the engine's arguments" for name in ("warn", "stop", "accept", "names")},
                          "log": "the print function",
                          **{name: "what the watch saw of the run since it was made" for name in
                             ("worst", "lowest", "warned", "_A")}}

    def __init__(self, warn=WATCH_WARN, stop=WATCH_STOP, accept=False, log=print, names=ENGINE_NAMES):
        self.warn, self.stop, self.accept, self.log, self.names = warn, stop, accept, log, names
        self.worst, self.lowest, self.warned, self._A = 0.0, 0.0, False, None

    def rebuilt(self):
        """The pores were rebuilt: the next water step starts a new comparison."""
        self._A = None

    def __call__(self, A, U, E_w, a_min, h):
        """Watch the water step of h [s] that ended at void areas A (Np,) [m^2], pressures U (Np,) [N/m]."""
        A = np.array(A, float)
        ratio = area_change(self._A, A, a_min) if self._A is not None and len(self._A) == len(A) else 0.0
        self._A = A
        self.seen(ratio, float(np.min(U)) / E_w if len(U) else 0.0, h)

    def seen(self, ratio, low, h):
        """Water steps of h [s] whose largest max |dA| / A was ``ratio`` and lowest U / E_w ``low``
        (one water step, or those of a compiled drive's call: kernels.watch_areas)."""
        ratio, low = float(ratio), float(low)
        self.worst, self.lowest = max(self.worst, ratio), min(self.lowest, low)
        cause = (f"a pore's void area changed by {ratio:.0%} in one water step of {h:.3g} s" if ratio > self.warn else
                 f"a pore's suction reached U = {low:.2f} E_w" if low < -1 else None)
        if cause is None:
            return
        fix = (f"shorten the water step ({self.names['interval']} or {self.names['dt']}): the pressure forces are "
               f"held for a water step while the discs move")
        if ratio > self.stop and not self.accept:
            raise AccuracyError(f"{cause} (above {self.stop:.0%}): the water lags the discs; {fix}, or accept it "
                                f"(WaterEngine accept_inaccurate=True)")
        if not self.warned:
            self.warned = True
            self.log(f"water: {cause} (warned above {self.warn:.0%}, stopped above {self.stop:.0%}): inaccurate; {fix}")


# -- Darcy ------------------------------------------------------------------------------------------
def exchange_matrix(water, A, link_contact):
    """(S, open) where S is the symmetric C^-1/2 G C^-1/2 [1/s] (sparse, over the open pores) of
    the linearised exchange of PoreWater ``water`` at void areas A, and open (Np,) bool."""
    fl = water.flows(A, link_contact)
    open_ = np.isfinite(fl.capacity)
    idx = np.cumsum(open_) - 1
    n = int(open_.sum())
    i, j = water.net.throat_conns[:, 0], water.net.throat_conns[:, 1]
    keep = open_[i] & open_[j] & (fl.g > 0)
    gi, gj, g = idx[i[keep]], idx[j[keep]], fl.g[keep]
    diag = np.bincount(gi, g, minlength=n) + np.bincount(gj, g, minlength=n) + fl.g_b[open_]
    G = sp.coo_matrix((np.concatenate([diag, -g, -g]), (np.concatenate([np.arange(n), gi, gj]),
                                                          np.concatenate([np.arange(n), gj, gi]))), shape=(n, n)).tocsr()
    s = 1.0 / np.sqrt(fl.capacity[open_])
    return sp.diags(s) @ G @ sp.diags(s), open_


def lambda_max(S):
    """Largest eigenvalue of the symmetric positive semi-definite S (eigsh; dense when small)."""
    n = S.shape[0]
    if n == 0:
        return 0.0
    if n < 50:
        return float(np.linalg.eigvalsh(S.toarray())[-1])
    return float(eigsh(S, k=1, which="LA", return_eigenvectors=False, tol=1e-8)[0])


def darcy_eigen_limit(water, A, link_contact):
    """2 / lambda_max [s] of the linearised exchange (inf without exchange)."""
    lam = lambda_max(exchange_matrix(water, A, link_contact)[0])
    return 2.0 / lam if lam > 0 else math.inf


def gershgorin_limit(lam):
    """2 / lambda [s] for the Gershgorin bound lambda [1/s] of the exchange (inf when 0)."""
    return 2.0 / lam if lam > 0 else math.inf


def substep_count(h, limit):
    """Equal sub-steps a water step of h [s] needs under the Darcy limit [s]: 1 or ceil(h / limit)."""
    return 1 if h <= limit else int(math.ceil(h / limit))


def substeps(h, limit, substep, E_w):
    """``substep_count(h, limit)``; a count above 1 without ``substep`` raises DarcyStabilityError."""
    n = substep_count(h, limit)
    if n > 1 and not substep:
        raise DarcyStabilityError(
            f"water step {h:.3e} s exceeds the explicit Darcy limit {limit:.3e} s (Gershgorin bound of eq 38-43 "
            f"at E_w = {E_w:g} N/m); reduce dt, water_interval or the permeabilities, or let the water sub-step "
            f"(WaterSettings substep=True; [water] substep = true in a scene file)")
    return n


def substep_cost(n):
    """The cost of a water step of n sub-steps, in water steps without sub-steps."""
    return 1 + SUBSTEP_COST * (n - 1)
