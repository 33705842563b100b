"""A packing: disc centres, radii, groups and density factors, saved as CSV (x, z, r, group, density_factor)."""
import os
from dataclasses import dataclass

import numpy as np

from engines.model.groups import GROUP_NAMES, WALL_BOTTOM, WALL_NONE
from engines.model.pores import check_discs


@dataclass
class Packing:
    """Discs of a scene. ``group``: 0 particle, 1 bottom wall, 2 left wall, 3 right wall (the wall
    codes of engines.model.pores). ``density_factor`` multiplies the material density (the
    paper's denser top discs and walls)."""

    xz: np.ndarray
    r: np.ndarray
    group: np.ndarray
    density_factor: np.ndarray

    def __post_init__(self):
        self.xz, self.r = check_discs(self.xz, self.r)
        self.group = np.asarray(self.group, np.int64)
        self.density_factor = np.asarray(self.density_factor, float)
        n = len(self.r)
        if self.group.shape != (n,) or not np.isin(self.group, list(GROUP_NAMES)).all():
            raise ValueError(f"group: expected {n} codes in {sorted(GROUP_NAMES)}")
        if self.density_factor.shape != (n,) or np.any(self.density_factor <= 0):
            raise ValueError(f"density_factor: expected {n} values > 0")

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

    def block_bounds(self, block_z):
        """Absolute [z0, z1) of pressure blocks given as fractions of the bed height [m]."""
        h = self.bed_top - self.bed_bottom
        return [(self.bed_bottom + a * h, self.bed_bottom + b * h) for a, b in block_z]

    def save(self, path):
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        data = np.column_stack([self.xz, self.r, self.group, self.density_factor])
        np.savetxt(path, data, delimiter=",", header="x_m,z_m,r_m,group,density_factor", comments="",
                   fmt=["%.12e", "%.12e", "%.12e", "%d", "%.6g"])

    @classmethod
    def load(cls, path):
        try:
            d = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        except (OSError, ValueError) as e:
            raise ValueError(f"packing file {path}: {e}") from None
        if d.shape[1] != 5:
            raise ValueError(f"packing file {path}: expected 5 columns x,z,r,group,density_factor, got {d.shape[1]}")
        return cls(d[:, :2], d[:, 2], d[:, 3].astype(np.int64), d[:, 4])
