"""The pore network's data: PoreNetwork (the topology, fixed between rebuilds), PoreMeasures (its
geometry at the current positions) and the shapes a checkpoint of it must have. No YADE."""
from dataclasses import dataclass

import numpy as np

from engines.model import flat_walls as fw
from engines.model.groups import LAST_GROUP, WALL_NAMES


OUTER = -1  # pore label of the outer face (and of closed faces) in link_pores
FLAT_VERTEX = LAST_GROUP + 1  # the wall code of a flat wall's vertex: a link between two is a wall edge


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
