"""Deposition under gravity into a box of fixed wall discs (seed 000 §4.2), run in YADE.

The box: a bottom row of ``n_bottom`` touching wall discs and two side columns of ``n_side``
discs sharing the corners (the quick-sand box: 15 + 8 + 8 = 31). Particles with log-normal
diameters start on a loose grid above the bottom and settle with the paper's packing law
(linear spring a, ks = 0, no water) plus YADE's numerical damping to come to rest sooner.
Afterwards the top layer (see ``mark_dense_top``) gets the density factor of the paper's heavy
top discs, and the walls their own density factor.

No particle may end outside the box: ``check_inside_box`` refuses a packing with one. With
``guard_walls`` the side columns are raised during deposition above the highest particle (the
extra wall discs are removed afterwards), so that particles dropped from the loose grid cannot
bounce out over the side walls (the seismic box with its soft kn = 1.4e5 N/m did, for every seed
tried, without them).
"""
import os

import numpy as np

from engines.model.pores import WALL_BOTTOM, WALL_LEFT, WALL_NONE, WALL_RIGHT
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


def guard_columns(n_bottom, n_side, radius, top):
    """Extra side-wall discs (M, 2) [m] and groups stacked on the two columns of ``wall_box`` up
    to height ``top`` [m]: the taller walls of the deposition."""
    step = 2 * radius
    zs = np.arange(n_side, max(n_side, int(np.ceil(top / step)) + 1)) * step
    x_right = (n_bottom - 1) * step
    xz = np.vstack([np.column_stack([np.zeros(len(zs)), zs]), np.column_stack([np.full(len(zs), x_right), zs])])
    return xz, np.concatenate([np.full(len(zs), WALL_LEFT), np.full(len(zs), WALL_RIGHT)])


def check_inside_box(packing, what="packing"):
    """Raise ValueError naming the particles outside the box (Packing.outside_box)."""
    out = packing.outside_box()
    if len(out):
        where = ", ".join(f"{i} at ({packing.xz[i, 0] * 1e3:.2f}, {packing.xz[i, 1] * 1e3:.2f}) mm" for i in out[:5])
        raise ValueError(f"{what}: {len(out)} particle(s) outside the box: {where}"
                         f"{' ...' if len(out) > 5 else ''} (raise the side walls: [packing] guard_walls = true)")


def loose_grid(diameters, x_left, x_right, z_bottom, rng):
    """Centres of the particles on a grid between x_left and x_right above z_bottom [m]."""
    pitch = 1.05 * diameters.max()
    per_row = max(1, int((x_right - x_left) // pitch))
    k = np.arange(len(diameters))
    x = x_left + pitch * (0.5 + k % per_row)
    z = z_bottom + pitch * (0.5 + k // per_row)
    jitter = 0.02 * pitch * (rng.random(len(k)) - 0.5)
    return np.column_stack([x + jitter, z])


def settle(scene, packing, duration=None, walls="discs"):
    """Let ``packing`` settle in YADE under the packing law; returns the settled Packing. ``walls``
    ([walls] kind): "discs", against its wall discs; "flat", against the flat walls at their inner
    faces (engines.model.pore_dem.scene_flat_walls; the wall discs stay in the Packing, unmoved)."""
    from engines.yade.coupling import YadeCoupling  # YADE only here

    p = scene.packing
    dep = scene.with_overrides({
        "contact": {"spring": "a", "ks": p.settle_ks, "eta_s": 0.0, "separation_adjustment": False},
        "water": {"enabled": False}, "loading": {"type": "none"}, "walls": {"kind": walls},
        "numerics": {"dt": p.settle_dt}})
    cp = YadeCoupling(dep, packing, newton_damping=SETTLE_DAMPING)
    cp.run(int(round((duration or p.settle_time) / p.settle_dt)))
    xz = packing.xz.copy()
    xz[packing.mobile if walls == "flat" else slice(None)] = cp.positions()
    return Packing(xz, packing.r, packing.group, packing.density_factor)


def mark_dense_top(packing, depth, factor, count=0, wall_factor=1.0):
    """Density factor ``factor`` for the top layer: particles whose top lies within ``depth`` of
    the highest particle top in their own column (particles overlapping them horizontally), or,
    with ``count`` > 0, the ``count`` particles with the highest centres (the paper numbers its
    seismic discs from the bottom up; discs 139-192 of 192 are the 54 highest). Wall discs get
    ``wall_factor``."""
    m = np.flatnonzero(packing.mobile)
    f = np.where(packing.mobile, 1.0, wall_factor)
    if count > 0:
        f[m[np.argsort(packing.xz[m, 1])[len(m) - count:]]] = factor
    else:
        x, top, r = packing.xz[m, 0], packing.xz[m, 1] + packing.r[m], packing.r[m]
        column = np.abs(x[:, None] - x[None, :]) < r[:, None] + r[None, :]
        local_top = np.max(np.where(column, top[None, :], -np.inf), axis=1)
        f[m[top >= local_top - depth]] = factor
    return Packing(packing.xz, packing.r, packing.group, f)


def _mark(scene, packing):
    p = scene.packing
    return mark_dense_top(packing, p.dense_top_depth, p.dense_top_factor, p.dense_top_count, p.wall_density_factor)


def deposit(scene):
    """Generate the scene's packing (eq 53-54, box, deposition, dense top). Needs YADE.

    ``cut_extra`` x n_particles more particles are deposited and the ``n_particles`` lowest kept,
    then re-settled: a scene cut out of a deposit, with a flat surface as in the paper (§4.2).
    The dense top is marked afterwards; with ``settle_loaded`` > 0 the packing settles once more
    with its masses, so that a run starts at rest (else the bed compacts under the added weight).
    With [walls] kind = "flat" every stage settles against the flat walls at the wall discs' inner
    faces (no dips between wall discs for a small grain to be driven into or through by the fall).
    Raises ValueError if a particle ends outside the box (``check_inside_box``).
    """
    p = scene.packing
    rng = np.random.default_rng(p.seed)
    n_dep = int(round(p.n_particles * (1 + p.cut_extra)))
    d = sample_diameters(n_dep, p.mean_diameter, p.std_diameter, p.d_min, p.d_max, rng)
    walls, groups = wall_box(p.n_bottom, p.n_side, p.wall_radius)
    inner_left, inner_right = p.wall_radius, (p.n_bottom - 1) * 2 * p.wall_radius - p.wall_radius
    xz = loose_grid(d, inner_left, inner_right, p.wall_radius, rng)
    if p.guard_walls:
        extra, extra_groups = guard_columns(p.n_bottom, p.n_side, p.wall_radius, (xz[:, 1] + d / 2).max() + d.max())
        walls, groups = np.vstack([walls, extra]), np.concatenate([groups, extra_groups])
    n_w = len(walls)
    loose = Packing(np.vstack([xz, walls]), np.concatenate([d / 2, np.full(n_w, p.wall_radius)]),
                    np.concatenate([np.full(n_dep, WALL_NONE), groups]), np.ones(n_dep + n_w))
    walls_kind = scene.walls.kind
    settled = settle(scene, loose, walls=walls_kind)
    check_inside_box(settled, f"deposit of seed {p.seed}")
    n_box = p.n_bottom + 2 * (p.n_side - 1)  # the guard discs come after the box's walls
    keep = np.argsort(settled.xz[:n_dep, 1])[:p.n_particles]
    keep = np.concatenate([np.sort(keep), np.arange(n_dep, n_dep + (n_w if p.cut_extra > 0 else n_box))])
    cut = Packing(settled.xz[keep], settled.r[keep], settled.group[keep], settled.density_factor[keep])
    if p.cut_extra > 0:
        cut = settle(scene, cut, duration=0.5 * p.settle_time, walls=walls_kind)
        check_inside_box(cut, f"deposit of seed {p.seed} after the cut")
        cut = Packing(cut.xz[:p.n_particles + n_box], cut.r[:p.n_particles + n_box],
                      cut.group[:p.n_particles + n_box], cut.density_factor[:p.n_particles + n_box])
    cut = _mark(scene, cut)
    if p.settle_loaded > 0:  # the dense top was settled at density 1: let the bed take its weight
        loaded = submerged(scene, cut) if p.settle_submerged else cut
        cut = Packing(settle(scene, loaded, duration=p.settle_loaded, walls=walls_kind).xz, cut.r, cut.group,
                      cut.density_factor)
        check_inside_box(cut, f"deposit of seed {p.seed} under the dense top")
    return cut


def submerged(scene, packing):
    """``packing`` with the density factors (rho f - rho_w) / rho of its particles: settled dry, it
    comes to rest under their buoyant weight (eq 34b), as a saturated bed does in its water."""
    rho, rho_w = scene.material.rho, scene.material.rho_w
    f = np.where(packing.mobile, (rho * packing.density_factor - rho_w) / rho, packing.density_factor)
    if (f[packing.mobile] <= 0).any():
        raise ValueError(f"[packing] settle_submerged: a particle no denser than the water (rho f <= rho_w = {rho_w} kg/m^3) "
                         f"does not settle in it")
    return Packing(packing.xz, packing.r, packing.group, f)


def settle_on_flat_walls(scene, packing):
    """The particles of ``packing`` settled again, with their masses, against the flat walls that
    replace its wall discs ([walls] kind = "flat"), for settle_loaded or else half of settle_time
    (under their buoyant weight with settle_submerged); each group of wall discs is then moved so that
    its inner face is where its flat wall stood (engines.model.pore_dem.scene_flat_walls keeps a
    wall there that the particles rest on): a run on the flat walls starts at rest."""
    from engines.model.pore_dem import scene_flat_walls

    p = scene.packing
    walls = scene_flat_walls(scene.settings, packing)
    loaded = submerged(scene, packing) if p.settle_submerged else packing
    xz = settle(scene, loaded, duration=p.settle_loaded or 0.5 * p.settle_time, walls="flat").xz
    faces = packing.inner_faces()
    for code, wall in walls.items():
        xz[packing.group == code, wall.axis] += wall.position - faces[code]
    out = Packing(xz, packing.r, packing.group, packing.density_factor)
    check_inside_box(out, "packing settled on the flat walls")
    return out


def scene_packing(scene):
    """The packing a scene runs on: its CSV file (source = file) or a fresh deposit."""
    if scene.packing.source == "file":
        if not os.path.exists(scene.packing.file):
            raise ValueError(f"[packing] file: not found: {scene.packing.file} (make packings regenerates it)")
        return Packing.load(scene.packing.file)
    return deposit(scene)
