"""Deposition under gravity into a box of fixed wall discs (seed 000 §4.2), run in YADE.

The box: a bottom row of ``n_bottom`` touching wall discs and two side columns of ``n_side``
discs sharing the corners (the quick-sand box: 15 + 8 + 8 = 31). Particles with log-normal
diameters start on a loose grid above the bottom and settle with the paper's packing law
(linear spring a, ks = 0, no water) plus YADE's numerical damping to come to rest sooner.
Afterwards the top layer (see ``mark_dense_top``) gets the density factor of the paper's heavy
top discs.
"""
import os

import numpy as np

from engines.pore_geometry import WALL_BOTTOM, WALL_LEFT, WALL_NONE, WALL_RIGHT
from packing.packing import Packing
from packing.psd import sample_diameters

SETTLE_DAMPING = 0.3  # NewtonIntegrator damping during deposition only


def wall_box(n_bottom, n_side, radius):
    """Wall disc centres (M, 2) [m] and groups of the box; corners belong to the bottom row."""
    step = 2 * radius
    bottom = np.column_stack([np.arange(n_bottom) * step, np.zeros(n_bottom)])
    zs = np.arange(1, n_side) * step
    left = np.column_stack([np.zeros(n_side - 1), zs])
    right = np.column_stack([np.full(n_side - 1, (n_bottom - 1) * step), zs])
    groups = np.concatenate([np.full(n_bottom, WALL_BOTTOM), np.full(n_side - 1, WALL_LEFT),
                             np.full(n_side - 1, WALL_RIGHT)])
    return np.vstack([bottom, left, right]), groups


def loose_grid(diameters, x_left, x_right, z_bottom, rng):
    """Centres of the particles on a grid between x_left and x_right above z_bottom [m]."""
    pitch = 1.05 * diameters.max()
    per_row = max(1, int((x_right - x_left) // pitch))
    k = np.arange(len(diameters))
    x = x_left + pitch * (0.5 + k % per_row)
    z = z_bottom + pitch * (0.5 + k // per_row)
    jitter = 0.02 * pitch * (rng.random(len(k)) - 0.5)
    return np.column_stack([x + jitter, z])


def settle(scene, packing, duration=None):
    """Let ``packing`` settle in YADE under the packing law; returns the settled Packing."""
    from engines.yade_coupling import YadeCoupling  # YADE only here

    p = scene.packing
    dep = scene.with_overrides({
        "contact": {"spring": "a", "ks": 0.0, "eta_s": 0.0, "separation_adjustment": False},
        "water": {"enabled": False}, "loading": {"type": "none"},
        "numerics": {"dt": p.settle_dt, "damping_eq44": False}})
    cp = YadeCoupling(dep, packing, newton_damping=SETTLE_DAMPING)
    cp.run(int(round((duration or p.settle_time) / p.settle_dt)))
    return Packing(cp.positions(), packing.r, packing.group, packing.density_factor)


def mark_dense_top(packing, depth, factor):
    """Density factor ``factor`` for the top layer: particles whose top lies within ``depth`` of
    the highest particle top in their own column (particles overlapping them horizontally)."""
    m = np.flatnonzero(packing.mobile)
    x, top, r = packing.xz[m, 0], packing.xz[m, 1] + packing.r[m], packing.r[m]
    column = np.abs(x[:, None] - x[None, :]) < r[:, None] + r[None, :]
    local_top = np.max(np.where(column, top[None, :], -np.inf), axis=1)
    f = np.ones(len(packing.r))
    f[m[top >= local_top - depth]] = factor
    return Packing(packing.xz, packing.r, packing.group, f)


def deposit(scene):
    """Generate the scene's packing (eq 53-54, box, deposition, dense top). Needs YADE.

    ``cut_extra`` x n_particles more particles are deposited and the ``n_particles`` lowest kept,
    then re-settled: a scene cut out of a deposit, with a flat surface as in the paper (§4.2).
    """
    p = scene.packing
    rng = np.random.default_rng(p.seed)
    n_dep = int(round(p.n_particles * (1 + p.cut_extra)))
    d = sample_diameters(n_dep, p.mean_diameter, p.std_diameter, p.d_min, p.d_max, rng)
    walls, groups = wall_box(p.n_bottom, p.n_side, p.wall_radius)
    inner_left, inner_right = p.wall_radius, (p.n_bottom - 1) * 2 * p.wall_radius - p.wall_radius
    xz = loose_grid(d, inner_left, inner_right, p.wall_radius, rng)
    n_w = len(walls)
    loose = Packing(np.vstack([xz, walls]), np.concatenate([d / 2, np.full(n_w, p.wall_radius)]),
                    np.concatenate([np.full(n_dep, WALL_NONE), groups]), np.ones(n_dep + n_w))
    settled = settle(scene, loose)
    keep = np.argsort(settled.xz[:n_dep, 1])[:p.n_particles]
    keep = np.concatenate([np.sort(keep), np.arange(n_dep, n_dep + n_w)])
    cut = Packing(settled.xz[keep], settled.r[keep], settled.group[keep], settled.density_factor[keep])
    if p.cut_extra > 0:
        cut = settle(scene, cut, duration=0.5 * p.settle_time)
    return mark_dense_top(cut, p.dense_top_depth, p.dense_top_factor)


def cut_and_resettle(scene, deposit_packing, x0, width):
    """A sub-scene: the particles of a deposit with centre x in [x0, x0 + width), moved into a
    new box of the scene's wall discs (sized to the window) and settled again (§4.2)."""
    p = scene.packing
    keep = deposit_packing.mobile & (deposit_packing.xz[:, 0] >= x0) & (deposit_packing.xz[:, 0] < x0 + width)
    if not keep.any():
        raise ValueError(f"cut: no particle with x in [{x0}, {x0 + width})")
    n_bottom = int(np.ceil(width / (2 * p.wall_radius))) + 2
    walls, groups = wall_box(n_bottom, p.n_side, p.wall_radius)
    xz = deposit_packing.xz[keep] - [x0 - 2 * p.wall_radius, deposit_packing.bed_bottom - p.wall_radius]
    r = deposit_packing.r[keep]
    cut = Packing(np.vstack([xz, walls]), np.concatenate([r, np.full(len(walls), p.wall_radius)]),
                  np.concatenate([np.full(len(r), WALL_NONE), groups]), np.ones(len(r) + len(walls)))
    return mark_dense_top(settle(scene, cut), p.dense_top_depth, p.dense_top_factor)


def scene_packing(scene):
    """The packing a scene runs on: its CSV file (source = file) or a fresh deposit."""
    if scene.packing.source == "file":
        if not os.path.exists(scene.packing.file):
            raise ValueError(f"[packing] file: not found: {scene.packing.file} (make packings regenerates it)")
        return Packing.load(scene.packing.file)
    return deposit(scene)
