"""The links of eq 28: the eq 28 pairs, and the edge flips that make every eq 28 pair that crosses no
link an edge of the triangulation (the pairs a Delaunay or regular triangulation can hide). No YADE."""
from collections import deque

import numpy as np
from scipy.spatial import cKDTree


def eq28_pairs(xz, r, reach):
    """All disc pairs (P, 2), i < j, with r_i + r_j + reach >= R_ij (eq 28 with reach = eps_m + l_m)."""
    if len(r) < 2:
        return np.zeros((0, 2), np.int64)
    pairs = cKDTree(xz).query_pairs(2 * float(r.max()) + reach, output_type="ndarray").astype(np.int64)
    d = xz[pairs[:, 1]] - xz[pairs[:, 0]]
    return pairs[r[pairs[:, 0]] + r[pairs[:, 1]] + reach >= np.hypot(d[:, 0], d[:, 1])]


def _orient(a, b, c):
    """Twice the signed area of the triangle a, b, c (points as (x, z) tuples); > 0 counter-clockwise."""
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


class _FlipTriangulation:
    """A triangulation edited by edge flips. ``third[(a, b)]`` is the third vertex c of the
    counter-clockwise triangle (a, b, c) on the left of the directed edge a -> b; ``star[v]`` the
    vertices joined to v by an edge."""

    def __init__(self, xz, tri):
        self.p = list(map(tuple, xz.tolist()))
        u, v, w = tri.ravel(), tri[:, [1, 2, 0]].ravel(), tri[:, [2, 0, 1]].ravel()
        self.third = dict(zip(zip(u.tolist(), v.tolist()), w.tolist()))
        order = np.argsort(u, kind="stable")
        self._u, self._v = u[order], v[order]
        self.star = {}  # filled on demand from the initial edges, then kept up to date by the flips

    def _star(self, k):
        if k not in self.star:
            lo, hi = np.searchsorted(self._u, [k, k + 1])
            self.star[k] = set(self._v[lo:hi].tolist())
        return self.star[k]

    def triangles(self):
        """The triangles (T, 3) counter-clockwise, each listed once."""
        ab = np.array(list(self.third), np.int64)
        c = np.fromiter(self.third.values(), np.int64, len(self.third))
        first = (ab[:, 0] < ab[:, 1]) & (ab[:, 0] < c)
        return np.column_stack([ab[first], c[first]])

    def crossed_edges(self, k, l):
        """Edges (right, left) crossed by the segment k -> l in order, or None if it runs
        through another vertex."""
        p, o = self.p, _orient
        for a in self._star(k):  # the star holds the edges k -> a with a triangle (k, a, b) on their left
            b = self.third[(k, a)]
            if o(p[k], p[a], p[l]) > 0 and o(p[k], p[b], p[l]) < 0:  # a right of k -> l, b left
                break
        else:
            return None  # no triangle at k straddles the segment: it runs through a neighbour of k
        right, left, edges = a, b, []
        while True:
            edges.append((right, left))
            c = self.third.get((left, right))
            if c is None:
                return None
            if c == l:
                return edges
            side = o(p[k], p[l], p[c])
            if side == 0:
                return None
            if side > 0:
                left = c
            else:
                right = c

    def insert(self, k, l, edges):
        """Flip the crossed ``edges`` until k - l is an edge (Sloan 1993: a crossed edge whose
        quadrilateral is not convex waits its turn; some crossed edge is always flippable)."""
        p, o = self.p, _orient
        queue = deque(edges)
        budget = 100 + 10 * len(edges) ** 2
        while queue:
            budget -= 1
            if budget < 0:
                raise RuntimeError(f"edge insertion of link {k}-{l} did not converge")
            u, v = queue.popleft()
            c, d = self.third[(u, v)], self.third[(v, u)]
            if not (o(p[u], p[d], p[c]) > 0 and o(p[d], p[v], p[c]) > 0):
                queue.append((u, v))  # quadrilateral u, d, v, c not strictly convex: later
                continue
            self._flip(u, v, c, d)
            if {c, d} != {k, l} and o(p[k], p[l], p[c]) * o(p[k], p[l], p[d]) < 0 \
                    and o(p[c], p[d], p[k]) * o(p[c], p[d], p[l]) < 0:
                queue.append((c, d))

    def _flip(self, u, v, c, d):
        """Triangles (u, v, c), (v, u, d) -> (u, d, c), (d, v, c)."""
        t = self.third
        del t[(u, v)], t[(v, u)]
        t[(u, d)], t[(d, c)], t[(c, u)] = c, u, d
        t[(d, v)], t[(v, c)], t[(c, d)] = c, d, v
        self._star(u).discard(v)
        self._star(v).discard(u)
        self._star(c).add(d)
        self._star(d).add(c)


def _missing_pairs(xz, r, reach, tri, wall_vertices=None):
    """The eq 28 pairs (M, 2), i < j, of triangulation vertices that are no edge of ``tri``; with
    ``wall_vertices``, the links disc - foot too (flat_walls.WallVertices.is_link)."""
    n = len(r)
    if wall_vertices is None:
        pairs = eq28_pairs(xz, r, reach)
    else:
        d = wall_vertices.n
        pairs = np.concatenate([eq28_pairs(xz[:d], r[:d], reach), wall_vertices.disc_feet(np.unique(tri))])
    is_vertex = np.zeros(n, bool)
    is_vertex[tri.ravel()] = True
    edge_keys = np.unique(np.sort(tri[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1) @ np.array([n, 1]))
    return pairs[~np.isin(pairs @ np.array([n, 1]), edge_keys) & is_vertex[pairs].all(axis=1)]
