"""Axis-aligned flat walls as pore boundaries (SPEC §2.6 "Flat walls"). Pure NumPy, no YADE.

A flat wall (a YADE ``Box`` face or ``Wall``) acts as a disc of infinite radius: disc i is linked
to it when its gap to the face is <= eps_m + l_m (eq 28), in contact when the gap is <= eps_m
(eq 43). The pores use it through zero-radius *wall vertices* added to the N discs:

* the *foot* of disc i on wall w, its orthogonal projection on the face, recomputed from the disc
  at every measure (vertex N + w N + i); the link disc i - its foot is the disc's link to the wall
  (its length is r_i + gap, so eq 43 reads gap <= eps_m);
* the *corner* of two walls of different axes (vertex N + W N + c, W walls), where the two faces
  meet, when both walls have a linked disc.

A wall may translate (the seismic base): WallVertices.shift (W, 2) [m] is each wall's displacement
from its FlatWall; the face moves with its normal component, and the feet, projections, with the
face. Along the face a translation moves no vertex; it is the feet's material motion, which the
paper's law feels (engines.model.paper_law).

Two wall vertices on a common wall are linked (the *wall edge*, along the face); a disc is linked
to its own feet only. With radius 0, a wall vertex has no sector (eq 29) and takes no pressure force
(eq 33), so polygon areas, sectors, link states and the arc forces are those of engines.model.pores
unchanged; the force U x length of a wall edge goes to the wall (pores.flat_wall_forces).
In a pore's vertex set (re-meshing rules (a)-(d)) all vertices of wall w count as one, N + w.
"""
from dataclasses import dataclass

import numpy as np

from engines.model.groups import words

@dataclass(frozen=True)
class FlatWall:
    """The face x = position (axis 0) or z = position (axis 1) [m]; the discs are on its side
    ``inward`` (+1: x or z > position, -1: below). ``boundary``: "undrained" (no flow across the
    wall edge), "drained" (exchange with U = 0 outside through k3, as drained side walls) or
    "inflow" (q_w [m^2/s] into each pore that has the wall as a vertex, as the bottom wall of §5.1;
    or inflow_velocity x each wall edge's length into the pore beside it, SPEC §2.7)."""

    axis: int
    position: float
    inward: int
    boundary: str = "undrained"

    def __post_init__(self):
        if self.axis not in (0, 1):
            raise ValueError(f"FlatWall: axis must be 0 (x = position) or 1 (z = position), got {self.axis!r}")
        if self.inward not in (1, -1):
            raise ValueError(f"FlatWall: inward must be +1 or -1, got {self.inward!r}")
        if not np.isfinite(self.position):
            raise ValueError(f"FlatWall: position must be finite [m], got {self.position!r}")
        if self.boundary not in words():
            raise ValueError(f"FlatWall: boundary must be one of {words()}, got {self.boundary!r}")

    def gap(self, xz, r):
        """Gaps (N,) [m] of discs at xz (N, 2) with radii r (N,) to the face (< 0: overlap)."""
        return self.inward * (np.asarray(xz, float)[:, self.axis] - self.position) - np.asarray(r, float)

    def normal(self):
        """The inward unit normal (2,): the direction from the face to the discs."""
        n = np.zeros(2)
        n[self.axis] = self.inward
        return n


def as_tables(walls, moving=None):
    """The FlatWalls as the tables' list [{"axis": "x" | "z", "position", "inward", "boundary",
    "moves"}] (the reference's input, engines.reference.model.read_flat_walls); ``moving`` (W,) bool:
    the walls that follow the input acceleration (default none)."""
    moving = np.zeros(len(walls), bool) if moving is None else moving
    return [{"axis": "xz"[w.axis], "position": w.position, "inward": w.inward, "boundary": w.boundary,
             "moves": bool(m)} for w, m in zip(walls, moving)]


class WallVertices:
    """The wall vertices of ``walls`` (FlatWall, ...) for N discs (module docstring).

    owner (V,): the disc of each vertex (itself for a disc, -1 for a corner); bits (V,): bit w set
    when the vertex lies on wall w (0 for a disc); corners (C, 2): the wall pairs of the corners;
    shift (W, 2) [m]: the walls' displacements (module docstring; ``move``), zero at the start.
    """

    CHECKPOINT_FIELDS = ("shift",)  # what a checkpoint stores (engines.model.state)
    CHECKPOINT_DERIVED = {name: "the scene's flat walls and the number of discs" for name in
                          ("walls", "n", "corners", "n_vertices", "owner", "bits")}

    def __init__(self, walls, n):
        self.walls, self.n = tuple(walls), int(n)
        if not all(isinstance(w, FlatWall) for w in self.walls):
            raise TypeError("flat_walls: expected FlatWall instances")
        n_w = len(self.walls)
        for a in range(n_w):
            for b in range(a + 1, n_w):
                wa, wb = self.walls[a], self.walls[b]
                if wa.axis == wb.axis and not (wa.inward == -wb.inward and (wb.position - wa.position) * wa.inward > 0):
                    raise ValueError(f"flat walls {a} and {b}: parallel walls must face each other ({wa}, {wb})")
        self.corners = np.array([(a, b) for a in range(n_w) for b in range(a + 1, n_w)
                                 if self.walls[a].axis != self.walls[b].axis], np.int64).reshape(-1, 2)
        self.n_vertices = n + n_w * n + len(self.corners)
        self.owner = np.concatenate([np.tile(np.arange(n), n_w + 1), np.full(len(self.corners), -1)])
        bit = np.int64(1) << np.arange(n_w, dtype=np.int64)
        self.bits = np.concatenate([np.zeros(n, np.int64), np.repeat(bit, n),
                                    bit[self.corners[:, 0]] | bit[self.corners[:, 1]]])
        self.shift = np.zeros((n_w, 2))

    def move(self, shift):
        """Set the walls' displacements ``shift`` (W, 2) [m] from their FlatWall positions."""
        shift = np.asarray(shift, float)
        if shift.shape != self.shift.shape or not np.all(np.isfinite(shift)):
            raise ValueError(f"flat walls: shift must be finite, of shape {self.shift.shape} [m], got {shift!r}")
        self.shift = shift.copy()

    def faces(self):
        """The faces' positions (W,) [m]: each wall's position moved by its shift along its axis."""
        return np.array([w.position + self.shift[k, w.axis] for k, w in enumerate(self.walls)])

    def gaps(self, w, xz, r):
        """Gaps (N,) [m] of discs at xz (N, 2) with radii r (N,) to the face of wall w (< 0: overlap)."""
        wall = self.walls[w]
        return wall.gap(xz, r) - wall.inward * self.shift[w, wall.axis]

    def foot(self, w, i):
        """The vertex id of the foot of disc(s) i on wall w."""
        return self.n + w * self.n + np.asarray(i)

    def positions(self, xz):
        """Positions (V, 2) [m] of all vertices: the discs at xz (N, 2), their feet, the corners."""
        n, out, faces = self.n, np.empty((self.n_vertices, 2)), self.faces()
        out[:n] = xz
        for w, wall in enumerate(self.walls):
            feet = out[self.foot(w, 0):self.foot(w, n)]
            feet[:] = xz
            feet[:, wall.axis] = faces[w]
        out[self.foot(len(self.walls), 0):] = self.corner_positions()
        return out

    def corner_positions(self):
        """Positions (C, 2) [m] of the corners, where the faces of their two walls meet."""
        out, faces = np.empty((len(self.corners), 2)), self.faces()
        for c, (a, b) in enumerate(self.corners.tolist()):
            for w in (a, b):
                out[c, self.walls[w].axis] = faces[w]
        return out

    def radii(self, r):
        """Radii (V,) [m]: the discs' r (N,), 0 for the wall vertices."""
        return np.concatenate([np.asarray(r, float), np.zeros(self.n_vertices - self.n)])

    def check_inside(self, xz):
        """Refuse a disc centre at xz (N, 2) [m] on the face or on the outer side of a wall."""
        for w, (wall, face) in enumerate(zip(self.walls, self.faces())):
            out = np.flatnonzero(self.gaps(w, xz, 0.0) <= 0)
            if len(out):
                raise ValueError(f"flat wall {w} ({'xz'[wall.axis]} = {face:g} m, inward {wall.inward:+d}): "
                                 f"disc {out[0]} has its centre at {xz[out[0], wall.axis]:g} m, not inside")

    def active(self, xz, r, reach):
        """Ids of the vertices of a build: the discs, the feet of the discs within ``reach`` =
        eps_m + l_m of their wall (eq 28), the corners of two walls that both have a foot."""
        feet = [self.foot(w, np.flatnonzero(self.gaps(w, xz, r) <= reach)) for w in range(len(self.walls))]
        has = np.array([len(f) > 0 for f in feet], bool)
        corner = self.foot(len(self.walls), np.flatnonzero(has[self.corners].all(axis=1)))
        return np.concatenate([np.arange(self.n), *feet, corner]).astype(np.int64)

    def disc_feet(self, active):
        """The links (M, 2) disc - foot among the ``active`` vertices."""
        f = active[(active >= self.n) & (self.owner[active] >= 0)]
        return np.column_stack([self.owner[f], f])

    def is_link(self, a, b, eq28):
        """Are the vertex pairs (a, b) links: two discs, eq28 (their eq 28); a disc and a wall vertex,
        when it is the disc's foot; two wall vertices, when they lie on a common wall."""
        wa, wb = a >= self.n, b >= self.n
        wall_wall = (self.bits[a] & self.bits[b]) != 0
        return np.where(wa | wb, np.where(wa & wb, wall_wall, self.owner[a] == self.owner[b]), eq28)

    def may_touch(self, a, b):
        """Can the vertices (a, b) be a contact pair of the paper's law: two discs, or a disc and
        its own foot (engines.model.paper_law)?"""
        return self.is_link(a, b, True)

    def split_bits(self, bits):
        """The set bits of ``bits`` (M,) (as in ``self.bits``): index (K,) and wall (K,), one pair
        per wall w whose bit is set in bits[index]."""
        pairs = [(np.flatnonzero((bits >> w) & 1), w) for w in range(len(self.walls))]
        return (np.concatenate([k for k, _ in pairs]).astype(np.int64),
                np.concatenate([np.full(len(k), w) for k, w in pairs]).astype(np.int64))
