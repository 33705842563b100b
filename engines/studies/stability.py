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
