"""The pair list of the contact law on a grid of cells (engines.model.contact.ContactLaw._pairs_near):
``near_pairs``, the pairs within r_i + r_j + eps_m + skin (eq 26 and the list's skin), and the grid
and counting sort it is built on (``_grid``, ``_groups``, ``_within``, ``_grown``; engines.compiled.pores
and engines.compiled.regular use them too). No YADE."""
import numpy as np

from engines.compiled.kernels.common import _beyond, jit


@jit
def _groups(key, n_groups):
    """Counting sort: (ptr (n_groups + 1,), order) with order[ptr[g]:ptr[g + 1]] the indices of the
    entries of key == g, increasing."""
    ptr = np.zeros(n_groups + 1, np.int64)
    for g in key:
        ptr[g + 1] += 1
    for g in range(n_groups):
        ptr[g + 1] += ptr[g]
    fill = ptr[:-1].copy()
    order = np.empty(len(key), np.int64)
    for e in range(len(key)):
        order[fill[key[e]]] = e
        fill[key[e]] += 1
    return ptr, order


@jit
def _grid(x, z, cell):
    """Square cells of side >= cell over the points (x, z): (x0, z0, cell, nx, nz, start, members),
    the points of cell (gx, gz) being members[start[g]:start[g + 1]], g = gx nz + gz, where
    gx = floor((x - x0) / cell)."""
    x0, z0 = x.min(), z.min()
    nx = int((x.max() - x0) / cell) + 1
    nz = int((z.max() - z0) / cell) + 1
    while nx * nz > 4 * len(x) + 16:  # scattered points: fewer, larger cells
        cell *= 2.0
        nx = int((x.max() - x0) / cell) + 1
        nz = int((z.max() - z0) / cell) + 1
    start, members = _groups(((x - x0) / cell).astype(np.int64) * nz + ((z - z0) / cell).astype(np.int64), nx * nz)
    return x0, z0, cell, nx, nz, start, members


@jit
def _within(dx, dz, s):
    """np.hypot(dx, dz) <= s, the hypot (~20 ns) computed only where dx^2 + dz^2 is not ``_beyond`` s."""
    if _beyond(dx * dx + dz * dz, s):
        return False
    return np.hypot(dx, dz) <= s


@jit
def _grown(x, m):
    """x with room for twice its m entries."""
    out = np.empty(2 * m, x.dtype)
    out[:m] = x[:m]
    return out


@jit
def near_pairs(xz, r, mobile, eps_m, skin, old_i, old_j, old_state):
    """engines.model.contact.ContactLaw._pairs_near before its pair filter: the pairs (i, j), i < j,
    with a mobile disc and R_ij <= r_i + r_j + eps_m + skin [m], sorted by (i, j), and their
    state (m, 6): the row of the same pair in (old_i, old_j, old_state) (sorted by (i, j)), else
    zeros. A grid of cells of side 2 max(r) + eps_m + skin finds them."""
    n = len(r)
    x0, z0, cell, nx, nz, start, in_cell = _grid(xz[:, 0], xz[:, 1], 2.0 * r.max() + eps_m + skin)
    pi = np.empty(8 * n + 16, np.int64)
    pj = np.empty(8 * n + 16, np.int64)
    partners = np.empty(n, np.int64)  # those j > i of disc i
    m = 0
    for i in range(n):
        cx, cz = int((xz[i, 0] - x0) / cell), int((xz[i, 1] - z0) / cell)
        k = 0
        for gx in range(max(cx - 1, 0), min(cx + 2, nx)):
            for gz in range(max(cz - 1, 0), min(cz + 2, nz)):
                g = gx * nz + gz
                for s in range(start[g], start[g + 1]):
                    j = in_cell[s]
                    if j > i and (mobile[i] or mobile[j]) and \
                            _within(xz[j, 0] - xz[i, 0], xz[j, 1] - xz[i, 1], r[i] + r[j] + eps_m + skin):
                        partners[k] = j
                        k += 1
        partners[:k].sort()
        while m + k > len(pi):
            pi, pj = _grown(pi, m), _grown(pj, m)
        pi[m:m + k] = i
        pj[m:m + k] = partners[:k]
        m += k
    state = np.zeros((m, old_state.shape[1]))
    o = 0
    for p in range(m):  # both lists sorted by (i, j): one merge
        while o < len(old_i) and (old_i[o] < pi[p] or (old_i[o] == pi[p] and old_j[o] < pj[p])):
            o += 1
        if o < len(old_i) and old_i[o] == pi[p] and old_j[o] == pj[p]:
            state[p] = old_state[o]
    return pi[:m].copy(), pj[:m].copy(), state
