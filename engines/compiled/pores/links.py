"""Compiled twins of engines.model.pores.links: the links of eq 28 (with flat walls' feet and
edges) and the linked pairs that are no edge of the triangulation. No YADE."""
import numba as nb
import numpy as np

from engines.compiled.kernels import _grid, _groups, _within
from engines.compiled.pores.triangulation import _half_edges

jit = nb.njit(cache=True, nogil=True)


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
