"""The stability map: how a short run at one setting ended. No YADE.

A run is *refused* when preflight (engines.run.preflight) refuses it before the first step, with a
message naming the limit; otherwise it is *bounded* when it ran to the end with finite positions,
its kinetic energy stayed within KE_FACTOR x that of its reference (the same setting at a finer
dt over the same window, so that physics that moves the discs hard is not taken for an
instability; plus KE_SLACK of the scene's potential energy scale, so that a still reference does
not make any motion "unbounded"), its particles stayed within the box (ESCAPE_RADII radii
above the initial bed top, above the bottom wall, between the side walls) and its water balance
error stayed below BALANCE_TOL; else *unbounded* (with the reason). An error raised by an engine
during the run (a Darcy limit reached as the pores changed) is *unbounded* too: the user was not
told before the run.

The map's points (map_points): quick-sand case 1 (QS) at the extremes of each knob, the seismic
box (LIQ) for dt/dt_crit too; engines.run.stability runs them, postproc.stability draws the map.
"""
import numpy as np

KE_FACTOR = 10.0
KE_SLACK = 0.01      # of m_total g h_bed [J/m]
ESCAPE_RADII = 20.0
BALANCE_TOL = 1e-6


def box_of(packing):
    """(x_min, x_max, z_min, z_max) [m] a particle of ``packing`` must stay in: between the side
    walls' centres (or the particles' extent), above the bottom wall's centres, below
    ESCAPE_RADII mean radii over the initial bed top."""
    mob = packing.mobile
    walls = ~mob
    x = packing.xz[walls if walls.any() else mob, 0]
    z_min = float(packing.xz[walls, 1].min()) if walls.any() else -np.inf
    return float(x.min()), float(x.max()), z_min, packing.bed_top + ESCAPE_RADII * float(packing.r[mob].mean())


def energy_scale(mass, packing, g):
    """m_total g h [J/m] of the particles, h the bed height above the bottom."""
    mob = packing.mobile
    return float(mass[mob].sum() * g * max(packing.bed_top - packing.bed_bottom, 0.0))


def classify(ke_max, ke_base, scale, finite, escaped, balance_error, error=None):
    """('bounded' | 'unbounded', reason) of a run that was not refused (module docstring)."""
    if error:
        return "unbounded", f"stopped by an engine: {error}"
    if not finite:
        return "unbounded", "non-finite positions"
    if escaped:
        return "unbounded", f"{escaped} particle(s) left the box"
    bound = KE_FACTOR * ke_base + KE_SLACK * scale
    if not ke_max <= bound:
        return "unbounded", f"kinetic energy {ke_max:.3g} J/m > {bound:.3g} J/m ({KE_FACTOR:g} x the reference's)"
    if not balance_error <= BALANCE_TOL:
        return "unbounded", f"water balance error {balance_error:.3g} > {BALANCE_TOL:g}"
    return "bounded", ""


def escaped(xz, box):
    """Number of particles outside ``box`` (box_of)."""
    x0, x1, z0, z1 = box
    return int(np.sum((xz[:, 0] < x0) | (xz[:, 0] > x1) | (xz[:, 1] < z0) | (xz[:, 1] > z1) | ~np.isfinite(xz).all(1)))


# -- the map's points -----------------------------------------------------------------------------
QS, LIQ = "quicksand_case1", "liquefaction_case1"
DT_RATIOS = (0.25, 0.5, 0.75, 0.9, 0.99, 1.05)
DT_WINDOW = 0.01
REF_DIVISOR = 4  # a point's reference: the same setting at dt / 4 (the dt points: the preset's dt)


def resolved(num, divisor):
    """Overrides of [numerics] for dt / divisor with the same rebuild period (and water_interval,
    so the water step shrinks with dt)."""
    return {"numerics": {"dt": num.dt / divisor, "rebuild_interval": num.rebuild_interval * divisor}}


def map_points():
    """[(case, knob, value, overrides)]: the knob's value and the scene overrides of each point
    (dt/dt_crit points get their dt from the packing at run time)."""
    pts = [(case, "dt/dt_crit", x, {}) for case in (QS, LIQ) for x in DT_RATIOS]
    pts += [(QS, "E_w", e, {"water": {"E_w": e}}) for e in (24.0, 2.4e3, 2.4e4, 2.4e5, 2.4e6, 2.4e7, 2.4e8)]
    pts += [(QS, "E_w", e, {"water": {"E_w": e}, "numerics": {"dt": 1e-5, "rebuild_interval": 100}})
            for e in (2.4e4, 2.4e5, 2.4e6)]
    pts += [(QS, "k1", k, {"water": {"k1": k}}) for k in (0.0, 1e3, 1e4, 1e5, 1e6, 1e9)]
    pts += [(QS, "k1", 1e6, {"water": {"k1": 1e6, "substep": False}})]  # the strict mode
    pts += [(QS, "k2", k, {"water": {"k2": k}}) for k in (0.0, 1e3, 1e5, 1e6)]
    pts += [(QS, "k2", 1e6, {"water": {"k2": 1e6, "substep": False}})]
    pts += [(QS, "eps_m", e, {"contact": {"eps_m": e}}) for e in (1e-5, 1e-4, 3e-4, 1e-3)]
    pts += [(QS, "f_max", f, {"contact": {"f_max": f}}) for f in (0.01, 0.1, 10.0, 1000.0)]
    return pts
