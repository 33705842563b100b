"""The regular (power) triangulation of the discs: the lower convex hull of the lifted points, its
triangles counter-clockwise in a canonical order, their neighbours, and point location. No YADE."""
import numpy as np


def _signed_area(p):
    """Signed areas (T,) of triangles with corner coordinates p (T, 3, 2); > 0 counter-clockwise."""
    return 0.5 * ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))


def _ccw(xz, tri):
    """Triangles (T, 3) reordered counter-clockwise."""
    tri = np.array(tri, dtype=np.int64)
    cw = _signed_area(xz[tri]) < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]
    return tri


LOWER_FACET_TOL = 1e-12  # a hull facet is lower when its unit normal's lift component is below -this


def _lower_triangles(hull, n, xz):
    """The counter-clockwise triangles (T, 3) of the lower facets of regular_triangulation's hull
    of n discs at xz (``canonical_triangles``), or None."""
    lower = (hull.equations[:, 2] < -LOWER_FACET_TOL) & (hull.simplices < n).all(axis=1)
    return canonical_triangles(_ccw(xz, hull.simplices[lower])) if lower.any() else None


def canonical_triangles(tri):
    """Triangles (T, 3), each from its smallest vertex (the cyclic order kept), in lexicographic
    order: the same array for the same triangles, whatever order a triangulation found them in."""
    k = np.argmin(tri, axis=1)
    out = np.take_along_axis(tri, (k[:, None] + np.arange(3)) % 3, axis=1)
    return out[np.lexsort(out.T[::-1])]


def _lifted_points(xz, r):
    """The points of regular_triangulation's hull (N + 1, 3), or None when the centres coincide."""
    scale = float(np.ptp(xz, axis=0).max())
    if not scale > 0:
        return None
    p = (xz - xz.mean(axis=0)) / scale
    lift = np.einsum("ij,ij->i", p, p) - (r / scale) ** 2
    return np.vstack([np.column_stack([p, lift]), [0.0, 0.0, lift.max() + 1.0]])


def _neighbours(tri):
    """nb (T, 3): the triangle across the edge opposite corner k of each triangle (-1: none)."""
    n = int(tri.max()) + 1
    a, b = tri[:, [1, 2, 0]].ravel(), tri[:, [2, 0, 1]].ravel()
    key, rev = a * n + b, b * n + a
    order = np.argsort(key)
    pos = np.minimum(np.searchsorted(key[order], rev), len(key) - 1)
    return np.where(key[order[pos]] == rev, order[pos] // 3, -1).reshape(tri.shape)


def _locate(xz, tri, points):
    """Index of a triangle containing each point (M, 2), -1 where none (brute force, for few points)."""
    a, b, c = (xz[tri[:, k]][None] for k in range(3))
    q = points[:, None, :]

    def side(u, v):
        return (v[..., 0] - u[..., 0]) * (q[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (q[..., 0] - u[..., 0])

    inside = (side(a, b) >= 0) & (side(b, c) >= 0) & (side(c, a) >= 0)
    return np.where(inside.any(axis=1), inside.argmax(axis=1), -1)
