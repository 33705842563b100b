"""The pore measure compiled (engines.model.pores.measure): polygon and sector areas, void area A
(eq 29) and the link states (contact: eq 43b) of every pore at the discs' positions, the links'
turns by ``turn`` (a series for small turns, else atan2); the range check of the areas
(engines.model.schedule.areas_in_range) and the flat walls' vertices
(engines.model.flat_walls.WallVertices). No YADE."""
import math
from collections import namedtuple

import numpy as np

from engines.compiled.kernels.common import _at, jit


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
def void_areas(xz, r, eps_m, links, link_pores, vec0, turn_weight, sector0):
    """The void areas (Np,) [m^2] of ``measure`` at xz of the LinkGeometry given by its arrays, its
    Measures made here: from Python, arrays spelled out take numba's fast argument check, where a
    tuple of arrays is typed in Python at every call (~50 us)."""
    n_p, n_l = len(sector0), len(links)
    out = Measures(np.empty(n_p), np.empty(n_p), np.empty(n_p), np.empty(n_l), np.empty(n_l, np.bool_),
                   np.empty((n_l, 2)), np.empty((n_p, 2)))
    measure(xz, r, eps_m, LinkGeometry(links, link_pores, vec0, turn_weight, sector0), out)
    return out.void


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
