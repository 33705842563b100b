"""A slow, literal NumPy reference of the seed-000 model (Tarumi & Hakuno), for cross-checks.

Written from the paper's equations and the project's documented conventions (SPEC §2, the module
docstrings of engines.contact, engines.pore_geometry, engines.pore_water), WITHOUT importing those
modules, so that a bug in the fast core or the YADE path does not hide in the reference too.
Clarity over speed: the contact law runs over every disc pair, pores are found by the paper's
walk around the link graph, pressure forces are the arc integrals of eq 33 pore by pore.

Units are SI per unit thickness (SPEC §1): positions [m], forces [N], U and E_w [N/m], areas [m^2].
Every floating-point state array has the dtype chosen by the caller (float32, float64, longdouble);
only the pore *topology* (Delaunay candidates, faces) is decided in float64.

Step k = 0 .. n_steps - 1 at time t = k dt (the order shared with engines/pore_dem.py):
  a. du = x_t - x_{t-dt}, dpsi = psi_t - psi_{t-dt} (zero at k = 0).
  b. contact forces, eq 1-13, 26-27 (``ContactState.forces``).
  c. velocity adjustment of particles that became free, eq 18-24 (``separation_adjustment``),
     on the velocities v = du/dt; the adjusted velocity replaces v before step e.
  d. water (scene.water.enabled): pores built at k = 0 from x_0 and rebuilt at k > 0,
     k % rebuild_interval == 0, pressures inherited by rules (a)-(d) of §3.4(2); the water is
     advanced at k % water_interval == 0 by water_interval dt at the void areas and link states of
     x_t (eq 32, 38-43), then the pressure forces (eq 33) are recomputed from the new U = eq 32(W, A(x_t))
     and held until the next water step.
  e. F = contact + pressure - rho f pi r^2 g (+ rho_w pi r^2 g with water, eq 34b);
     v += F/m dt, x += v dt, omega += M/I dt, psi += omega dt (eq 14-17; eq 44 optional).
  f. moving walls: v_w += a(t) dt, x_w += v_w dt; other walls stay put.
  g. after the step, when (k + 1) % record_every == 0, a sample at t = (k + 1) dt: positions,
     block-mean U (eq 32 with the current W and the areas at the recorded positions), total water
     and the relative water-balance error.
"""
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import Delaunay, QhullError

from engines.trajectory import Trajectory

G0 = 9.80665                 # standard gravity for records given in g [m/s^2]
DEGENERATE_FRACTION = 1e-4   # a face with void area <= this x mean(pi r^2) at build is closed (no pore)
PARTICLE, BOTTOM, LEFT, RIGHT = 0, 1, 2, 3   # Packing.group codes


# ------------------------------------------------------------------------------------------------
# Contact law (eq 1-13, 26-27)
# ------------------------------------------------------------------------------------------------
class ContactState:
    """The contact law over every pair of discs except wall-wall pairs (no neighbour list).

    Per pair (i, j), i < j, with n from i to j: touching (delta = r_i + r_j + eps_m - R >= 0,
    eq 1, 26), the accumulated approach u_n [m], the elastic forces e_n, e_s [N] after eq 6, 10, 11,
    and the approach velocity at first touch vn_coll [m/s] (eq 20-21) for eq 19.
    """

    def __init__(self, settings, r, group, dtype):
        self.s = settings
        self.dtype = dtype
        n = len(r)
        i, j = np.triu_indices(n, 1)
        keep = (group[i] == PARTICLE) | (group[j] == PARTICLE)  # wall-wall pairs are ignored
        self.i, self.j = i[keep], j[keep]
        self.r = np.asarray(r, dtype)
        m = len(self.i)
        self.touching = np.zeros(m, bool)
        self.u_n = np.zeros(m, dtype)
        self.e_n = np.zeros(m, dtype)
        self.e_s = np.zeros(m, dtype)
        self.f_n = np.zeros(m, dtype)
        self.vn_coll = np.zeros(m, dtype)
        self.kn, self.eta_n, self.ks, self.eta_s = (dtype(v) for v in (settings.kn, settings.eta_n, settings.ks, settings.eta_s))
        self.mu, self.f_max, self.eps_m = dtype(settings.mu), dtype(settings.f_max), dtype(settings.eps_m)

    def forces(self, x, du, dpsi, dt):
        """Contact forces (N, 2) [N] and moments (N,) [N m, counter-clockwise] at positions x.

        du (N, 2) [m] and dpsi (N,) [rad] are the increments of the last step (eq 17); du/dt are
        the velocities. Returns (F, M, events), events = [(i, j, n, Vn_ij)] for the pairs that
        touched at the previous step and do not now (n the unit vector from i to j, Vn_ij the
        approach velocity at their first touch, eq 20-21).
        """
        i, j, r, dtype = self.i, self.j, self.r, self.dtype
        dx = x[j, 0] - x[i, 0]
        dz = x[j, 1] - x[i, 1]
        R = np.sqrt(dx * dx + dz * dz)                      # eq 1b
        cos_a, sin_a = dx / R, dz / R                       # eq 2: cos a = -(x_i - x_j)/R
        delta = r[i] + r[j] + self.eps_m - R
        now = delta >= 0                                    # eq 1a, 26
        new = now & ~self.touching
        dui = du[i] - du[j]
        dun = dui[:, 0] * cos_a + dui[:, 1] * sin_a                                   # eq 3a
        dus = -dui[:, 0] * sin_a + dui[:, 1] * cos_a + r[i] * dpsi[i] + r[j] * dpsi[j]  # eq 3b

        u_n = np.where(new, delta, self.u_n + dun)          # the overlap, from first touch on
        spring = self.s.spring
        if spring in ("a", "b"):
            e_n = self.kn * u_n                             # eq 4a, 5a, 25
        elif spring == "c":
            e_n = np.minimum(self.kn * u_n, self.f_max)     # eq 27 on the elastic path
        else:
            e_n = np.minimum(np.where(new, self.kn * delta, self.e_n + self.kn * dun), self.f_max)  # eq 5a, 27
        d_n = self.eta_n * dun / dt                         # eq 4b, 5b
        e_s = np.where(new, dtype(0), self.e_s) + self.ks * dus   # eq 8a, 9a
        d_s = self.eta_s * dus / dt                         # eq 8b, 9b

        off = (e_n < 0) | ~now                              # eq 6, 10 (and nothing out of reach)
        e_n, d_n = np.where(off, dtype(0), e_n), np.where(off, dtype(0), d_n)
        e_s, d_s = np.where(off, dtype(0), e_s), np.where(off, dtype(0), d_s)
        slip = np.abs(e_s) > self.mu * e_n                  # eq 11
        e_s = np.where(slip, self.mu * e_n * np.sign(e_s), e_s)
        d_s = np.where(slip, dtype(0), d_s)
        f_n, f_s = e_n + d_n, e_s + d_s                     # eq 7, 12

        n = len(r)
        fx = -f_n * cos_a + f_s * sin_a                     # eq 13a, on i
        fz = -f_n * sin_a - f_s * cos_a                     # eq 13b, on i
        F = np.zeros((n, 2), dtype)
        M = np.zeros(n, dtype)
        np.add.at(F[:, 0], i, fx)
        np.add.at(F[:, 1], i, fz)
        np.add.at(F[:, 0], j, -fx)                          # j gets the opposite force
        np.add.at(F[:, 1], j, -fz)
        np.add.at(M, i, -r[i] * f_s)                        # eq 13c
        np.add.at(M, j, -r[j] * f_s)

        events = [(int(i[p]), int(j[p]), np.array([cos_a[p], sin_a[p]]), self.vn_coll[p])
                  for p in np.flatnonzero(self.touching & ~now)]
        v = du / dt
        vn_i = v[i, 0] * cos_a + v[i, 1] * sin_a            # eq 20a
        vn_j = -v[j, 0] * cos_a - v[j, 1] * sin_a           # eq 20b
        zero = dtype(0)
        self.vn_coll = np.where(new, vn_i + vn_j, np.where(now, self.vn_coll, zero))   # eq 21, at first touch
        self.touching = now
        self.u_n = np.where(now, u_n, zero)
        self.e_n = np.where(now, e_n, zero)
        self.e_s = np.where(now, e_s, zero)
        self.f_n = np.where(now, f_n, zero)
        return F, M, events

    def touch_count(self, n):
        """Number of partners each disc touches now."""
        t = self.touching
        return np.bincount(self.i[t], minlength=n) + np.bincount(self.j[t], minlength=n)


# ------------------------------------------------------------------------------------------------
# Velocity adjustment at separation (eq 18-24, Fig. 3)
# ------------------------------------------------------------------------------------------------
def separation_adjustment(events, touching_now, v, mass, mobile, e):
    """New velocities {disc: (2,) [m/s]} of particles that became free this step (eq 18-24).

    ``events``: (i, j, n, Vn_ij) for each pair that touched at the previous step and does not now,
    n the unit vector from i to j at separation and Vn_ij the approach velocity at first touch.
    ``touching_now`` (N,) bool; ``v`` (N, 2) current velocities du/dt; ``e`` the restitution.

    Vn_a = v_a . n_ab, Vn_b = -v_b . n_ab (eq 20, approach positive); a pair is adjusted only when
    it separates faster than restitution allows, -(Vn'_a + Vn'_b) > e Vn_ab > 0 (eq 18).
      (d) a and b were touching only each other and both are free: Rk_a, Rk_b from
          Rk_a Vn'_a + Rk_b Vn'_b = -e Vn_ab (eq 24a) and the normal momentum of the pair at
          separation kept (eq 24b), then eq 23 for both.
      otherwise, in rounds: a free disc is adjusted against its *reference* partners - discs that are
      not free (walls, discs still touching), or free discs adjusted in an earlier round - with
      Rk_a = (-e Vn_ab - Vn'_b)/Vn'_a (eq 22), the smallest Rk_a of those pairs and eq 23 along that
      pair's normal: (a) one partner, (b) several, (c) a free partner with other, non-free partners
      is adjusted first (round 1) and the disc that left only it follows against its new velocity.
    Free discs with no reference (a free cluster of three or more) are not adjusted.
    """
    left = {}
    for i, j, n, vn in events:
        left.setdefault(i, []).append((j, n, vn))
        left.setdefault(j, []).append((i, -n, vn))
    free = {d for d in left if mobile[d] and not touching_now[d]}
    vel = {d: np.array(v[d]) for d in left}
    done = set()

    def normal_velocities(a, b, n):
        return vel[a] @ n, -(vel[b] @ n)            # eq 20

    for a in sorted(free):                           # (d)
        if a in done or len(left[a]) != 1:
            continue
        b, n, vn = left[a][0]
        if b not in free or len(left[b]) != 1:
            continue
        done |= {a, b}
        vn_a, vn_b = normal_velocities(a, b, n)
        if not -(vn_a + vn_b) > e * vn > 0:          # eq 18
            continue
        target = -e * vn                             # eq 19: Vn''_ab
        p = mass[a] * vn_a - mass[b] * vn_b          # eq 24b
        new_a = (p + mass[b] * target) / (mass[a] + mass[b])   # Rk_a Vn'_a
        new_b = target - new_a                       # eq 24a: Rk_b Vn'_b
        vel[a] = vel[a] - (vn_a - new_a) * n         # eq 23 for a
        vel[b] = vel[b] + (vn_b - new_b) * n         # eq 23 for b (its normal is -n)

    while True:                                      # (a), (b), then (c)
        ref = lambda d: d not in free or d in done
        ready = [a for a in sorted(free - done) if any(ref(b) for b, _, _ in left[a])]
        if not ready:
            break
        adjusted = {}
        for a in ready:
            best = None
            for b, n, vn in left[a]:
                if not ref(b):
                    continue
                vn_a, vn_b = normal_velocities(a, b, n)
                if vn_a == 0 or not -(vn_a + vn_b) > e * vn > 0:   # eq 18
                    continue
                rk = (-e * vn - vn_b) / vn_a                         # eq 22
                if best is None or rk < best[0]:
                    best = (rk, vn_a, n)
            if best is not None:
                rk, vn_a, n = best
                adjusted[a] = vel[a] - (1 - rk) * vn_a * n           # eq 23
        vel.update(adjusted)
        done |= set(ready)
    return {d: vel[d] for d in done if mobile[d]}


# ------------------------------------------------------------------------------------------------
# Pores (§3.1, eq 28-31)
# ------------------------------------------------------------------------------------------------
@dataclass
class Pores:
    """Topology of the pores between two rebuilds.

    A pore is a bounded face of the planar graph of links (Delaunay edges of the centres passing
    eq 28), found by the paper's walk (at each disc, turn to the next link clockwise), so its
    boundary runs counter-clockwise with the pore on the left. Per pore (Np pores):
      half-edges he_pore, he_a, he_b: boundary links a -> b;
      corners corner_pore, corner_disc, corner_prev, corner_next: disc d reached from prev, left to next;
      rattlers rattler_pore, rattler_disc: unlinked discs inside (their whole area is not void);
      vertex_sets (frozenset of discs), surface / bottom / side (bool arrays), neighbours (sets).
    Links (L, 2) i < j with the pore on their left / right of i -> j (-1: outer or closed face);
    throats (T, 2) pairs of distinct pores sharing link throat_link (T,).
    a_min: faces with void area <= a_min at build are closed (not pores); pores whose area falls
    to <= a_min later keep their water but exchange none.
    """

    n_pores: int = 0
    he_pore: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    he_a: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    he_b: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    corner_pore: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    corner_disc: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    corner_prev: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    corner_next: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    rattler_pore: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    rattler_disc: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    links: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), int))
    throats: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), int))
    throat_link: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    surface: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    bottom: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    side: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    vertex_sets: list = field(default_factory=list)
    neighbours: list = field(default_factory=list)
    a_min: float = 0.0


def _direction(x, a, b):
    """Angle of the direction a -> b in [0, 2 pi) (eq 30-31; arctan2 is their quadrant-resolved
    inverse, accurate near the axes where eq 31's arcsin/arccos are not)."""
    return np.mod(np.arctan2(x[b, 1] - x[a, 1], x[b, 0] - x[a, 0]), 2 * np.pi)


def corner_angles(x, disc, prev, nxt):
    """Interior angle [rad] at disc d of the boundary prev -> d -> next (eq 29):
    theta = theta_(d->prev) - theta_(d->next), + 2 pi if negative. At the end of a dangling link
    (prev = next) the pore wraps the whole disc: theta = 2 pi."""
    two_pi = 2 * np.arctan2(x.dtype.type(0), x.dtype.type(-1))
    theta = _direction(x, disc, prev) - _direction(x, disc, nxt)       # eq 29a
    theta = np.where(theta < 0, theta + two_pi, theta)                   # eq 29b
    return np.where(prev == nxt, two_pi, theta)


def build_pores(x, r, group, eps_m, l_m):
    """Links (eq 28) and pores (§3.1) of discs at x (N, 2) [m], radii r [m], Packing groups.

    The topology is decided in float64. Fewer than three discs or collinear centres: no pores.
    """
    x = np.asarray(x, np.float64)
    r = np.asarray(r, np.float64)
    n = len(r)
    a_min = DEGENERATE_FRACTION * float(np.mean(np.pi * r**2)) if n else 0.0
    if n < 3:
        return Pores(a_min=a_min)
    try:
        dl = Delaunay(x)
    except QhullError:
        return Pores(a_min=a_min)
    tris = []
    for t in dl.simplices.tolist():               # counter-clockwise corners
        p0, p1, p2 = x[t[0]], x[t[1]], x[t[2]]
        ccw = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]) > 0
        tris.append(t if ccw else [t[0], t[2], t[1]])

    def is_link(a, b):                            # eq 28
        return r[a] + r[b] + eps_m + l_m >= np.hypot(*(x[b] - x[a]))

    edge_tri = {}                                 # directed edge -> triangle on its left
    for k, (a, b, c) in enumerate(tris):
        for e in ((a, b), (b, c), (c, a)):
            edge_tri[e] = k
    links = sorted({(min(e), max(e)) for e in edge_tri if is_link(*e)})
    link_set = set(links)

    # Faces: triangles joined across non-link edges; OUT (= len(tris)) is outside the hull.
    out = len(tris)
    parent = list(range(out + 1))

    def find(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for (a, b), k in edge_tri.items():
        if (min(a, b), max(a, b)) not in link_set:
            parent[find(k)] = find(edge_tri.get((b, a), out))
    outer = find(out)

    def face_left(a, b):
        return find(edge_tri[(a, b)]) if (a, b) in edge_tri else outer

    # The paper's walk: from a -> b, go on to the neighbour of b next clockwise from a.
    around = {d: [] for d in range(n)}
    for a, b in links:
        around[a].append(b)
        around[b].append(a)
    for d, nb in around.items():
        nb.sort(key=lambda b: np.arctan2(x[b, 1] - x[d, 1], x[b, 0] - x[d, 0]))

    def next_half_edge(a, b):
        nb = around[b]
        return b, nb[nb.index(a) - 1]

    cycles_of_face = {}
    seen = set()
    for a, b in links:
        for h0 in ((a, b), (b, a)):
            if h0 in seen:
                continue
            cycle, h = [], h0
            while h not in seen:
                seen.add(h)
                cycle.append(h)
                h = next_half_edge(*h)
            faces = {face_left(*he) for he in cycle}
            if len(faces) != 1:
                raise RuntimeError(f"walk from {h0} crosses faces {faces}: links are not planar")
            cycles_of_face.setdefault(faces.pop(), []).append(cycle)
    rattlers_of_face = {}
    for d in range(n):
        if not around[d]:
            k = next((k for k, t in enumerate(tris) if d in t), None)
            if k is not None:
                rattlers_of_face.setdefault(find(k), []).append(d)

    # Void area at build (eq 29) to close degenerate faces; then number the pores.
    def void_area(face):
        cycles = cycles_of_face[face]
        he = np.array([h for c in cycles for h in c])
        poly = 0.5 * np.sum(x[he[:, 0], 0] * x[he[:, 1], 1] - x[he[:, 1], 0] * x[he[:, 0], 1])
        cd, cp, cn = _corners(cycles)
        sectors = 0.5 * np.sum(corner_angles(x, cd, cp, cn) * r[cd] ** 2)
        rat = rattlers_of_face.get(face, [])
        return poly - sectors - np.pi * np.sum(r[rat] ** 2)

    bounded = sorted((f for f in cycles_of_face if f != outer), key=lambda f: min(min(c) for c in cycles_of_face[f]))
    open_faces = [f for f in bounded if void_area(f) > a_min]
    pore_of = {f: p for p, f in enumerate(open_faces)}
    n_p = len(open_faces)

    he_pore, he_a, he_b, c_pore, c_disc, c_prev, c_next, r_pore, r_disc = ([] for _ in range(9))
    vertex_sets = []
    for p, f in enumerate(open_faces):
        cycles = cycles_of_face[f]
        for c in cycles:
            for a, b in c:
                he_pore.append(p), he_a.append(a), he_b.append(b)
        cd, cp, cn = _corners(cycles)
        c_pore += [p] * len(cd)
        c_disc += cd.tolist()
        c_prev += cp.tolist()
        c_next += cn.tolist()
        rat = rattlers_of_face.get(f, [])
        r_pore += [p] * len(rat)
        r_disc += rat
        vertex_sets.append(frozenset(int(a) for c in cycles for a, _ in c) | frozenset(rat))

    link_arr = np.array(links, int).reshape(-1, 2)
    sides = [(pore_of.get(face_left(a, b), -1), pore_of.get(face_left(b, a), -1)) for a, b in links]
    throats, throat_link = [], []
    surface = np.zeros(n_p, bool)
    wall = np.asarray(group) != PARTICLE
    for l, ((a, b), (pl, pr)) in enumerate(zip(links, sides)):
        if pl >= 0 and pr >= 0 and pl != pr:
            throats.append((pl, pr))
            throat_link.append(l)
        if not (wall[a] and wall[b]):             # a wall-wall link is a wall element, not surface
            fl, fr = face_left(a, b), face_left(b, a)
            if fl == outer and pr >= 0:
                surface[pr] = True
            if fr == outer and pl >= 0:
                surface[pl] = True
    neighbours = [set() for _ in range(n_p)]
    for p, q in throats:
        neighbours[p].add(q)
        neighbours[q].add(p)
    g = np.asarray(group)
    arr = lambda v: np.array(v, int)
    return Pores(
        n_pores=n_p, he_pore=arr(he_pore), he_a=arr(he_a), he_b=arr(he_b),
        corner_pore=arr(c_pore), corner_disc=arr(c_disc), corner_prev=arr(c_prev), corner_next=arr(c_next),
        rattler_pore=arr(r_pore), rattler_disc=arr(r_disc), links=link_arr,
        throats=arr(throats).reshape(-1, 2), throat_link=arr(throat_link), surface=surface,
        bottom=np.array([any(g[v] == BOTTOM for v in vs) for vs in vertex_sets], bool).reshape(-1),
        side=np.array([any(g[v] in (LEFT, RIGHT) for v in vs) for vs in vertex_sets], bool).reshape(-1),
        vertex_sets=vertex_sets, neighbours=neighbours, a_min=a_min,
    )


def _corners(cycles):
    """(disc, prev, next) of every corner of the boundary cycles: half-edge (prev -> d) then (d -> next)."""
    d, p, q = [], [], []
    for c in cycles:
        for k, (a, b) in enumerate(c):
            d.append(b), p.append(a), q.append(c[(k + 1) % len(c)][1])
    return np.array(d, int), np.array(p, int), np.array(q, int)


@dataclass
class PoreGeometry:
    """Pores measured at one set of positions: polygon area, void area A (eq 29) [m^2] per pore,
    interior angle per corner [rad], area-weighted polygon centroid (Np, 2) [m], and per link its
    length R [m] and contact state (eq 43b: r_k + r_l + eps_m >= R)."""

    polygon_area: np.ndarray
    void_area: np.ndarray
    corner_angle: np.ndarray
    centroid: np.ndarray
    link_contact: np.ndarray


def measure(pores, x, r, eps_m):
    """Areas (eq 29), corner angles and link states of ``pores`` at positions x (in x's dtype)."""
    dtype = x.dtype.type
    n_p = pores.n_pores
    # shoelace relative to one vertex of each pore: the same area, without the cancellation of
    # absolute coordinates (condition number ~ (|x| / pore size)^2)
    anchor = np.zeros((n_p, 2), x.dtype)
    anchor[pores.he_pore[::-1]] = x[pores.he_a[::-1]]
    o = anchor[pores.he_pore]
    pa, pb = x[pores.he_a] - o, x[pores.he_b] - o
    cross = pa[:, 0] * pb[:, 1] - pb[:, 0] * pa[:, 1]
    poly = np.zeros(n_p, dtype)
    np.add.at(poly, pores.he_pore, cross / 2)                            # shoelace
    cx, cz = np.zeros(n_p, dtype), np.zeros(n_p, dtype)
    np.add.at(cx, pores.he_pore, (pa[:, 0] + pb[:, 0]) * cross)
    np.add.at(cz, pores.he_pore, (pa[:, 1] + pb[:, 1]) * cross)
    with np.errstate(invalid="ignore", divide="ignore"):
        centroid = anchor + np.column_stack([cx, cz]) / (6 * poly[:, None])
    theta = corner_angles(x, pores.corner_disc, pores.corner_prev, pores.corner_next)
    sectors = np.zeros(n_p, dtype)
    np.add.at(sectors, pores.corner_pore, theta * r[pores.corner_disc] ** 2 / 2)   # eq 29
    pi = 2 * np.arctan2(dtype(1), dtype(0))
    np.add.at(sectors, pores.rattler_pore, pi * r[pores.rattler_disc] ** 2)
    k, l = pores.links[:, 0], pores.links[:, 1]
    R = np.sqrt((x[l, 0] - x[k, 0]) ** 2 + (x[l, 1] - x[k, 1]) ** 2)
    contact = r[k] + r[l] + dtype(eps_m) >= R                            # eq 43b
    return PoreGeometry(poly, poly - sectors, theta, centroid, contact)


def pressure_forces(pores, x, r, U, theta):
    """Force (N, 2) [N] of the pore pressures U (Np,) [N/m] on the discs (eq 33).

    Pore by pore, on the arc of each corner disc d inside it, from alpha_1 = direction d -> next
    counter-clockwise to alpha_2 = alpha_1 + theta (the interior angle, eq 29):
      F_x = int -U r cos(a) da = -U r (sin a2 - sin a1),  F_z = int -U r sin(a) da = U r (cos a2 - cos a1).
    Rattlers are wrapped by one pressure: no net force. No torque (the pressure acts through the centre).
    """
    d = pores.corner_disc
    a1 = _direction(x, d, pores.corner_next)
    a2 = a1 + theta
    u_r = U[pores.corner_pore] * r[d]
    F = np.zeros(x.shape, x.dtype)
    np.add.at(F[:, 0], d, -u_r * (np.sin(a2) - np.sin(a1)))              # eq 33a
    np.add.at(F[:, 1], d, u_r * (np.cos(a2) - np.cos(a1)))               # eq 33b
    return F


# ------------------------------------------------------------------------------------------------
# Pore water (§3.2-3.4, eq 32-46)
# ------------------------------------------------------------------------------------------------
def pore_pressure(W, A, E_w):
    """U = E_w (W - A) / W [N/m] (eq 32)."""
    return E_w * (W - A) / W


class Water:
    """Water areas W (Np,) [m^2] of the pores and their cumulative budget [m^2]."""

    def __init__(self, pores, A, settings, dtype):
        self.pores, self.s, self.dtype = pores, settings, dtype
        self.E_w, self.k1, self.k2, self.k3, self.q_w = (dtype(v) for v in (settings.E_w, settings.k1,
                                                                              settings.k2, settings.k3, settings.q_w))
        self.W = A.copy()                                   # after packing: W = A, U = 0
        self.initial = np.sum(self.W)                       # the budget [m^2], in the run's dtype too
        self.inflow = self.surface_out = self.side_out = self.remesh_change = dtype(0)
        self.A_used = A.copy()                              # eq 45: the area used at the last water step
        self.q_used = None                                  # eq 46: the throat flows used at the last step

    def total(self):
        return float(np.sum(self.W))

    def balance_error(self):
        """|sum W - (initial + inflow - outflows + re-meshing change)| / initial water."""
        expected = self.initial + self.inflow - self.surface_out - self.side_out + self.remesh_change
        return float(abs(np.sum(self.W) - expected) / max(self.initial, 1e-300))

    def flows(self, A, contact):
        """Throat flows q (T,) from pore 0 to pore 1 of each throat, surface and side outflow, inflow
        (Np,) [m^2/s], and the stability bound of the explicit step [s] (eq 38-43)."""
        pores, W, E_w, zero = self.pores, self.W, self.E_w, self.dtype(0)
        U = pore_pressure(W, A, E_w)                        # eq 32
        open_ = A > pores.a_min                             # a pinched pore exchanges nothing
        p, q = pores.throats[:, 0], pores.throats[:, 1]
        both = open_[p] & open_[q]
        k = np.where(contact[pores.throat_link], self.k2, self.k1)          # eq 43
        A_pq = W[p] * W[q] / np.where(both, A[p] + A[q], 1)                 # eq 40 (W_i W_j, not W' W_j)
        i_pq = (U[p] - U[q]) / E_w                                           # eq 39
        q_t = np.where(both, k * A_pq * i_pq, zero)                          # eq 41
        drained = pores.side if self.s.sides == "drained" else np.zeros_like(pores.side)
        q_surface = np.where(open_ & pores.surface, self.k1 * W * U / E_w, zero)   # outside at U = 0
        q_side = np.where(open_ & drained, self.k3 * W * U / E_w, zero)
        q_in = np.where(pores.bottom, self.q_w, zero)                        # §5.1
        # explicit stability (Gershgorin): dt <= 2 / max (2 sum g + g_b) / c, c = W^2 / (E_w A)
        g = np.where(both, k * A_pq / E_w, zero)
        g_sum = np.zeros(pores.n_pores, self.dtype)
        np.add.at(g_sum, p, g)
        np.add.at(g_sum, q, g)
        g_b = np.where(open_ & pores.surface, self.k1 * W / E_w, zero) + np.where(open_ & drained, self.k3 * W / E_w, zero)
        rate = np.where(open_, (2 * g_sum + g_b) * E_w * A / W**2, zero)
        limit = 2 / float(np.max(rate)) if pores.n_pores and np.max(rate) > 0 else np.inf
        return q_t, q_surface, q_side, q_in, limit

    def advance(self, dt, A, contact):
        """Advance W by dt [s] at void areas A and link states (eq 42); eq 45-46 if smoothing."""
        if self.s.smoothing:                                # eq 45: [A]_t = ([A]_{t-dt} + [A']_t) / 2
            A = (self.A_used + A) / 2
            self.A_used = A
        flows = self.flows(A, contact)
        n_sub = 1
        if dt > flows[4]:
            if not self.s.substep:
                raise ValueError(f"water step {dt:.3e} s exceeds the explicit Darcy limit {flows[4]:.3e} s")
            n_sub = int(np.ceil(dt / flows[4]))
        h = self.dtype(dt / n_sub)
        for sub in range(n_sub):
            q_t, q_surface, q_side, q_in, _ = flows if sub == 0 else self.flows(A, contact)
            if self.s.smoothing:                            # eq 46: [q]_t = ([q]_{t-dt} + [q']_t) / 2
                q_t = q_t if self.q_used is None else (self.q_used + q_t) / 2
                self.q_used = q_t
            out = q_surface + q_side - q_in
            np.add.at(out, self.pores.throats[:, 0], q_t)
            np.add.at(out, self.pores.throats[:, 1], -q_t)
            W = self.W - out * h                            # eq 42 (outflow positive)
            if np.any(W <= 0):
                raise ValueError(f"water area of pore {int(np.argmax(W <= 0))} fell to <= 0 in a step of {h:.3e} s")
            self.W = W
            self.inflow += np.sum(q_in) * h
            self.surface_out += np.sum(q_surface) * h
            self.side_out += np.sum(q_side) * h

    def remesh(self, new_pores, A_new, A_old):
        """Move the water onto rebuilt pores keeping U continuous (§3.4(2)); W from eq 32."""
        U_old = pore_pressure(self.W, A_old, self.E_w)
        U_new = inherit_pressures(self.pores, U_old, A_old > self.pores.a_min, new_pores)
        W_new = A_new * self.E_w / (self.E_w - np.asarray(U_new, self.dtype))   # eq 32 solved for W
        self.remesh_change += np.sum(W_new) - np.sum(self.W)
        self.pores, self.W, self.A_used, self.q_used = new_pores, W_new, A_new.copy(), None


def inherit_pressures(old, U_old, old_valid, new):
    """U of each new pore by the rules of §3.4(2), in the project's reading:
    (a) the U of the old pore with the same vertex set; else (b) the mean U of the old pores whose
    vertex set contains or is contained in the new one (split / merge); else (c) the mean U of the
    neighbouring new pores already assigned (the outer face counts as one neighbour at U = 0 for a
    surface pore), in rounds until nothing changes; else (d) U = 0. Old pores pinched to A <= a_min
    pass nothing on."""
    valid = [p for p in range(old.n_pores) if old_valid[p]]
    by_set = {old.vertex_sets[p]: p for p in valid}
    U = [None] * new.n_pores
    for p, vs in enumerate(new.vertex_sets):
        if vs in by_set:                                                    # (a)
            U[p] = float(U_old[by_set[vs]])
            continue
        near = [q for q in valid if old.vertex_sets[q] <= vs or vs <= old.vertex_sets[q]]
        if near:                                                            # (b)
            U[p] = float(np.mean([float(U_old[q]) for q in near]))
    while True:                                                             # (c)
        assign = {}
        for p in range(new.n_pores):
            known = [U[q] for q in new.neighbours[p] if U[q] is not None]
            if U[p] is None and known:
                assign[p] = sum(known) / (len(known) + bool(new.surface[p]))
        if not assign:
            break
        for p, u in assign.items():
            U[p] = u
    return [0.0 if u is None else u for u in U]                             # (d)


# ------------------------------------------------------------------------------------------------
# The model
# ------------------------------------------------------------------------------------------------
def input_acceleration(loading):
    """a(t) [m/s^2] of the moving walls: amplitude cos(2 pi f t), or the record (time * time_scale,
    acc_g * G0 * amplitude_scale) interpolated linearly (0 after its end); None for no loading."""
    if loading.type == "none":
        return None
    if loading.type == "cosine":
        return lambda t: loading.amplitude * np.cos(2 * np.pi * loading.frequency * t)
    rec = np.loadtxt(loading.record, comments="#", ndmin=2)
    t_rec, a_rec = rec[:, 0] * loading.time_scale, rec[:, 1] * G0 * loading.amplitude_scale
    return lambda t: float(np.interp(t, t_rec, a_rec, right=0.0))


class ReferenceModel:
    """State of one run of the reference; ``step`` advances it by one dt (see the module docstring).

    Attributes in the run's dtype: x, v (N, 2) [m, m/s], psi, omega (N,) [rad, rad/s], mass,
    inertia (N,) [kg/m, kg m]. ``contact`` (ContactState), ``pores`` / ``water`` (None when dry).
    """

    def __init__(self, scene, packing, dtype=np.float64):
        dt_ = np.dtype(dtype).type
        self.dtype, self.scene, self.packing = dt_, scene, packing
        self.group = np.asarray(packing.group)
        self.mobile = self.group == PARTICLE
        self.r = np.asarray(packing.r, dt_)
        self.x = np.asarray(packing.xz, dt_).copy()
        self.x_prev = self.x.copy()
        self.v = np.zeros_like(self.x)
        self.psi = np.zeros_like(self.r)
        self.psi_prev = self.psi.copy()
        self.omega = np.zeros_like(self.r)
        self.dt = dt_(scene.numerics.dt)
        self.k = 0
        pi = 2 * np.arctan2(dt_(1), dt_(0))
        mat = scene.material
        self.mass = dt_(mat.rho) * np.asarray(packing.density_factor, dt_) * pi * self.r**2   # eq 15a per unit thickness
        self.inertia = self.mass * self.r**2 / 2                                                # eq 15b
        if self.mobile.any():
            limit = scene.numerics.dt_safety * 2 * np.sqrt(float(self.mass[self.mobile].min()) / scene.contact.kn)
            if scene.numerics.dt > limit:
                raise ValueError(f"[numerics] dt = {scene.numerics.dt:.3e} s exceeds dt_safety x 2 sqrt(m_min/kn) = {limit:.3e} s (eq 52)")
        self.weight = np.zeros_like(self.x)
        self.weight[:, 1] = -self.mass * dt_(mat.g)
        if scene.water.enabled:
            self.weight[:, 1] += dt_(mat.rho_w) * pi * self.r**2 * dt_(mat.g)              # eq 34b buoyancy
        self.contact = ContactState(scene.contact_settings(), self.r, self.group, dt_)
        self.accel = input_acceleration(scene.loading)
        moving = {"bottom": (BOTTOM,), "box": (BOTTOM, LEFT, RIGHT)}[scene.loading.moves]
        self.moving = np.isin(self.group, moving) & (self.accel is not None)
        self.wall_v = dt_(0)
        self.bounds = packing.block_bounds(scene.output.block_z)
        self.pores = self.water = None
        self.F_pressure = np.zeros_like(self.x)
        if scene.water.enabled:
            self.pores = self._build()
            A = self._measure().void_area
            self.water = Water(self.pores, A, scene.water, dt_)

    def _build(self):
        return build_pores(self.x, self.r, self.group, self.scene.contact.eps_m, self.scene.water.l_m)

    def _measure(self, pores=None):
        return measure(self.pores if pores is None else pores, self.x, self.r, self.scene.contact.eps_m)

    def step(self):
        """One DEM step k at t = k dt (a-f of the module docstring)."""
        num, dt, k = self.scene.numerics, self.dt, self.k
        du = self.x - self.x_prev                                           # a
        dpsi = self.psi - self.psi_prev
        F, M, events = self.contact.forces(self.x, du, dpsi, dt)            # b
        cs = self.scene.contact
        if cs.separation_adjustment and events:                             # c
            fixes = separation_adjustment(events, self.contact.touch_count(len(self.r)) > 0, du / dt,
                                          self.mass, self.mobile, self.dtype(cs.restitution))
            for d, vel in fixes.items():
                self.v[d] = vel
        if self.water is not None:                                          # d
            if k > 0 and k % num.rebuild_interval == 0:
                new = self._build()
                self.water.remesh(new, self._measure(new).void_area, self._measure().void_area)
                self.pores = new
            if k % num.water_interval == 0:
                geo = self._measure()
                self.water.advance(num.water_interval * self.scene.numerics.dt, geo.void_area, geo.link_contact)
                U = pore_pressure(self.water.W, geo.void_area, self.water.E_w)
                self.F_pressure = pressure_forces(self.pores, self.x, self.r, U, geo.corner_angle)
        F = F + self.F_pressure + self.weight                               # e
        m = self.mobile
        self.v[m] += F[m] / self.mass[m, None] * dt                         # eq 14, 16
        self.omega[m] += M[m] / self.inertia[m] * dt
        step_x, step_psi = self.v[m] * dt, self.omega[m] * dt               # eq 17
        if num.damping_eq44:
            step_x, step_psi = (du[m] + step_x) / 2, (dpsi[m] + step_psi) / 2   # eq 44
        self.x_prev, self.psi_prev = self.x.copy(), self.psi.copy()
        self.x[m] += step_x
        self.psi[m] += step_psi
        if self.accel is not None:                                          # f
            self.wall_v += self.dtype(self.accel(k * self.scene.numerics.dt)) * dt
            self.x[self.moving, 0] += self.wall_v * dt
        self.k += 1

    def block_pressures(self):
        """Mean U [N/m] of the pores whose polygon centroid z lies in each block [z0, z1) (nan if none),
        U from eq 32 with the current W and the areas at the current positions."""
        if self.water is None:
            return np.full(len(self.bounds), np.nan)
        geo = self._measure()
        U = pore_pressure(self.water.W, geo.void_area, self.water.E_w)
        cz = geo.centroid[:, 1]
        out = []
        for z0, z1 in self.bounds:
            sel = (cz >= z0) & (cz < z1)
            out.append(float(np.mean(U[sel])) if sel.any() else np.nan)
        return np.array(out)

    def record(self, traj):
        """Append the current state to a Trajectory (t = k dt after k steps)."""
        w = self.water
        traj.append(self.k * self.scene.numerics.dt, self.x, self.block_pressures(),
                    w.total() if w else np.nan, w.balance_error() if w else np.nan)


def simulate_reference(scene, packing, n_steps, record_every, dtype=np.float64):
    """Run ``scene`` from ``packing`` for n_steps and record a Trajectory after every
    ``record_every`` steps (at t = (k + 1) dt); the contract shared with engines.yade_coupling."""
    model = ReferenceModel(scene, packing, dtype)
    traj = Trajectory(info={"implementation": "reference", "dtype": np.dtype(dtype).name})
    for k in range(n_steps):
        model.step()
        if (k + 1) % record_every == 0:
            model.record(traj)
    return traj
