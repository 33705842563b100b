"""A slow, literal NumPy reference of the seed-000 model (Tarumi & Hakuno), for cross-checks.

Independent of the fast modules: it imports nothing from engines/ but the recording contract
(engines/reference/trajectory.py). Its settings are read straight from the scene's tables (a plain dict,
``scene.as_dict()``), its contact law is written from eq 1-13, 18-27 and SPEC §2.1 with the
paper's variable names, one record per *ordered* pair (i, j) seen from element i (eq 2: alpha_ij),
so Newton's third law is not built in but checked; pores are found by the paper's walk around
the link graph and eq 33 is integrated arc by arc. Where the paper is silent or ambiguous the
reading taken here is listed in docs/READINGS.md.

Units are SI per unit thickness (SPEC §1): positions [m], forces [N], U and E_w [N/m], areas [m^2].
Every floating-point state array has the dtype chosen by the caller (float32, float64, longdouble);
only the pore *topology* (candidate links, faces) is decided in float64.

Step k = 0 .. n_steps - 1 at time t = k dt (the order shared with engines/model/pore_dem.py):
  a. du = x_t - x_{t-dt}, dpsi = psi_t - psi_{t-dt} (zero at k = 0).
  b. contact forces, eq 1-13, 25-27 (``PairRecords.forces``); with flat walls (SPEC §2.6) also
     those of the walls on the particles, a wall acting as a fixed disc of infinite radius
     (``wall_records``).
  c. velocity adjustment of particles that became free, eq 18-24 (``adjust_free_particles``),
     on the velocities v = du/dt (eq 17: the velocity is constant over a step); the adjusted
     velocity replaces v before step e.
  d. water (water.enabled): pores (closed by the flat walls, ``build_pores``) built at k = 0 from
     x_0 and rebuilt at k > 0, k % rebuild_interval == 0 (or at the steps a run recorded, when
     given them: SPEC §2.6), pressures inherited by rules (a)-(d) of §3.4(2); the water is
     advanced at k % water_interval == 0 by water_interval dt at the void areas and link states of
     x_t (eq 32, 38-43, 45-46), then the pressure forces (eq 33) are recomputed from the U of eq 32
     with the area actually used (eq 45) and held until the next water step, as are the flat walls'
     water forces (``wall_water_forces``, ``ReferenceModel.wall_reactions``).
  e. F = contact + pressure - rho f pi r^2 g (+ rho_w pi r^2 g with water, eq 34b);
     v += F/m dt, x += v dt, omega += M/I dt, psi += omega dt (eq 14-17).
     Side walls on springs ([loading] side_walls = "springs", §6.1, Fig. 27): the side-wall discs
     are integrated the same way in x only, under the contact forces of the particles, the pore
     pressures and the ties of their column (``column_ties``, ``tie_forces``; velocities du/dt of a).
  f. moving walls follow the input acceleration (§6.1: velocity and displacement by the
     constant-(average-)acceleration method, ``WallMotion``): x_w += v_w dt + a_bar dt^2/2,
     v_w += a_bar dt with a_bar = (a(t_k) + a(t_k+1)) / 2; a flat wall that moves (``moves``)
     translates by the same x_w: the face of an x-wall with it, a z-wall along its face (its foot
     points, projections of the discs, stay; as contact elements they move by the wall's du).
  g. after the step, when (k + 1) % record_every == 0, a sample at t = (k + 1) dt: positions,
     block-mean U (eq 32 with the current W and the areas at the recorded positions), total water
     and the relative water-balance error.
"""
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, QhullError

from engines.reference.trajectory import Trajectory

G0 = 9.80665                 # standard gravity for records given in g [m/s^2]
DEGENERATE_FRACTION = 1e-4   # a face with void area <= this x mean(pi r^2) at build is closed (no pore)
PARTICLE, BOTTOM, LEFT, RIGHT = 0, 1, 2, 3   # disc group codes of a packing


# ------------------------------------------------------------------------------------------------
# Settings: read from the scene's tables (a plain dict of dicts)
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Settings:
    """Every constant the reference uses, flat, with the paper's names (SI, per unit thickness)."""

    spring: str
    kn: float
    eta_n: float
    ks: float
    eta_s: float
    mu: float
    e: float                # restitution of eq 19
    f_max: float
    eps_m: float
    adjust: bool            # eq 18-24 on/off
    rho: float
    rho_w: float
    g: float
    wet: bool
    E_w: float
    k1: float
    k2: float
    k3: float
    q_w: float
    drained: bool
    l_m: float
    smoothing: bool
    substep: bool
    loading: dict
    dt: float
    dt_safety: float
    rebuild_interval: int
    water_interval: int
    block_z: list
    side_walls: bool        # side-wall columns on springs (Fig. 27), else fixed
    ks_wall: float          # k'_s of the ties [N/m]
    eta_s_wall: float       # eta'_s of the ties [N s/m]
    flat_walls: tuple = ()  # FlatWall (SPEC §2.6), from tables["walls"]["flat"]


def read_settings(tables):
    """Settings from a scene's tables ({table: {field: value}}, e.g. ``scene.as_dict()``)."""
    c, w, m, n = tables["contact"], tables["water"], tables["material"], tables["numerics"]
    return Settings(
        spring=c["spring"], kn=c["kn"], eta_n=c["eta_n"], ks=c["ks"], eta_s=c["eta_s"], mu=c["mu"],
        e=c["restitution"], f_max=c["f_max"], eps_m=c["eps_m"], adjust=c["separation_adjustment"],
        rho=m["rho"], rho_w=m["rho_w"], g=m["g"], wet=w["enabled"], E_w=w["E_w"], k1=w["k1"], k2=w["k2"],
        k3=w["k3"], q_w=w["q_w"], drained=w["sides"] == "drained", l_m=w["l_m"], smoothing=w["smoothing"],
        substep=w["substep"], loading=dict(tables["loading"]), dt=n["dt"], dt_safety=n["dt_safety"],
        rebuild_interval=n["rebuild_interval"], water_interval=n["water_interval"],
        block_z=[list(b) for b in tables["output"]["block_z"]],
        side_walls=tables["loading"]["side_walls"] == "springs", ks_wall=c["ks_wall"], eta_s_wall=c["eta_s_wall"],
        flat_walls=read_flat_walls(tables))


@dataclass(frozen=True)
class FlatWall:
    """An axis-aligned flat wall (SPEC §2.6): the face x = position (axis 0) or z = position
    (axis 1) [m], the discs on the side ``inward`` (+1: inward normal +e_axis, -1: -e_axis);
    boundary "undrained", "drained" (k3, U = 0 outside) or "inflow" (q_w into each of its pores);
    ``moves``: it follows the input acceleration in x (step f), else it is fixed."""

    axis: int
    position: float
    inward: int
    boundary: str
    moves: bool = False

    def distance(self, x):
        """Distance (N,) [m] of the centres x (N, 2) from the face along the inward normal."""
        return self.inward * (x[:, self.axis] - x.dtype.type(self.position))


FLAT_WALL_KEYS = ("axis", "position", "inward", "boundary", "moves")


def read_flat_walls(tables):
    """The FlatWalls of tables["walls"]["flat"], a list of {"axis": "x" | "z", "position": [m],
    "inward": +1 | -1, "boundary": "undrained" | "drained" | "inflow", "moves": true | false}; none
    when absent. Raises ValueError for anything else and for two walls facing the same way on one
    axis (the discs would lie on the outer one's side of the inner one)."""
    walls = []
    for k, w in enumerate(tables.get("walls", {}).get("flat", [])):
        if sorted(w) != sorted(FLAT_WALL_KEYS):
            raise ValueError(f"flat wall {k}: needs exactly the keys {FLAT_WALL_KEYS} (got {sorted(w)})")
        if w["axis"] not in ("x", "z") or w["inward"] not in (1, -1) or \
                w["boundary"] not in ("undrained", "drained", "inflow") or not isinstance(w["moves"], bool):
            raise ValueError(f"flat wall {k}: axis 'x' | 'z', inward +1 | -1, boundary 'undrained' | 'drained' "
                             f"| 'inflow', moves true | false (got {w})")
        walls.append(FlatWall("xz".index(w["axis"]), float(w["position"]), int(w["inward"]), w["boundary"],
                              w["moves"]))
    faces = [(w.axis, w.inward) for w in walls]
    if len(set(faces)) < len(faces):
        raise ValueError("two flat walls face the same way on one axis: at most one wall per side of the box")
    return tuple(walls)


# ------------------------------------------------------------------------------------------------
# Contact law (eq 1-13, 25-27): one record per ordered pair (i, j), seen from element i
# ------------------------------------------------------------------------------------------------
class PairRecords:
    """The quantities of eq 1-13 for every ordered pair (i, j), i a particle and j any other disc,
    or i a side-wall disc on springs (``sliding``) and j a particle (the walls push each other only
    through the ties of Fig. 27; fixed and driven walls take no force).

    Record p is pair (I[p], J[p]); its force acts on element I[p] only, so the force on i is the sum
    over the records of i (the Sigma of eq 13) and Newton's third law holds only because record
    (j, i) computes the mirror value. Per record: in_contact (eq 1a, 26), e_n and e_s [N] (eq 5a,
    9a after eq 6, 10, 11, 27), f_n [N] (eq 7), the displacement eps [m] of the elastic spring (c)
    (eq 25), and Vn_ij [m/s], the approach velocity at collision (eq 20-21). ``pairs`` (I, J): the
    records given instead (the flat walls', ``wall_records``).
    """

    def __init__(self, s, r, mobile, dtype, sliding=None, pairs=None):
        n = len(r)
        mobile = np.asarray(mobile, bool)
        sliding = np.zeros(n, bool) if sliding is None else np.asarray(sliding, bool)
        self.mobile = mobile
        if pairs is None:
            self.I, self.J = np.nonzero((mobile[:, None] & ~np.eye(n, dtype=bool)) | (sliding[:, None] & mobile[None, :]))
        else:                                   # given records (I, J), I ascending: the flat walls' (wall_records)
            self.I, self.J = (np.asarray(v, int) for v in pairs)
        self.s, self.dtype, self.n = s, dtype, n
        self.r_i, self.r_j = np.asarray(r, dtype)[self.I], np.asarray(r, dtype)[self.J]
        self.kn, self.eta_n, self.ks, self.eta_s, self.mu, self.f_max, self.eps_m = (
            dtype(v) for v in (s.kn, s.eta_n, s.ks, s.eta_s, s.mu, s.f_max, s.eps_m))
        self.first = np.flatnonzero(np.r_[True, self.I[1:] != self.I[:-1]]) if len(self.I) else self.I
        m = len(self.I)
        self.in_contact = np.zeros(m, bool)
        self.e_n, self.e_s, self.eps, self.Vn_ij, self.f_n = (np.zeros(m, dtype) for _ in range(5))

    def forces(self, x, du, dpsi, dt):
        """Forces (N, 2) [N], moments Fm (N,) [N m, counter-clockwise] on the elements (eq 13), and
        the records of particles i that were in contact at t - dt and are not at t: {i: [(j, n_ij, Vn_ij)]},
        n_ij = (cos alpha_ij, sin alpha_ij) the unit normal from i to j."""
        I, J, z = self.I, self.J, self.dtype(0)
        R_ij = np.sqrt((x[I, 0] - x[J, 0]) ** 2 + (x[I, 1] - x[J, 1]) ** 2)   # eq 1b
        sin_a = -(x[I, 1] - x[J, 1]) / R_ij                                   # eq 2a
        cos_a = -(x[I, 0] - x[J, 0]) / R_ij                                   # eq 2b
        touching = self.r_i + self.r_j + self.eps_m >= R_ij                   # eq 1a, 26
        collision = touching & ~self.in_contact
        du_rel, dw_rel = du[I, 0] - du[J, 0], du[I, 1] - du[J, 1]
        du_n = du_rel * cos_a + dw_rel * sin_a                                # eq 3a (approach > 0)
        du_s = -du_rel * sin_a + dw_rel * cos_a + (self.r_i * dpsi[I] + self.r_j * dpsi[J])  # eq 3b

        overlap = self.r_i + self.r_j + self.eps_m - R_ij      # eq 25-26: the displacement at first touch
        spring = self.s.spring
        if spring == "c":     # nonlinear elastic: f = min(kn eps, f_max) on one path (SPEC §2.1)
            eps = np.where(collision, overlap, self.eps + du_n)
            e_n = np.minimum(self.kn * eps, self.f_max)
        else:                 # eq 4a, 5a incrementally, from kn eps at collision (eq 25)
            eps = self.eps
            e_n = np.where(collision, self.kn * overlap, self.e_n + self.kn * du_n)
            if spring == "d":
                e_n = np.minimum(e_n, self.f_max)                             # eq 27
        d_n = self.eta_n * du_n / dt                                          # eq 4b, 5b
        e_s = np.where(collision, z, self.e_s) + self.ks * du_s               # eq 8a, 9a
        d_s = self.eta_s * du_s / dt                                          # eq 8b, 9b
        tension = (e_n < 0) | ~touching
        e_n, d_n = np.where(tension, z, e_n), np.where(tension, z, d_n)       # eq 6
        e_s, d_s = np.where(tension, z, e_s), np.where(tension, z, d_s)       # eq 10
        sliding = np.abs(e_s) > self.mu * e_n
        e_s = np.where(sliding, self.mu * e_n * np.sign(e_s), e_s)            # eq 11a
        d_s = np.where(sliding, z, d_s)                                       # eq 11b
        f_n, f_s = e_n + d_n, e_s + d_s                                       # eq 7, 12

        F = np.zeros((self.n, 2), self.dtype)
        Fm = np.zeros(self.n, self.dtype)
        if len(I):                          # the records of element i are contiguous: sum each run
            owner = I[self.first]
            F[owner, 0] = np.add.reduceat(-f_n * cos_a + f_s * sin_a, self.first)   # eq 13a
            F[owner, 1] = np.add.reduceat(-f_n * sin_a - f_s * cos_a, self.first)   # eq 13b
            Fm[owner] = -self.r_i[self.first] * np.add.reduceat(f_s, self.first)   # eq 13c
        left = {}
        for p in np.flatnonzero(self.in_contact & ~touching & self.mobile[I]):
            left.setdefault(int(I[p]), []).append((int(J[p]), np.array([cos_a[p], sin_a[p]]), self.Vn_ij[p]))

        V = du / dt                                                           # eq 17
        Vn_i = V[I, 0] * cos_a + V[I, 1] * sin_a                              # eq 20a
        Vn_j = -V[J, 0] * cos_a - V[J, 1] * sin_a                             # eq 20b
        self.Vn_ij = np.where(collision, Vn_i + Vn_j, np.where(touching, self.Vn_ij, z))   # eq 21
        self.in_contact = touching
        self.e_n, self.e_s = np.where(touching, e_n, z), np.where(touching, e_s, z)
        self.eps = np.where(touching, eps, z)
        self.f_n = np.where(touching, f_n, z)
        return F, Fm, left

    def contacts_of(self):
        """Number of elements each element touches now (fixed and driven walls: 0, they carry no
        records; a side-wall disc on springs: the particles it touches)."""
        return np.bincount(self.I[self.in_contact], minlength=self.n)


def wall_records(s, r, mobile, walls, dtype):
    """Contact records of the particles with the flat walls (SPEC §2.6), or (None, []) without
    walls: one record per (particle, wall), particle by particle, the wall as a disc of infinite
    radius: element N + k of record k is the foot point of its disc on the face, radius 0, moving
    with its wall (at rest when fixed), so eq 1-13 give R_ij = the distance to the face, the normal
    along the wall's normal, the overlap of eq 25-26 r_i + eps_m - R_ij, and eq 3b's rolling
    r_i dpsi_i: the law of a wall disc. Returns (PairRecords over the N + K elements, wall index (K,) of each record)."""
    if not walls:
        return None, []
    disc = np.repeat(np.flatnonzero(mobile), len(walls))
    wall = np.tile(np.arange(len(walls)), int(np.count_nonzero(mobile)))
    n, k = len(r), len(disc)
    records = PairRecords(s, np.concatenate([r, np.zeros(k, dtype)]), np.r_[mobile, np.zeros(k, bool)], dtype,
                          pairs=(disc, n + np.arange(k)))
    return records, wall


# ------------------------------------------------------------------------------------------------
# Velocity adjustment at separation (§2.2(1), eq 18-24, Fig. 3)
# ------------------------------------------------------------------------------------------------
def adjust_free_particles(left, n_contacts, V, mass, e, counts=None):
    """New velocities {i: V''_i (2,)} of the particles that became free (eq 18-24).

    ``left``: {i: [(j, n_ij, Vn_ij)]} the elements particle i touched at t - dt and not at t;
    ``n_contacts`` (N,) elements each particle touches at t; ``V`` (N, 2) velocities (the primed
    values at separation); ``e`` the restitution. Vn'_i = V'_i . n_ij, Vn'_j = -V'_j . n_ij (eq 20).
    A separation is adjusted only when it is faster than eq 19 allows: -(Vn'_i + Vn'_j) > e Vn_ij > 0
    (the problem eq 18 names). A particle i is free when it touches nothing at t. Patterns (Fig. 3):
      (d) i and j both free and each left only the other: eq 24a with the pair's normal momentum at
          separation kept (eq 24b), eq 23 for both;
      (a) i left one element j that is not free (a wall, or j still touches others): Rk_i of eq 22
          and eq 23; (b) i left several such elements: the smallest Rk_i, along that pair's normal;
      (c) a partner j is free too but left others as well: j is settled first against the elements
          that are not free, then i against the new velocity of j.
    ``counts``: optional dict pattern -> number of particles adjusted, updated in place.
    """
    free = {i for i in left if n_contacts[i] == 0}
    Vnew = {i: np.array(V[i]) for i in left}
    for i, lst in left.items():
        for j, _, _ in lst:
            Vnew.setdefault(j, np.array(V[j]))
    settled, out = _adjust_free_pairs(left, free, Vnew, mass, e, counts)          # (d)
    pending = set(free) - settled                                              # (a), (b), (c)
    while pending:
        ready = [i for i in sorted(pending) if any(j not in pending for j, _, _ in left[i])]
        if not ready:
            break                                 # a free cluster with no settled element: left as is
        new = {}
        for i in ready:
            best = _slowest_separation(left[i], pending, Vnew, Vnew[i], e)
            if best is not None:
                Rk_i, Vn_i, n = best
                new[i] = Vnew[i] - (1 - Rk_i) * Vn_i * n                       # eq 23
                if counts is not None:
                    pattern = "c" if any(j in free for j, _, _ in left[i]) else ("a" if len(left[i]) == 1 else "b")
                    counts[pattern] = counts.get(pattern, 0) + 1
        Vnew.update(new)
        out.update(new)
        pending -= set(ready)
    return out


def _too_fast(Vn_i, Vn_j, Vn_ij, e):
    """The separation is faster than eq 19 allows (eq 18-19)."""
    return -(Vn_i + Vn_j) > e * Vn_ij > 0


def _adjust_free_pairs(left, free, Vnew, mass, e, counts):
    """Pattern (d) of adjust_free_particles: i and j both free, each left only the other: eq 24a
    with the pair's normal momentum kept (eq 24b), eq 23 for both; Vnew updated in place. Returns
    (the particles settled, {i: V''_i} of those adjusted)."""
    settled, out = set(), {}
    for i in sorted(free):
        if len(left[i]) != 1 or i in settled:
            continue
        j, n, Vn_ij = left[i][0]
        if j not in free or len(left[j]) != 1:
            continue
        settled |= {i, j}
        Vn_i, Vn_j = Vnew[i] @ n, -(Vnew[j] @ n)
        if not _too_fast(Vn_i, Vn_j, Vn_ij, e):
            continue
        target = -e * Vn_ij                                                    # eq 19: Vn''_ij
        momentum = mass[i] * Vn_i - mass[j] * Vn_j                             # eq 24b, left side
        X = (momentum + mass[j] * target) / (mass[i] + mass[j])                # Rk_i Vn'_i
        Y = target - X                                                         # eq 24a: Rk_j Vn'_j
        Vnew[i] = Vnew[i] - (Vn_i - X) * n                                     # eq 23
        Vnew[j] = Vnew[j] + (Vn_j - Y) * n
        out[i], out[j] = Vnew[i], Vnew[j]
        if counts is not None:
            counts["d"] = counts.get("d", 0) + 2
    return settled, out


def _slowest_separation(left_i, pending, Vnew, V_i, e):
    """Patterns (a)-(c): of the elements j a particle of velocity V_i left (``left_i``) that are not
    pending and separate too fast, the one of the smallest Rk_i (eq 22), as (Rk_i, Vn'_i, n_ij);
    None: none."""
    best = None
    for j, n, Vn_ij in left_i:
        if j in pending:
            continue
        Vn_i, Vn_j = V_i @ n, -(Vnew[j] @ n)
        if Vn_i == 0 or not _too_fast(Vn_i, Vn_j, Vn_ij, e):
            continue
        Rk_i = (-e * Vn_ij - Vn_j) / Vn_i                                      # eq 22
        if best is None or Rk_i < best[0]:
            best = (Rk_i, Vn_i, n)
    return best


# ------------------------------------------------------------------------------------------------
# Pores (§3.1, eq 28-31)
# ------------------------------------------------------------------------------------------------
@dataclass
class Pores:
    """Topology of the pores between two rebuilds.

    A pore is a bounded face of the planar graph of links (edges of the regular triangulation
    passing eq 28, plus the eq 28 pairs it hides: ``build_pores``), found by the paper's walk (at
    each disc, turn to the next link clockwise), so its boundary runs counter-clockwise with the
    pore on the left. Per pore (Np pores):
      half-edges he_pore, he_a, he_b: boundary links a -> b;
      corners corner_pore, corner_disc, corner_prev, corner_next: disc d reached from prev, left to next;
      rattlers rattler_pore, rattler_disc: unlinked discs inside (their whole area is not void);
      vertex_sets (frozenset of discs, and -1 - w for flat wall w), surface / bottom / side (bool
      arrays), neighbours (sets).
    Links (L, 2) i < j; throats (T, 2) pairs of distinct pores sharing link throat_link (T,).
    a_min: faces with void area <= a_min at build are closed (not pores); pores whose area falls
    to <= a_min later keep their water but exchange none.
    Flat walls (SPEC §2.6): ``walls`` (FlatWall); the vertices N, N + 1, ... after the N discs are
    virtual, radius 0 (``wall_vertices``): the foot point of disc foot_disc[f] on wall foot_wall[f]
    (F,), then the corner of walls corner_wall[c] = (x-wall, z-wall) (C, 2). he_wall (H,): the wall
    of a half-edge on a face, -1 for the others; wall_drained / wall_inflow (Np,): pores with an
    edge on a drained / inflow wall.
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
    walls: tuple = ()
    foot_disc: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    foot_wall: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    corner_wall: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), int))
    he_wall: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    wall_drained: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    wall_inflow: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))


def flat_wall_vertices(x, r, walls, reach):
    """The virtual vertices of the flat walls (SPEC §2.6) for discs at x (N, 2) [m], radii r [m]:
    disc d is linked to wall w when its gap to the face, distance - r_d, is <= reach = eps_m + l_m
    (eq 28 with the wall as a disc of infinite radius). Returns {foot_disc, foot_wall} (F,), wall
    by wall and along each face by the coordinate along it, and {corner_wall} (C, 2): every
    (x-wall, z-wall) pair of which both walls have linked discs. Raises ValueError for a disc whose
    centre is on or beyond a face."""
    foot_disc, foot_wall = [], []
    for w, wall in enumerate(walls):
        h = wall.distance(x)
        if np.any(h <= 0):
            raise ValueError(f"flat wall {w}: disc {int(np.argmin(h))} has its centre on or beyond the face")
        d = np.flatnonzero(h - r <= reach)
        foot_disc += d[np.argsort(x[d, 1 - wall.axis], kind="stable")].tolist()
        foot_wall += [w] * len(d)
    linked = set(foot_wall)
    corners = [(a, b) for a in sorted(linked) for b in sorted(linked) if walls[a].axis == 0 and walls[b].axis == 1]
    return dict(foot_disc=np.array(foot_disc, int), foot_wall=np.array(foot_wall, int),
                corner_wall=np.array(corners, int).reshape(-1, 2))


def wall_vertices(pores, x, r):
    """Positions (N + F + C, 2) [m] and radii of the discs followed by the virtual vertices of
    ``pores``' flat walls, in x's dtype: the foot points (the orthogonal projections of their discs
    on the face, moving with them) and the corners (fixed), radius 0 (no sector in eq 29, no
    pressure force in eq 33). Without flat-wall vertices: x and r themselves."""
    if not len(pores.foot_disc):
        return x, r
    t = x.dtype.type
    feet = x[pores.foot_disc].copy()
    for f, w in enumerate(pores.foot_wall):
        feet[f, pores.walls[w].axis] = t(pores.walls[w].position)
    corners = np.array([[pores.walls[a].position, pores.walls[b].position] for a, b in pores.corner_wall],
                       x.dtype).reshape(-1, 2)
    return np.vstack([x, feet, corners]), np.concatenate([r, np.zeros(len(feet) + len(corners), r.dtype)])


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


def regular_triangles(x, r):
    """Counter-clockwise triangles [[a, b, c], ...] of the regular (power) triangulation of the
    discs: the lower convex hull of the centres lifted to (x, z, x^2 + z^2 - r^2) (READINGS D4).

    Coordinates are taken relative to the mean centre and divided by the largest extent (the same
    hull, better conditioned). A hull facet is lower when its unit outward normal has a lift
    component below -1e-12 (the facets standing on collinear centres have 0). A disc whose lifted
    point lies above the lower hull (an empty power cell) is in no triangle. If the lifted points
    span no volume (three discs, or four cocircular equal ones) every triangulation of the centres
    is regular: Delaunay's. Collinear centres: no triangles.
    """
    c = x - x.mean(axis=0)
    size = float(np.max(np.abs(c)))
    if not size > 0:
        return []
    c, rr = c / size, r / size
    lifted = np.column_stack([c, c[:, 0] ** 2 + c[:, 1] ** 2 - rr**2])
    try:
        hull = ConvexHull(lifted)
        simplices = hull.simplices[hull.equations[:, 2] < -1e-12].tolist()
    except QhullError:
        try:
            simplices = Delaunay(x).simplices.tolist()
        except QhullError:
            return []
    tris = []
    for a, b, d in simplices:
        area2 = (x[b, 0] - x[a, 0]) * (x[d, 1] - x[a, 1]) - (x[b, 1] - x[a, 1]) * (x[d, 0] - x[a, 0])
        tris.append([a, b, d] if area2 > 0 else [a, d, b])
    return tris


def _turn(p, q, s):
    """Twice the signed area of the triangle p, q, s: > 0 when s lies left of p -> q."""
    return (q[0] - p[0]) * (s[1] - p[1]) - (q[1] - p[1]) * (s[0] - p[0])


def _crosses(p, q, a, b):
    """Segments p-q and a-b cross at a point inside both (no shared end, not collinear)."""
    return (_turn(p, q, a) * _turn(p, q, b) < 0) and (_turn(a, b, p) * _turn(a, b, q) < 0)


def insert_hidden_links(x, r, tris, reach, is_link, n_discs=None, extra=()):
    """Add to the triangles' links every eq 28 pair (r_i + r_j + reach >= R_ij) of triangle
    vertices that is not an edge and crosses no link, by flipping the edges it crosses
    (READINGS D4). Pairs are taken from the closest gap R - r_i - r_j up, ties by index; a pair
    whose segment runs through another centre is left out. Only non-link edges are flipped, so
    no link is lost. With flat walls the eq 28 pairs are those among the discs 0 .. n_discs - 1,
    and ``extra`` [(gap, d, v)] adds the disc-wall links (disc d to its foot point v) to the same
    order. Returns (triangles, pairs inserted). Brute force over the edges (a reference, not a
    fast path)."""
    pts = [tuple(p) for p in x.tolist()]
    verts = np.array(sorted({v for t in tris for v in t}), int)
    tri_of = {}                                   # directed edge (a, b) -> the third corner c of ccw (a, b, c)
    for a, b, c in tris:
        tri_of[(a, b)], tri_of[(b, c)], tri_of[(c, a)] = c, a, b
    discs = verts if n_discs is None else verts[verts < n_discs]
    xv, rv = x[discs], r[discs]
    gap = np.sqrt(((xv[:, None, :] - xv[None, :, :]) ** 2).sum(axis=2)) - rv[:, None] - rv[None, :]
    iu, ju = np.nonzero(np.triu(gap <= reach, 1))
    pairs = [(gap[a, b], discs[a], discs[b]) for a, b in zip(iu.tolist(), ju.tolist())] + list(extra)
    pairs = sorted(p for p in pairs if (p[1], p[2]) not in tri_of and (p[2], p[1]) not in tri_of)
    inserted = 0
    for _, k, l in pairs:
        if (k, l) in tri_of:
            continue                              # became an edge by an earlier insertion
        P, Q = pts[k], pts[l]
        if any(v not in (k, l) and _turn(P, Q, pts[v]) == 0 and
               min(P[0], Q[0]) <= pts[v][0] <= max(P[0], Q[0]) and min(P[1], Q[1]) <= pts[v][1] <= max(P[1], Q[1])
               for v in verts.tolist()):
            continue                              # through another centre
        crossed = [(a, b) for (a, b) in tri_of if a < b and _crosses(P, Q, pts[a], pts[b])]
        if any(is_link(a, b) for a, b in crossed):
            continue
        queue = list(crossed)
        while queue:                              # Lawson's flips towards k - l (Sloan 1993)
            a, b = queue.pop(0)
            c, d = tri_of[(a, b)], tri_of[(b, a)]     # (a, b, c) left of a -> b, (b, a, d) right
            if not (_turn(pts[c], pts[d], pts[a]) * _turn(pts[c], pts[d], pts[b]) < 0
                    and _turn(pts[a], pts[b], pts[c]) * _turn(pts[a], pts[b], pts[d]) < 0):
                queue.append((a, b))              # quadrilateral a, d, b, c not convex: later
                continue
            for e in ((a, b), (b, c), (c, a), (b, a), (a, d), (d, b)):
                del tri_of[e]
            tri_of[(c, d)], tri_of[(d, b)], tri_of[(b, c)] = b, c, d      # triangle (c, d, b)
            tri_of[(d, c)], tri_of[(c, a)], tri_of[(a, d)] = a, d, c      # triangle (d, c, a)
            if {c, d} != {k, l} and _crosses(P, Q, pts[c], pts[d]):
                queue.append((min(c, d), max(c, d)))
        inserted += 1
    out = [[a, b, c] for (a, b), c in tri_of.items() if a < b and a < c]
    return out, inserted


def build_pores(x, r, group, eps_m, l_m, walls=()):
    """Links (eq 28) and pores (§3.1) of discs at x (N, 2) [m], radii r [m], group codes, closed
    by the flat walls ``walls`` (FlatWall, SPEC §2.6).

    Candidate links: the edges of the regular triangulation, then the eq 28 pairs it hides
    (``insert_hidden_links``; READINGS D4). The topology is decided in float64. Fewer than three
    vertices or collinear ones: no pores. With flat walls the vertices are the discs followed by
    the walls' virtual vertices of radius 0 (``flat_wall_vertices``): a foot point per linked disc
    and the corners. Their links are the disc-wall links (a disc to its own foot point, eq 28 with
    the wall as a disc of infinite radius) and the wall edges (consecutive virtual vertices along a
    face); they enter the same regular triangulation and the same insertion (READINGS F1-F3).
    """
    x = np.asarray(x, np.float64)
    r = np.asarray(r, np.float64)
    n = len(r)
    a_min = DEGENERATE_FRACTION * float(np.mean(np.pi * r**2)) if n else 0.0
    walls = tuple(walls)
    frame = Pores(a_min=a_min, walls=walls, **flat_wall_vertices(x, r, walls, eps_m + l_m))
    x_disc = x
    x, r = wall_vertices(frame, x, r)             # the discs, then the walls' virtual vertices
    if len(r) < 3:
        return Pores(a_min=a_min, walls=walls)
    on_walls = [{int(w)} for w in frame.foot_wall] + [set(map(int, c)) for c in frame.corner_wall]
    is_link = _link_rule(x, r, n, frame, walls, on_walls, eps_m, l_m)
    extra = [(float(walls[w].distance(x_disc[[d]])[0] - r[d]), int(d), n + f)
             for f, (d, w) in enumerate(zip(frame.foot_disc, frame.foot_wall))]
    tris, _ = insert_hidden_links(x, r, regular_triangles(x, r), eps_m + l_m, is_link, n, extra)
    if not tris:
        return Pores(a_min=a_min, walls=walls)
    links, face_of, face_left = _link_faces(tris, is_link)
    outer = face_of[len(tris)]
    cycles_of_face = _paper_walk(x, links, face_left, len(r))
    rattlers_of_face = _rattlers(x, n, tris, links, face_of)
    bounded = sorted((f for f in cycles_of_face if f != outer), key=lambda f: min(min(c) for c in cycles_of_face[f]))
    open_faces = [f for f in bounded if _void_area(x, r, cycles_of_face[f], rattlers_of_face.get(f, [])) > a_min]
    pore_of = {f: p for p, f in enumerate(open_faces)}
    n_p = len(open_faces)
    b = _pore_boundaries(open_faces, cycles_of_face, rattlers_of_face, on_walls, n)
    wall = np.r_[np.asarray(group) != PARTICLE, np.ones(len(r) - n, bool)]   # virtual vertices are wall
    throats, throat_link, surface, neighbours = _throats_and_surface(links, face_left, pore_of, outer, wall, n_p)
    g = np.asarray(group)
    arr = lambda v: np.array(v, int)
    he_pore, he_wall, vertex_sets = arr(b["he_pore"]), arr(b["he_wall"]), b["vertex_sets"]
    return Pores(
        n_pores=n_p, he_pore=he_pore, he_a=arr(b["he_a"]), he_b=arr(b["he_b"]),
        corner_pore=arr(b["c_pore"]), corner_disc=arr(b["c_disc"]), corner_prev=arr(b["c_prev"]),
        corner_next=arr(b["c_next"]), rattler_pore=arr(b["r_pore"]), rattler_disc=arr(b["r_disc"]),
        links=np.array(links, int).reshape(-1, 2),
        throats=arr(throats).reshape(-1, 2), throat_link=arr(throat_link), surface=surface,
        bottom=np.array([any(v >= 0 and g[v] == BOTTOM for v in vs) for vs in vertex_sets], bool).reshape(-1),
        side=np.array([any(v >= 0 and g[v] in (LEFT, RIGHT) for v in vs) for vs in vertex_sets], bool).reshape(-1),
        vertex_sets=vertex_sets, neighbours=neighbours, a_min=a_min,
        walls=walls, foot_disc=frame.foot_disc, foot_wall=frame.foot_wall, corner_wall=frame.corner_wall,
        he_wall=he_wall, wall_drained=_on_wall_edge(he_pore, he_wall, walls, n_p, "drained"),
        wall_inflow=_on_wall_edge(he_pore, he_wall, walls, n_p, "inflow"),
    )


def _on_wall_edge(he_pore, he_wall, walls, n_p, boundary):
    """(n_p,) bool: the pores with a half-edge on a flat wall of this boundary ("drained", "inflow")."""
    hit = np.zeros(n_p, bool)
    for p, w in zip(he_pore, he_wall):
        hit[p] |= w >= 0 and walls[w].boundary == boundary
    return hit


def _link_rule(x, r, n, frame, walls, on_walls, eps_m, l_m):
    """is_link(a, b) of the vertices (n discs, then the walls' virtual vertices on the walls
    ``on_walls``): two discs by eq 28; a disc and its own foot point; two virtual vertices
    consecutive along a face (a wall edge) (READINGS F1-F3)."""
    foot_of = {n + f: int(d) for f, d in enumerate(frame.foot_disc)}
    chain = set()                                 # wall edges: consecutive virtual vertices along a face
    for w, wall in enumerate(walls):
        along = sorted((x[v, 1 - wall.axis], v) for v in range(n, len(r)) if w in on_walls[v - n])
        chain |= {(min(a, b), max(a, b)) for (_, a), (_, b) in zip(along, along[1:])}

    def is_link(a, b):
        if a < n and b < n:                       # eq 28
            return r[a] + r[b] + eps_m + l_m >= np.hypot(*(x[b] - x[a]))
        if a < n or b < n:                        # a disc and its own foot point
            return foot_of.get(max(a, b)) == min(a, b)
        return (min(a, b), max(a, b)) in chain

    return is_link


def _link_faces(tris, is_link):
    """The links (i < j, sorted) among the edges of the triangles ``tris`` and the faces of the link
    graph: triangles joined across non-link edges, OUT (= len(tris)) outside the hull. Returns
    (links, face_of (len(tris) + 1,) the face of each triangle and of OUT, face_left(a, b): the face
    on the left of the directed edge a -> b)."""
    edge_tri = {}                                 # directed edge -> triangle on its left
    for k, (a, b, c) in enumerate(tris):
        for e in ((a, b), (b, c), (c, a)):
            edge_tri[e] = k
    links = sorted({(min(e), max(e)) for e in edge_tri if is_link(*e)})
    link_set = set(links)
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
    face_of = [find(k) for k in range(out + 1)]

    def face_left(a, b):
        return face_of[edge_tri[(a, b)]] if (a, b) in edge_tri else face_of[out]

    return links, face_of, face_left


def _neighbours_around(x, links, n_vertices):
    """The vertices linked to each vertex, sorted by the angle of the link."""
    around = {d: [] for d in range(n_vertices)}
    for a, b in links:
        around[a].append(b)
        around[b].append(a)
    for d, nb in around.items():
        nb.sort(key=lambda b: np.arctan2(x[b, 1] - x[d, 1], x[b, 0] - x[d, 0]))
    return around


def _paper_walk(x, links, face_left, n_vertices):
    """The boundary cycles of the half-edges of every face, by the paper's walk: from a -> b, go on
    to the neighbour of b next clockwise from a. Returns {face: [cycle of half-edges, ...]}."""
    around = _neighbours_around(x, links, n_vertices)

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
    return cycles_of_face


def _rattlers(x, n, tris, links, face_of):
    """{face: [unlinked discs]}: an unlinked disc is in the face of a triangle it is a corner of, or
    (empty power cell) of the first triangle that contains its centre."""
    linked = {v for link in links for v in link}
    rattlers_of_face = {}
    for d in range(n):
        if d not in linked:
            k = next((k for k, t in enumerate(tris) if d in t), None)
            if k is None:
                k = next((k for k, (a, b, c) in enumerate(tris) if min(
                    _turn(x[a], x[b], x[d]), _turn(x[b], x[c], x[d]), _turn(x[c], x[a], x[d])) >= 0), None)
            if k is not None:
                rattlers_of_face.setdefault(face_of[k], []).append(d)
    return rattlers_of_face


def _void_area(x, r, cycles, rattlers):
    """Void area (eq 29) of a face with boundary ``cycles`` and unlinked discs ``rattlers`` at the
    build: the polygon (shoelace) less the sectors at its corners less the rattlers whole."""
    he = np.array([h for c in cycles for h in c])
    poly = 0.5 * np.sum(x[he[:, 0], 0] * x[he[:, 1], 1] - x[he[:, 1], 0] * x[he[:, 0], 1])
    cd, cp, cn = _corners(cycles)
    sectors = 0.5 * np.sum(corner_angles(x, cd, cp, cn) * r[cd] ** 2)
    return poly - sectors - np.pi * np.sum(r[rattlers] ** 2)


def _pore_boundaries(open_faces, cycles_of_face, rattlers_of_face, on_walls, n):
    """The pores (the open faces, in order): their half-edges (he_pore, he_a, he_b, he_wall: the
    wall the edge lies on, -1: none), corners (c_pore, c_disc, c_prev, c_next), rattlers (r_pore,
    r_disc) and vertex sets (a disc is itself, a wall the vertex -1 - w: READINGS F4), by name."""
    def tokens(a):
        return (a,) if a < n else tuple(-1 - w for w in sorted(on_walls[a - n]))

    out = {k: [] for k in ("he_pore", "he_a", "he_b", "he_wall", "c_pore", "c_disc", "c_prev", "c_next",
                           "r_pore", "r_disc", "vertex_sets")}
    for p, f in enumerate(open_faces):
        cycles = cycles_of_face[f]
        for c in cycles:
            for a, b in c:
                out["he_pore"].append(p), out["he_a"].append(a), out["he_b"].append(b)
                out["he_wall"].append(min(on_walls[a - n] & on_walls[b - n]) if a >= n and b >= n else -1)
        cd, cp, cn = _corners(cycles)
        out["c_pore"] += [p] * len(cd)
        out["c_disc"] += cd.tolist()
        out["c_prev"] += cp.tolist()
        out["c_next"] += cn.tolist()
        rat = rattlers_of_face.get(f, [])
        out["r_pore"] += [p] * len(rat)
        out["r_disc"] += rat
        out["vertex_sets"].append(frozenset(int(t) for c in cycles for a, _ in c for t in tokens(a)) | frozenset(rat))
    return out


def _throats_and_surface(links, face_left, pore_of, outer, wall, n_p):
    """Throats (pore pairs across a link, and the link), the free surface (n_p,) bool: a pore
    beside the outer face across a link that is not wall-wall (a wall element), and each pore's
    neighbours across throats."""
    sides = [(pore_of.get(face_left(a, b), -1), pore_of.get(face_left(b, a), -1)) for a, b in links]
    throats, throat_link = [], []
    surface = np.zeros(n_p, bool)
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
    return throats, throat_link, surface, neighbours


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
    contact state (eq 43b: r_k + r_l + eps_m >= R)."""

    polygon_area: np.ndarray
    void_area: np.ndarray
    corner_angle: np.ndarray
    centroid: np.ndarray
    link_contact: np.ndarray


def measure(pores, x, r, eps_m):
    """Areas (eq 29), corner angles and link states of ``pores`` at positions x (in x's dtype);
    a disc-wall link is in contact when the disc's gap to the face is <= eps_m (eq 43b with r = 0
    at the foot point)."""
    x, r = wall_vertices(pores, x, r)
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
    The virtual vertices of flat walls have r = 0: the walls' share is ``wall_water_forces``.
    """
    n = len(x)
    x, r = wall_vertices(pores, x, r)
    d = pores.corner_disc
    a1 = _direction(x, d, pores.corner_next)
    a2 = a1 + theta
    u_r = U[pores.corner_pore] * r[d]
    F = np.zeros(x.shape, x.dtype)
    np.add.at(F[:, 0], d, -u_r * (np.sin(a2) - np.sin(a1)))              # eq 33a
    np.add.at(F[:, 1], d, u_r * (np.cos(a2) - np.cos(a1)))               # eq 33b
    return F[:n]


def wall_water_forces(pores, x, U):
    """Normal force (W,) [N per m of thickness] of the pore pressures U (Np,) [N/m] on each flat wall
    (SPEC §2.6): U x the length of every wall edge of a pore, positive along the inward normal (the
    wall pushes the water in; the water pushes the wall out)."""
    out = np.zeros(len(pores.walls), x.dtype)
    if not len(pores.walls) or not pores.n_pores:
        return out
    x, _ = wall_vertices(pores, x, np.zeros(len(x), x.dtype))
    sel = pores.he_wall >= 0
    a, b = pores.he_a[sel], pores.he_b[sel]
    length = np.sqrt((x[b, 0] - x[a, 0]) ** 2 + (x[b, 1] - x[a, 1]) ** 2)
    np.add.at(out, pores.he_wall[sel], U[pores.he_pore[sel]] * length)
    return out


def mesh_void_fraction(x, r, group, eps_m, l_m, walls=()):
    """Void over polygon area of the pores of a network built at x (eq 28-29), closed by the flat
    ``walls``, nan without pores: the void fraction of the pore mesh (not the window porosity that
    runs report)."""
    pores = build_pores(x, r, group, eps_m, l_m, walls)
    geo = measure(pores, np.asarray(x, np.float64), np.asarray(r, np.float64), eps_m)
    total = float(np.sum(geo.polygon_area))
    return float(np.sum(geo.void_area)) / total if total > 0 else np.nan


# ------------------------------------------------------------------------------------------------
# Pore water (§3.2-3.4, eq 32-46)
# ------------------------------------------------------------------------------------------------
def pore_pressure(W, A, E_w):
    """U = E_w (W - A) / W [N/m] (eq 32)."""
    return E_w * (W - A) / W


def permeability(contact, water):
    """The permeability law [1/s] (eq 43; §5.1 the free surface, §6.1 drained walls): k2 across a
    contact (``contact`` true), k1 across a gap, for each link; k1 to the outside across a free
    surface; k3 through a drained wall. ``water`` holds k1, k2, k3 (in the run's dtype)."""
    return np.where(contact, water.k2, water.k1), water.k1, water.k3


class Water:
    """Water areas W (Np,) [m^2] of the pores and their cumulative budget [m^2]."""

    def __init__(self, pores, A, s, dtype):
        self.pores, self.s, self.dtype = pores, s, dtype
        self.E_w, self.k1, self.k2, self.k3, self.q_w = (dtype(v) for v in (s.E_w, s.k1, s.k2, s.k3, s.q_w))
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
        k, k_surface, k_drained = permeability(contact[pores.throat_link], self)   # eq 43
        A_pq = W[p] * W[q] / np.where(both, A[p] + A[q], 1)                 # eq 40 (W_i W_j, not W' W_j)
        i_pq = (U[p] - U[q]) / E_w                                           # eq 39
        q_t = np.where(both, k * A_pq * i_pq, zero)                          # eq 41
        drained = pores.side if self.s.drained else np.zeros_like(pores.side)        # §6.1
        drained = drained | pores.wall_drained                                          # §2.6
        q_surface = np.where(open_ & pores.surface, k_surface * W * U / E_w, zero)   # outside at U = 0
        q_side = np.where(open_ & drained, k_drained * W * U / E_w, zero)            # §6.1: outside 0, k3
        q_in = np.where(pores.bottom | pores.wall_inflow, self.q_w, zero)    # §5.1, §2.6
        # explicit stability (Gershgorin): dt <= 2 / max (2 sum g + g_b) / c, c = W^2 / (E_w A)
        g = np.where(both, k * A_pq / E_w, zero)
        g_sum = np.zeros(pores.n_pores, self.dtype)
        np.add.at(g_sum, p, g)
        np.add.at(g_sum, q, g)
        g_b = np.where(open_ & pores.surface, k_surface * W / E_w, zero) + np.where(open_ & drained, k_drained * W / E_w, zero)
        rate = np.where(open_, (2 * g_sum + g_b) * E_w * A / W**2, zero)
        limit = 2 / float(np.max(rate)) if pores.n_pores and np.max(rate) > 0 else np.inf
        return q_t, q_surface, q_side, q_in, limit

    def used_area(self, A):
        """The area of eq 45, [A]_t = ([A]_{t-dt} + [A']_t) / 2 with smoothing, else A' itself."""
        if self.s.smoothing:
            self.A_used = (self.A_used + A) / 2
            return self.A_used
        return A

    def advance(self, dt, A, contact):
        """Advance W by dt [s] at the area actually used A (eq 45) and link states (eq 42, 46)."""
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
        """Move the water onto rebuilt pores keeping U continuous (§3.4(2)); W from eq 32.
        Returns the rule of each new pore."""
        U_old = pore_pressure(self.W, A_old, self.E_w)
        U_new, rules = inherit_pressures(self.pores, U_old, A_old > self.pores.a_min, new_pores)
        W_new = A_new * self.E_w / (self.E_w - np.asarray(U_new, self.dtype))   # eq 32 solved for W
        self.remesh_change += np.sum(W_new) - np.sum(self.W)
        self.pores, self.W, self.A_used, self.q_used = new_pores, W_new, A_new.copy(), None
        return rules


def inherit_pressures(old, U_old, old_valid, new):
    """(U, rule) of each new pore by the rules of §3.4(2), in the project's reading:
    (a) the U of the old pore with the same vertex set; else (b) the mean U of the old pores whose
    vertex set contains or is contained in the new one (split / merge); else (c) the mean U of the
    neighbouring new pores already assigned ("まわりのすべての図形": pores only, the outside is
    not one; READINGS D2), in rounds until nothing changes; else (d) U = 0. Old pores pinched to
    A <= a_min pass nothing on."""
    valid = [p for p in range(old.n_pores) if old_valid[p]]
    by_set = {old.vertex_sets[p]: p for p in valid}
    U, rule = [None] * new.n_pores, [""] * new.n_pores
    for p, vs in enumerate(new.vertex_sets):
        if vs in by_set:                                                    # (a)
            U[p], rule[p] = float(U_old[by_set[vs]]), "a"
            continue
        near = [q for q in valid if old.vertex_sets[q] <= vs or vs <= old.vertex_sets[q]]
        if near:                                                            # (b)
            U[p], rule[p] = float(np.mean([float(U_old[q]) for q in near])), "b"
    while True:                                                             # (c)
        assign = {}
        for p in range(new.n_pores):
            known = [U[q] for q in new.neighbours[p] if U[q] is not None]
            if U[p] is None and known:
                assign[p] = sum(known) / len(known)
        if not assign:
            break
        for p, u in assign.items():
            U[p], rule[p] = u, "c"
    for p in range(new.n_pores):                                            # (d)
        if U[p] is None:
            U[p], rule[p] = 0.0, "d"
    return U, rule


# ------------------------------------------------------------------------------------------------
# Input motion of the moving walls (§6.1)
# ------------------------------------------------------------------------------------------------
def input_acceleration(loading):
    """a(t) [m/s^2] of the moving walls from the [loading] table, or None for no loading.

    cosine: amplitude cos(2 pi frequency t). record: a two-column file (time [s], acceleration in
    record_units: g, gal or m/s2) rescaled by time_scale and amplitude_scale, linear between
    samples (a digital record samples a continuous motion; READINGS D1), 0 before the first and
    after the last sample.
    """
    kind = loading["type"]
    if kind == "none":
        return None
    if kind == "cosine":
        A, f = loading["amplitude"], loading["frequency"]
        return lambda t: A * np.cos(2 * np.pi * f * t)
    data = np.loadtxt(loading["record"], comments="#", ndmin=2)
    t_rec = data[:, 0] * loading["time_scale"]
    unit = {"g": G0, "gal": 0.01, "m/s2": 1.0}[loading.get("record_units", "g")]
    a_rec = data[:, 1] * unit * loading["amplitude_scale"]
    return lambda t: float(np.interp(t, t_rec, a_rec, left=0.0, right=0.0))


class WallMotion:
    """Velocity v [m/s] of the walls that follow the input a(t), advanced one step at a time by
    §6.1's "速度、変位を等加速度法で求める", read as the constant average acceleration method (Newmark
    beta = 1/4, gamma = 1/2; READINGS D1): over step k the acceleration is the mean of its ends,
    a_bar = (a(t_k) + a(t_k+1)) / 2, and
        u_k+1 = u_k + v_k dt + a_bar dt^2 / 2,   v_k+1 = v_k + a_bar dt.
    """

    def __init__(self, accel, dt, dtype=np.float64):
        self.accel, self.dt, self.dtype = accel, dtype(dt), dtype
        self.v = dtype(0)

    def step(self, k):
        """The displacement du [m] of step k (t_k = k dt -> t_k+1); advances v."""
        dt = self.dt
        a0 = self.dtype(self.accel(k * float(dt)))
        a_bar = (a0 + self.dtype(self.accel((k + 1) * float(dt)))) / 2
        du = self.v * dt + a_bar * dt * dt / 2
        self.v = self.v + a_bar * dt
        return du


# ------------------------------------------------------------------------------------------------
# Side walls on springs (§6.1, Fig. 27)
# ------------------------------------------------------------------------------------------------
def column_ties(x, group):
    """The ties of Fig. 27 as (lower, upper) (M,) disc indices: in each side-wall column (LEFT,
    RIGHT) every disc to the one above it, and the lowest to the corner disc of the bottom wall
    (the bottom-wall disc nearest to it). Raises ValueError for a column without a bottom wall."""
    x, group = np.asarray(x, float), np.asarray(group)
    bottom = np.flatnonzero(group == BOTTOM)
    lower, upper = [], []
    for side in (LEFT, RIGHT):
        column = np.flatnonzero(group == side)
        if not len(column):
            continue
        if not len(bottom):
            raise ValueError("side walls on springs need a bottom wall to tie the columns to")
        column = column[np.argsort(x[column, 1], kind="stable")]           # bottom to top
        d2 = (x[bottom, 0] - x[column[0], 0]) ** 2 + (x[bottom, 1] - x[column[0], 1]) ** 2
        chain = [int(bottom[np.argmin(d2)])] + column.tolist()
        lower += chain[:-1]
        upper += chain[1:]
    return np.array(lower, int), np.array(upper, int)


def tie_forces(x, V, lower, upper, rest, ks, eta):
    """x-forces (N,) [N] of the ties (lower, upper) on every disc: a tie is a tangential spring k'_s
    and dashpot eta'_s, and tangential to a vertical tie is x, so on the upper disc
        f_u = -k'_s [(x_u - x_l) - rest] - eta'_s (V_u - V_l),   on the lower disc -f_u,
    x (N, 2) positions [m], V (N, 2) velocities [m/s], rest (M,) x_u - x_l when the ties were made [m]."""
    F = np.zeros(len(x), x.dtype)
    for l, u, x0 in zip(lower, upper, rest):
        f = -ks * ((x[u, 0] - x[l, 0]) - x0) - eta * (V[u, 0] - V[l, 0])
        F[u] += f
        F[l] -= f
    return F


# ------------------------------------------------------------------------------------------------
# The model
# ------------------------------------------------------------------------------------------------
def block_bounds(xz, r, group, block_z, flat_walls=()):
    """Absolute [z0, z1) of the output blocks given as fractions of the bed height: from the bottom
    wall (the top of its discs, or the face of a flat bottom wall; the lowest particle bottom
    without either) to the highest particle top."""
    xz, r, group = np.asarray(xz, float), np.asarray(r, float), np.asarray(group)
    bottom = group == BOTTOM
    floor = [w.position for w in flat_walls if w.axis == 1 and w.inward == 1]
    z_bed = (np.max(xz[bottom, 1] + r[bottom]) if bottom.any() else floor[0] if floor else np.min(xz[:, 1] - r))
    mob = group == PARTICLE
    h = np.max(xz[mob, 1] + r[mob]) - z_bed
    return [(z_bed + a * h, z_bed + b * h) for a, b in block_z]


class ReferenceModel:
    """State of one run of the reference; ``step`` advances it by one dt (see the module docstring).

    ``tables``: the scene as {table: {field: value}} (or an object with ``as_dict()``); ``packing``:
    any object with xz (N, 2), r (N,), group (N,) and density_factor (N,). Attributes in the run's
    dtype: x, v (N, 2) [m, m/s], psi, omega (N,) [rad, rad/s], mass, inertia (N,) [kg/m, kg m];
    ``sliding`` (N,) the side-wall discs on springs, ``ties`` (lower, upper) and ``tie_rest``
    (column_ties). ``contact`` (PairRecords), ``pores`` / ``water`` (None when dry); ``counts``:
    re-meshing rules, separation patterns, rebuilds. ``rebuild_steps``: the steps of the pore
    rebuilds, instead of every rebuild_interval (simulate_reference). Flat walls (SPEC §2.6):
    ``flat`` (FlatWall), ``wall_contact`` / ``wall_of`` (wall_records; None / [] without them),
    ``wall_water`` (W,) [N per m of thickness] (wall_water_forces); ``wall_reactions``.
    """

    def __init__(self, tables, packing, dtype=np.float64, rebuild_steps=None):
        tables = tables if isinstance(tables, dict) else tables.as_dict()
        self.rebuild_steps = None if rebuild_steps is None else set(rebuild_steps)
        s = self.s = read_settings(tables)
        dt_ = self.dtype = np.dtype(dtype).type
        self.group = np.asarray(packing.group)
        self.mobile = self.group == PARTICLE
        self.r = np.asarray(packing.r, dt_)
        self.x = np.asarray(packing.xz, dt_).copy()
        self.x_prev = self.x.copy()
        self.v = np.zeros_like(self.x)
        self.psi = np.zeros_like(self.r)
        self.psi_prev = self.psi.copy()
        self.omega = np.zeros_like(self.r)
        self.dt = dt_(s.dt)
        self.k = 0
        pi = 2 * np.arctan2(dt_(1), dt_(0))
        self.mass = dt_(s.rho) * np.asarray(packing.density_factor, dt_) * pi * self.r**2   # eq 15a per unit thickness
        self.inertia = self.mass * self.r**2 / 2                                              # eq 15b
        if self.mobile.any():
            limit = s.dt_safety * 2 * np.sqrt(float(self.mass[self.mobile].min()) / s.kn)
            if s.dt > limit:
                raise ValueError(f"[numerics] dt = {s.dt:.3e} s exceeds dt_safety x 2 sqrt(m_min/kn) = {limit:.3e} s (eq 52)")
        self.weight = np.zeros_like(self.x)
        self.weight[:, 1] = -self.mass * dt_(s.g)
        if s.wet:
            self.weight[:, 1] += dt_(s.rho_w) * pi * self.r**2 * dt_(s.g)                    # eq 34b buoyancy
        self.sliding = np.isin(self.group, (LEFT, RIGHT)) & s.side_walls
        self.ties = column_ties(packing.xz, self.group) if s.side_walls else (np.zeros(0, int),) * 2
        self.tie_rest = self.x[self.ties[1], 0] - self.x[self.ties[0], 0]
        if self.sliding.any() and s.ks_wall > 0:   # <= 2 ties a disc: w^2 <= 4 k'_s / m, stable for w dt < 2
            limit = np.sqrt(float(self.mass[self.sliding].min()) / s.ks_wall)
            if s.dt > limit:
                raise ValueError(f"[numerics] dt = {s.dt:.3e} s exceeds sqrt(m_min/k's) = {limit:.3e} s of the "
                                 f"side-wall ties ([contact] ks_wall)")
        # the degrees of freedom integrated in e: x and z of the particles, x of the sliding walls
        self.free = np.column_stack([self.mobile | self.sliding, self.mobile])
        self.contact = PairRecords(s, self.r, self.mobile, dt_, self.sliding)
        self.flat = s.flat_walls
        self.wall_contact, self.wall_of = wall_records(s, self.r, self.mobile, self.flat, dt_)
        self.wall_water = np.zeros(len(self.flat), dt_)
        self.flat_du = np.zeros((len(self.flat), 2), dt_)   # each flat wall's displacement in the last step f
        accel = input_acceleration(s.loading)
        self.walls = None if accel is None else WallMotion(accel, s.dt, dt_)
        moving = {"bottom": (BOTTOM,), "box": (BOTTOM, LEFT, RIGHT)}[s.loading["moves"]]
        self.moving = np.isin(self.group, moving) & (accel is not None)
        self.bounds = block_bounds(packing.xz, packing.r, self.group, s.block_z, self.flat)
        self.counts = {"rebuilds": 0, "remesh": dict.fromkeys("abcd", 0), "separation": dict.fromkeys("abcd", 0),
                       "history": []}   # history: (step, rule counts) of every rebuild
        self.pores = self.water = None
        self.F_pressure = np.zeros_like(self.x)
        if s.wet:
            self.pores = self._build()
            self.water = Water(self.pores, self._measure().void_area, s, dt_)

    def _build(self):
        return build_pores(self.x, self.r, self.group, self.s.eps_m, self.s.l_m, self.flat)

    def _wall_forces(self, du, dpsi):
        """Contact forces (N, 2) [N], moments (N,) [N m] of the flat walls on the particles and the
        records that separated (as PairRecords.forces): record k acts on disc I[k] from the element
        N + k, the foot point of the disc on its wall, which moved with its wall (``wall_records``)."""
        n, m = len(self.x), len(self.wall_of)
        feet = self.x[self.wall_contact.I].copy()
        for w, wall in enumerate(self.flat):
            feet[self.wall_of == w, wall.axis] = self.dtype(wall.position)
        x = np.vstack([self.x, feet])
        du = np.vstack([du, self.flat_du[self.wall_of]])
        dpsi = np.concatenate([dpsi, np.zeros(m, dpsi.dtype)])
        F, M, left = self.wall_contact.forces(x, du, dpsi, self.dt)
        return F[:n], M[:n], left

    def wall_reactions(self):
        """(normal, water): the normal force (W,) of each flat wall on the discs and the water along
        its inward normal [N per m of thickness, positive when the wall pushes inward], and the part
        of it from the water. normal = the f_n of its contacts at the last step (eq 7) + U x its
        wetted length at the last water step (``wall_water_forces``, held until the next one)."""
        contact = np.zeros(len(self.flat), self.dtype)
        if self.wall_contact is not None:
            np.add.at(contact, self.wall_of, self.wall_contact.f_n)
        return contact + self.wall_water, self.wall_water.copy()

    def _measure(self, pores=None):
        return measure(self.pores if pores is None else pores, self.x, self.r, self.s.eps_m)

    def rebuild(self):
        """New pores at the current positions, pressures inherited by §3.4(2)."""
        new = self._build()
        rules = self.water.remesh(new, self._measure(new).void_area, self._measure().void_area)
        this = {r: rules.count(r) for r in "abcd"}
        for r, c in this.items():
            self.counts["remesh"][r] += c
        self.counts["history"].append((self.k, this))
        self.counts["rebuilds"] += 1
        self.pores = new

    def step(self):
        """One DEM step k at t = k dt (a-f of the module docstring)."""
        s, dt, k = self.s, self.dt, self.k
        du = self.x - self.x_prev                                           # a
        dpsi = self.psi - self.psi_prev
        F, M, left = self.contact.forces(self.x, du, dpsi, dt)              # b
        n_contacts, V = self.contact.contacts_of(), du / dt
        if self.wall_contact is not None:                                   # b: flat walls, elements not free
            F_w, M_w, left_w = self._wall_forces(du, dpsi)
            F, M = F + F_w, M + M_w
            for i, records in left_w.items():
                left.setdefault(i, []).extend(records)
            n_contacts = n_contacts + self.wall_contact.contacts_of()[:len(V)]
            V = np.vstack([V, self.flat_du[self.wall_of] / dt])
        if s.adjust and left:                                               # c
            fixes = adjust_free_particles(left, n_contacts, V, self.mass, self.dtype(s.e), self.counts["separation"])
            for d, vel in fixes.items():
                self.v[d] = vel
        if self.water is not None:                                          # d
            if (k in self.rebuild_steps) if self.rebuild_steps is not None else (k > 0 and k % s.rebuild_interval == 0):
                self.rebuild()
            if k % s.water_interval == 0:
                geo = self._measure()
                A = self.water.used_area(geo.void_area)                     # eq 45
                self.water.advance(s.water_interval * s.dt, A, geo.link_contact)
                U = pore_pressure(self.water.W, A, self.water.E_w)
                self.F_pressure = pressure_forces(self.pores, self.x, self.r, U, geo.corner_angle)
                self.wall_water = wall_water_forces(self.pores, self.x, U)
        F = F + self.F_pressure + self.weight                               # e
        if self.sliding.any():                                              # Fig. 27
            F[:, 0] += tie_forces(self.x, du / dt, *self.ties, self.tie_rest, self.dtype(s.ks_wall),
                                  self.dtype(s.eta_s_wall))
        m, free = self.mobile, self.free
        self.v[free] += F[free] / np.broadcast_to(self.mass[:, None], F.shape)[free] * dt   # eq 14, 16
        self.omega[m] += M[m] / self.inertia[m] * dt
        step_x, step_psi = self.v * dt, self.omega[m] * dt                  # eq 17
        self.x_prev, self.psi_prev = self.x.copy(), self.psi.copy()
        self.x[free] += step_x[free]
        self.psi[m] += step_psi
        if self.walls is not None:                                          # f
            step_w = self.walls.step(k)
            self.x[self.moving, 0] += step_w
            self._move_flat_walls(step_w)
        self.k += 1

    def _move_flat_walls(self, step_w):
        """Translate the flat walls that move by step_w [m] in x (step f): an x-wall's face moves."""
        moves = np.array([w.moves for w in self.flat], bool)
        if not moves.any():
            return
        self.flat_du[moves, 0] = step_w
        self.flat = tuple(replace(w, position=w.position + step_w) if w.moves and w.axis == 0 else w
                          for w in self.flat)
        if self.pores is not None:
            self.pores.walls = self.flat

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
        traj.append(self.k * self.s.dt, self.x, self.block_pressures(),
                    w.total() if w else np.nan, w.balance_error() if w else np.nan)


def simulate_reference(tables, packing, n_steps, record_every, dtype=np.float64, rebuild_steps=None):
    """Run the scene ``tables`` (or a Scene) from ``packing`` for n_steps and record a Trajectory
    after every ``record_every`` steps (at t = (k + 1) dt); the contract shared with
    engines.yade.coupling. ``traj.info["counts"]`` holds the re-meshing and separation counts.
    ``rebuild_steps``: the steps at which to rebuild the pores instead of every rebuild_interval
    (those a run rebuilding by displacement recorded)."""
    model = ReferenceModel(tables, packing, dtype, rebuild_steps)
    traj = Trajectory(info={"implementation": "reference", "dtype": np.dtype(dtype).name})
    for k in range(n_steps):
        model.step()
        if (k + 1) % record_every == 0:
            model.record(traj)
    traj.info["counts"] = model.counts
    return traj
