"""Figures of the seed-000 runs: snapshots (Fig. 22/24) and block pressure histories (Fig. 21/23).

They read what the runs write (postproc/run_files.py): history.csv (columns named as written),
snapshot .npz files and summary.json. ``python3 -m postproc.plots RUN_DIR`` redraws a run's figures.
"""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PatchCollection, PolyCollection  # noqa: E402
from matplotlib.colors import Normalize  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, Patch  # noqa: E402

from engines import files  # noqa: E402
from engines.model.groups import GROUP_NAMES, WALL_NONE  # noqa: E402
from postproc.run_files import read_history, read_snapshot, read_summary, run_dir, snapshot_files  # noqa: E402,F401

GROUP_COLOURS = {code: "0.85" if code == WALL_NONE else "0.35" for code in GROUP_NAMES}  # particles light
U_CMAP = "RdBu_r"           # diverging: blue suction, white U = 0, red excess pressure
FORCE_COLOUR, ARROW_COLOUR = "darkred", "navy"
FLAT_WALL_COLOUR = "dimgrey"  # a flat wall's face in the snapshots
FORCE_WIDTH = (0.3, 3.5)    # line width [pt] = 0.3 + 3.5 f_n / f_max
HISTORY_PANELS = [("porosity", "porosity [-]", 1.0), ("kinetic_energy", "kinetic energy [J/m]", 1.0),
                  ("fn_bottom_mean", "mean normal force, block 1 [N/m]", 1.0), ("bed_top", "bed top [mm]", 1e3)]


def nan_runs(t, y):
    """[(t_start, t_end)] of the runs of NaN in y, each widened to the neighbouring samples."""
    edges = np.diff(np.concatenate([[0], np.isnan(y).astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [(t[max(a - 1, 0)], t[min(b + 1, len(t) - 1)]) for a, b in zip(starts, ends)]


def block_label(k, n, bounds=None):
    """The name of block k (0 = bottom) of n by its position: bottom, surface or its number from the
    bottom, with its z range [mm] when ``bounds`` [(z0, z1)] [m] are given (the surface block's from z0 up)."""
    where = "bottom" if k == 0 else "surface" if k == n - 1 else ""
    if bounds:
        z0, z1 = (1e3 * z for z in bounds[k])
        where += (", " if where else "") + (f"z > {z0:.1f} mm" if k == n - 1 else f"z {z0:.1f}–{z1:.1f} mm")
    return f"block {k + 1}" + (f" ({where})" if where else "")


def plot_block_pressures(history, E_w, path, title, bounds=None):
    """block_pressure_figure saved to ``path`` (grown to hold the key and the note under the axes)."""
    fig = block_pressure_figure(history, E_w, title, bounds)
    files.save_figure(fig, path, dpi=120, bbox_inches="tight", pad_inches=0.15)
    plt.close(fig)


def block_pressure_figure(history, E_w, title, bounds=None):
    """Block-mean excess pore pressure against time, one line per block (Fig. 21/23), each named
    by its position (``block_label``; ``bounds``: the blocks' z ranges [m]); the axis spans the
    data, with the bound E_w of eq 32 drawn when it lies within a quarter above the data, else named
    in the key. A block holding no pore has no mean (NaN in history.csv): drawn as a hatched band
    in its colour."""
    fig, ax = plt.subplots(figsize=(7.5, 4.9))
    t_ms = history["t"] * 1e3
    handles, any_gap = [], False
    names = sorted((c for c in history if c.startswith("U_block")), key=lambda c: int(c[len("U_block"):]))
    for k, name in enumerate(names):
        colour = f"C{k}"
        label = block_label(k, len(names), bounds)
        handles += ax.plot(t_ms, history[name], color=colour, label=label)
        gaps = nan_runs(t_ms, history[name])
        for t0, t1 in gaps:
            ax.axvspan(t0, t1, ymin=0.01 + 0.07 * k, ymax=0.07 + 0.07 * k, facecolor="none",
                       edgecolor=colour, hatch="////", linewidth=0)
        if gaps:
            any_gap = True
            share = np.isnan(history[name]).mean()
            handles.append(Patch(facecolor="none", edgecolor=colour, hatch="////", linewidth=0,
                                 label=f"{label}: no pore, no mean ({100 * share:.0f} % of the time)"))
    data = np.concatenate([history[c][np.isfinite(history[c])] for c in names] + [np.zeros(1)])
    lo, hi = data.min(), data.max()
    pad = 0.05 * max(hi - lo, 1e-9)
    if np.isfinite(E_w) and E_w <= 1.25 * hi:
        handles.append(ax.axhline(E_w, color="0.5", ls="--", lw=0.8, label=f"E_w = {E_w:g} N/m (bound of eq 32)"))
        hi = max(hi, E_w)
    elif np.isfinite(E_w):
        handles.append(Line2D([], [], color="none", label=f"E_w = {E_w:g} N/m (bound of eq 32): above the axis"))
    ax.set_ylim(lo - pad, hi + pad)
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("block-mean excess pore pressure U [N/m]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    key = ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=8,
                    frameon=False)
    fig.tight_layout()
    if any_gap:  # the note goes under the key, wherever the key's rows end
        fig.canvas.draw()
        below = key.get_window_extent().transformed(ax.transAxes.inverted()).y0
        ax.text(0.0, below - 0.02, "Hatched: no pore centroid lies in the block at that time (its discs lost their\n"
                "links as the bed loosened), so the block has no mean U and the line breaks.",
                transform=ax.transAxes, fontsize=8, color="0.3", va="top")
    return fig


def plot_history_panels(history, path, title):
    """Porosity, kinetic energy, bottom normal force and bed top against time (HISTORY_PANELS)."""
    fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
    t_ms = history["t"] * 1e3
    for ax, (col, label, scale) in zip(axes.ravel(), HISTORY_PANELS):
        if col in history:
            ax.plot(t_ms, history[col] * scale)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("t [ms]")
    fig.suptitle(title)
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


def force_width(fn, f_max):
    """Line width [pt] of a normal force [N/m: per metre of thickness] on the shared scale."""
    lo, span = FORCE_WIDTH
    return lo + span * np.clip(fn, 0, None) / f_max


def draw_snapshot(ax, snap, U_norm=None, velocity_scale=None, force_scale=None):
    """Discs, pores coloured by U, normal-force network (width ~ force) and velocity arrows.

    U_norm: colour normalisation of U (default centred on 0 at +-max|U|); velocity_scale [m/s]
    is drawn one mean diameter long; force_scale [N/m] gets the widest line. Returns the pore
    collection (for a colour bar) or None and the quiver (for a key) or None."""
    xz, r, group = snap["xz"] * 1e3, snap["r"] * 1e3, snap["group"]
    polys = None
    if "tri" in snap and len(snap["tri"]):
        U = snap["U"][snap["tri_pore"]]
        if U_norm is None:
            u = max(np.abs(U).max(), 1e-9)
            U_norm = Normalize(-u, u)
        vertices = snap["vertices"] * 1e3 if "vertices" in snap else xz  # with flat walls: discs, then wall vertices
        polys = PolyCollection(vertices[snap["tri"]], array=U, cmap=U_CMAP, norm=U_norm, edgecolors="face",
                               linewidths=0.2, zorder=0)
        ax.add_collection(polys)
    for axis, position, _ in snap.get("flat_walls", ()):  # a face x = position (axis 0) or z = position
        (ax.axvline if axis == 0 else ax.axhline)(position * 1e3, color=FLAT_WALL_COLOUR, linewidth=3, zorder=1)
    circles = [Circle(p, rr) for p, rr in zip(xz, r)]
    ax.add_collection(PatchCollection(circles, facecolor=[GROUP_COLOURS[g] for g in group], edgecolor="k",
                                      linewidth=0.4, alpha=0.55, zorder=1))
    dense = snap["density_factor"] > 1
    if dense.any():
        ax.add_collection(PatchCollection([c for c, d in zip(circles, dense) if d], facecolor="none",
                                          edgecolor="k", linewidth=1.6, zorder=2))
    pairs, fn = snap["pairs"], snap["f_n"]
    if len(fn):
        ax.add_collection(LineCollection(xz[pairs], linewidths=force_width(fn, force_scale or max(fn.max(), 1e-12)),
                                         colors=FORCE_COLOUR, zorder=3))
    v = snap["vel"]
    mob = group == 0
    quiver = None
    if mob.any():
        vs = velocity_scale or max(np.hypot(*v[mob].T).max(), 1e-12)
        quiver = ax.quiver(xz[mob, 0], xz[mob, 1], v[mob, 0], v[mob, 1], angles="xy", scale_units="xy",
                           scale=vs / (2 * r.mean()), color=ARROW_COLOUR, width=0.004, zorder=4)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    return polys, quiver


def _nice(x):
    """A round number near x (1, 2 or 5 x 10^k) for scale keys."""
    if x <= 0:
        return 1.0
    e = np.floor(np.log10(x))
    m = x / 10**e
    return float((1 if m < 1.5 else 2 if m < 3.5 else 5) * 10**e)


def plot_snapshots(snaps, path, title, blocks=None):
    """snapshot_figure saved to ``path``."""
    fig = snapshot_figure(snaps, title, blocks)
    files.save_figure(fig, path, dpi=110)
    plt.close(fig)


SNAPSHOT_COLUMNS = (3, 2)  # panels per row of a snapshot figure: the count that leaves fewest cells empty, the first on a tie
KEY_ENTRY_WIDTH = 2.7  # [in]: one column of a snapshot figure's key (a handle and a label of ~30 characters)
WINDOW_DISCS = 2000    # a scene of more discs is drawn in a window of its middle with about this many
KEY_SHARE = 0.78       # of the figure's width: the key's columns; the velocity arrow's key on the right


def snapshot_figure(snaps, title, blocks=None):
    """One panel per snapshot (rows of SNAPSHOT_COLUMNS) with shared scales: pores coloured by U
    on one diverging scale centred on 0 (one colour bar), normal-force widths, velocity arrows and
    axis limits. Titles give each panel's own maxima; a key explains discs, walls, line widths and
    arrows. ``blocks``: [(z0, z1)] [m] of the pressure blocks, drawn as brackets on the right."""
    n = len(snaps)
    cols = min(n, min(SNAPSHOT_COLUMNS, key=lambda c: -n % c))
    rows = -(-n // cols)
    lo, hi, window = _snapshot_bounds(snaps)
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])  # panel height / width of the scene
    f_max = max([s["f_n"].max() for s in snaps if len(s["f_n"])] or [1.0])
    key = _snapshot_key(snaps, f_max, blocks)
    width = max(4.3 * cols + 1.2, 8.6)
    key_cols = max(1, int(KEY_SHARE * width / KEY_ENTRY_WIDTH))
    key_height = 0.22 * -(-len(key) // key_cols) + 0.2  # [in]: the key's rows
    panel_height = 4.3 * min(aspect, 1.5) + 0.8      # [in]: a panel and its three-line title
    fig = plt.figure(figsize=(width, rows * panel_height + key_height + 0.8), layout="constrained")
    grid = fig.add_gridspec(rows + 1, cols, height_ratios=(panel_height,) * rows + (key_height,))
    axes = [fig.add_subplot(grid[k // cols, k % cols]) for k in range(n)]
    key_ax = fig.add_subplot(grid[rows, :])
    key_ax.axis("off")
    Us = [s["U"] for s in snaps if "U" in s and len(s["U"])]
    u_max = max((np.abs(u).max() for u in Us), default=0.0) or 1.0
    speed = [np.hypot(*s["vel"][s["group"] == 0].T) for s in snaps]
    moving = max(v.max(initial=0.0) for v in speed) > 0
    v_max = max(v.max(initial=0.0) for v in speed) if moving else 1.0
    v_key = _nice(v_max / 2)
    colour_source, quiver = _snapshot_panels(axes, snaps, speed, Normalize(-u_max, u_max), v_max, f_max, blocks)
    pad = 0.3
    for k, ax in enumerate(axes):
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        if k % cols:
            ax.set_ylabel("")
            ax.tick_params(labelleft=False)
    if colour_source is not None:
        fig.colorbar(colour_source, ax=axes, label="pore excess pressure U [N/m]\n(0 = hydrostatic)",
                     shrink=0.85, pad=0.01)
    key_ax.legend(handles=key, loc="center left", bbox_to_anchor=(0.0, 0.0, KEY_SHARE, 1.0), ncol=key_cols,
                  fontsize=8, frameon=False)
    if quiver is not None and moving:
        fig.canvas.draw()  # a quiver key belongs to its quiver's axes: place it in figure units, after layout
        box = key_ax.get_position()
        axes[0].quiverkey(quiver, box.x0 + (KEY_SHARE + 0.02) * box.width, box.y0 + 0.5 * box.height, v_key,
                          f"particle velocity {v_key:g} m/s", labelpos="E", coordinates="figure",
                          color=ARROW_COLOUR, fontproperties={"size": 8})
    fig.suptitle(title + ":\npores coloured by U, normal forces (line width), particle velocities (arrows)" + window)
    return fig


def _snapshot_bounds(snaps):
    """(lower left, upper right) [mm] of the panels and the title's note of the window: a scene of
    more than WINDOW_DISCS discs is drawn in a window of its middle about WINDOW_DISCS discs wide."""
    lo = np.min([s["xz"] - s["r"][:, None] for s in snaps], axis=(0, 1)) * 1e3
    hi = np.max([s["xz"] + s["r"][:, None] for s in snaps], axis=(0, 1)) * 1e3
    window = ""
    n_discs = len(snaps[0]["r"])
    if n_discs > WINDOW_DISCS:
        mid, half = (lo[0] + hi[0]) / 2, (hi[0] - lo[0]) * WINDOW_DISCS / n_discs / 2
        window = (f" (x = {mid - half:.0f} to {mid + half:.0f} mm of {lo[0]:.0f} to {hi[0]:.0f} mm; "
                  f"the titles' maxima of the whole scene)")
        lo[0], hi[0] = mid - half, mid + half
    return lo, hi, window


def _snapshot_key(snaps, f_max, blocks):
    """The key's handles: the kinds of discs and walls drawn, two force widths, the blocks."""
    dense = max(s["density_factor"].max() for s in snaps)
    key = [Patch(facecolor=GROUP_COLOURS[0], edgecolor="k", linewidth=0.4, label="particle")]
    if dense > 1:
        key.append(Patch(facecolor=GROUP_COLOURS[0], edgecolor="k", linewidth=1.6,
                         label=f"dense top particle (density x {dense:g})"))
    if any((s["group"] != 0).any() for s in snaps):
        key.append(Patch(facecolor=GROUP_COLOURS[1], edgecolor="k", linewidth=0.4, label="wall disc"))
    if any("flat_walls" in s for s in snaps):
        key.append(Line2D([], [], color=FLAT_WALL_COLOUR, lw=3, label="flat wall"))
    key += [Line2D([], [], color=FORCE_COLOUR, lw=force_width(f, f_max), label=f"normal force {f:.2g} N/m")
            for f in (f_max / 4, f_max)]
    if blocks:
        key += [Patch(color=f"C{k}", label=f"z range of block {k + 1}") for k in range(len(blocks))]
    return key


def _snapshot_panels(axes, snaps, speed, norm, v_max, f_max, blocks):
    """Draw each snapshot on its panel on the shared scales, titled with its own maxima (``speed``:
    each snapshot's particle speeds [m/s]); returns (the first pore collection, the first quiver)."""
    colour_source = quiver = None
    for ax, s, v in zip(axes, snaps, speed):
        polys, q = draw_snapshot(ax, s, norm, v_max, f_max)
        colour_source = colour_source or polys
        quiver = quiver or q
        lines = [f"max |v| = {v.max(initial=0.0):.3g} m/s, max f_n = {s['f_n'].max(initial=0.0):.3g} N"]
        if "U" in s and len(s["U"]):
            lines.append(f"U in [{s['U'].min():.0f}, {s['U'].max():.0f}] N/m")
        ax.set_title(f"t = {float(s['t']) * 1e3:.0f} ms\n" + "\n".join(lines), fontsize=8.5)
        if blocks:
            for k, (z0, z1) in enumerate(blocks):
                ax.axhspan(z0 * 1e3, z1 * 1e3, xmin=0.985, xmax=1.0, color=f"C{k}", alpha=0.8, zorder=5)
    return colour_source, quiver


def stress_path_figure(history, title, band_bounds=None):
    """The p'-q stress path of each band of the bed (history.csv's p_band*, q_band* [Pa]:
    engines.model.effective_stress, q the radius of Mohr's circle), one panel per band from the
    surface down, coloured by time, its start and end marked; each panel's scale its own (a band
    near the surface carries far less). ``band_bounds``: the bands' [z0, z1] [m] for the titles."""
    n = sum(c.startswith("p_band") for c in history)
    cols = min(n, 4)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols, 3.0 * rows + 0.8), squeeze=False, layout="constrained")
    t_ms = history["t"] * 1e3
    norm = Normalize(t_ms[0], t_ms[-1])
    for k, ax in zip(range(n, 0, -1), axes.ravel()):
        p, q = history[f"p_band{k}"], history[f"q_band{k}"]
        pts = np.column_stack([p, q])
        lines = LineCollection(np.stack([pts[:-1], pts[1:]], axis=1), cmap="viridis", norm=norm, linewidths=1.0)
        lines.set_array(0.5 * (t_ms[:-1] + t_ms[1:]))
        ax.add_collection(lines)
        ax.plot(p[0], q[0], "o", color="k", ms=4, label="start")
        ax.plot(p[-1], q[-1], "s", color="C3", ms=4, label="end")
        hi = max(float(np.nanmax(np.r_[p, q, 1e-9])), 1e-9)
        ax.plot([0, hi], [0, hi], color="0.6", lw=0.6, ls="--")  # q = p': a band's stress without tension
        ax.set_xlim(min(0.0, float(np.nanmin(p))) - 0.05 * hi, 1.05 * hi)
        ax.set_ylim(0.0, 1.05 * hi)
        where = f"z {1e3 * band_bounds[k - 1][0]:.1f}–{1e3 * band_bounds[k - 1][1]:.1f} mm" if band_bounds else ""
        ax.set_title(f"band {k}" + (" (bottom)" if k == 1 else " (surface)" if k == n else "") +
                     (f"\n{where}" if where else ""), fontsize=8.5)
        ax.set_xlabel("p' [Pa]", fontsize=8)
        ax.set_ylabel("q [Pa]", fontsize=8)
        ax.tick_params(labelsize=7.5)
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    axes[0, 0].legend(fontsize=7, loc="upper left")
    fig.colorbar(plt.cm.ScalarMappable(norm, "viridis"), ax=axes, label="t [ms]", shrink=0.8)
    fig.suptitle(f"{title}: stress paths of the bed's bands (p' = (σ'_xx + σ'_zz)/2, q = Mohr's radius; "
                 "dashed: q = p')", fontsize=10)
    return fig


def figures_of_run(run_dir):
    """Redraw a run's figures from its files (history.csv, snapshot_*.npz, summary.json)."""
    summary = read_summary(run_dir)
    params = summary.get("parameters", {})
    title = summary.get("scene", os.path.basename(os.path.normpath(run_dir)))
    history = read_history(os.path.join(run_dir, "history.csv"))
    written = []
    if len(history.get("t", [])) >= 2:
        if params.get("water", {}).get("enabled", True) and any(c.startswith("U_block") for c in history):
            written.append(os.path.join(run_dir, "pressure_blocks.png"))
            plot_block_pressures(history, params.get("water", {}).get("E_w", np.nan), written[-1],
                                 f"{title}: block-mean excess pore pressure", summary.get("block_bounds_m"))
        written.append(os.path.join(run_dir, "history_panels.png"))
        plot_history_panels(history, written[-1], title)
        if "p_band1" in history:
            written.append(os.path.join(run_dir, "stress_paths.png"))
            fig = stress_path_figure(history, title, summary.get("band_bounds_m"))
            files.save_figure(fig, written[-1], dpi=110)
            plt.close(fig)
    snaps = [read_snapshot(f) for f in snapshot_files(run_dir)]
    if snaps:
        written.append(os.path.join(run_dir, "snapshots.png"))
        plot_snapshots(snaps, written[-1], title, summary.get("block_bounds_m"))
    return written


def plot_packing(packing, path, title, flat_walls=()):
    """A packing: particles light, walls dark, denser particles outlined (Fig. 15, 18); with
    ``flat_walls`` ((axis, position [m]), ...: faces x = position for axis 0, z = position for axis
    1) the faces as lines and the particles alone."""
    if flat_walls:
        packing = packing.particles()
    fig, ax = plt.subplots(figsize=(8, 6))
    for axis, position in flat_walls:
        (ax.axvline if axis == 0 else ax.axhline)(position * 1e3, color=FLAT_WALL_COLOUR, linewidth=3, zorder=0)
    xz, r = packing.xz * 1e3, packing.r * 1e3
    circles = [Circle(p, rr) for p, rr in zip(xz, r)]
    colours = [GROUP_COLOURS[g] for g in packing.group]
    widths = np.where(packing.density_factor > 1, 1.2, 0.3)
    ax.add_collection(PatchCollection(circles, facecolor=colours, edgecolor="k", linewidths=widths))
    ax.set_aspect("equal")
    ax.set_xlim(xz[:, 0].min() - 1.5 * r.max(), xz[:, 0].max() + 1.5 * r.max())
    ax.set_ylim(xz[:, 1].min() - 1.5 * r.max(), xz[:, 1].max() + 1.5 * r.max())
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    bounds = f"{len(flat_walls)} flat walls" if flat_walls else f"{int((~packing.mobile).sum())} wall discs"
    ax.set_title(f"{title}: {int(packing.mobile.sum())} particles, {bounds}")
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    from engines.files.inputs import ArgumentParser
    ap = ArgumentParser(prog="python3 -m postproc.plots",
                                 description="Redraw the figures of runs from their files (history.csv, snapshots, "
                                             "summary.json): pressure_blocks.png, history_panels.png, snapshots.png.")
    ap.add_argument("runs", nargs="+", type=run_dir, metavar="RUN_DIR", help="a run's --out folder")
    for run in ap.parse_args().runs:
        print("\n".join(figures_of_run(run)))
