"""The regular (power) triangulation of discs, compiled, where it is certain: the triangles of
engines.model.pores.regular_triangulation (the lower hull of the lifted points that Qhull builds)
for a fraction of Qhull's time. No YADE.

``regular_triangles(xz, r)`` inserts the discs one by one, in the order of a grid of cells, into
a triangulation closed by a ghost vertex (each edge of the convex hull has a ghost triangle outside
it), each insertion restored to regular by flips of the edges around the new disc:

  - a real edge (a, b) between triangles (a, b, c) and (b, a, d) flips to (c, d) when d lies inside
    the power circle of (a, b, c): its lifted point (x, z, x^2 + z^2 - r^2) below their plane
    (``_power``);
  - a hull vertex between two ghost triangles leaves the hull where the hull is not convex there
    (``_orient``): a disc inserted outside the hull joins it;
  - a disc inside a triangle whose lifted point lies above its plane has an empty power cell: it is
    in no triangle, as in the lower hull.

Every decision is made only when the predicate is farther from zero than a bound far above its
round-off (``CERTAIN``, relative to the sum of the magnitudes of its terms), and at the end every
edge, hull vertex, triangle and hidden disc is checked again with the same bound: then the lower
hull is unique and the triangles are Qhull's. Anything closer to a tie than that (cocircular discs of
lattices, a disc on an inner edge or on another, a flip that needs a disc removed) answers
UNSURE and the caller builds the hull. Discs on a straight edge of the hull (a row of
wall discs) are exact ties of the orientation, settled by the lifted heights along the edge
(``_above_chord``).

The triangles come counter-clockwise, each from its smallest disc index, in lexicographic order
(engines.model.pores.canonical_triangles, the order of the hull's triangles too).
"""
import numba as nb
import numpy as np

from engines.compiled.kernels import _grid, _groups

jit = nb.njit(cache=True, nogil=True)
GHOST = -1
CERTAIN = 1e-10  # a predicate decides where it exceeds CERTAIN x the magnitudes of its terms
UNSURE, COLLINEAR, DONE = 0, 1, 2  # regular_triangles' answers


@jit
def _orient(x, z, a, b, c):
    """(twice the signed area of a, b, c (> 0: counter-clockwise), the magnitude of its terms)."""
    u, v = (x[b] - x[a]) * (z[c] - z[a]), (z[b] - z[a]) * (x[c] - x[a])
    return u - v, abs(u) + abs(v)


@jit
def _power(x, z, w, a, b, c, d):
    """(> 0 where the lifted point of d lies below the plane of those of a, b, c (counter-clockwise):
    d inside their power circle; the magnitude of its terms). w = r^2, the lift |p - p_d|^2 - w + w_d."""
    adx, adz, bdx, bdz, cdx, cdz = x[a] - x[d], z[a] - z[d], x[b] - x[d], z[b] - z[d], x[c] - x[d], z[c] - z[d]
    al = adx * adx + adz * adz - w[a] + w[d]
    bl = bdx * bdx + bdz * bdz - w[b] + w[d]
    cl = cdx * cdx + cdz * cdz - w[c] + w[d]
    det = adx * (bdz * cl - bl * cdz) - adz * (bdx * cl - bl * cdx) + al * (bdx * cdz - bdz * cdx)
    mag = (abs(adx) * (abs(bdz * cl) + abs(bl * cdz)) + abs(adz) * (abs(bdx * cl) + abs(bl * cdx))
           + abs(al) * (abs(bdx * cdz) + abs(bdz * cdx)))
    return det, mag


@jit
def _above_chord(x, z, w, a, m, b):
    """(> 0 where the lifted point of m, on the segment a-b, lies above the chord of those of a and b,
    so that m is in no triangle; the magnitude of its terms)."""
    ex, ez = x[b] - x[a], z[b] - z[a]
    L2 = ex * ex + ez * ez
    t = ((x[m] - x[a]) * ex + (z[m] - z[a]) * ez) / L2
    d = -t * (1.0 - t) * L2 - w[m] + (1.0 - t) * w[a] + t * w[b]
    return d, abs(t * (1.0 - t) * L2) + w[m] + abs(1.0 - t) * w[a] + abs(t) * w[b]


@jit
def _sure(value, magnitude):
    return abs(value) > CERTAIN * magnitude


@jit
def _point_back(tn, u, old, new):
    """In triangle u (>= 0), the neighbour pointer to ``old`` made to point to ``new``."""
    for k in range(3):
        if tn[u, k] == old:
            tn[u, k] = new
            return


@jit
def _set(tv, tn, t, a, b, c, na, nb_, nc):
    """Triangle t = (a, b, c) with neighbours opposite a, b, c."""
    tv[t, 0], tv[t, 1], tv[t, 2] = a, b, c
    tn[t, 0], tn[t, 1], tn[t, 2] = na, nb_, nc


@jit
def _ghost_at(tv, t):
    """The index of the ghost vertex in triangle t, or -1."""
    for k in range(3):
        if tv[t, k] == GHOST:
            return k
    return -1


@jit
def _locate(x, z, tv, tn, q, t, max_steps):
    """(triangle, where) for point q, walking from triangle t: where = 3 strictly inside a real
    triangle, k in 0..2 on its edge opposite vertex k, 4 outside the hull beyond the ghost triangle's
    edge, 5 on that hull edge strictly between its ends, -1 unsure (on a vertex, a walk too long)."""
    for step in range(max_steps):
        g = _ghost_at(tv, t)
        if g >= 0:
            a, b = tv[t, (g + 1) % 3], tv[t, (g + 2) % 3]
            o = _orient(x, z, a, b, q)[0]
            if o > 0:
                return t, 4
            if o == 0:
                s = (x[q] - x[a]) * (x[b] - x[a]) + (z[q] - z[a]) * (z[b] - z[a])
                L2 = (x[b] - x[a]) ** 2 + (z[b] - z[a]) ** 2
                if 0 < s < L2:
                    return t, 5
            t = tn[t, g]
            continue
        zero, moved = -1, False
        for i in range(3):
            k = (i + step) % 3  # a rotating first edge keeps the walk from cycling (max_steps bounds it)
            o = _orient(x, z, tv[t, (k + 1) % 3], tv[t, (k + 2) % 3], q)[0]
            if o < 0:
                t, moved = tn[t, k], True
                break
            if o == 0:
                if zero >= 0:
                    return t, -1  # on a vertex
                zero = k
        if not moved:
            return t, (3 if zero < 0 else zero)
    return t, -1


@jit
def _flip_due(x, z, w, tv, tn, t, k):
    """Is the edge of triangle t opposite its vertex k to be flipped: 1 yes, 0 no, -1 unsure."""
    u = tn[t, k]
    p0, p1, p2 = tv[t, k], tv[t, (k + 1) % 3], tv[t, (k + 2) % 3]
    o = tv[u, 0] + tv[u, 1] + tv[u, 2] - p1 - p2  # the apex of u across the edge (p1, p2)
    if p1 == GHOST or p2 == GHOST:  # two ghost triangles: is the hull vertex m between them reflex?
        a, m, b = (o, p2, p0) if p1 == GHOST else (p0, p1, o)  # the hull a -> m -> b, clockwise
        turn, mag = _orient(x, z, a, m, b)
        if turn == 0:  # a straight hull edge: m stays on it if its lifted point is below the chord
            d, dm = _above_chord(x, z, w, a, m, b)
            return -1 if d > 0 or not _sure(d, dm) else 0
        if not _sure(turn, mag):
            return -1
        return 1 if turn > 0 else 0  # a left turn: the flip makes (a, m, b) a triangle
    if p0 == GHOST or o == GHOST:  # an edge of the hull stays
        return 0
    det, mag = _power(x, z, w, p0, p1, p2, o)
    if not _sure(det, mag):
        return -1
    if det < 0:
        return 0
    for a, b in ((p1, o), (o, p2)):  # the flipped triangles (p0, p1, o), (p0, o, p2) must turn left
        turn, tmag = _orient(x, z, p0, a, b)
        if not (turn > 0 and _sure(turn, tmag)):
            return -1  # not convex: a disc would have to leave the triangulation
    return 1


@jit
def _flip(tv, tn, t, k):
    """Flip the edge of triangle t opposite its vertex k: t = (p0, p1, o), its neighbour u =
    (p0, o, p2) (the slots kept, their outer neighbours pointed back). Returns u."""
    u = tn[t, k]
    p0, p1, p2 = tv[t, k], tv[t, (k + 1) % 3], tv[t, (k + 2) % 3]
    n1, n2 = tn[t, (k + 1) % 3], tn[t, (k + 2) % 3]  # across (p2, p0) and (p0, p1)
    m = 0
    while tn[u, m] != t:
        m += 1
    o = tv[u, m]
    n3, n4 = tn[u, (m + 1) % 3], tn[u, (m + 2) % 3]  # across (p1, o) and (o, p2): u = (o, p2, p1)
    _set(tv, tn, t, p0, p1, o, n3, u, n2)
    _set(tv, tn, u, p0, o, p2, n4, n1, t)
    _point_back(tn, n3, u, t)
    _point_back(tn, n1, t, u)
    return u


@jit
def _restore(x, z, w, tv, tn, stack, top, apex):
    """Flip the edges on the stack (triangle, edge opposite vertex) until regular, pushing the two
    edges opposite the new disc ``apex`` after each flip. False when a decision is unsure."""
    while top > 0:
        top -= 1
        t, k = stack[top, 0], stack[top, 1]
        if tv[t, k] != apex:  # the triangle changed since: its edge opposite the disc is pushed again
            continue
        due = _flip_due(x, z, w, tv, tn, t, k)
        if due < 0:
            return False
        if due == 0:
            continue
        u = _flip(tv, tn, t, k)
        if top + 2 > len(stack):
            return False
        stack[top, 0], stack[top, 1] = t, 0   # t = (apex, p1, o): its edge (p1, o)
        stack[top + 1, 0], stack[top + 1, 1] = u, 0  # u = (apex, o, p2): its edge (o, p2)
        top += 2
    return True


@jit
def _regular_from(x, z, w, order):
    """The triangulation of the discs in ``order`` (answer, tv, tn, n_triangles, hidden mask): the
    first triangle, then each disc inserted where it lies (``_split_inside``, ``_split_beyond``,
    ``_split_on_hull``) and the triangulation restored to regular by flips (``_restore``)."""
    n = len(x)
    cap = 3 * n + 8
    tv = np.empty((cap, 3), np.int64)
    tn = np.empty((cap, 3), np.int64)
    hidden = np.zeros(n, np.bool_)
    answer, first = _first_triangle(x, z, order, tv, tn)
    if answer != DONE:
        return answer, tv, tn, 0, hidden
    m = 4
    stack = np.empty((4 * n + 16, 2), np.int64)
    last = 0
    for s in range(2, len(order)):
        if s == first:
            continue
        q = order[s]
        t, where = _locate(x, z, tv, tn, q, last, 4 * n + 16)
        if where < 0:
            return UNSURE, tv, tn, m, hidden
        if where == 3:  # inside a real triangle
            top = _split_inside(x, z, w, tv, tn, stack, t, q, m)
        elif where == 4:  # outside the hull, beyond the edge of the ghost triangle t
            top = _split_beyond(tv, tn, stack, t, q, m)
        else:  # on an edge: of the hull only (where 5: of ghost t; k: of real t, whose neighbour is a ghost)
            if where != 5:
                if _ghost_at(tv, tn[t, where]) < 0:
                    return UNSURE, tv, tn, m, hidden  # on an inner edge
                t = tn[t, where]
            top = _split_on_hull(x, z, w, tv, tn, stack, t, q, m)
        if top < 0:
            return UNSURE, tv, tn, m, hidden
        if top == 0:
            hidden[q] = True
            continue
        m += 2
        if not _restore(x, z, w, tv, tn, stack, top, q):
            return UNSURE, tv, tn, m, hidden
        last = t
    return DONE, tv, tn, m, hidden


@jit
def _first_triangle(x, z, order, tv, tn):
    """(answer, s): the first triangle (a, b, c) counter-clockwise, c = order[s] the first disc off
    the line of the first two, and its three ghosts (b, a, G), (c, b, G), (a, c, G), set as
    triangles 0-3 of tv, tn; answer UNSURE or COLLINEAR when there is none."""
    a, b = order[0], order[1]
    if x[a] == x[b] and z[a] == z[b]:
        return UNSURE, -1
    first = -1
    for s in range(2, len(order)):
        turn, mag = _orient(x, z, a, b, order[s])
        if turn != 0:
            if not _sure(turn, mag):
                return UNSURE, -1
            first = s
            break
    if first < 0:
        return COLLINEAR, -1
    c = order[first]
    if _orient(x, z, a, b, c)[0] < 0:
        b, c = c, b
    _set(tv, tn, 0, a, b, c, 2, 3, 1)
    _set(tv, tn, 1, b, a, GHOST, 3, 2, 0)
    _set(tv, tn, 2, c, b, GHOST, 1, 3, 0)
    _set(tv, tn, 3, a, c, GHOST, 2, 1, 0)
    return DONE, first


@jit
def _split_inside(x, z, w, tv, tn, stack, t, q, m):
    """Disc q inside the real triangle t (p0, p1, p2): hidden when its lifted point lies above the
    triangle's plane (returns 0), else three triangles around q, t and the new m, m + 1, put on
    ``stack`` (returns 3); -1: unsure."""
    p0, p1, p2 = tv[t, 0], tv[t, 1], tv[t, 2]
    det, mag = _power(x, z, w, p0, p1, p2, q)
    if not _sure(det, mag):
        return -1
    if det < 0:
        return 0
    n0, n1, n2 = tn[t, 0], tn[t, 1], tn[t, 2]
    _set(tv, tn, t, q, p1, p2, n0, m, m + 1)
    _set(tv, tn, m, q, p2, p0, n1, m + 1, t)
    _set(tv, tn, m + 1, q, p0, p1, n2, t, m)
    _point_back(tn, n1, t, m)
    _point_back(tn, n2, t, m + 1)
    for e, tri in enumerate((t, m, m + 1)):
        stack[e, 0], stack[e, 1] = tri, 0
    return 3


@jit
def _split_beyond(tv, tn, stack, t, q, m):
    """Disc q outside the hull, beyond the edge (p1, p2) of the ghost triangle t: the real triangle
    (q, p1, p2) in t and two ghosts m, m + 1 of the hull edges q -> p2, p1 -> q, put on ``stack``
    (returns 3)."""
    g = _ghost_at(tv, t)
    p1, p2 = tv[t, (g + 1) % 3], tv[t, (g + 2) % 3]
    real, n_after, n_before = tn[t, g], tn[t, (g + 1) % 3], tn[t, (g + 2) % 3]
    _set(tv, tn, t, q, p1, p2, real, m, m + 1)      # the real triangle (q, p1, p2)
    _set(tv, tn, m, q, p2, GHOST, n_after, m + 1, t)  # hull edge q -> p2
    _set(tv, tn, m + 1, q, GHOST, p1, n_before, t, m)  # hull edge p1 -> q
    _point_back(tn, n_after, t, m)
    _point_back(tn, n_before, t, m + 1)
    stack[0, 0], stack[0, 1] = t, 0
    stack[1, 0], stack[1, 1] = m, 0
    stack[2, 0], stack[2, 1] = m + 1, 0
    return 3


@jit
def _split_on_hull(x, z, w, tv, tn, stack, t, q, m):
    """Disc q on the hull edge p1 -> p2 of the ghost triangle t (G, p1, p2): hidden when it lies above
    the chord of the lifted heights (returns 0), else the real triangle (p2, p1, c) beyond the edge
    split in two at q and two ghosts, put on ``stack`` (returns 4); -1: unsure."""
    g = _ghost_at(tv, t)
    p1, p2 = tv[t, (g + 1) % 3], tv[t, (g + 2) % 3]  # the ghost (G, p1, p2) beyond the hull edge p1 -> p2
    d, dm = _above_chord(x, z, w, p1, q, p2)
    if not _sure(d, dm):
        return -1
    if d > 0:
        return 0
    real = tn[t, g]  # (p2, p1, c)
    r0 = 0
    while tn[real, r0] != t:
        r0 += 1
    c = tv[real, r0]
    n_c1, n_c2 = tn[real, (r0 + 1) % 3], tn[real, (r0 + 2) % 3]  # across (p1, c) and (c, p2)
    n_after, n_before = tn[t, (g + 1) % 3], tn[t, (g + 2) % 3]  # across (p2, G) and (G, p1)
    _set(tv, tn, real, q, c, p2, n_c2, t, m)         # (q, c, p2)
    _set(tv, tn, m, q, p1, c, n_c1, real, m + 1)     # (q, p1, c)
    _set(tv, tn, t, q, p2, GHOST, n_after, m + 1, real)  # hull edge q -> p2
    _set(tv, tn, m + 1, q, GHOST, p1, n_before, m, t)    # hull edge p1 -> q
    _point_back(tn, n_c1, real, m)
    _point_back(tn, n_before, t, m + 1)
    for e, tri in enumerate((real, m, t, m + 1)):
        stack[e, 0], stack[e, 1] = tri, 0
    return 4


@jit
def _all_certain(x, z, w, tv, tn, m, hidden):
    """The final checks: every real triangle counter-clockwise, every inner edge regular, every hull
    vertex convex (or on a straight hull edge below its chord) and every hidden disc inside a
    triangle and above its plane, each by more than the bound."""
    for t in range(m):
        g = _ghost_at(tv, t)
        if g < 0:
            turn, mag = _orient(x, z, tv[t, 0], tv[t, 1], tv[t, 2])
            if not (turn > 0 and _sure(turn, mag)):
                return False
        for k in range(3):
            u = tn[t, k]
            if u < t:
                continue  # each edge once
            if _flip_due(x, z, w, tv, tn, t, k) != 0:
                return False
    for q in np.flatnonzero(hidden):
        t, where = _locate(x, z, tv, tn, q, 0, 4 * len(x) + 16)
        if where == 3:
            det, mag = _power(x, z, w, tv[t, 0], tv[t, 1], tv[t, 2], q)
            if not (det < 0 and _sure(det, mag)):
                return False
        elif where == 5:
            g = _ghost_at(tv, t)
            d, dm = _above_chord(x, z, w, tv[t, (g + 1) % 3], q, tv[t, (g + 2) % 3])
            if not (d > 0 and _sure(d, dm)):
                return False
        else:
            return False
    return True


@jit
def canonical(tri):
    """Triangles (T, 3), each from its smallest vertex (the cyclic order kept), in lexicographic
    order: engines.model.pores.canonical_triangles."""
    out = np.empty_like(tri)
    for t in range(len(tri)):
        k = 0
        if tri[t, 1] < tri[t, k]:
            k = 1
        if tri[t, 2] < tri[t, k]:
            k = 2
        for j in range(3):
            out[t, j] = tri[t, (k + j) % 3]
    n = out.max() + 1 if len(out) else 1
    key = (out[:, 0] * n + out[:, 1]) * n + out[:, 2]
    return out[np.argsort(key)]


@jit
def _insertion_order(x, z, w):
    """The discs in the order of a grid of cells, column by column, every other column downwards
    (consecutive discs lie close: short walks), then, largest first, those whose centre lies inside
    a larger disc by more than their own radius: the only ones another disc can hide, which the
    flips cannot take out of the triangulation once in it."""
    n = len(x)
    gx0, gz0, cell, ncx, ncz, start, members = _grid(x, z, 2.0 / np.sqrt(n))
    cx = ((x - gx0) / cell).astype(np.int64)
    cz = ((z - gz0) / cell).astype(np.int64)
    reach = int(np.ceil(np.sqrt(w.max()) / cell))
    inside = np.zeros(n, np.bool_)
    for i in range(n):
        for gx in range(max(cx[i] - reach, 0), min(cx[i] + reach + 1, ncx)):
            for gz in range(max(cz[i] - reach, 0), min(cz[i] + reach + 1, ncz)):
                g = gx * ncz + gz
                for s in range(start[g], start[g + 1]):
                    j = members[s]
                    if (x[i] - x[j]) ** 2 + (z[i] - z[j]) ** 2 + w[i] < w[j]:
                        inside[i] = True
    key = np.where(cx % 2 == 0, cx * ncz + cz, cx * ncz + ncz - 1 - cz)
    key = np.where(inside, ncx * ncz, key)
    ptr, order = _groups(key, ncx * ncz + 1)
    last = order[ptr[-2]:]
    order[ptr[-2]:] = last[np.argsort(-w[last])]
    return order


@jit
def regular_triangles(xz, r):
    """(answer, triangles (T, 3)) of the regular triangulation of the discs at xz (N, 2) [m] with
    radii r (N,) [m]: DONE with the triangles (``canonical``), COLLINEAR (no triangle), or UNSURE:
    a decision was too close to a tie, build the hull."""
    n = len(r)
    empty = np.zeros((0, 3), np.int64)
    if n < 3:
        return COLLINEAR, empty
    x0, z0 = xz[:, 0].mean(), xz[:, 1].mean()
    scale = max(xz[:, 0].max() - xz[:, 0].min(), xz[:, 1].max() - xz[:, 1].min())
    if not scale > 0:
        return COLLINEAR, empty
    x, z, w = (xz[:, 0] - x0) / scale, (xz[:, 1] - z0) / scale, (r / scale) ** 2
    answer, tv, tn, m, hidden = _regular_from(x, z, w, _insertion_order(x, z, w))
    if answer != DONE:
        return answer, empty
    if not _all_certain(x, z, w, tv, tn, m, hidden):
        return UNSURE, empty
    real = np.empty((m, 3), np.int64)
    k = 0
    for t in range(m):
        if _ghost_at(tv, t) < 0:
            real[k] = tv[t]
            k += 1
    return DONE, canonical(real[:k])
