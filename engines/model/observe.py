"""Observables of a run: the porosity of a fixed window of the box (Fig. 40, 41, 46), block means.

The porosity reported for the seismic cases is the void fraction of a fixed rectangle, not of the
pore mesh (whose area jumps when the mesh is rebuilt):

    n = 1 - sum_i |disc_i ∩ window| / |window|

over the particles (wall discs excluded), with each disc-rectangle area in closed form
(``disc_rectangle_area``). Overlapping discs are counted twice, as the pore areas of eq 29 neglect
overlaps. The window (``box_window``) spans x between the inner faces of the side walls and z from
the top of the bottom wall (``Packing.inner_faces``, or the faces of the flat walls) up to a stated
fraction of the initial bed height (the scene's ``output.porosity_window``, [0, 0.8] by default: it
stops about two grain diameters below the initial surface, so the loose top grains do not count). In a shaken box the
window moves with the base: ``Window.shifted(base displacement)``.
"""
from dataclasses import dataclass

import numpy as np

from engines.model.pores import WALL_BOTTOM, WALL_LEFT, WALL_RIGHT


def _clip(x, lo, hi):
    """np.clip(x, lo, hi) (lo <= hi), the same values without np.clip's checks (about 8 µs a call,
    most of a history row's porosity)."""
    return np.minimum(np.maximum(x, lo), hi)


def _chord_primitive(x, r):
    """G(x) = integral from -r to x of sqrt(r^2 - s^2) ds for x clipped to [-r, r]."""
    x = _clip(x, -r, r)
    return 0.5 * (x * np.sqrt(np.maximum(r * r - x * x, 0.0)) + r * r * np.arcsin(_clip(x / r, -1.0, 1.0))) \
        + 0.25 * np.pi * r * r


def quadrant_area(X, Z, r):
    """Area of the disc of radius r centred at the origin that lies in {x < X, z < Z}.

    Integrated over x: where the chord height h = sqrt(r^2 - x^2) exceeds |Z| (|x| < w =
    sqrt(r^2 - Z^2)) the disc below Z is the strip Z + h; elsewhere it is the whole chord 2h when
    Z >= 0 and nothing when Z < 0.
    """
    X, Z, r = np.broadcast_arrays(np.asarray(X, float), np.asarray(Z, float), np.asarray(r, float))
    w = np.sqrt(np.maximum(r * r - Z * Z, 0.0))
    b1, b2, b3 = _clip(X, -r, -w), _clip(X, -w, w), _clip(X, w, r)
    G = _chord_primitive
    strip = G(b2, r) - G(-w, r) + Z * (b2 + w)
    whole = 2 * (G(b1, r) - G(-r, r)) + 2 * (G(b3, r) - G(w, r))
    return np.where(Z >= 0, strip + whole, strip)


def disc_rectangle_area(xz, r, x0, x1, z0, z1):
    """Area (N,) [m^2] of each disc (centres xz (N, 2), radii r (N,) [m]) inside [x0, x1] x [z0, z1]."""
    xz, r = np.asarray(xz, float), np.asarray(r, float)
    dx0, dx1 = x0 - xz[:, 0], x1 - xz[:, 0]
    dz0, dz1 = z0 - xz[:, 1], z1 - xz[:, 1]
    Q = quadrant_area
    return Q(dx1, dz1, r) - Q(dx0, dz1, r) - Q(dx1, dz0, r) + Q(dx0, dz0, r)


@dataclass(frozen=True)
class Window:
    """A rectangle [x0, x1] x [z0, z1] [m]."""

    x0: float
    x1: float
    z0: float
    z1: float

    def __post_init__(self):
        if not (self.x0 < self.x1 and self.z0 < self.z1):
            raise ValueError(f"window: need x0 < x1 and z0 < z1, got {self}")

    @property
    def area(self):
        return (self.x1 - self.x0) * (self.z1 - self.z0)

    def shifted(self, dx):
        """The same window moved by dx [m] along x (with the base of a shaken box)."""
        return Window(self.x0 + dx, self.x1 + dx, self.z0, self.z1)


def box_window(packing, z_fractions, faces=None):
    """The porosity window of a box packing: x between the inner faces of the side walls, z from
    the bottom wall's face to bottom + f * (bed_top - bottom) for ``z_fractions`` = [f0, f1] of the
    initial bed height. ``faces``: {wall code: position [m]} of the box's walls (default: the wall
    discs' inner faces, Packing.inner_faces; without a bottom wall: Packing.bed_bottom)."""
    faces = packing.inner_faces() if faces is None else faces
    if not (WALL_LEFT in faces and WALL_RIGHT in faces):
        raise ValueError("porosity window: the packing has no left and right wall columns")
    bottom = faces.get(WALL_BOTTOM, packing.bed_bottom)
    h = packing.bed_top - bottom
    f0, f1 = z_fractions
    return Window(faces[WALL_LEFT], faces[WALL_RIGHT], bottom + f0 * h, bottom + f1 * h)


def porosity(xz, r, window):
    """Void fraction of ``window`` around the discs xz (N, 2), r (N,) [m] (pass the particles only)."""
    return 1.0 - float(np.sum(disc_rectangle_area(xz, r, window.x0, window.x1, window.z0, window.z1))) / window.area


def block_means(centroid_z, U, bounds):
    """Mean U of the pores whose centroid z lies in each [z0, z1) of ``bounds`` (nan if none)."""
    out = []
    for z0, z1 in bounds:
        sel = (centroid_z >= z0) & (centroid_z < z1)
        out.append(float(np.mean(U[sel])) if sel.any() else np.nan)
    return np.array(out)
