"""The water-conserving transfer at re-meshing: the overlap areas of the pores of two networks
(triangles clipped against triangles). No YADE."""
import numpy as np
from scipy.spatial import cKDTree

from engines.model.pores.measure import vertex_positions
from engines.model.pores.triangulation import _signed_area


def _clip_areas(subj, clip):
    """Areas (K,) of the intersections of triangles subj (K, 3, 2) and clip (K, 3, 2), both
    counter-clockwise: Sutherland-Hodgman clipping of subj by the three edges of clip, vectorised
    over the pairs on padded vertex arrays."""
    poly, count = subj.copy(), np.full(len(subj), 3)
    for e in range(3):
        a, b = clip[:, e][:, None, :], clip[:, (e + 1) % 3][:, None, :]
        m = poly.shape[1]
        i = np.arange(m)[None, :]
        nxt = np.where(i + 1 < count[:, None], i + 1, 0)
        p_next = np.take_along_axis(poly, nxt[..., None], axis=1)

        def side(p):
            return (b[..., 0] - a[..., 0]) * (p[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (p[..., 0] - a[..., 0])

        s, s_next = side(poly), side(p_next)
        valid = i < count[:, None]
        keep = valid & (s >= 0)
        cross = valid & ((s >= 0) != (s_next >= 0))
        t = np.where(cross, s / np.where(cross, s - s_next, 1.0), 0.0)[..., None]
        cand = np.stack([poly, poly + t * (p_next - poly)], axis=2).reshape(len(poly), 2 * m, 2)
        mask = np.stack([keep, cross], axis=2).reshape(len(poly), 2 * m)
        order = np.argsort(~mask, axis=1, kind="stable")
        count = mask.sum(axis=1)
        width = max(int(count.max(initial=0)), 1)
        poly = np.take_along_axis(cand, order[:, :width, None], axis=1)
    i = np.arange(poly.shape[1])[None, :]
    nxt = np.take_along_axis(poly, np.where(i + 1 < count[:, None], i + 1, 0)[..., None], axis=1)
    cr = poly[..., 0] * nxt[..., 1] - nxt[..., 0] * poly[..., 1]
    return np.where(count >= 3, 0.5 * np.sum(np.where(i < count[:, None], cr, 0.0), axis=1), 0.0)


def pore_overlaps(old_net, new_net, xz):
    """Polygon overlap areas of the pores of two networks at positions xz (N, 2) [m].

    Returns (p_old, q_new, area [m^2]) for every overlapping pair. Each pore is a union of
    triangles: a triangle present in both networks (same three discs) overlaps only itself; the
    others are clipped against the nearby triangles of the other network (``_clip_areas``).
    Compiled twin: engines.compiled.pores.REMESH.pore_overlaps (the same pairs, the areas summed in
    another order). Both networks have the same flat walls, if any.
    """
    xz = vertex_positions(old_net, xz)
    n = len(xz)
    to, tn = old_net.tri, new_net.tri

    def keys(tri):
        s = np.sort(tri, axis=1)
        return (s[:, 0] * n + s[:, 1]) * n + s[:, 2]

    _, io, jn = np.intersect1d(keys(to), keys(tn), assume_unique=True, return_indices=True)
    same = np.abs(_signed_area(xz[to[io]]))
    ro = np.setdiff1d(np.arange(len(to)), io)
    rn = np.setdiff1d(np.arange(len(tn)), jn)
    p, q, area = [old_net.tri_pore[io]], [new_net.tri_pore[jn]], [same]
    if len(ro) and len(rn):
        P, Q = xz[to[ro]], xz[tn[rn]]
        P[_signed_area(P) < 0] = P[_signed_area(P) < 0][:, [0, 2, 1]]  # an old triangle turned over since its build
        cp, cq = P.mean(axis=1), Q.mean(axis=1)
        rp = np.max(np.hypot(*(P - cp[:, None]).transpose(2, 0, 1)), axis=1)
        rq = np.max(np.hypot(*(Q - cq[:, None]).transpose(2, 0, 1)), axis=1)
        near = cKDTree(cp).sparse_distance_matrix(cKDTree(cq), rp.max() + rq.max(), output_type="ndarray")
        near = near[near["v"] < rp[near["i"]] + rq[near["j"]]]
        a = _clip_areas(P[near["i"]], Q[near["j"]])
        p.append(old_net.tri_pore[ro[near["i"]]])
        q.append(new_net.tri_pore[rn[near["j"]]])
        area.append(a)
    p, q, area = np.concatenate(p), np.concatenate(q), np.concatenate(area)
    keep = area > 0
    key, inv = np.unique(p[keep] * max(new_net.n_pores, 1) + q[keep], return_inverse=True)
    return key // max(new_net.n_pores, 1), key % max(new_net.n_pores, 1), np.bincount(inv, area[keep])
