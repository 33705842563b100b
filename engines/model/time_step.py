"""The automatic time step, ``[numerics] dt = "auto"``: the smallest of the stability
limits of the scene at its start, times ``[numerics] dt_auto_factor``. No YADE.

Limits [s] (``limits``):

* contact (eq 52): 2 sqrt(m_min / kn) over the particles;
* ties: sqrt(m_min / k'_s) of the side-wall springs (only with [loading] side_walls = "springs";
  the engines' own bound, engines.model.side_walls);
* water stiffness: a disc moved by dx changes the void of each pore it bounds by at most its width
  2 r dx, so the pressure of that pore by E_w 2 r dx / A (eq 32 at W = A), which pushes the disc
  over at most 2 r: the water adds a spring k_w = E_w sum_p (2 r)^2 / A_p (over the open pores p
  the disc bounds; of order E_w r^2 / A per pore) and 2 sqrt(m / k_w) is the eq 52 bound of that
  spring, taken over the particles;
* darcy: 2 / lambda_max of the linearised exchange dU/dt = -C^-1 G U of the pores at the start
  (engines.model.pore_water: conductances g, boundary g_b, capacities c = W^2 / (E_w A)), from
  scipy.sparse.linalg.eigsh on the symmetric C^-1/2 G C^-1/2, divided by water_interval (the
  water step is water_interval x dt). The engines check every water step against the Gershgorin
  bound of the same matrix (0.74-0.8 of 2 / lambda_max on the seismic box), so with
  [water] substep = false the chosen dt is also capped at that check ("darcy_check").

With [water] substep = true (the default) the Darcy limits do not bound dt: dt = dt_auto_factor x
min(contact, ties, water stiffness), the water is sub-stepped where a water step exceeds the
Darcy check, and the choice reports the sub-steps per water step at the start and their cost.
With substep = false: dt = dt_auto_factor x min(contact, ties, water stiffness, darcy), then
capped by darcy_check.
The limits are those of the start and dt is not changed during the run: the pores change as the
discs move, and the engines check the Darcy limit at every water step (sub-stepping by default,
which is the Darcy limit refreshed at every water step rather than at rebuilds); the contact and
tie limits do not change; the water-stiffness limit is not refreshed.
"""
import math

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

from engines.model import pores as pg
from engines.model.contact import critical_time_step
from engines.model.pore_water import PoreWater

AUTO = "auto"
SUBSTEP_COST = 0.25  # one sub-step costs about a quarter of a water step (engines.yade.water_engine)


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


def darcy_limit(water, A, link_contact):
    """2 / lambda_max [s] of the linearised exchange (inf without exchange)."""
    lam = lambda_max(exchange_matrix(water, A, link_contact)[0])
    return 2.0 / lam if lam > 0 else math.inf


def water_stiffness(net, A, r, E_w):
    """k_w (N,) [N/m]: E_w sum over the open pores p that disc i bounds of (2 r_i)^2 / A_p."""
    k = np.zeros(net.n_discs)
    for p in np.flatnonzero(A > net.a_min):
        v = net.vertices_of(p)
        k[v] += E_w * (2 * r[v]) ** 2 / A[p]
    return k


def water_stiffness_limit(net, A, r, E_w, mass, mobile):
    """min over the particles of 2 sqrt(m / k_w) [s] (inf where the water adds no stiffness)."""
    k = water_stiffness(net, A, r, E_w)[mobile]
    m = np.asarray(mass)[mobile]
    has = k > 0
    return float(np.min(2 * np.sqrt(m[has] / k[has]))) if has.any() else math.inf


def start_pores(scene, packing):
    """(network, measures, PoreWater) of the pores at the start (W = A), as the engines build them."""
    net = pg.build_pores(packing.xz, packing.r, eps_m=scene.contact.eps_m, l_m=scene.water.l_m, walls=packing.group)
    m = pg.measure(net, packing.xz, packing.r)
    return net, m, PoreWater(net, m.void_area, scene.water_settings())


def limits(scene, packing):
    """{name: limit [s]} of the scene at the start (module docstring); darcy_check is the engines'
    Gershgorin check of the water step, per DEM step (divided by water_interval)."""
    from engines.model.pore_dem import disc_masses, side_wall_ties

    mass, _ = disc_masses(scene, packing)
    mob = packing.mobile
    out = {"contact": critical_time_step(mass[mob], scene.contact.kn)}
    ties = side_wall_ties(scene, packing)
    if ties is not None:
        out["ties"] = ties.stable_time_step(mass)
    if scene.water.enabled:
        net, m, water = start_pores(scene, packing)
        M = scene.numerics.water_interval
        out["water_stiffness"] = water_stiffness_limit(net, m.void_area, packing.r, scene.water.E_w, mass, mob)
        out["darcy"] = darcy_limit(water, m.void_area, m.link_contact) / M
        out["darcy_check"] = water.darcy_limit(m.void_area, m.link_contact) / M
    return out


def choose(lims, factor, substep=False):
    """(dt, binding limit's name, sub-steps per water step at the start) from ``limits``."""
    scaled = {k: factor * v for k, v in lims.items() if k != "darcy_check" and not (substep and k == "darcy")}
    name = min(scaled, key=scaled.get)
    dt = scaled[name]
    check = lims.get("darcy_check", math.inf)
    if not substep and check < dt:
        dt, name = check, "darcy_check"
    n_sub = max(1, math.ceil(dt / check * (1 - 1e-12))) if substep and math.isfinite(check) else 1
    return dt, name, n_sub


def auto_time_step(scene, packing):
    """(dt [s], {name: limit [s]}, binding name, sub-steps per water step at the start)."""
    lims = limits(scene, packing)
    dt, name, n_sub = choose(lims, scene.numerics.dt_auto_factor, scene.water.enabled and scene.water.substep)
    return dt, lims, name, n_sub


def describe(dt, lims, name, n_sub, factor):
    """The lines a run prints about its automatic time step."""
    shown = ", ".join(f"{k} {v:.3g} s" for k, v in lims.items())
    text = (f"dt = auto: {dt:.3g} s, bound by the {name} limit"
            + ("" if name == "darcy_check" else f" x dt_auto_factor {factor:g}") + f" (limits at the start: {shown})")
    if n_sub > 1:
        text += (f"\nwater: {n_sub} sub-steps per water step at the start (substep = true, Gershgorin Darcy limit "
                 f"{lims['darcy_check']:.3g} s per DEM step); each costs about {SUBSTEP_COST:.0%} of a water step, "
                 f"so the water costs about {1 + SUBSTEP_COST * (n_sub - 1):.2g}x a water step without sub-steps")
    return text


def resolve_dt(scene, packing, log=print):
    """``scene`` itself when its dt is a number; for dt = "auto" a copy with the chosen dt (the
    choice printed through ``log``; None: silent)."""
    if scene.numerics.dt != AUTO:
        return scene
    dt, lims, name, n_sub = auto_time_step(scene, packing)
    if log is not None:
        log(describe(dt, lims, name, n_sub, scene.numerics.dt_auto_factor))
    out = scene.with_overrides({"numerics": {"dt": dt}})
    out.overrides = scene.overrides  # "auto" stays the recorded choice; parameters hold the number
    return out
