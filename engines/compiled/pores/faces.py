"""Compiled twins of engines.model.pores.faces: the faces of the link graph (a union-find over
triangles across non-link edges, eq 29 closing), then links, throats, surface, vertex sets, the
half-edge walk and the corner angles (eq 29), returned as engines.model.pores.faces.NetworkArrays. No YADE."""
import numba as nb
import numpy as np

from engines.compiled.kernels import _groups
from engines.compiled.pores.links import _is_link
from engines.compiled.pores.triangulation import _half_edges, _signed_area, _twin
from engines.model.groups import LAST_GROUP
from engines.model.pores.faces import NetworkArrays
from engines.model.pores.network import OUTER

jit = nb.njit(cache=True, nogil=True)


@jit
def _sort_by(idx, key):
    """Sort the entries of idx in place by key[idx], stably (insertion sort when they are few)."""
    if len(idx) > 32:
        idx[:] = idx[np.argsort(key[idx], kind="mergesort")]
        return
    for s in range(1, len(idx)):
        e = idx[s]
        q = s
        while q > 0 and key[idx[q - 1]] > key[e]:
            idx[q] = idx[q - 1]
            q -= 1
        idx[q] = e


@jit
def _mix64(v):
    """engines.model.pores.faces._mix64 of one disc index (splitmix64; uint64 arithmetic wraps)."""
    z = np.uint64(v) + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@jit
def _find(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@jit
def faces(xz, r, tri, reach, a_min, owner, bits, n_discs):
    """engines.model.pores.faces._faces compiled: (nb (3T,), is_link (3T,), tri_pore (T,), bounded (T,), n_pores,
    n_closed, off_mesh); the links by ``_is_link``."""
    t_count, n = len(tri), len(r)
    m = 3 * t_count
    a, b = _half_edges(tri)
    ptr, order = _groups(a, n)
    nb_ = np.full(m, -1, np.int64)
    is_link = np.empty(m, np.bool_)
    parent = np.arange(t_count + 1)
    for h in range(m):
        twin = _twin(a, b, ptr, order, h)
        if twin >= 0:
            nb_[h] = twin // 3
        is_link[h] = _is_link(xz, r, reach, a[h], b[h], owner, bits, n_discs)
        if not is_link[h]:  # triangles joined across non-link edges; a non-link hull edge joins the outer face
            u, v = _find(parent, h // 3), _find(parent, nb_[h] if nb_[h] >= 0 else t_count)
            if u != v:
                parent[max(u, v)] = min(u, v)
    outer = _find(parent, t_count)
    face_of_root = np.full(t_count + 1, -1, np.int64)
    face = np.full(t_count, -1, np.int64)
    n_faces = 0
    for t in range(t_count):
        root = _find(parent, t)
        if root != outer:
            if face_of_root[root] < 0:
                face_of_root[root] = n_faces
                n_faces += 1
            face[t] = face_of_root[root]
    void = np.zeros(n_faces)  # eq 29 at build, to close degenerate faces
    for t in range(t_count):
        if face[t] >= 0:
            sectors = 0.0
            for k in range(3):
                i, j, l = tri[t, k], tri[t, (k + 1) % 3], tri[t, (k + 2) % 3]
                e1x, e1z = xz[j, 0] - xz[i, 0], xz[j, 1] - xz[i, 1]
                e2x, e2z = xz[l, 0] - xz[i, 0], xz[l, 1] - xz[i, 1]
                sectors += np.arctan2(e1x * e2z - e1z * e2x, e1x * e2x + e1z * e2z) * r[i] ** 2
            void[face[t]] += _signed_area(xz, tri[t, 0], tri[t, 1], tri[t, 2]) - 0.5 * sectors
    pore_of_face = np.full(n_faces, OUTER, np.int64)
    n_pores = 0
    for f in range(n_faces):
        if void[f] > a_min:
            pore_of_face[f] = n_pores
            n_pores += 1
    tri_pore = np.full(t_count, OUTER, np.int64)
    on_mesh = np.zeros(n, np.bool_)
    for t in range(t_count):
        if face[t] >= 0:
            tri_pore[t] = pore_of_face[face[t]]
        for k in range(3):
            on_mesh[tri[t, k]] = True
    return nb_, is_link, tri_pore, face >= 0, n_pores, n_faces - n_pores, np.flatnonzero(~on_mesh)


@jit
def links_and_corners(xz, r, walls, tri, nb_, is_link, tri_pore, bounded, n_pores, rat_disc, rat_pore):
    """engines.model.pores.faces._links_and_corners compiled: the same NetworkArrays."""
    n = len(r)
    links, link_pores, is_throat, pore_surface = _link_records(r, walls, tri, nb_, is_link, tri_pore, bounded, n_pores)
    tri_k, tp, ptr, pv_pore, pv_disc = _vertex_sets(tri, tri_pore, n_pores, rat_disc, rat_pore)
    signature, touches = _signatures_and_touches(walls, ptr, pv_pore, pv_disc, n_pores)
    he_org, he_dst, he_left, he_next, ang = _link_walk(xz, links, link_pores, n)
    n_l = len(links)
    h, theta0 = _corner_angles(ang[:n_l], he_left, he_next, n_l)
    throat_link = np.flatnonzero(is_throat)
    corner_link, corner_next_link = np.empty(len(h), np.int64), np.empty(len(h), np.int64)
    corner_sign, corner_r2 = np.empty(len(h)), np.empty(len(h))
    for s in range(len(h)):
        corner_link[s], corner_next_link[s] = h[s] % n_l, he_next[h[s]] % n_l
        corner_sign[s] = 1.0 if h[s] < n_l else -1.0
        corner_r2[s] = r[he_dst[h[s]]] ** 2
    return NetworkArrays(  # by position, in the order of its fields (numba takes at most 15 by keyword)
        tri_k, tp, links, link_pores, link_pores[throat_link], throat_link, pore_surface,  # tri ... pore_surface
        ptr, pv_disc, signature,  # pore_vertex_ptr, pore_vertex_idx, pore_signature
        he_org, he_dst, he_left, he_next,
        he_left[h], he_dst[h], corner_link, corner_next_link, corner_sign, corner_r2, theta0,  # corner_pore ... theta0
        _rattler_areas(r, he_org, pv_pore, pv_disc, n_pores), touches)


@jit
def _link_records(r, walls, tri, nb_, is_link, tri_pore, bounded, n_pores):
    """Links (eq 28): one per undirected edge (its first half-edge), sorted by (i, j), i < j; the
    pores on the left and right of i -> j; is_throat (between two distinct pores); and pore_surface
    (Np,): the pore has a link on the true outer face that is no wall edge (two discs of walls)."""
    n = len(r)
    a, b = _half_edges(tri)
    ptr, order = _groups(a, n)
    first = np.zeros(len(a), np.bool_)
    for h in range(len(a)):
        if is_link[h]:
            twin = _twin(a, b, ptr, order, h)
            first[h] = twin < 0 or twin > h
    lk = np.flatnonzero(first)
    lo = np.minimum(a[lk], b[lk])
    hi = np.maximum(a[lk], b[lk])
    i_ptr, by_i = _groups(lo, n)
    for g in range(n):  # by j within each i (few)
        _sort_by(by_i[i_ptr[g]:i_ptr[g + 1]], hi)
    lk = lk[by_i]
    n_l = len(lk)
    links = np.empty((n_l, 2), np.int64)
    link_pores = np.empty((n_l, 2), np.int64)
    is_throat = np.zeros(n_l, np.bool_)
    pore_surface = np.zeros(n_pores, np.bool_)
    for u_ in range(n_l):
        h = lk[u_]
        t = h // 3
        la, lb = a[h], b[h]
        rt = nb_[h]
        left_p, right_p = tri_pore[t], tri_pore[rt] if rt >= 0 else OUTER
        flip = la > lb
        lp0, lp1 = (right_p, left_p) if flip else (left_p, right_p)
        i, j = min(la, lb), max(la, lb)
        links[u_, 0], links[u_, 1] = i, j
        link_pores[u_, 0], link_pores[u_, 1] = lp0, lp1
        is_throat[u_] = lp0 >= 0 and lp1 >= 0 and lp0 != lp1
        wall_edge = walls[i] != 0 and walls[j] != 0
        outer_link = ((lp0 == OUTER) != (lp1 == OUTER)) and not wall_edge
        # a link next to a closed face is not on the free surface: only the true outer face counts
        left_b, right_b = bounded[t], rt >= 0 and bounded[rt]
        outer_side_is_outer = not (right_b if flip else left_b) if lp0 == OUTER else not (left_b if flip else right_b)
        if outer_link and outer_side_is_outer:
            sp = lp1 if lp0 == OUTER else lp0
            if sp >= 0:
                pore_surface[sp] = True
    return links, link_pores, is_throat, pore_surface


@jit
def _vertex_sets(tri, tri_pore, n_pores, rat_disc, rat_pore):
    """The triangles in pores (tri_k, tp) and the vertex sets of the pores: the discs of their
    triangles and their rattlers, sorted, each once, as CSR (ptr (Np + 1,), pv_pore, pv_disc)."""
    t_count = len(tri)
    in_pore = tri_pore >= 0
    n_in = in_pore.sum()
    tri_k = np.empty((n_in, 3), np.int64)
    tp = np.empty(n_in, np.int64)
    ent_pore = np.empty(3 * n_in + len(rat_disc), np.int64)
    ent_disc = np.empty(3 * n_in + len(rat_disc), np.int64)
    c = 0
    for t in range(t_count):
        if in_pore[t]:
            tp[c] = tri_pore[t]
            for k in range(3):
                tri_k[c, k] = tri[t, k]
                ent_pore[3 * c + k], ent_disc[3 * c + k] = tri_pore[t], tri[t, k]
            c += 1
    for s in range(len(rat_disc)):
        ent_pore[3 * n_in + s], ent_disc[3 * n_in + s] = rat_pore[s], rat_disc[s]
    p_ptr, by_pore = _groups(ent_pore, n_pores)
    pv_pore = np.empty(len(ent_disc), np.int64)
    pv_disc = np.empty(len(ent_disc), np.int64)
    ptr = np.zeros(n_pores + 1, np.int64)
    c = 0
    for p in range(n_pores):
        _sort_by(by_pore[p_ptr[p]:p_ptr[p + 1]], ent_disc)
        for s in range(p_ptr[p], p_ptr[p + 1]):
            v = ent_disc[by_pore[s]]
            if s == p_ptr[p] or v != pv_disc[c - 1]:
                pv_pore[c], pv_disc[c] = p, v
                c += 1
        ptr[p + 1] = c
    return tri_k, tp, ptr, pv_pore[:c].copy(), pv_disc[:c].copy()


@jit
def _signatures_and_touches(walls, ptr, pv_pore, pv_disc, n_pores):
    """The pores' set signatures (Np,) (the wrapping sum of ``_mix64`` of their vertices) and
    touches (codes, Np): the pore has a disc of that wall code."""
    signature = np.zeros(n_pores, np.uint64)
    touches = np.zeros((max(LAST_GROUP, walls.max()) + 1, n_pores), np.bool_)
    for s in range(len(pv_disc)):
        signature[pv_pore[s]] += _mix64(pv_disc[s])
        touches[walls[pv_disc[s]], pv_pore[s]] = True
    return signature, touches


@jit
def _link_walk(xz, links, link_pores, n):
    """The half-edges of the links (org, dst, left (2 L,)) and the paper's walk: next = clockwise
    turn at the end disc; with the angle of each half-edge."""
    n_l = len(links)
    he_org = np.concatenate((links[:, 0], links[:, 1]))
    he_dst = np.concatenate((links[:, 1], links[:, 0]))
    he_left = np.concatenate((link_pores[:, 0], link_pores[:, 1]))
    n_he = 2 * n_l
    ang = np.empty(n_he)
    for e in range(n_he):
        ang[e] = np.arctan2(xz[he_dst[e], 1] - xz[he_org[e], 1], xz[he_dst[e], 0] - xz[he_org[e], 0])
    o_ptr, order = _groups(he_org, n)
    for g in range(n):  # by disc, then angle
        _sort_by(order[o_ptr[g]:o_ptr[g + 1]], ang)
    pos = np.empty(n_he, np.int64)
    prev = np.empty(n_he, np.int64)  # the previous half-edge around the same disc, cyclic
    g0 = 0
    for s in range(n_he):
        pos[order[s]] = s
        if s > 0 and he_org[order[s]] != he_org[order[s - 1]]:
            g0 = s
        prev[s] = s - 1
        if s == n_he - 1 or he_org[order[s + 1]] != he_org[order[s]]:
            prev[g0] = s
    he_next = np.empty(n_he, np.int64)
    for e in range(n_he):
        twin = e + n_l if e < n_l else e - n_l
        he_next[e] = order[prev[pos[twin]]]
    return he_org, he_dst, he_left, he_next, ang


@jit
def _corner_angles(phi, he_left, he_next, n_l):
    """The boundary half-edges h of the pores and the interior angle theta0 (eq 29) at the disc each
    leads to, from the links' angles phi (L,): in [0, 2 pi), 2 pi at the end of a dangling link."""
    h = np.flatnonzero(he_left >= 0)
    theta0 = np.empty(len(h))
    for s in range(len(h)):
        e, f = h[s], he_next[h[s]]
        twin = e + n_l if e < n_l else e - n_l
        if f == twin:
            theta0[s] = 2 * np.pi  # the end of a dangling link: all around the disc
        else:
            phi_twin = phi[twin % n_l] + (np.pi if twin >= n_l else 0.0)
            phi_f = phi[f % n_l] + (np.pi if f >= n_l else 0.0)
            theta0[s] = np.mod(phi_twin - phi_f, 2 * np.pi)  # eq 29, in [0, 2 pi)
    return h, theta0


@jit
def _rattler_areas(r, he_org, pv_pore, pv_disc, n_pores):
    """(Np,) [m^2] the area of the unlinked discs (rattlers) of each pore's vertex set: void-free,
    subtracted whole (eq 29)."""
    linked = np.zeros(len(r), np.bool_)
    for e in range(len(he_org)):
        linked[he_org[e]] = True
    rattler_area = np.zeros(n_pores)
    for s in range(len(pv_disc)):
        if not linked[pv_disc[s]]:
            rattler_area[pv_pore[s]] += np.pi * r[pv_disc[s]] ** 2
    return rattler_area
