"""Pore polygons between discs (seed 000 §3.1, SPEC §2.2). Pure NumPy/SciPy, no YADE.

Vocabulary (per unit thickness, SI): discs have centres ``xz`` (N, 2) [m] and radii ``r`` (N,) [m].

* A *link* joins two discs i, j when r_i + r_j + eps_m + l_m >= R_ij (eq 28). Candidates are the
  edges of a triangulation of the centres, so links never cross and the link graph is planar.
  The triangulation is the regular (radius-weighted, power) triangulation: the lower convex hull
  of the lifted points (x, z, x^2 + z^2 - r^2), its triangles in a canonical order
  (``canonical_triangles``), so that networks are numbered alike however it was found. Where one
  of its edges that is not a link hides an eq 28 pair (the other diagonal of a quadrilateral,
  which a Delaunay or regular triangulation can leave out at a long l_m), that pair is put in by
  edge flips (``insert_missing_links``), so that *every eq 28 pair that crosses no link is a
  link*; of two such pairs that cross each other, the one with the smaller gap R - r_i - r_j is
  put in first.
* A *pore* is a bounded face of the link graph. It is stored as the set of triangles that lie in
  it (triangles joined across non-link edges). The unbounded outer face is not a pore.
* Void area A = polygon area - sum of the disc sectors theta * r^2 / 2 inside it (eq 29); overlaps
  are neglected, as in the paper. The pore's boundary is walked as in the paper (turn clockwise at
  each disc) at the build, which gives each corner its interior angle theta0; a rattler inside a
  pore (a disc without links) is subtracted whole. Each step, both areas are sums over the pore's
  boundary links (``measure``): the polygon area the shoelace sum, and the sectors their build-time
  area plus the links' turns since the build, each corner's angle having changed by the
  difference of its two links' turns (eq 29 telescoped over links, as eq 33 is). The tests check
  these areas against the pore's triangles.
* The pressure force of eq 33 on the arc of a disc inside a pore, summed over the pores around the
  disc, telescopes to a sum over the disc's links of (U_right - U_left) * r * perp(u_link):
  a uniform pressure gives exactly zero net force.
* Flat walls (engines.model.flat_walls, SPEC §2.6) add zero-radius vertices on the faces: the feet of
  the discs linked to a wall and the corners of two walls. The link arrays index these vertices
  after the N discs (``vertex_positions``); the pores' vertex sets count each wall as one vertex.

Every step of a build but qhull (``BuildSteps``), and of the re-meshing in engines.model.pore_water, has
a compiled twin in engines.compiled.pores (``steps=engines.compiled.pores.BUILD``, what the water engine
uses), tested to give the same network.

Degenerate pores: a face whose void area is <= ``a_min`` when the pores are built is *closed*: it is
not a pore (no water, U = 0). ``a_min = degenerate_fraction * mean(pi r^2)``.
Fewer than three discs or collinear centres give a network with no pores. A disc whose power cell
is empty (a small disc deep inside a larger one) is not a vertex of the regular triangulation: it
gets no links and counts as a rattler of the pore that contains its centre.
"""
from collections import deque
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree

from engines.model import flat_walls as fw
from engines.model.groups import LAST_GROUP, WALL_BOTTOM, WALL_CODES, WALL_LEFT, WALL_NAMES, WALL_NONE, WALL_RIGHT  # noqa: F401

OUTER = -1  # pore label of the outer face (and of closed faces) in link_pores
FLAT_VERTEX = LAST_GROUP + 1  # the wall code of a flat wall's vertex: a link between two is a wall edge


def check_finite_array(name, a, shape=None):
    """Return ``a`` as float64, raising ValueError naming ``name`` on bad shape or NaN/inf."""
    a = np.asarray(a, dtype=float)
    if shape is not None and (a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape))):
        raise ValueError(f"{name}: expected shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.flatnonzero(~np.isfinite(a.ravel()))[0]
        raise ValueError(f"{name}: non-finite value {a.ravel()[bad]} at flat index {bad}")
    return a


def check_nonnegative(name, value):
    """Raise ValueError naming ``name`` unless ``value`` is a finite number >= 0."""
    if not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be finite and >= 0, got {value}")


LINK_RANGE = (0.01, 2.0)  # the accepted l_m, in median radii: below, a few pores; above, links across grains


def check_lengths(l_m, eps_m, r, names=("l_m", "eps_m")):
    """Refuse a link range l_m [m] outside LINK_RANGE x the median radius of r (N,) [m] (lengths
    typed in another unit: l_m = 2.3e-4 radii builds two pores), or a contact range eps_m [m]
    above l_m; ``names``: how the caller calls them."""
    r_med = float(np.median(r))
    lo, hi = LINK_RANGE
    if not lo * r_med <= l_m <= hi * r_med:
        raise ValueError(f"{names[0]} = {l_m:.3g} m is {l_m / r_med:.3g} x the median disc radius {r_med:.3g} m, "
                         f"outside {lo:g}-{hi:g} x it: the link range beyond touching (eq 28) is a fraction of a "
                         f"grain; check the units of the radii and of {names[0]} (both in m)")
    if eps_m > l_m:
        raise ValueError(f"{names[1]} = {eps_m:.3g} m exceeds {names[0]} = {l_m:.3g} m: the contact range (eq 43b) "
                         f"lies within the link range (eq 28); reduce {names[1]} or raise {names[0]}")


def check_discs(xz, r):
    """Validate disc centres (N, 2) [m] and radii (N,) [m] > 0; return float arrays."""
    xz = check_finite_array("xz", xz, (None, 2))
    r = check_finite_array("r", r, (xz.shape[0],))
    if np.any(r <= 0):
        i = int(np.flatnonzero(r <= 0)[0])
        raise ValueError(f"r must be > 0, got r[{i}] = {r[i]}")
    return xz, r


# PoreNetwork's arrays as a checkpoint holds them: (shape by size, lowest index, the size indices are
# below, or None for values): P pores, L links, H = 2 L half-edges, T throats, K corners, R triangles,
# S vertex-set entries, V vertices (discs, then flat walls' feet and corners), W flat walls
CHECKPOINT_SHAPES = {
    "tri": (("R", 3), 0, "V"), "tri_pore": (("R",), 0, "P"), "links": (("L", 2), 0, "V"),
    "link_pores": (("L", 2), -1, "P"), "throat_conns": (("T", 2), 0, "P"), "throat_link": (("T",), 0, "L"),
    "pore_surface": (("P",), None, None), "pore_vertex_ptr": (("P+1",), 0, "S"),
    "pore_vertex_idx": (("S",), 0, "V"), "pore_signature": (("P",), None, None),
    "he_org": (("H",), 0, "V"), "he_dst": (("H",), 0, "V"), "he_left": (("H",), -1, "P"),
    "he_next": (("H",), -1, "H"), "corner_pore": (("K",), 0, "P"), "corner_disc": (("K",), 0, "V"),
    "corner_link": (("K",), 0, "L"), "corner_next_link": (("K",), 0, "L"), "corner_sign": (("K",), None, None),
    "corner_r2": (("K",), None, None), "corner_theta0": (("K",), None, None), "rattler_area": (("P",), None, None),
    "link_vec0": (("L", 2), None, None), "sector_area0": (("P",), None, None),
    "link_turn_weight": (("L",), None, None), "pore_walls": (("W", "P"), None, None),
}


@dataclass
class PoreNetwork:
    """Topology of the pores; fixed between rebuilds (positions move, the graph does not).

    Attributes (N discs, L links, Np pores, Nt throats, K pore corners, W flat walls):
      n_discs, n_pores
      wall_vertices  the flat_walls.WallVertices of the flat walls (None: none); with them the
                     disc indices of tri, links, he_* and corner_disc run over its vertices
      pore_walls     (W, Np) bool: the pore has flat wall w as a vertex
      tri, tri_pore  triangles inside pores (counter-clockwise at build) and their pore
      links          (L, 2) linked disc pairs (eq 28), i < j
      link_pores     (L, 2) pore on the left and on the right of i->j (OUTER = outer face or closed)
      throat_conns   (Nt, 2) pore pairs sharing a link (eq 38-41), throat_link (Nt,) its link
      pore_surface   (Np,) bool: the pore has a non-wall edge on the outer face (free surface)
      pore_touches   dict wall name -> (Np,) bool: the pore has a disc of that wall as a vertex
      pore_vertex_ptr, pore_vertex_idx   the vertex set of each pore (rattlers included) in CSR
                     form: sorted discs of pore p are idx[ptr[p]:ptr[p + 1]]; flat wall w is N + w
      pore_signature (Np,) uint64 hash of each vertex set (equal sets, equal signatures)
      he_org, he_dst, he_left, he_next   half-edges of the links: h < L runs i->j of link h,
                     h >= L runs j->i of link h - L; he_left is the pore on its left; he_next the
                     next half-edge of that pore's boundary (the paper's clockwise turn)
      corner_*       per boundary half-edge h of a pore (K of them): the pore, the disc dst(h) at
                     the corner, the links of h and next(h), the shoelace sign, r^2 of the disc,
                     and the build-time angle (eq 29)
      link_vec0      (L, 2) the link vectors x_j - x_i at the build [m]: ``measure`` turns the
                     corner angles by the links' turns since
      rattler_area   (Np,) area of the unlinked discs inside each pore [m^2]
      sector_area0   (Np,) the pore's sector area at the build, its rattlers whole [m^2] (eq 29)
      link_turn_weight  (L,) (r_j^2 - r_i^2) / 2 [m^2]: the sector area the pore on the left of
                     i->j gains, and the pore on its right loses, per radian the link turns
                     (``measure``)
      a_min          area below which a face is closed [m^2]; n_closed faces closed at build
      n_inserted     eq 28 pairs the regular triangulation hid, put in by edge flips at build
    """

    # what a checkpoint stores (engines.model.state): every field but wall_vertices; the arrays are per
    # pore, link, throat, triangle or corner, so of any length (checked by checkpoint_restored)
    CHECKPOINT_FIELDS = ("n_discs", "tri", "tri_pore", "links", "link_pores", "throat_conns", "throat_link",
                         "pore_surface", "pore_touches", "pore_vertex_ptr", "pore_vertex_idx", "pore_signature",
                         "he_org", "he_dst", "he_left", "he_next", "corner_pore", "corner_disc", "corner_link",
                         "corner_next_link", "corner_sign", "corner_r2", "corner_theta0", "rattler_area", "link_vec0",
                         "sector_area0", "link_turn_weight", "a_min", "n_closed", "eps_m", "l_m", "n_inserted",
                         "pore_walls")
    CHECKPOINT_RESIZED = CHECKPOINT_FIELDS
    CHECKPOINT_DERIVED = {"wall_vertices": "the water model's WallVertices (WaterModel.wall_vertices), shared"}

    n_discs: int
    tri: np.ndarray
    tri_pore: np.ndarray
    links: np.ndarray
    link_pores: np.ndarray
    throat_conns: np.ndarray
    throat_link: np.ndarray
    pore_surface: np.ndarray
    pore_touches: dict
    pore_vertex_ptr: np.ndarray
    pore_vertex_idx: np.ndarray
    pore_signature: np.ndarray
    he_org: np.ndarray
    he_dst: np.ndarray
    he_left: np.ndarray
    he_next: np.ndarray
    corner_pore: np.ndarray
    corner_disc: np.ndarray
    corner_link: np.ndarray
    corner_next_link: np.ndarray
    corner_sign: np.ndarray
    corner_r2: np.ndarray
    corner_theta0: np.ndarray
    rattler_area: np.ndarray
    link_vec0: np.ndarray
    sector_area0: np.ndarray
    link_turn_weight: np.ndarray
    a_min: float
    n_closed: int = 0
    eps_m: float = 0.0
    l_m: float = 0.0
    n_inserted: int = 0
    wall_vertices: fw.WallVertices = None
    pore_walls: np.ndarray = None

    @property
    def n_pores(self):
        return len(self.pore_surface)

    @property
    def flat_walls(self):
        """The FlatWall tuple of the network (empty: none)."""
        return () if self.wall_vertices is None else self.wall_vertices.walls

    def flat_wall_pores(self, boundary):
        """(Np,) bool: the pore has a flat wall of that boundary ("drained", "inflow", ...) as a vertex."""
        on = [w for w, wall in enumerate(self.flat_walls) if wall.boundary == boundary]
        return self.pore_walls[on].any(axis=0) if on else np.zeros(self.n_pores, bool)

    def checkpoint_restored(self):
        """Refuse a stored network whose arrays do not fit together: the shapes of CHECKPOINT_SHAPES
        and the indices within the ranges they index (a kernel does not check them)."""
        P, L, T, K = len(self.pore_surface), len(self.links), len(self.throat_conns), len(self.corner_pore)
        sizes = {"P": P, "P+1": P + 1, "L": L, "H": 2 * L, "T": T, "K": K, "R": len(self.tri),
                 "S": len(self.pore_vertex_idx), "W": len(self.flat_walls), 2: 2, 3: 3,
                 "V": self.n_discs if self.wall_vertices is None else self.wall_vertices.n_vertices}
        for name, (shape, lo, hi) in CHECKPOINT_SHAPES.items():
            a = getattr(self, name)
            if a is None and self.wall_vertices is None:  # pore_walls without flat walls
                continue
            want = tuple(sizes[d] for d in shape)
            if a.shape != want:
                raise ValueError(f"pore network: {name} has shape {a.shape}, expected {want}")
            top = sizes[hi] + (name == "pore_vertex_ptr") if hi else None  # the pointers run to S inclusive
            if lo is not None and a.size and (a.min() < lo or a.max() >= top):
                raise ValueError(f"pore network: {name} holds indices outside [{lo}, {top})")
        for k, a in self.pore_touches.items():
            if a.shape != (P,):
                raise ValueError(f"pore network: pore_touches[{k!r}] has shape {a.shape}, expected {(P,)}")
        if P and (np.any(np.diff(self.pore_vertex_ptr) < 0) or self.pore_vertex_ptr[-1] != len(self.pore_vertex_idx)):
            raise ValueError("pore network: pore_vertex_ptr is not the start of each pore's vertices")

    def vertices_of(self, p):
        """Sorted disc indices of the vertex set of pore p."""
        return self.pore_vertex_idx[self.pore_vertex_ptr[p]:self.pore_vertex_ptr[p + 1]]


@dataclass
class PoreMeasures:
    """Per-step geometry of the pores at the current positions.

    polygon_area (Np,) [m^2], sector_area (Np,) [m^2], void_area A (Np,) [m^2] (eq 29),
    link_length R (L,) [m], link_contact (L,) bool: r_k + r_l + eps_m >= R (eq 43b, k = k2),
    corner_angle (K,) [rad] interior angle of each pore corner (eq 29),
    link_vector (L, 2) [m] centre of j minus centre of i for each link (i, j).
    """

    polygon_area: np.ndarray
    sector_area: np.ndarray
    void_area: np.ndarray
    link_length: np.ndarray
    link_contact: np.ndarray
    corner_angle: np.ndarray
    link_vector: np.ndarray


def _empty_network(n, a_min, eps_m, l_m):
    """A network without pores (fewer than three discs or collinear centres)."""
    z2 = np.zeros((0, 2), dtype=np.int64)
    zi = np.zeros(0, dtype=np.int64)
    zf = np.zeros(0)
    return PoreNetwork(
        n_discs=n, tri=np.zeros((0, 3), dtype=np.int64), tri_pore=zi, links=z2, link_pores=z2,
        throat_conns=z2, throat_link=zi, pore_surface=np.zeros(0, bool),
        pore_touches={name: np.zeros(0, bool) for name in WALL_NAMES.values()},
        pore_vertex_ptr=np.zeros(1, np.int64), pore_vertex_idx=zi, pore_signature=np.zeros(0, np.uint64),
        he_org=zi, he_dst=zi, he_left=zi, he_next=zi, corner_pore=zi, corner_disc=zi, corner_link=zi,
        corner_next_link=zi, corner_sign=zf, corner_r2=zf, corner_theta0=zf,
        rattler_area=zf, link_vec0=np.zeros((0, 2)), sector_area0=zf, link_turn_weight=zf, a_min=a_min,
        eps_m=eps_m, l_m=l_m,
    )


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


def regular_triangulation(xz, r, steps=None):
    """Counter-clockwise triangles (T, 3) of the regular (power) triangulation of the discs, or None.

    The lower convex hull of the lifted points (x, z, x^2 + z^2 - r^2) (centred and scaled by the
    extent of the centres), one triangle per hull facet whose outward normal points down. An extra
    point lifted above all others, at the centroid, is never on the lower hull; it makes a 3D hull
    of three discs or of lifted points that lie in one plane (cocircular equal discs). Collinear
    centres stay flat: None. Discs whose power cell is empty are in no triangle. ``steps``:
    BuildSteps (default NUMPY_BUILD); with its certain_triangles (engines.compiled.pores.BUILD),
    the hull is built only where that answers it is not certain. The triangles in the order of
    ``canonical_triangles``.
    """
    steps = steps or NUMPY_BUILD
    n = len(xz)
    if n < 3:
        return None
    if steps.certain_triangles is not None:
        certain, tri = steps.certain_triangles(xz, r)
        if certain:
            return tri
    points = steps.lifted_points(xz, r)
    if points is None:
        return None
    try:
        hull = ConvexHull(points)
    except QhullError:
        return None
    return steps.lower_triangles(hull, n, xz)


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
        for a in self._star(k):
            b = self.third.get((k, a))
            if b is None:
                continue
            oa, ob = o(p[k], p[a], p[l]), o(p[k], p[b], p[l])
            if oa == 0 and (p[a][0] - p[k][0]) * (p[l][0] - p[k][0]) + (p[a][1] - p[k][1]) * (p[l][1] - p[k][1]) > 0:
                return None  # a lies on the segment
            if oa > 0 and ob < 0:
                break
        else:
            return None
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


def insert_missing_links(xz, r, tri, reach, steps=None, wall_vertices=None):
    """Make every eq 28 pair between triangulation vertices that crosses no link an edge (and so a
    link), by edge flips, the pairs in order of their gap R - r_i - r_j (then of their indices).
    Only edges that are not links are flipped, so no link is lost.

    Returns (tri, number of pairs inserted). ``reach`` = eps_m + l_m [m]; ``steps``: BuildSteps
    (default NUMPY_BUILD); ``wall_vertices``: the flat_walls.WallVertices of xz, r (their links).
    """
    wv = wall_vertices
    missing = (steps or NUMPY_BUILD).missing_pairs(xz, r, reach, tri, wv)
    if not len(missing):
        return tri, 0
    d = xz[missing[:, 1]] - xz[missing[:, 0]]  # closest gap first (of two crossing pairs, the nearer is linked)
    missing = missing[np.lexsort((missing[:, 1], missing[:, 0], np.hypot(d[:, 0], d[:, 1]) - r[missing].sum(axis=1)))]
    ft = _FlipTriangulation(xz, tri)
    rr = r.tolist()

    def is_link(a, b):  # eq 28
        eq28 = rr[a] + rr[b] + reach >= np.hypot(ft.p[b][0] - ft.p[a][0], ft.p[b][1] - ft.p[a][1])
        return eq28 if wv is None else bool(wv.is_link(a, b, eq28))

    inserted = 0
    for k, l in missing.tolist():
        edges = ft.crossed_edges(k, l)
        if edges is None or any(is_link(a, b) for a, b in edges):
            continue  # it runs through a disc centre or crosses a link
        ft.insert(k, l, edges)
        inserted += 1
    return (ft.triangles() if inserted else tri), inserted


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


def _locate(xz, tri, points):
    """Index of a triangle containing each point (M, 2), -1 where none (brute force, for few points)."""
    a, b, c = (xz[tri[:, k]][None] for k in range(3))
    q = points[:, None, :]

    def side(u, v):
        return (v[..., 0] - u[..., 0]) * (q[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (q[..., 0] - u[..., 0])

    inside = (side(a, b) >= 0) & (side(b, c) >= 0) & (side(c, a) >= 0)
    return np.where(inside.any(axis=1), inside.argmax(axis=1), -1)


def build_pores(xz, r, eps_m=0.0, l_m=0.0, walls=None, degenerate_fraction=1e-4, steps=None, flat_walls=()):
    """Build links (eq 28) and pores (§3.1) for discs at ``xz`` [m] with radii ``r`` [m].

    ``walls``: optional (N,) int wall code per disc (WALL_NONE, WALL_BOTTOM, WALL_LEFT, WALL_RIGHT).
    An edge between two wall discs is a wall element, not a free surface. The candidate links are
    the regular triangulation plus the eq 28 pairs it hides (module docstring).
    ``flat_walls``: flat_walls.FlatWall, ... (SPEC §2.6), or their flat_walls.WallVertices (with its
    shift: translated walls): the triangulation is that of the discs and the wall vertices of the
    build (flat_walls.WallVertices.active).
    ``steps``: the BuildSteps, by default NUMPY_BUILD, the readable NumPy functions (``_lifted_points``,
    ``_faces``, ``_links_and_corners``, ...); engines.compiled.pores.BUILD: everything but qhull by
    compiled kernels, the same network (tests/compiled/test_pores.py).
    Returns a PoreNetwork; positions may then move and ``measure`` gives the new areas.
    """
    xz, r = check_discs(xz, r)
    check_nonnegative("eps_m", eps_m)
    check_nonnegative("l_m", l_m)
    check_nonnegative("degenerate_fraction", degenerate_fraction)
    n = len(r)
    walls = np.zeros(n, np.int64) if walls is None else np.asarray(walls, np.int64)
    if walls.shape != (n,):
        raise ValueError(f"walls: expected shape ({n},), got {walls.shape}")
    bad = (walls < WALL_NONE) | (walls > LAST_GROUP)
    if bad.any():
        raise ValueError(f"walls: codes must be {WALL_NONE}-{LAST_GROUP}, got {walls[bad][0]}")
    a_min = degenerate_fraction * float(np.mean(np.pi * r**2)) if n else 0.0
    steps = steps or NUMPY_BUILD
    if flat_walls:
        wv = flat_walls if isinstance(flat_walls, fw.WallVertices) else fw.WallVertices(flat_walls, n)
        return _build_with_flat_walls(xz, r, eps_m, l_m, walls, a_min, steps, wv)
    tri = regular_triangulation(xz, r, steps)
    if tri is None:
        return _empty_network(n, a_min, eps_m, l_m)
    tri, n_inserted = insert_missing_links(xz, r, tri, eps_m + l_m, steps)
    return _network(xz, r, walls, tri, n_inserted, eps_m, l_m, a_min, steps.faces, steps.links_and_corners)


def _network(xz, r, walls, tri, n_inserted, eps_m, l_m, a_min, faces, links_and_corners):
    """The PoreNetwork of the vertices at xz with radii r and wall codes ``walls`` on the
    triangulation ``tri`` (links inserted), by the steps ``faces`` and ``links_and_corners``."""
    nb, is_link, tri_pore_all, bounded, n_pores, n_closed, off_mesh = faces(xz, r, tri, eps_m + l_m, a_min)
    t_in = _locate(xz, tri, xz[off_mesh]) if len(off_mesh) else off_mesh  # empty power cells: rattlers where they lie
    p_in = np.where(t_in >= 0, tri_pore_all[t_in], OUTER)
    *arrays, touches = links_and_corners(xz, r, walls, tri, nb, is_link, tri_pore_all, bounded, n_pores,
                                   off_mesh[p_in >= 0], p_in[p_in >= 0])
    arrays = dict(zip(NETWORK_ARRAYS, arrays))
    links = arrays["links"]
    return PoreNetwork(
        n_discs=len(r), **arrays, link_vec0=xz[links[:, 1]] - xz[links[:, 0]], **_sector_terms(r, arrays),
        pore_touches={name: touches[code] for code, name in WALL_NAMES.items()},
        a_min=a_min, n_closed=int(n_closed), eps_m=float(eps_m), l_m=float(l_m), n_inserted=n_inserted,
    )


def _sector_terms(r, a):
    """sector_area0 (Np,) and link_turn_weight (L,) [m^2] of PoreNetwork from the radii r of its
    vertices and the arrays ``a`` of ``_links_and_corners`` (by name). The corner at the end d of
    a half-edge turns by the turn of its link minus that of the next link (eq 29), so over a pore's
    corners each link's turn counts with r^2 of the disc it leads to (+) and of the disc it leaves
    (-): (r_j^2 - r_i^2) / 2 for the pore on the left of i->j, the opposite on its right."""
    links, n_p = a["links"], len(a["pore_surface"])
    sector0 = 0.5 * np.bincount(a["corner_pore"], a["corner_theta0"] * a["corner_r2"], minlength=n_p)
    return {"sector_area0": sector0 + a["rattler_area"],
            "link_turn_weight": 0.5 * (r[links[:, 1]] ** 2 - r[links[:, 0]] ** 2)}


def _build_with_flat_walls(xz, r, eps_m, l_m, walls, a_min, steps, wv):
    """build_pores with the flat walls of the flat_walls.WallVertices ``wv``: the network of the
    discs and the wall vertices (flat_walls module docstring), whose vertex sets count each wall
    as one vertex (``_wall_vertex_sets``)."""
    wv.check_inside(xz)
    n, reach = wv.n, eps_m + l_m
    points, radii = wv.positions(xz), wv.radii(r)
    active = wv.active(xz, r, reach)
    tri = regular_triangulation(points[active], radii[active], steps)
    if tri is None:
        net = _empty_network(n, a_min, eps_m, l_m)
    else:
        tri, n_inserted = insert_missing_links(points, radii, active[tri], reach, steps, wv)
        codes = np.concatenate([walls, np.full(wv.n_vertices - n, FLAT_VERTEX)])

        def faces(*args):  # the wall vertices that are no vertex of the build are no rattlers
            *out, off_mesh = steps.faces(*args, wall_vertices=wv)
            return *out, off_mesh[off_mesh < n]

        net = _network(points, radii, codes, tri, n_inserted, eps_m, l_m, a_min, faces, steps.links_and_corners)
    net.n_discs, net.wall_vertices = n, wv
    net.pore_vertex_ptr, net.pore_vertex_idx, net.pore_signature, net.pore_walls = _wall_vertex_sets(
        wv, net.pore_vertex_ptr, net.pore_vertex_idx)
    return net


def _wall_vertex_sets(wv, ptr, idx):
    """The pores' vertex sets (CSR ptr, idx over the vertices of flat_walls.WallVertices ``wv``) with
    the vertices on flat wall w counted as one, N + w (re-meshing rules (a)-(d)): (ptr, idx,
    signature, pore_walls (W, Np) bool: the pore has a vertex on wall w)."""
    n, n_p = wv.n, len(ptr) - 1
    pore = np.repeat(np.arange(n_p), np.diff(ptr))
    disc = idx < n
    k, w = wv.split_bits(wv.bits[idx])
    pore_walls = np.zeros((len(wv.walls), n_p), bool)
    pore_walls[w, pore[k]] = True
    m = n + len(wv.walls)
    key = np.unique(np.concatenate([pore[disc] * m + idx[disc], pore[k] * m + n + w]))
    ptr = np.searchsorted(key // m, np.arange(n_p + 1))
    return ptr, key % m, _set_signatures(ptr, key % m), pore_walls


NETWORK_ARRAYS = ("tri", "tri_pore", "links", "link_pores", "throat_conns", "throat_link", "pore_surface",
                  "pore_vertex_ptr", "pore_vertex_idx", "pore_signature", "he_org", "he_dst", "he_left", "he_next",
                  "corner_pore", "corner_disc", "corner_link", "corner_next_link", "corner_sign", "corner_r2",
                  "corner_theta0", "rattler_area")  # of PoreNetwork, as _links_and_corners returns them


def _faces(xz, r, tri, reach, a_min, wall_vertices=None):
    """The faces of the link graph from counter-clockwise triangles ``tri`` (T, 3).

    Half-edge h = 3 t + k of triangle t runs a = tri[t, k+1] -> b = tri[t, k+2] (the edge opposite
    corner k), with t on its left and nb[h] on its right (-1: none). Returns (nb (3T,), is_link (3T,)
    (eq 28 with reach = eps_m + l_m), tri_pore (T,) pore of each triangle (OUTER: the outer face or
    a closed one), bounded (T,) the triangle is not in the outer face, n_pores, n_closed faces,
    off_mesh: the discs in no triangle). Pores are numbered in the order of their first triangle.
    ``wall_vertices``: the flat_walls.WallVertices of xz, r (their links: WallVertices.is_link).
    """
    t_count, n = len(tri), len(r)
    nb = _neighbours(tri).ravel()
    a = tri[:, [1, 2, 0]].ravel()
    b = tri[:, [2, 0, 1]].ravel()
    d = xz[b] - xz[a]
    is_link = r[a] + r[b] + reach >= np.hypot(d[:, 0], d[:, 1])  # eq 28
    if wall_vertices is not None:
        is_link = wall_vertices.is_link(a, b, is_link)

    # Pores: triangles joined across non-link edges; a non-link hull edge joins the outer face.
    joins = ~is_link
    other = np.where(nb >= 0, nb, t_count)
    left_tri = np.repeat(np.arange(t_count), 3)
    graph = coo_matrix((np.ones(joins.sum()), (left_tri[joins], other[joins])), shape=(t_count + 1, t_count + 1))
    _, comp = connected_components(graph, directed=False)
    face = comp[:t_count]
    bounded = face != comp[t_count]

    # Void area per face at build (eq 29) to close degenerate faces.
    labels, face_id = np.unique(face[bounded], return_inverse=True)
    sig_area, sectors = _triangle_void(xz, r, tri[bounded])
    void = np.bincount(face_id, sig_area - sectors, minlength=len(labels))
    is_open = void > a_min
    pore_of_face = np.full(len(labels), OUTER)
    pore_of_face[is_open] = np.arange(is_open.sum())
    tri_pore = np.full(t_count, OUTER)
    tri_pore[bounded] = pore_of_face[face_id]
    return (nb, is_link, tri_pore, bounded, int(is_open.sum()), int((~is_open).sum()),
            np.setdiff1d(np.arange(n), tri.ravel()))


def _links_and_corners(xz, r, walls, tri, nb, is_link, tri_pore, bounded, n_pores, rat_disc, rat_pore):
    """Links, throats, free surface, vertex sets and pore corners of the faces of ``_faces``;
    rat_disc, rat_pore: the discs in no triangle that lie in a pore, and that pore.

    Returns the arrays of PoreNetwork named in NETWORK_ARRAYS, in that order, then touches (4, Np):
    touches[code, p] is True when pore p has a disc of wall code ``code`` as a vertex.
    """
    n = len(r)
    a = tri[:, [1, 2, 0]].ravel()
    b = tri[:, [2, 0, 1]].ravel()

    # Links: one record per undirected link, pores on the left and right of i->j (i < j).
    lk = np.flatnonzero(is_link)
    la, lb = a[lk], b[lk]
    left_tri, right_tri = lk // 3, nb[lk]
    left_p = tri_pore[left_tri]
    right_p = np.where(right_tri >= 0, tri_pore[np.maximum(right_tri, 0)], OUTER)
    key = np.minimum(la, lb) * n + np.maximum(la, lb)
    ukey, first = np.unique(key, return_index=True)
    links = np.column_stack([ukey // n, ukey % n])
    flip = la[first] > lb[first]
    link_pores = np.column_stack([np.where(flip, right_p[first], left_p[first]),
                                  np.where(flip, left_p[first], right_p[first])])

    # Throats between two distinct pores, and the free surface.
    lp0, lp1 = link_pores[:, 0], link_pores[:, 1]
    is_throat = (lp0 >= 0) & (lp1 >= 0) & (lp0 != lp1)
    wall_edge = (walls[links[:, 0]] != WALL_NONE) & (walls[links[:, 1]] != WALL_NONE)
    outer_link = ((lp0 == OUTER) ^ (lp1 == OUTER)) & ~wall_edge
    # a link next to a closed face is not on the free surface: only the true outer face counts
    left_bounded = bounded[left_tri[first]]
    right_bounded = np.where(right_tri[first] >= 0, bounded[np.maximum(right_tri[first], 0)], False)
    outer_side_is_outer = np.where(lp0 == OUTER, ~np.where(flip, right_bounded, left_bounded),
                                   ~np.where(flip, left_bounded, right_bounded))
    surface_pores = np.where(lp0 == OUTER, lp1, lp0)[outer_link & outer_side_is_outer]
    pore_surface = np.zeros(n_pores, bool)
    pore_surface[surface_pores[surface_pores >= 0]] = True

    # Pore vertex sets.
    in_pore = tri_pore >= 0
    tp = tri_pore[in_pore]
    pv_key = np.unique(np.concatenate([np.repeat(tp, 3) * n + tri[in_pore].ravel(), rat_pore * n + rat_disc]))
    pv_pore, pv_disc = pv_key // n, pv_key % n
    ptr = np.searchsorted(pv_pore, np.arange(n_pores + 1))
    signature = _set_signatures(ptr, pv_disc)
    touches = np.zeros((max(LAST_GROUP, int(walls.max(initial=0))) + 1, n_pores), bool)
    touches[walls[pv_disc], pv_pore] = True

    # Boundary corners of the pores: the paper's walk over the link half-edges.
    he_org, he_dst, he_left, he_next = _link_half_edges(xz, links, link_pores)
    n_l = len(links)
    h = np.flatnonzero(he_left >= 0)
    he_link = np.concatenate([np.arange(n_l), np.arange(n_l)])
    phi = _link_angles(xz, links)
    twin = np.concatenate([np.arange(n_l, 2 * n_l), np.arange(n_l)])
    phi_he = phi[he_link] + np.pi * (np.arange(2 * n_l) >= n_l)
    theta0 = np.mod(phi_he[twin[h]] - phi_he[he_next[h]], 2 * np.pi)  # eq 29, in [0, 2 pi)
    theta0[he_next[h] == twin[h]] = 2 * np.pi  # the end of a dangling link: all around the disc

    # Unlinked discs (rattlers) inside a pore are void-free: subtract them whole.
    linked = np.zeros(n, bool)
    linked[links.ravel()] = True
    rat = ~linked[pv_disc]
    rattler_area = np.bincount(pv_pore[rat], np.pi * r[pv_disc[rat]] ** 2, minlength=n_pores).astype(float)
    return (tri[in_pore], tp, links, link_pores, link_pores[is_throat], np.flatnonzero(is_throat), pore_surface,
            ptr, pv_disc, signature, he_org, he_dst, he_left, he_next, he_left[h], he_dst[h], he_link[h],
            he_link[he_next[h]], np.where(h < n_l, 1.0, -1.0), r[he_dst[h]] ** 2, theta0, rattler_area, touches)


class BuildSteps(NamedTuple):
    """The parts of ``build_pores`` that have compiled twins (engines.compiled.pores.BUILD), and a
    triangulation that spares the hull where it is certain (none in NumPy: the hull always)."""

    lifted_points: Callable      # (xz, r) -> the hull's points (N + 1, 3), or None
    lower_triangles: Callable    # (hull, n, xz) -> the lower facets (canonical_triangles), or None
    missing_pairs: Callable      # as _missing_pairs
    faces: Callable              # as _faces
    links_and_corners: Callable  # as _links_and_corners
    certain_triangles: Callable = None  # (xz, r) -> (True, regular_triangulation's answer) or (False, None)


NUMPY_BUILD = BuildSteps(_lifted_points, _lower_triangles, _missing_pairs, _faces, _links_and_corners)


def _set_signatures(ptr, v):
    """(Np,) uint64 signature of each vertex set v[ptr[p]:ptr[p + 1]] (none empty): the wrapping sum
    of the vertices' ``_mix64`` keys."""
    return np.add.reduceat(_mix64(v), ptr[:-1]) if len(ptr) > 1 else np.zeros(0, np.uint64)


def _mix64(v):
    """splitmix64 of integers: a well-spread 64-bit key per disc; a pore's set signature is the
    wrapping sum of its discs' keys, so a collision between different sets has odds ~2^-64."""
    z = v.astype(np.uint64) + np.uint64(0x9E3779B97F4A7C15)
    with np.errstate(over="ignore"):
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


def _link_angles(xz, links):
    d = xz[links[:, 1]] - xz[links[:, 0]]
    return np.arctan2(d[:, 1], d[:, 0])


def _triangle_void(xz, r, tri):
    """Signed triangle areas and sector areas sum(theta r^2 / 2) at their corners (eq 29)."""
    p = xz[tri]
    e1 = p[:, [1, 2, 0]] - p
    e2 = p[:, [2, 0, 1]] - p
    theta = np.arctan2(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0], np.einsum("tkc,tkc->tk", e1, e2))
    return _signed_area(p), 0.5 * np.sum(theta * r[tri] ** 2, axis=1)


def _link_half_edges(xz, links, link_pores):
    """Half-edges of the link graph and the paper's walk: next = clockwise turn at the end disc."""
    org = np.concatenate([links[:, 0], links[:, 1]])
    dst = np.concatenate([links[:, 1], links[:, 0]])
    left = np.concatenate([link_pores[:, 0], link_pores[:, 1]])
    if len(org) == 0:
        return org, dst, left, org.copy()
    d = xz[dst] - xz[org]
    ang = np.arctan2(d[:, 1], d[:, 0])
    order = np.lexsort((ang, org))
    pos = np.empty_like(order)
    pos[order] = np.arange(len(order))
    sorted_org = org[order]
    group_start = np.searchsorted(sorted_org, sorted_org, side="left")
    group_end = np.searchsorted(sorted_org, sorted_org, side="right") - 1
    s = np.arange(len(order))
    prev_pos = np.where(s == group_start, group_end, s - 1)
    n_l = len(links)
    twin = np.concatenate([np.arange(n_l, 2 * n_l), np.arange(n_l)])
    nxt = order[prev_pos[pos[twin]]]
    return org, dst, left, nxt


def measure(net, xz, r):
    """Areas of the pores and state of the links at positions ``xz`` [m] (eq 29, 43).

    Sums over each pore's boundary links, the pore on the left of i->j taking + and the one on its
    right -: the polygon area, the shoelace sum of x_i z_j - x_j z_i over 2; the sector area, the
    build-time one (sector_area0) plus link_turn_weight times the link's turn since the build
    (from ``link_vec0``). The same sectors as the interior angle of each corner (eq 29), the
    build-time angle plus the difference of its two links' turns, given as corner_angle (valid
    while no corner turns by pi between rebuilds). Flat walls: their vertices are placed from the
    discs (``vertex_positions``), with radius 0.
    """
    xz, r = vertex_positions(net, xz), vertex_radii(net, r)
    i, j = net.links[:, 0], net.links[:, 1]
    x, z = np.ascontiguousarray(xz[:, 0]), np.ascontiguousarray(xz[:, 1])
    xi, zi = x[i], z[i]
    dx, dz = x[j] - xi, z[j] - zi
    length = np.sqrt(dx * dx + dz * dz)
    d0 = net.link_vec0
    turn = np.arctan2(d0[:, 0] * dz - d0[:, 1] * dx, d0[:, 0] * dx + d0[:, 1] * dz)
    cross = xi * dz - dx * zi  # x_i z_j - x_j z_i
    poly = 0.5 * _left_minus_right(net, cross)
    sect = net.sector_area0 + _left_minus_right(net, net.link_turn_weight * turn)  # eq 29
    theta = net.corner_theta0 + turn[net.corner_link] - turn[net.corner_next_link]  # eq 29
    contact = r[i] + r[j] + net.eps_m >= length  # eq 43b
    return PoreMeasures(poly, sect, poly - sect, length, contact, theta, np.column_stack([dx, dz]))


def _left_minus_right(net, v):
    """(Np,): the sum of v (L,) over the links with the pore on their left less that over the links
    with the pore on their right."""
    left, right = net.link_pores[:, 0], net.link_pores[:, 1]
    return (np.bincount(left[left >= 0], v[left >= 0], minlength=net.n_pores)
            - np.bincount(right[right >= 0], v[right >= 0], minlength=net.n_pores))


def pressure_forces(net, r, U, meas):
    """Force of the pore pressures U (Np,) [N/m] on every disc (N, 2) [N per m thickness] (eq 33).

    Summing eq 33 over the pores around disc a gives, per link a-b with unit vector u = (b - a)/R,
    F_a += r_a (U_right - U_left) perp(u), perp(u) = (-u_z, u_x), and the same for b with r_b.
    The outer face and closed faces have U = 0. No torque (pressure acts through the centre).
    ``meas`` is the PoreMeasures of the current positions. The wall vertices of flat walls have
    r = 0 and take nothing here: their wall edges' force is ``flat_wall_forces``.
    """
    r = vertex_radii(net, r)
    n = len(r)
    F = np.zeros((n, 2))
    if len(net.links) == 0:
        return F[:net.n_discs]
    Uo = np.append(np.asarray(U, float), 0.0)  # index OUTER (-1) -> 0
    i, j = net.links[:, 0], net.links[:, 1]
    s = (Uo[net.link_pores[:, 1]] - Uo[net.link_pores[:, 0]]) / meas.link_length
    px, pz = -meas.link_vector[:, 1] * s, meas.link_vector[:, 0] * s
    ri, rj = r[i], r[j]
    F[:, 0] = np.bincount(i, ri * px, minlength=n) + np.bincount(j, rj * px, minlength=n)
    F[:, 1] = np.bincount(i, ri * pz, minlength=n) + np.bincount(j, rj * pz, minlength=n)
    return F[:net.n_discs]


def flat_wall_forces(net, U, meas):
    """Normal force (W,) [N per m thickness] of the pore pressures U (Np,) [N/m] on each flat wall,
    positive when it pushes the wall outward (away from the discs; SPEC §2.6): the sum over the
    wall's edges of U x edge length. A wall edge lies on the face, so its outer side is the outer
    face (U = 0) and U of its pore is the sum over both sides. ``meas``: PoreMeasures."""
    k, w = wall_edges(net)
    Uo = np.append(np.asarray(U, float), 0.0)  # index OUTER (-1) -> 0
    U_edge = Uo[net.link_pores[k, 0]] + Uo[net.link_pores[k, 1]]
    return np.bincount(w, U_edge * meas.link_length[k], minlength=len(net.flat_walls))


def wall_edges(net):
    """The wall edges of the flat walls of ``net``: (link indices (K,), their wall (K,)), a link
    once per wall it lies on (empty without flat walls)."""
    wv = net.wall_vertices
    if wv is None:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return wv.split_bits(wv.bits[net.links[:, 0]] & wv.bits[net.links[:, 1]])


class WallReactions(NamedTuple):
    """Normal forces (W,) [N per m thickness] on the flat walls, positive pushing a wall outward
    (the wall's reaction on the bed is the same along its inward normal)."""

    total: np.ndarray  # the water's part plus the discs' contact forces
    water: np.ndarray  # flat_wall_forces: the pore pressures on the wall edges


def wall_reactions(net, U, meas, contact):
    """WallReactions of the flat walls of ``net`` at pore pressures U (Np,) [N/m] (PoreMeasures
    ``meas``), ``contact`` (W,) [N/m] the normal force of the discs' contacts on each wall (from
    the DEM's contact law, positive pushing the wall outward)."""
    water = flat_wall_forces(net, U, meas)
    return WallReactions(water + np.asarray(contact, float), water)


def vertex_positions(net, xz):
    """Positions [m] of the network's vertices: the discs' xz (N, 2), then the flat walls' vertices
    (flat_walls.WallVertices.positions)."""
    return xz if net.wall_vertices is None else net.wall_vertices.positions(xz)


def vertex_radii(net, r):
    """Radii [m] of the network's vertices: the discs' r (N,), then 0 for the flat walls' vertices."""
    return r if net.wall_vertices is None else net.wall_vertices.radii(r)


def pore_centroids(net, xz):
    """Area-weighted centroid of each pore polygon (Np, 2) [m]."""
    xz = vertex_positions(net, xz)
    p = xz[net.tri]
    area = _signed_area(p)
    c = p.mean(axis=1)
    w = np.bincount(net.tri_pore, area, minlength=net.n_pores)
    cx = np.bincount(net.tri_pore, area * c[:, 0], minlength=net.n_pores)
    cz = np.bincount(net.tri_pore, area * c[:, 1], minlength=net.n_pores)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.column_stack([cx / w, cz / w])


# -- water-conserving transfer at re-meshing ------------------------------------------------
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
