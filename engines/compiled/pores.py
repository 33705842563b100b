"""Compiled (numba) kernels of the pore rebuild: the network of engines.model.pores.build_pores and
the re-meshing of engines.model.pore_water.PoreWater.remesh. No YADE.

Each kernel repeats, loop by loop, the arithmetic of a readable NumPy function, which stays the
reference path and is tested against it (tests/compiled/test_pores.py: integer arrays equal, floats
to 1e-12 relative):

  lifted_points      model.pores._lifted_points           the points of the regular triangulation's hull
  lower_ccw          model.pores._lower_triangles         the lower hull facets, counter-clockwise
  missing_pairs      model.pores._missing_pairs           the eq 28 pairs that are no edge
  faces              model.pores._faces                   neighbours, eq 28 links, faces (a union-find
                                                          over triangles across non-link edges), eq 29
  links_and_corners  model.pores._links_and_corners       links, throats, surface, vertex sets, the
                                                          half-edge walk, corner angles (eq 29)
  near_vertex_sets   pore_water.near_vertex_sets          rule (b): old vertex sets that contain or are
                                                          contained in a new one
  spread_to_neighbours  pore_water.spread_to_neighbours   rule (c)
  pore_overlaps      model.pores.pore_overlaps            overlap areas of old and new pores (clipping
                                                          as model.pores._clip_areas)

Flat walls (engines.model.flat_walls): the kernels run over the discs and the wall vertices, with
the links of flat_walls.WallVertices.is_link (``_is_link``, from the vertices' owner and bits).

Numbering follows the NumPy functions (pores in the order of their first triangle, links by (i, j),
half-edges sorted by disc then angle), so the networks are the same array for array. Sorting is by
counting sort over discs or pores and insertion sort of the few entries of each (the sorts of the
NumPy path cost more than the rest at these sizes); pairs are found on grids of cells. Sums that
NumPy makes in another order (means of rules (b), (c), overlap sums) agree to round-off. numba
compiles on first use and caches the machine code beside this file (``cache=True``); fastmath is off.

``BUILD`` and ``REMESH`` are these kernels as the steps of engines.model.pores.build_pores and
engines.model.pore_water.PoreWater.remesh (``steps=``), what the compiled WaterModel uses. BUILD
triangulates by engines.compiled.regular where that is certain (the same triangles as the hull's,
without Qhull), else by the hull.
"""
import numba as nb
import numpy as np

from engines.compiled import regular
from engines.compiled.kernels import _grid, _groups, _grown, _within
from engines.model import pore_water
from engines.model import pores as pg

jit = nb.njit(cache=True, nogil=True)
OUTER, LAST_GROUP = pg.OUTER, pg.LAST_GROUP
NO_WALL_VERTICES = np.zeros(0, np.int64)  # owner and bits of _is_link without flat walls


@jit
def lifted_points(xz, r, centre):
    """engines.model.pores._lifted_points compiled (the same arithmetic), centre = xz.mean(axis=0)."""
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


@jit
def _is_link(xz, r, reach, a, b, owner, bits, n_discs):
    """engines.model.flat_walls.WallVertices.is_link of the vertices a, b: two discs (< n_discs) by
    eq 28 (reach = eps_m + l_m); a disc and a wall vertex when it is the disc's foot (owner: the
    disc of each vertex); two wall vertices when they lie on a common wall (bits: the walls of each
    vertex). Without flat walls n_discs = len(r) and owner, bits are not read."""
    if a >= n_discs or b >= n_discs:
        if a >= n_discs and b >= n_discs:
            return (bits[a] & bits[b]) != 0
        return owner[a] == owner[b]
    return _within(xz[b, 0] - xz[a, 0], xz[b, 1] - xz[a, 1], r[a] + r[b] + reach)  # eq 28


@jit
def missing_pairs(xz, r, reach, tri, owner, bits, n_discs):
    """The linked pairs (M, 2), i < j, at least one a disc (``_is_link``: eq 28 or a disc and its
    foot), that are no edge of the triangles, both being vertices; in no particular order. A grid of
    cells of side 2 max(r) + reach finds them (a disc's foot in the build is within r + reach of it)."""
    n = len(r)
    a, b = _half_edges(tri)
    ptr, order = _groups(a, n)
    x0, z0, cell, nx, nz, start, in_cell = _grid(xz[:, 0], xz[:, 1], 2.0 * r.max() + reach)
    out = np.empty((16 * n + 16, 2), np.int64)
    m = 0
    for i in range(n_discs):  # the pairs of a disc i and a vertex j > i
        if ptr[i] == ptr[i + 1]:
            continue  # not a vertex
        cx, cz = int((xz[i, 0] - x0) / cell), int((xz[i, 1] - z0) / cell)
        for gx in range(max(cx - 1, 0), min(cx + 2, nx)):
            for gz in range(max(cz - 1, 0), min(cz + 2, nz)):
                g = gx * nz + gz
                for s in range(start[g], start[g + 1]):
                    j = in_cell[s]
                    if j <= i or ptr[j] == ptr[j + 1]:
                        continue
                    if not _is_link(xz, r, reach, i, j, owner, bits, n_discs):
                        continue
                    edge = False
                    for e in range(ptr[i], ptr[i + 1]):
                        edge = edge or b[order[e]] == j
                    for e in range(ptr[j], ptr[j + 1]):
                        edge = edge or b[order[e]] == i
                    if edge:
                        continue
                    if m == len(out):
                        grown = np.empty((2 * m, 2), np.int64)
                        grown[:m] = out
                        out = grown
                    out[m, 0], out[m, 1] = i, j
                    m += 1
    return out[:m].copy()


@jit
def _mix64(v):
    """engines.model.pores._mix64 of one disc index (splitmix64; uint64 arithmetic wraps)."""
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
    """engines.model.pores._faces compiled: (nb (3T,), is_link (3T,), tri_pore (T,), bounded (T,), n_pores,
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
    """engines.model.pores._links_and_corners compiled: the same arrays."""
    n, t_count = len(r), len(tri)
    # links: one per undirected edge (its first half-edge), sorted by (i, j), i < j
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

    # pore vertex sets: the discs of each pore, sorted, each once
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
    pv_pore, pv_disc = pv_pore[:c].copy(), pv_disc[:c].copy()
    signature = np.zeros(n_pores, np.uint64)
    touches = np.zeros((max(LAST_GROUP, walls.max()) + 1, n_pores), np.bool_)
    for s in range(c):
        signature[pv_pore[s]] += _mix64(pv_disc[s])
        touches[walls[pv_disc[s]], pv_pore[s]] = True

    # the half-edges of the links and the paper's walk: next = clockwise turn at the end disc
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

    # corners of the pores (eq 29)
    phi = ang[:n_l]
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

    # unlinked discs (rattlers) inside a pore are void-free: subtract them whole
    linked = np.zeros(n, np.bool_)
    for e in range(n_he):
        linked[he_org[e]] = True
    rattler_area = np.zeros(n_pores)
    for s in range(len(pv_disc)):
        if not linked[pv_disc[s]]:
            rattler_area[pv_pore[s]] += np.pi * r[pv_disc[s]] ** 2
    throat_link = np.flatnonzero(is_throat)
    corner_link, corner_next_link = np.empty(len(h), np.int64), np.empty(len(h), np.int64)
    corner_sign, corner_r2 = np.empty(len(h)), np.empty(len(h))
    for s in range(len(h)):
        corner_link[s], corner_next_link[s] = h[s] % n_l, he_next[h[s]] % n_l
        corner_sign[s] = 1.0 if h[s] < n_l else -1.0
        corner_r2[s] = r[he_dst[h[s]]] ** 2
    return (tri_k, tp, links, link_pores, link_pores[throat_link], throat_link, pore_surface, ptr, pv_disc, signature,
            he_org, he_dst, he_left, he_next, he_left[h], he_dst[h], corner_link, corner_next_link, corner_sign,
            corner_r2, theta0, rattler_area, touches)


@jit
def _subset_or_superset(x, y):
    """Sorted sets x, y: one contains the other."""
    i = j = 0
    x_in_y = y_in_x = True
    while i < len(x) and j < len(y):
        if x[i] == y[j]:
            i += 1
            j += 1
        elif x[i] < y[j]:
            x_in_y = False
            i += 1
        else:
            y_in_x = False
            j += 1
    return (x_in_y and i == len(x)) or (y_in_x and j == len(y))


@jit
def near_vertex_sets(old_ptr, old_idx, old_valid, new_ptr, new_idx, todo, U_old, n_vertices):
    """Rule (b) of pore_water.pressures_by_rule: for each new pore in todo, the mean U_old of the
    valid old pores whose vertex set (of vertices < n_vertices) contains or is contained in its own
    (nan: none)."""
    n_old = len(old_ptr) - 1
    owner = np.empty(len(old_idx), np.int64)
    for q in range(n_old):
        owner[old_ptr[q]:old_ptr[q + 1]] = q
    v_ptr, by_disc = _groups(old_idx, n_vertices)  # the old pores of each vertex
    seen = np.full(n_old, -1, np.int64)
    U = np.full(len(todo), np.nan)
    for s in range(len(todo)):
        p = todo[s]
        mine = new_idx[new_ptr[p]:new_ptr[p + 1]]
        total, count = 0.0, 0
        for v in mine:
            for e in range(v_ptr[v], v_ptr[v + 1]):
                q = owner[by_disc[e]]
                if seen[q] == p or not old_valid[q]:
                    continue
                seen[q] = p
                if _subset_or_superset(old_idx[old_ptr[q]:old_ptr[q + 1]], mine):
                    total += U_old[q]
                    count += 1
        if count:
            U[s] = total / count
    return U


@jit
def spread_to_neighbours(U, rule, conns):
    """Rule (c) of pore_water.pressures_by_rule, in place: in rounds, each pore with U nan takes the
    mean U of its distinct neighbours (pairs conns) that had one at the round's start, rule 3."""
    n = len(U)
    ends = np.concatenate((conns[:, 0], conns[:, 1]))
    others = np.concatenate((conns[:, 1], conns[:, 0]))
    ptr, order = _groups(ends, n)
    seen = np.full(n, -1, np.int64)
    known = np.empty(n)
    while True:
        known[:] = U
        changed = False
        for p in range(n):
            if not np.isnan(known[p]):
                continue
            total, count = 0.0, 0
            for e in range(ptr[p], ptr[p + 1]):
                q = others[order[e]]
                if seen[q] != p and q != p and not np.isnan(known[q]):
                    total += known[q]
                    count += 1
                seen[q] = p
            if count:
                U[p] = total / count
                rule[p] = 3
                changed = True
        seen[:] = -1
        if not changed:
            return


@jit
def _clip_area(P, Q, poly, cut):
    """Area of the intersection of the counter-clockwise triangles P (3, 2) and Q (3, 2): P clipped
    by the three edges of Q (Sutherland-Hodgman, as engines.model.pores._clip_areas); poly, cut (9, 2) scratch."""
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
    n = len(xz)
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
    ro, rn = np.flatnonzero(match_o < 0), np.flatnonzero(match_n < 0)
    n_pairs = len(to) - len(ro)
    cap = n_pairs + 16 * (len(ro) + len(rn)) + 16
    p, q, area = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
    m = 0
    for t in range(len(to)):
        if match_o[t] >= 0:
            p[m], q[m] = tp_old[t], tp_new[match_o[t]]
            area[m] = abs(_signed_area(xz, to[t, 0], to[t, 1], to[t, 2]))
            m += 1
    if len(ro) and len(rn):
        P = np.empty((len(ro), 3, 2))
        Q = np.empty((len(rn), 3, 2))
        cp, cq = np.empty((len(ro), 3)), np.empty((len(rn), 3))  # centroid x, z, radius
        for s in range(len(ro)):
            P[s] = _corners(xz, to[ro[s]])
            if _signed_area(xz, to[ro[s], 0], to[ro[s], 1], to[ro[s], 2]) < 0:  # turned over since its build
                P[s, 1], P[s, 2] = _corners(xz, to[ro[s]])[2], _corners(xz, to[ro[s]])[1]
            cp[s, 0], cp[s, 1], cp[s, 2] = _bounding_circle(P[s])
        for s in range(len(rn)):
            Q[s] = _corners(xz, tn[rn[s]])
            cq[s, 0], cq[s, 1], cq[s, 2] = _bounding_circle(Q[s])
        x0, z0, cell, nx, nz, start, in_cell = _grid(cq[:, 0], cq[:, 1], cp[:, 2].max() + cq[:, 2].max())
        poly, cut = np.empty((9, 2)), np.empty((9, 2))
        for s in range(len(ro)):
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
                            p[m], q[m], area[m] = tp_old[ro[s]], tp_new[rn[u]], a_
                            m += 1
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


def _lifted_points(xz, r):
    return lifted_points(xz, r, xz.mean(axis=0))


def _lower_triangles(hull, n, xz):
    tri = lower_ccw(hull.simplices, hull.equations[:, 2], n, xz, pg.LOWER_FACET_TOL)
    return regular.canonical(tri) if len(tri) else None


def _certain_triangles(xz, r):
    answer, tri = regular.regular_triangles(np.ascontiguousarray(xz, float), np.ascontiguousarray(r, float))
    if answer == regular.UNSURE:
        return False, None
    return True, (tri if answer == regular.DONE else None)


def _wall_rule(wall_vertices, n):
    """The arguments (owner, bits, n_discs) of ``_is_link`` for the flat_walls.WallVertices of n
    vertices (None: n discs)."""
    if wall_vertices is None:
        return NO_WALL_VERTICES, NO_WALL_VERTICES, n
    return wall_vertices.owner, wall_vertices.bits, wall_vertices.n


def _missing_pairs(xz, r, reach, tri, wall_vertices=None):
    return missing_pairs(xz, r, float(reach), tri, *_wall_rule(wall_vertices, len(r)))


def _faces(xz, r, tri, reach, a_min, wall_vertices=None):
    return faces(xz, r, tri, float(reach), a_min, *_wall_rule(wall_vertices, len(r)))


def _near_vertex_sets(old_net, U_old, old_valid, new_net, todo):
    n_vertices = new_net.n_discs + len(new_net.flat_walls)  # flat wall w is vertex N + w of the sets
    return near_vertex_sets(old_net.pore_vertex_ptr, old_net.pore_vertex_idx, np.asarray(old_valid, bool),
                            new_net.pore_vertex_ptr, new_net.pore_vertex_idx, todo, U_old, n_vertices)


def _pore_overlaps(old_net, new_net, xz):
    return pore_overlaps(old_net.tri, old_net.tri_pore, new_net.tri, new_net.tri_pore,
                         pg.vertex_positions(old_net, xz), new_net.n_pores)


BUILD = pg.BuildSteps(_lifted_points, _lower_triangles, _missing_pairs, _faces, links_and_corners, _certain_triangles)
REMESH = pore_water.RemeshSteps(_pore_overlaps, _near_vertex_sets, spread_to_neighbours)
