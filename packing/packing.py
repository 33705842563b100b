"""A packing: disc centres, radii, groups and density factors, saved as CSV (x, z, r, group, density_factor).

A packing file is a regular file of at most 200 MB (LIMIT) whose line 1 is the header HEADER,
checked by its column names (a file without it is refused, not read losing its first disc).

Refusals name the disc: in a file by its line number (the header is line 1, so the first disc is
line 2), otherwise by its 0-based index. A packing refuses a non-finite value, a radius or density
factor <= 0, a group code not in engines.model.groups, and two discs with the same centre
(duplicated rows); ``check_fit`` also refuses particles outside the walls' box and overlaps deeper
than a tolerance (preflight gives it the scene's contact law).
"""
import os
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from engines import files
from engines.files.inputs import MB, check_input_file
from engines.model.groups import GROUP_NAMES, WALL_BOTTOM, WALL_NONE, disc_groups, kind
from engines.model.pores import check_discs

COLUMNS = ("x", "z", "r", "group", "density_factor")
HEADER = ("x_m", "z_m", "r_m", "group", "density_factor")  # line 1 of a packing file
LIMIT = 200 * MB  # the largest packing file read [bytes]


@dataclass
class Packing:
    """Discs of a scene. ``group``: 0 particle, 1 bottom wall, 2 left wall, 3 right wall (the wall
    codes of engines.model.pores). ``density_factor`` multiplies the material density (the
    paper's denser top discs and walls)."""

    xz: np.ndarray
    r: np.ndarray
    group: np.ndarray
    density_factor: np.ndarray
    path: str = None  # the CSV file it was read from (named in refusals)
    lines: np.ndarray = None  # the file's line of each disc (1-based), when not simply index + 2

    def __post_init__(self):
        r = np.asarray(self.r, float)
        n = r.shape[0] if r.ndim == 1 else -1
        columns = dict(zip(COLUMNS, (*np.asarray(self.xz, float).T, r, np.asarray(self.group, float),
                                     np.asarray(self.density_factor, float))))
        if np.shape(self.xz) != (n, 2) or any(v.shape != (n,) for v in columns.values()):
            raise ValueError(f"{self.source}: expected columns x, z, r, group, density_factor of one length, "
                             f"got xz {np.shape(self.xz)}, r {np.shape(self.r)}, group {np.shape(self.group)}, "
                             f"density_factor {np.shape(self.density_factor)}")
        for name, values in columns.items():
            self._refuse_first(~np.isfinite(values), f"{name} = {{}} is not a number", values)
        self._refuse_first(r <= 0, "r = {} m: a radius must be > 0", r)
        self._refuse_first(columns["density_factor"] <= 0, "density_factor = {}: must be > 0", columns["density_factor"])
        g = columns["group"]
        self._refuse_first(~np.isin(g, list(GROUP_NAMES)), f"group = {{}}: not a group code "
                           f"({', '.join(f'{c} {name}' for c, name in GROUP_NAMES.items())})", g)
        _, first, inverse = np.unique(columns["x"] + 1j * columns["z"], return_index=True, return_inverse=True)
        twin = first[inverse.ravel()]
        self._refuse_first(twin != np.arange(n), "the same centre as {}: a duplicated disc",
                           np.array([self.row_name(i) for i in twin], dtype=object))
        self.xz, self.r = check_discs(self.xz, r)
        self.group = g.astype(np.int64)
        self.density_factor = columns["density_factor"]

    @property
    def source(self):
        return f"packing file {self.path}" if self.path else "packing"

    def row_name(self, i):
        """Disc ``i`` as refusals name it: its line in the file (the header is line 1) or its index."""
        if not self.path:
            return f"disc {i}"
        return f"line {i + 2 if self.lines is None else int(self.lines[i])}"

    def _refuse_first(self, bad, what, values):
        """ValueError naming the file, the first disc where ``bad`` and ``what`` with its value."""
        if np.any(bad):
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"{self.source}, {self.row_name(i)}: {what.format(values[i])}")

    def inner_faces(self):
        """The walls' inner faces [m] by wall code, of the walls present: the left wall discs'
        max(x + r), the right's min(x - r), the bottom's max(z + r)."""
        faces = {}
        for k in disc_groups():  # the face of each wall group (engines.model.groups): inward x its discs' edge
            w = self.group == k.group
            if w.any():
                axis, inward = k.face
                faces[k.group] = inward * float((inward * self.xz[w, axis] + self.r[w]).max())
        return faces

    def outside_box(self):
        """Indices of the particles whose centre is not strictly inside the walls' box: between the
        side walls' inner faces and above the bottom's (``inner_faces``; open at the top)."""
        out = np.zeros(len(self.r), bool)
        for code, face in self.inner_faces().items():
            axis, inward = kind(GROUP_NAMES[code]).face
            out |= inward * self.xz[:, axis] <= inward * face
        return np.flatnonzero(out & self.mobile)

    def check_fit(self, max_overlap, tolerance="the tolerance", wall_discs=True):
        """Refuse (ValueError naming the file and line) a particle outside the walls' box
        (``outside_box``) and two discs (not both wall discs) overlapping by more than
        ``max_overlap`` [m] (named ``tolerance``). ``wall_discs`` False: the wall discs are not
        there (flat walls stand in their place): two particles only."""
        out = self.outside_box() if wall_discs else []
        if len(out):
            i = out[0]
            faces = ", ".join(f"{GROUP_NAMES[c]} {'xz'[kind(GROUP_NAMES[c]).face[0]]} = {f:.6g}"
                              for c, f in self.inner_faces().items())
            raise ValueError(f"{self.source}, {self.row_name(i)}: particle centre (x, z) = ({self.xz[i, 0]:.6g}, "
                             f"{self.xz[i, 1]:.6g}) m is outside the walls' box (inner faces {faces} m)")
        m = self.mobile
        pairs = cKDTree(self.xz).query_pairs(2 * self.r.max(), output_type="ndarray")
        i, j = pairs.T
        overlap = self.r[i] + self.r[j] - np.linalg.norm(self.xz[i] - self.xz[j], axis=1)
        bad = (overlap > max_overlap) & ((m[i] | m[j]) if wall_discs else (m[i] & m[j]))
        if bad.any():
            k = np.flatnonzero(bad)
            k = k[np.lexsort((j[k], i[k]))[0]]  # the first disc in the file, then its first partner
            raise ValueError(f"{self.source}, {self.row_name(i[k])}: overlaps {self.row_name(j[k])} by "
                             f"{overlap[k]:.3g} m ({overlap[k] / min(self.r[i[k]], self.r[j[k]]):.1%} of the smaller "
                             f"radius), deeper than {tolerance} = {max_overlap:.3g} m")

    def particles(self):
        """The packing of the particles alone (the wall discs left out; no file: its refusals name
        the discs by their new index)."""
        m = self.mobile
        return Packing(self.xz[m], self.r[m], self.group[m], self.density_factor[m])

    @property
    def mobile(self):
        return self.group == WALL_NONE

    @property
    def bed_bottom(self):
        """z of the bottom wall centres' top edge [m] (or the lowest particle bottom if no wall)."""
        walls = self.group == WALL_BOTTOM
        if walls.any():
            return float(np.max(self.xz[walls, 1] + self.r[walls]))
        return float(np.min(self.xz[:, 1] - self.r))

    @property
    def bed_top(self):
        """Highest particle top [m]."""
        m = self.mobile
        return float(np.max(self.xz[m, 1] + self.r[m]))

    def block_bounds(self, block_z, bottom=None):
        """Absolute [z0, z1) of pressure blocks given as fractions of the bed height [m] above
        ``bottom`` [m] (default bed_bottom)."""
        bottom = self.bed_bottom if bottom is None else bottom
        h = self.bed_top - bottom
        return [(bottom + a * h, bottom + b * h) for a, b in block_z]

    def save(self, path):
        """Write the CSV (HEADER, one disc a line) atomically (engines.files)."""
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        data = np.column_stack([self.xz, self.r, self.group, self.density_factor])
        with files.saved(path) as tmp:
            np.savetxt(tmp, data, delimiter=",", header=",".join(HEADER), comments="",
                       fmt=["%.12e", "%.12e", "%.12e", "%d", "%.6g"])

    @classmethod
    def load(cls, path):
        """Read a CSV packing: a regular file of at most LIMIT bytes whose line 1 is the header
        (HEADER; x, z, r without "_m" accepted), then one disc a line. Refusals (ValueError) name the
        file and the line as an editor counts it."""
        check_input_file(path, "packing file", LIMIT)
        with open(path, errors="replace") as f:
            header = f.readline()
        names = [name.strip().lower() for name in header.split(",")]
        if names not in ([*HEADER], [*COLUMNS]):
            row = "a row of numbers" if all(_is_number(n) for n in names) else repr(header.strip()[:80])
            raise ValueError(f"packing file {path}, line 1: expected the header {','.join(HEADER)}, got {row}"
                             f"{' (a file without its header: add the header line)' if row.startswith('a row') else ''}")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)  # "input contained no data": refused below
                d = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        except (OSError, ValueError):
            raise ValueError(_first_bad_line(path)) from None
        if d.size == 0:
            raise ValueError(f"packing file {path}: holds the header and no discs")
        return cls(d[:, :2], d[:, 2], d[:, 3], d[:, 4], path=path, lines=_disc_lines(path, len(d)))


def _is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def _disc_lines(path, n):
    """The line (1-based) of each of the ``n`` discs numpy read from ``path``, or None when they
    are lines 2 to n + 1 (no blank or comment line among them)."""
    with open(path, "rb") as f:
        text = f.read()
    if text.count(b"\n") + (not text.endswith(b"\n")) == n + 1:
        return None
    data = [k for k, line in enumerate(text.decode(errors="replace").splitlines(), 1)
            if k > 1 and line.split("#", 1)[0].strip()]
    return np.array(data) if len(data) == n else None


def _first_bad_line(path):
    """Why numpy could not read the packing file ``path``: its first line (1-based, the header
    line 1) that is not 5 comma-separated numbers."""
    with open(path, errors="replace") as f:
        next(f)
        for k, line in enumerate(f, 2):
            line = line.split("#", 1)[0]
            cells = line.strip().split(",")
            if not line.strip():
                continue
            if len(cells) != len(COLUMNS):
                return (f"packing file {path}, line {k}: expected {len(COLUMNS)} columns {','.join(HEADER)}, "
                        f"got {len(cells)}: {line.strip()[:80]!r}")
            bad = [c for c in cells if not _is_number(c)]
            if bad:
                return f"packing file {path}, line {k}: not a number: {bad[0].strip()[:40]!r}"
    return f"packing file {path}: cannot be read as CSV numbers"
