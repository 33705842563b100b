"""Effective stress from the contact forces and the pore-pressure ratio (SPEC §2.8). No YADE.

Per metre of thickness, compression positive, in Pa. The mean stress of the contacts of a region
of area A (Love–Weber):

    sigma'_ij = -(1/A) sum_c f_i^c b_j^c                                            (L1)

over the contacts c whose contact point lies in the region: f^c the force on a particle, b^c the
branch vector from that particle's centre to the contact point. A contact of two particles counts
once for each (together: f ⊗ l with l the centre-to-centre vector); a contact with a wall (a wall
disc or a flat wall's foot) counts for its particle only. The minus makes compression positive; the
symmetric part is kept. From the tensor (``invariants``):

    sigma'_v = sigma'_zz, sigma'_h = sigma'_xx, p' = (sigma'_xx + sigma'_zz)/2,
    q = sqrt(((sigma'_zz - sigma'_xx)/2)^2 + sigma'_xz^2)  (the radius of Mohr's circle, >= 0)  (L2)

A particle's own stress is (L1) over its contacts with A = pi r^2 / (1 - n), n the porosity (the
particle's share of the region it stands for; ``disc_stress``). The regions: horizontal bands of
the bed, n equal bands between the bed's bottom and its top at the start (``bands``), and the
scene's pressure blocks, each as wide as the box and cut at the bed's top at the start
(``region_areas``). Their excess pore pressure is the mean U of the pores whose centroid lies in
them, weighted by the pores' void areas (``region_pressure``), and the pore-pressure ratio is

    r_u = U / (sigma'_v0 * 1 m)                                                     (L3)

with U [N/m] = Delta u [Pa] x 1 m and sigma'_v0 the region's sigma'_v at the start (r_u = 1: the
contacts carry nothing). Beside it, the buoyant overburden (``overburden``): the buoyant weight of
the solid above a depth over the box's width, averaged over the region's height (L4). The water's
load on the grains (buoyancy, the pressure forces of eq 33) is not part of sigma'.
"""
from dataclasses import dataclass

import numpy as np

from engines.model.observe import disc_rectangle_area
from engines.model.pores import WALL_BOTTOM, WALL_LEFT, WALL_RIGHT

SURFACE_DIAMETERS = 2.0  # a band whose top is closer to the bed's top [mean diameters] has too little
#                         overburden for its r_u and p'/p'_0 to be read (sigma'_v0 -> 0)


@dataclass(frozen=True)
class Contacts:
    """Contacts as their particles see them (M of them): ``disc`` (M,) the particle's index,
    ``point`` (M, 2) the contact point [m], ``force`` (M, 2) the force on the particle [N per m]."""

    disc: np.ndarray
    point: np.ndarray
    force: np.ndarray

    def __add__(self, other):
        return Contacts(np.concatenate([self.disc, other.disc]), np.vstack([self.point, other.point]),
                        np.vstack([self.force, other.force]))


def no_contacts():
    return Contacts(np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros((0, 2)))


def pair_contacts(xz, r, pairs, f_n, f_s, particle):
    """Contacts (L1) of the touching pairs (i, j) of vertices at xz (V, 2) with radii r (V,) [m]
    (discs, wall discs, a flat wall's feet of radius 0), normal force f_n (K,) [N, compression
    positive] and shear force f_s (K,) [N, along t of eq 3b], as the law applies them (eq 13: on i
    -f_n n - f_s t, n from i to j, t = (-n_z, n_x); j the opposite). The contact point lies in the
    middle of the overlap, r_i - delta/2 from i along n (delta = r_i + r_j - R). Each side whose
    vertex is a ``particle`` (V,) bool counts."""
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    i, j = pairs[:, 0], pairs[:, 1]
    d = xz[j] - xz[i]
    R = np.hypot(d[:, 0], d[:, 1])
    n = d / R[:, None]
    point = xz[i] + (0.5 * (r[i] - r[j] + R))[:, None] * n  # r_i - delta/2 along n
    f_n, f_s = np.asarray(f_n, float), np.asarray(f_s, float)
    on_i = -f_n[:, None] * n - f_s[:, None] * np.column_stack([-n[:, 1], n[:, 0]])
    si, sj = particle[i], particle[j]
    return Contacts(np.concatenate([i[si], j[sj]]), np.vstack([point[si], point[sj]]), np.vstack([on_i[si], -on_i[sj]]))


def tensor_terms(xz, contacts):
    """(M, 3) the terms -f ⊗ b of (L1) of each contact: xx, zz and the symmetric xz [N m per m]."""
    b = contacts.point - xz[contacts.disc]
    f = contacts.force
    return -np.column_stack([f[:, 0] * b[:, 0], f[:, 1] * b[:, 1], 0.5 * (f[:, 0] * b[:, 1] + f[:, 1] * b[:, 0])])


def region_stress(xz, contacts, x0, x1, bounds, areas):
    """(R, 3) sigma'_xx, sigma'_zz, sigma'_xz [Pa] of the regions x in [x0, x1], z in [z0, z1) of
    ``bounds`` [(z0, z1)] [m] (bottom first) with areas (R,) [m^2] (L1: the contacts whose point
    lies in each). The lowest region reaches down and the highest up: a contact with the bottom wall
    has its point half the overlap below the face, a heaving bed's top rises above its start."""
    terms = tensor_terms(xz, contacts)
    px, pz = contacts.point[:, 0], contacts.point[:, 1]
    z0 = np.array([z for z, _ in bounds], float)
    z1 = np.array([z for _, z in bounds], float)
    z0[0], z1[-1] = -np.inf, np.inf
    inside = ((px >= x0) & (px <= x1))[:, None] & (pz[:, None] >= z0) & (pz[:, None] < z1)  # (M, R)
    return (inside.T.astype(float) @ terms) / np.asarray(areas, float)[:, None]


def disc_stress(xz, r, contacts, porosity):
    """(N, 3) sigma'_xx, sigma'_zz, sigma'_xz [Pa] of each disc: (L1) over its contacts with
    A = pi r^2 / (1 - porosity) (zeros for a disc without contacts)."""
    terms = tensor_terms(xz, contacts)
    n = len(r)
    sums = np.column_stack([np.bincount(contacts.disc, terms[:, c], minlength=n) for c in range(3)])
    return sums * ((1.0 - porosity) / (np.pi * np.asarray(r, float) ** 2))[:, None]


def invariants(s):
    """(sigma'_v, sigma'_h, p', q) [Pa] of tensors s (..., 3) = (xx, zz, xz) (L2)."""
    s = np.asarray(s, float)
    xx, zz, xz = s[..., 0], s[..., 1], s[..., 2]
    return zz, xx, 0.5 * (xx + zz), np.hypot(0.5 * (zz - xx), xz)


def counted_bands(bounds, bed_top, mean_diameter):
    """The indices of the bands (bounds [(z0, z1)] [m], bottom first) whose top lies at least
    SURFACE_DIAMETERS mean diameters below the bed's top ``bed_top`` [m]."""
    return [k for k, (_, z1) in enumerate(bounds) if z1 <= bed_top - SURFACE_DIAMETERS * mean_diameter]


def bands(bottom, top, n):
    """[(z0, z1)] of n equal bands between the bed's bottom and top [m] (bottom first)."""
    if not (top > bottom and n >= 1):
        raise ValueError(f"bands: need top > bottom and n >= 1, got bottom {bottom}, top {top}, n {n}")
    z = np.linspace(bottom, top, n + 1)
    return [(float(a), float(b)) for a, b in zip(z[:-1], z[1:])]


def region_areas(x0, x1, bounds, top):
    """(R,) areas [m^2] of the regions [x0, x1] x [z0, min(z1, top)) (a pressure block reaching
    above the bed's top ``top`` [m] counts up to it)."""
    return np.array([(x1 - x0) * max(min(z1, top) - z0, 0.0) for z0, z1 in bounds])


def region_pressure(centroid_z, A, U, bounds):
    """(R,) the mean U [N/m] of the pores whose centroid z lies in each [z0, z1), weighted by their
    void areas A [m^2] (SPEC §2.8; nan where no pore)."""
    out = np.full(len(bounds), np.nan)
    for k, (z0, z1) in enumerate(bounds):
        sel = (centroid_z >= z0) & (centroid_z < z1)
        if sel.any() and A[sel].sum() > 0:
            out[k] = float(np.sum(A[sel] * U[sel]) / A[sel].sum())
    return out


def pore_pressure_ratio(U, sigma_v0):
    """r_u = U / (sigma'_v0 * 1 m) (L3): U [N/m], sigma'_v0 [Pa]; nan where sigma'_v0 <= 0."""
    U, sigma_v0 = np.asarray(U, float), np.asarray(sigma_v0, float)
    return np.where(sigma_v0 > 0, U / np.where(sigma_v0 > 0, sigma_v0, 1.0), np.nan)


def overburden(xz, r, unit_weight, x0, x1, bounds, samples=32):
    """(R,) the buoyant overburden [Pa] of each region (L4): at a depth z the unit weight [N/m^3]
    (rho g, or (rho - rho_w) g submerged) of each disc times its area above z, summed, over the
    width x1 - x0, averaged over ``samples`` heights of [z0, z1) (midpoints)."""
    xz, r = np.asarray(xz, float), np.asarray(r, float)
    w = np.broadcast_to(np.asarray(unit_weight, float), r.shape)
    lo, hi = (xz - r[:, None]).min(axis=0) - 1.0, (xz + r[:, None]).max(axis=0) + 1.0  # past every disc
    out = np.zeros(len(bounds))
    for k, (z0, z1) in enumerate(bounds):
        zs = z0 + (np.arange(samples) + 0.5) / samples * (z1 - z0)
        out[k] = np.mean([np.sum(w * disc_rectangle_area(xz, r, lo[0], hi[0], z, hi[1])) for z in zs]) / (x1 - x0)
    return out


def bed_bands(packing, faces, n):
    """(bands, areas (n,) [m^2]) of the bed of ``packing`` at the start: n equal bands from the
    bottom face (``faces``: {wall code: position [m]}, Start.faces; else Packing.bed_bottom) to the
    particles' top (Packing.bed_top), as wide as the box between the side faces (else the
    particles' extent)."""
    m = packing.mobile
    xz, r = packing.xz[m], packing.r[m]
    x0 = faces.get(WALL_LEFT, float(np.min(xz[:, 0] - r)))
    x1 = faces.get(WALL_RIGHT, float(np.max(xz[:, 0] + r)))
    bottom, top = faces.get(WALL_BOTTOM, packing.bed_bottom), packing.bed_top
    b = bands(bottom, top, n)
    return b, region_areas(x0, x1, b, top)
