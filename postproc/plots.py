"""Figures of the seed-000 runs: snapshots (Fig. 22/24) and block pressure histories (Fig. 21/23).

They read what the runs write: snapshot .npz files and history.csv (columns named as written).
"""
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PatchCollection, PolyCollection  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

GROUP_COLOURS = {0: "0.85", 1: "0.35", 2: "0.35", 3: "0.35"}


def read_history(path):
    """history.csv as {column: array}."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else {}


def plot_block_pressures(history, E_w, path, title):
    """Block-mean excess pore pressure against time, one line per block (Fig. 21/23)."""
    fig, ax = plt.subplots(figsize=(6.5, 4))
    t_ms = history["t"] * 1e3
    for name in sorted(k for k in history if k.startswith("U_block")):
        label = {"U_block1": "block 1 (bottom)", "U_block2": "block 2 (surface)"}.get(name, name)
        ax.plot(t_ms, history[name], label=label)
    ax.axhline(E_w, color="0.5", ls="--", lw=0.8, label=f"E_w = {E_w:g} N/m (bound of eq 32)")
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("excess pore pressure U [N/m]")
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_history_panels(history, path, title):
    """Porosity, kinetic energy, bottom normal force and water balance error against time."""
    panels = [("porosity", "porosity [-]"), ("kinetic_energy", "kinetic energy [J/m]"),
              ("fn_bottom_mean", "mean normal force, block 1 [N]"), ("bed_top", "bed top [mm]")]
    fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
    t_ms = history["t"] * 1e3
    for ax, (col, label) in zip(axes.ravel(), panels):
        if col in history:
            y = history[col] * (1e3 if col == "bed_top" else 1.0)
            ax.plot(t_ms, y)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("t [ms]")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def draw_snapshot(ax, snap, U_range=None, velocity_scale=None, force_scale=None):
    """Discs, pores coloured by U, normal-force network (width ~ force) and velocity arrows."""
    xz, r, group = snap["xz"] * 1e3, snap["r"] * 1e3, snap["group"]
    if "tri" in snap and len(snap["tri"]):
        U = snap["U"][snap["tri_pore"]]
        vmin, vmax = U_range if U_range else (min(U.min(), 0), max(U.max(), 1e-9))
        polys = PolyCollection(xz[snap["tri"]], array=U, cmap="coolwarm", edgecolors="none", zorder=0)
        polys.set_clim(vmin, vmax)
        ax.add_collection(polys)
        plt.colorbar(polys, ax=ax, label="pore excess pressure U [N/m]", shrink=0.8)
    circles = [Circle(p, rr) for p, rr in zip(xz, r)]
    ax.add_collection(PatchCollection(circles, facecolor=[GROUP_COLOURS[g] for g in group], edgecolor="k",
                                      linewidth=0.4, alpha=0.55, zorder=1))
    dense = snap["density_factor"] > 1
    if dense.any():
        ax.add_collection(PatchCollection([c for c, d in zip(circles, dense) if d], facecolor="none",
                                          edgecolor="k", linewidth=1.6, zorder=2))
    pairs, fn = snap["pairs"], snap["f_n"]
    if len(fn):
        scale = force_scale or max(fn.max(), 1e-12)
        ax.add_collection(LineCollection(xz[pairs], linewidths=0.3 + 3.5 * np.clip(fn, 0, None) / scale,
                                         colors="darkred", zorder=3))
    v = snap["vel"]
    mob = group == 0
    if mob.any():
        vs = velocity_scale or max(np.abs(v[mob]).max(), 1e-12)
        ax.quiver(xz[mob, 0], xz[mob, 1], v[mob, 0], v[mob, 1], angles="xy", scale_units="xy",
                  scale=vs / (2 * r.mean()), color="navy", width=0.004, zorder=4)
    ax.set_aspect("equal")
    pad = r.max()
    ax.set_xlim(xz[:, 0].min() - pad, xz[:, 0].max() + pad)
    ax.set_ylim(xz[:, 1].min() - pad, xz[:, 1].max() + 2 * pad)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")


def plot_snapshots(snaps, path, title):
    """One panel per snapshot, with shared colour range, force and velocity scales."""
    n = len(snaps)
    fig, axes = plt.subplots(1, n, figsize=(5.2 * n, 5.2), squeeze=False)
    Us = [s["U"] for s in snaps if "U" in s and len(s["U"])]
    U_range = (min(0.0, min(u.min() for u in Us)), max(u.max() for u in Us)) if Us else None
    fmax = max([s["f_n"].max() for s in snaps if len(s["f_n"])] or [1.0])
    vmax = max(np.abs(s["vel"][s["group"] == 0]).max() for s in snaps) or 1.0
    for ax, s in zip(axes[0], snaps):
        draw_snapshot(ax, s, U_range, vmax, fmax)
        ax.set_title(f"t = {float(s['t']) * 1e3:.0f} ms   (max |v| = {vmax:.3g} m/s, max f_n = {fmax:.3g} N)",
                     fontsize=9)
    fig.suptitle(title + ": pores coloured by U, normal forces (width ~ f_n), velocities (arrows)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_packing(packing, path, title):
    """A packing: particles light, walls dark, denser particles outlined (Fig. 15, 18)."""
    fig, ax = plt.subplots(figsize=(8, 6))
    xz, r = packing.xz * 1e3, packing.r * 1e3
    circles = [Circle(p, rr) for p, rr in zip(xz, r)]
    colours = [GROUP_COLOURS[g] for g in packing.group]
    widths = np.where(packing.density_factor > 1, 1.2, 0.3)
    ax.add_collection(PatchCollection(circles, facecolor=colours, edgecolor="k", linewidths=widths))
    ax.set_aspect("equal")
    ax.set_xlim(xz[:, 0].min() - r.max(), xz[:, 0].max() + r.max())
    ax.set_ylim(xz[:, 1].min() - r.max(), xz[:, 1].max() + r.max())
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_title(f"{title}: {int(packing.mobile.sum())} particles, {int((~packing.mobile).sum())} wall discs")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
