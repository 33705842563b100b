"""The faces of the link graph (the pores, SPEC §2.2) on a triangulation: triangles joined across
non-link edges, closed when their void (eq 29) is below a_min; then the links, throats, free
surface, vertex sets and the corners of the paper's walk around each pore (eq 29). No YADE."""
from typing import NamedTuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from engines.model.groups import LAST_GROUP, WALL_NONE
from engines.model.pores.network import OUTER
from engines.model.pores.triangulation import _neighbours, _signed_area


class NetworkArrays(NamedTuple):
    """What ``_links_and_corners`` and its compiled twin return: the arrays of PoreNetwork under
    its names (its docstring gives their meaning), then touches (codes, Np) bool: touches[c, p] is
    True when pore p has a disc of wall code c as a vertex."""

    tri: np.ndarray
    tri_pore: np.ndarray
    links: np.ndarray
    link_pores: np.ndarray
    throat_conns: np.ndarray
    throat_link: np.ndarray
    pore_surface: np.ndarray
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
    touches: np.ndarray


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
    rat_disc, rat_pore: the discs in no triangle that lie in a pore, and that pore. Returns the
    NetworkArrays."""
    a = tri[:, [1, 2, 0]].ravel()
    b = tri[:, [2, 0, 1]].ravel()
    links, link_pores, flip, left_tri, right_tri = _link_records(len(r), a, b, nb, is_link, tri_pore)
    lp0, lp1 = link_pores[:, 0], link_pores[:, 1]
    is_throat = (lp0 >= 0) & (lp1 >= 0) & (lp0 != lp1)  # a link between two distinct pores
    in_pore = tri_pore >= 0
    tp = tri_pore[in_pore]
    ptr, pv_pore, pv_disc, touches = _vertex_sets(len(r), walls, tri[in_pore], tp, n_pores, rat_disc, rat_pore)
    he_org, he_dst, he_left, he_next = _link_half_edges(xz, links, link_pores)
    h, he_link, theta0 = _corner_angles(xz, links, he_left, he_next)
    n_l = len(links)
    return NetworkArrays(
        tri=tri[in_pore], tri_pore=tp, links=links, link_pores=link_pores, throat_conns=link_pores[is_throat],
        throat_link=np.flatnonzero(is_throat),
        pore_surface=_surface_pores(walls, links, link_pores, flip, left_tri, right_tri, bounded, n_pores),
        pore_vertex_ptr=ptr, pore_vertex_idx=pv_disc, pore_signature=_set_signatures(ptr, pv_disc),
        he_org=he_org, he_dst=he_dst, he_left=he_left, he_next=he_next, corner_pore=he_left[h],
        corner_disc=he_dst[h], corner_link=he_link[h], corner_next_link=he_link[he_next[h]],
        corner_sign=np.where(h < n_l, 1.0, -1.0), corner_r2=r[he_dst[h]] ** 2, corner_theta0=theta0,
        rattler_area=_rattler_areas(r, links, pv_pore, pv_disc, n_pores), touches=touches)


def _link_records(n, a, b, nb, is_link, tri_pore):
    """Links (eq 28): one record per undirected link among the half-edges a -> b (3T,), as (i, j)
    with i < j in order, and the pores on the left and right of i -> j; then for the record's
    first half-edge: flip (it runs j -> i) and the triangles on its left and right (-1: none)."""
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
    return links, link_pores, flip, left_tri[first], right_tri[first]


def _surface_pores(walls, links, link_pores, flip, left_tri, right_tri, bounded, n_pores):
    """(Np,) bool, the free surface: the pore has a link on the true outer face that is not a wall
    edge (two discs of walls); the records as ``_link_records`` gives them."""
    lp0, lp1 = link_pores[:, 0], link_pores[:, 1]
    wall_edge = (walls[links[:, 0]] != WALL_NONE) & (walls[links[:, 1]] != WALL_NONE)
    outer_link = ((lp0 == OUTER) ^ (lp1 == OUTER)) & ~wall_edge
    # a link next to a closed face is not on the free surface: only the true outer face counts
    left_bounded = bounded[left_tri]
    right_bounded = np.where(right_tri >= 0, bounded[np.maximum(right_tri, 0)], False)
    outer_side_is_outer = np.where(lp0 == OUTER, ~np.where(flip, right_bounded, left_bounded),
                                   ~np.where(flip, left_bounded, right_bounded))
    surface_pores = np.where(lp0 == OUTER, lp1, lp0)[outer_link & outer_side_is_outer]
    pore_surface = np.zeros(n_pores, bool)
    pore_surface[surface_pores[surface_pores >= 0]] = True
    return pore_surface


def _vertex_sets(n, walls, tri, tp, n_pores, rat_disc, rat_pore):
    """The vertex sets of the pores: the discs of the triangles ``tri`` in pores ``tp`` and the
    rattlers rat_disc in rat_pore, each once, as CSR (ptr (Np + 1,), pv_pore, pv_disc sorted), and
    touches (codes, Np) of NetworkArrays from the wall codes ``walls`` of the n discs."""
    pv_key = np.unique(np.concatenate([np.repeat(tp, 3) * n + tri.ravel(), rat_pore * n + rat_disc]))
    pv_pore, pv_disc = pv_key // n, pv_key % n
    ptr = np.searchsorted(pv_pore, np.arange(n_pores + 1))
    touches = np.zeros((max(LAST_GROUP, int(walls.max(initial=0))) + 1, n_pores), bool)
    touches[walls[pv_disc], pv_pore] = True
    return ptr, pv_pore, pv_disc, touches


def _corner_angles(xz, links, he_left, he_next):
    """The pores' corners, from the paper's walk over the link half-edges: the boundary half-edges h
    of the pores, the link of every half-edge (2 L,), and the interior angle theta0 (eq 29) at the
    disc each h leads to, in [0, 2 pi) (2 pi at the end of a dangling link)."""
    n_l = len(links)
    h = np.flatnonzero(he_left >= 0)
    he_link = np.concatenate([np.arange(n_l), np.arange(n_l)])
    phi = _link_angles(xz, links)
    twin = np.concatenate([np.arange(n_l, 2 * n_l), np.arange(n_l)])
    phi_he = phi[he_link] + np.pi * (np.arange(2 * n_l) >= n_l)
    theta0 = np.mod(phi_he[twin[h]] - phi_he[he_next[h]], 2 * np.pi)  # eq 29, in [0, 2 pi)
    theta0[he_next[h] == twin[h]] = 2 * np.pi  # the end of a dangling link: all around the disc
    return h, he_link, theta0


def _rattler_areas(r, links, pv_pore, pv_disc, n_pores):
    """(Np,) [m^2] the area of the unlinked discs (rattlers) in each pore's vertex set: void-free,
    subtracted whole (eq 29)."""
    linked = np.zeros(len(r), bool)
    linked[links.ravel()] = True
    rat = ~linked[pv_disc]
    return np.bincount(pv_pore[rat], np.pi * r[pv_disc[rat]] ** 2, minlength=n_pores).astype(float)


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
