"""Compiled twins of the re-meshing rules of engines.model.pore_water.pressures_by_rule: rule (b),
the old pores whose vertex sets contain or are contained in a new one's, and rule (c), the spread
to neighbours. No YADE."""
import numba as nb
import numpy as np

from engines.compiled.kernels import _groups

jit = nb.njit(cache=True, nogil=True)


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
