"""Compiled twin of engines.model.pores.overlaps: the overlap areas of the pores of two networks
(triangles clipped against triangles, Sutherland-Hodgman). No YADE."""
import numba as nb
import numpy as np

from engines.compiled.kernels import _grid, _groups, _grown
from engines.compiled.pores.triangulation import _signed_area

jit = nb.njit(cache=True, nogil=True)


@jit
def _clip_area(P, Q, poly, cut):
    """Area of the intersection of the counter-clockwise triangles P (3, 2) and Q (3, 2): P clipped
    by the three edges of Q (Sutherland-Hodgman, as engines.model.pores.overlaps._clip_areas); poly, cut (9, 2) scratch."""
    m = 3
    poly[:3] = P
    for e in range(3):
        ax, az = Q[e, 0], Q[e, 1]
        bx, bz = Q[(e + 1) % 3, 0], Q[(e + 1) % 3, 1]
        c = 0
        for i in range(m):
            nx_, nz_ = poly[(i + 1) % m, 0], poly[(i + 1) % m, 1]
            s = (bx - ax) * (poly[i, 1] - az) - (bz - az) * (poly[i, 0] - ax)
            s_next = (bx - ax) * (nz_ - az) - (bz - az) * (nx_ - ax)
            if s >= 0:
                cut[c] = poly[i]
                c += 1
            if (s >= 0) != (s_next >= 0):
                t = s / (s - s_next)
                cut[c, 0] = poly[i, 0] + t * (nx_ - poly[i, 0])
                cut[c, 1] = poly[i, 1] + t * (nz_ - poly[i, 1])
                c += 1
        m = c
        poly[:m] = cut[:m]
    if m < 3:
        return 0.0
    area = 0.0
    for i in range(m):
        area += poly[i, 0] * poly[(i + 1) % m, 1] - poly[(i + 1) % m, 0] * poly[i, 1]
    return 0.5 * area


@jit
def _corners(xz, t):
    """Corner coordinates (3, 2) of the triangle t (3,) of discs."""
    out = np.empty((3, 2))
    for k in range(3):
        out[k, 0], out[k, 1] = xz[t[k], 0], xz[t[k], 1]
    return out


@jit
def _bounding_circle(c):
    """Centroid (x, z) of the corners c (3, 2) and the largest distance from it to a corner."""
    cx, cz = (c[0, 0] + c[1, 0] + c[2, 0]) / 3, (c[0, 1] + c[1, 1] + c[2, 1]) / 3
    rad = 0.0
    for k in range(3):
        rad = max(rad, np.hypot(c[k, 0] - cx, c[k, 1] - cz))
    return cx, cz, rad


@jit
def pore_overlaps(to, tp_old, tn, tp_new, xz, n_new):
    """engines.model.pores.pore_overlaps compiled: (p_old, q_new, area) of the triangles (to, tn) in pores
    (tp_old, tp_new) at xz, summed per pore pair, sorted by (p, q). A triangle of the same three discs
    in both overlaps only itself; the others are clipped against the triangles of the other network
    whose bounding circle (about the centroid) they cross."""
    match_o, match_n = _same_triangles(to, tn, len(xz))
    ro, rn = np.flatnonzero(match_o < 0), np.flatnonzero(match_n < 0)
    n_pairs = len(to) - len(ro)
    cap = n_pairs + 16 * (len(ro) + len(rn)) + 16
    p, q, area = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
    m = 0
    for t in range(len(to)):  # a triangle in both: its own area
        if match_o[t] >= 0:
            p[m], q[m] = tp_old[t], tp_new[match_o[t]]
            area[m] = abs(_signed_area(xz, to[t, 0], to[t, 1], to[t, 2]))
            m += 1
    if len(ro) and len(rn):
        P, cp = _placed(xz, to, ro, True)  # an old triangle turned over since its build: counter-clockwise again
        Q, cq = _placed(xz, tn, rn, False)
        p, q, area, m = _clipped(P, cp, Q, cq, tp_old[ro], tp_new[rn], p, q, area, m)
    return _summed_by_pair(p, q, area, m, n_new)


@jit
def _same_triangles(to, tn, n):
    """match_o (len(to),): the triangle of tn with the same three of the n vertices as each of
    ``to`` (-1: none), and match_n (len(tn),) the other way round."""
    lo_n = np.empty(len(tn), np.int64)
    for t in range(len(tn)):
        lo_n[t] = min(tn[t, 0], tn[t, 1], tn[t, 2])
    ptr, by_lo = _groups(lo_n, n)
    match_n = np.full(len(tn), -1, np.int64)
    match_o = np.full(len(to), -1, np.int64)
    for t in range(len(to)):
        a, b, c = to[t, 0], to[t, 1], to[t, 2]
        for s in range(ptr[min(a, b, c)], ptr[min(a, b, c) + 1]):
            u = by_lo[s]
            x, y, z = tn[u, 0], tn[u, 1], tn[u, 2]
            if (a == x or a == y or a == z) and (b == x or b == y or b == z) and (c == x or c == y or c == z):
                match_o[t], match_n[u] = u, t
    return match_o, match_n


@jit
def _placed(xz, tri, rest, upright):
    """The corners (K, 3, 2) at xz of the triangles tri[rest] (counter-clockwise when ``upright``)
    and their bounding circles (K, 3): centroid x, z and radius."""
    P = np.empty((len(rest), 3, 2))
    c = np.empty((len(rest), 3))
    for s in range(len(rest)):
        P[s] = _corners(xz, tri[rest[s]])
        if upright and _signed_area(xz, tri[rest[s], 0], tri[rest[s], 1], tri[rest[s], 2]) < 0:
            P[s, 1], P[s, 2] = _corners(xz, tri[rest[s]])[2], _corners(xz, tri[rest[s]])[1]
        c[s, 0], c[s, 1], c[s, 2] = _bounding_circle(P[s])
    return P, c


@jit
def _clipped(P, cp, Q, cq, pore_p, pore_q, p, q, area, m):
    """Append to (p, q, area)[:m] the pores (pore_p, pore_q) and overlap area of every pair of
    triangles P, Q whose bounding circles cp, cq cross (found on a grid of cells); returns the
    arrays (grown when full) and the new count."""
    x0, z0, cell, nx, nz, start, in_cell = _grid(cq[:, 0], cq[:, 1], cp[:, 2].max() + cq[:, 2].max())
    poly, cut = np.empty((9, 2)), np.empty((9, 2))
    for s in range(len(P)):
        ix = int(np.floor((cp[s, 0] - x0) / cell))
        iz = int(np.floor((cp[s, 1] - z0) / cell))
        for hx in range(max(ix - 1, 0), min(ix + 2, nx)):
            for hz in range(max(iz - 1, 0), min(iz + 2, nz)):
                g = hx * nz + hz
                for e in range(start[g], start[g + 1]):
                    u = in_cell[e]
                    if np.hypot(cp[s, 0] - cq[u, 0], cp[s, 1] - cq[u, 1]) < cp[s, 2] + cq[u, 2]:
                        a_ = _clip_area(P[s], Q[u], poly, cut)
                        if m == len(area):
                            p, q, area = _grown(p, m), _grown(q, m), _grown(area, m)
                        p[m], q[m], area[m] = pore_p[s], pore_q[u], a_
                        m += 1
    return p, q, area, m


@jit
def _summed_by_pair(p, q, area, m, n_new):
    """The positive areas of (p, q, area)[:m] summed per pore pair, sorted by (p, q): (p, q, area)."""
    keep = np.flatnonzero(area[:m] > 0)
    key = p[keep] * max(n_new, 1) + q[keep]
    order = np.argsort(key, kind="mergesort")
    out_p, out_q, out_a = np.empty(len(keep), np.int64), np.empty(len(keep), np.int64), np.empty(len(keep))
    k = -1
    for s in range(len(order)):
        e = order[s]
        if s == 0 or key[e] != key[order[s - 1]]:
            k += 1
            out_p[k], out_q[k], out_a[k] = p[keep[e]], q[keep[e]], 0.0
        out_a[k] += area[keep[e]]
    return out_p[:k + 1].copy(), out_q[:k + 1].copy(), out_a[:k + 1].copy()
