"""Compiled twins of engines.model.pores.triangulation: the lifted points of the regular
triangulation's hull and its lower facets; the triangles' half-edges, shared by the other kernels of
the build. No YADE."""
import numba as nb
import numpy as np

jit = nb.njit(cache=True, nogil=True)


@jit
def lifted_points(xz, r, centre):
    """engines.model.pores.triangulation._lifted_points compiled (the same arithmetic), centre = xz.mean(axis=0)."""
    scale = max(xz[:, 0].max() - xz[:, 0].min(), xz[:, 1].max() - xz[:, 1].min())
    if not scale > 0:
        return None
    points = np.empty((len(r) + 1, 3))
    for i in range(len(r)):
        px, pz, q = (xz[i, 0] - centre[0]) / scale, (xz[i, 1] - centre[1]) / scale, r[i] / scale
        points[i, 0], points[i, 1], points[i, 2] = px, pz, px * px + pz * pz - q * q
    points[-1, 0], points[-1, 1], points[-1, 2] = 0.0, 0.0, points[:-1, 2].max() + 1.0
    return points


@jit
def lower_ccw(simplices, normal_lift, n, xz, tol):
    """Triangles (T, 3) of the hull facets whose normal's lift component is < -tol and whose corners
    are all discs (< n), counter-clockwise in xz."""
    keep = np.zeros(len(simplices), np.bool_)
    for f in range(len(simplices)):
        keep[f] = normal_lift[f] < -tol and simplices[f, 0] < n and simplices[f, 1] < n and simplices[f, 2] < n
    tri = np.empty((keep.sum(), 3), np.int64)
    t = 0
    for f in range(len(simplices)):
        if keep[f]:
            i, j, k = simplices[f, 0], simplices[f, 1], simplices[f, 2]
            if _signed_area(xz, i, j, k) < 0:
                j, k = k, j
            tri[t, 0], tri[t, 1], tri[t, 2] = i, j, k
            t += 1
    return tri


@jit
def _signed_area(xz, i, j, k):
    """Signed area of the triangle i, j, k; > 0 counter-clockwise."""
    return 0.5 * ((xz[j, 0] - xz[i, 0]) * (xz[k, 1] - xz[i, 1]) - (xz[j, 1] - xz[i, 1]) * (xz[k, 0] - xz[i, 0]))


@jit
def _half_edges(tri):
    """Origins a and ends b (3T,) of the triangles' half-edges h = 3 t + k (the edge opposite corner k)."""
    a = np.empty(3 * len(tri), np.int64)
    b = np.empty(3 * len(tri), np.int64)
    for t in range(len(tri)):
        for k in range(3):
            a[3 * t + k], b[3 * t + k] = tri[t, (k + 1) % 3], tri[t, (k + 2) % 3]
    return a, b


@jit
def _twin(a, b, ptr, order, h):
    """The half-edge b[h] -> a[h] (-1: none); ptr, order: the half-edges grouped by origin."""
    for s in range(ptr[b[h]], ptr[b[h] + 1]):
        if b[order[s]] == a[h]:
            return order[s]
    return -1
