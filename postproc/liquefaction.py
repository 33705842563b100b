"""Figures and the comparison study of the seismic liquefaction cases (seed 000 §6).

They read what the runs write (postproc/run_files.py). ``run_figures(run_dir)`` draws one run's
block pressures the way Fig. 35 and 37 present them (``blocks.png``: the blocks on the initial
packing, the base input, then the block-mean U from the surface block 6 down to block 1 on one
scale centred on 0); its snapshots (Fig. 36/38/43/45) and history panels are drawn by
postproc.plots when the run ends. ``study(root)`` reads ROOT/case1 ... ROOT/case7 (and
ROOT/case1-conserving, ROOT/case3-conserving when present), each one run or an ensemble of starts
(engines.run.ensemble: every completed start is read), and writes ROOT/summary.json (per case and start:
porosity change, mean and peak U per block, wall time, re-meshing water change; the drainage
times of yade_scripts/liquefaction_drainage.py when ROOT/drainage.json exists), the figures
Fig. 40, 41, 46 (porosity of the cases compared, with the block pressures of the wet ones), the
transfer comparison and ROOT/trends.md (the paper's trends against our numbers, each criterion's
quantity with its 95 % interval over the starts and a verdict holds / fails / undecided:
engines.studies.liquefaction.trends).
``run_figures`` also draws ``depth.png`` (``depth_figure``: pore pressure and porosity by depth over
time); ``reconstruction(out, baseline)`` writes the trends on each variant of the reconstruction
(engines.studies.reconstruction.judged: reconstruction.json, .md, .png).

    /usr/bin/python3 -m postproc.liquefaction RUN_DIR [RUN_DIR ...]     # one run's figures
    /usr/bin/python3 -m postproc.liquefaction --study ROOT              # the study
"""
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

from engines import files  # noqa: E402
from engines.model.groups import WALL_LEFT, WALL_RIGHT  # noqa: E402
from engines.model.observe import Window, porosity  # noqa: E402
from engines.studies.ensemble import CONFIDENCE  # noqa: E402
from engines.studies.liquefaction import PERIOD, TRENDS, holds_if, trends  # noqa: E402
from engines.studies.reconstruction import VARIANTS, ensemble_path, judged  # noqa: E402
from packing.packing import Packing  # noqa: E402
from postproc.plots import GROUP_COLOURS, block_label  # noqa: E402
from postproc.run_files import (  # noqa: E402
    ensemble_history,
    read_history,
    read_snapshot,
    read_summary,
    run_dir,
    run_folders,
    snapshot_files,
)

LOW_BLOCKS = 4       # blocks 1-4: below the two surface blocks, whose U drains to the surface (§6.2)
CASES = {  # SPEC §2.5
    1: "saturated, undrained, spring d, cosine",
    2: "dry, spring d, cosine",
    3: "saturated, drained sides (k3 = 1e3), spring d, cosine",
    4: "saturated, undrained, elastic spring a, cosine",
    5: "dry, elastic spring a, cosine",
    6: "saturated, undrained, spring d, El Centro",
    7: "dry, spring d, El Centro",
}
STUDY_FIGURES = {  # the paper's porosity figures: the cases drawn together
    "fig40_porosity_cosine_spring_d.png": ("Fig. 40: cosine, hysteretic spring (d)", (1, 2, 3)),
    "fig41_porosity_cosine_elastic.png": ("Fig. 41: cosine, elastic spring (a)", (4, 5)),
    "fig46_porosity_elcentro_spring_d.png": ("Fig. 46: El Centro, hysteretic spring (d)", (6, 7)),
}
TRANSFER_CASES = (1, 3)


def block_columns(history):
    """The U_block columns in block order (1 = bottom)."""
    return sorted((c for c in history if c.startswith("U_block")), key=lambda c: int(c[len("U_block"):]))


# -- one run ------------------------------------------------------------------------------------------
def draw_blocks_on_packing(ax, snap, bounds):
    """Fig. 35: the discs at t = 0 with the z range of each pressure block shaded and numbered."""
    xz, r = snap["xz"] * 1e3, snap["r"] * 1e3
    ax.add_collection(PatchCollection([Circle(p, rr) for p, rr in zip(xz, r)],
                                      facecolor=[GROUP_COLOURS[g] for g in snap["group"]], edgecolor="k", linewidth=0.3))
    x0, x1 = (xz[:, 0] - r).min(), (xz[:, 0] + r).max()
    top = (xz[:, 1] + r).max()
    for k, (z0, z1) in enumerate(bounds):
        z0, z1 = z0 * 1e3, min(z1 * 1e3, top)
        ax.axhspan(z0, z1, color=f"C{k}", alpha=0.25, lw=0)
        ax.text(x1 + 0.3, 0.5 * (z0 + z1), str(k + 1), color=f"C{k}", va="center", fontsize=10, weight="bold")
    ax.set_xlim(x0 - 0.2, x1 + 1.2)
    ax.set_ylim((xz[:, 1] - r).min() - 0.2, top + 0.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_title("Fig. 35: pressure blocks (t = 0)", fontsize=9)


def blocks_figure(history, title, bounds=None, snap0=None):
    """Fig. 37/39/42/44: Fig. 35 (the blocks on the initial packing) and the base acceleration and
    displacement on top, then the block-mean excess pore pressure U [N/m] of blocks 6 (surface)
    ... 1 (bottom), one panel each, on one scale symmetric about 0."""
    cols = block_columns(history)
    t = history["t"] * 1e3
    n = len(cols)
    fig = plt.figure(figsize=(11, 1.3 * n + 3.6), layout="constrained")
    grid = fig.add_gridspec(n + 1, 2, width_ratios=(1.0, 1.6), height_ratios=(2.4,) + (1,) * n)
    ax = fig.add_subplot(grid[0, 1])
    axes = [fig.add_subplot(grid[k, :], sharex=ax) for k in range(1, n + 1)]
    zero = np.zeros_like(t)  # a scene without base motion has no base columns: drawn still
    ax.plot(t, history.get("base_acc", zero) * 100, color="0.2", lw=0.8, label="base acceleration [gal]")
    ax.set_ylabel("a [gal]")
    ax.set_xlabel("t [ms]")
    ax2 = ax.twinx()
    ax2.plot(t, history.get("base_disp", zero) * 1e6, color="C3", lw=0.9, label="base displacement [µm]")
    ax2.set_ylabel("u [µm]", color="C3")
    ax.legend(handles=ax.get_lines() + ax2.get_lines(), fontsize=7.5, loc="lower center", ncol=2,
              bbox_to_anchor=(0.5, 1.0), frameon=False)
    ax.grid(alpha=0.3)
    finite = np.concatenate([history[c][np.isfinite(history[c])] for c in cols] + [np.zeros(1)])
    lim = 1.05 * max(np.abs(finite).max(), 1e-9)
    for k, (a, c) in enumerate(zip(axes, reversed(cols))):
        b = n - 1 - k
        y = history[c]
        a.plot(t, y, color=f"C{b}", lw=0.8)
        a.axhline(0.0, color="0.3", lw=0.6)
        a.set_ylim(-lim, lim)
        ok = np.isfinite(y)
        stats = f"mean {np.mean(y[ok]):.0f}, max {np.max(y[ok]):.0f} N/m" if ok.any() else "no pore"
        a.text(0.005, 0.93, f"{block_label(b, n, bounds)}: {stats}", transform=a.transAxes, fontsize=7.5, va="top")
        a.set_ylabel("U [N/m]")
        a.grid(alpha=0.3)
        if a is not axes[-1]:
            a.tick_params(labelbottom=False)
    axes[-1].set_xlabel("t [ms]")
    if snap0 is not None and bounds:
        draw_blocks_on_packing(fig.add_subplot(grid[0, 0]), snap0, bounds)
    fig.suptitle(f"{title}: base input and block-mean excess pore pressure")
    return fig


def band_porosity(snap, bounds, top):
    """Porosity of each band [z0, z1) of ``bounds`` [m] (the last up to ``top``) between the inner
    faces of the side walls in snapshot ``snap`` (engines.model.observe.porosity)."""
    pk = Packing(snap["xz"], snap["r"], snap["group"], snap["density_factor"])
    faces = pk.inner_faces()
    m = pk.mobile
    return np.array([porosity(pk.xz[m], pk.r[m], Window(faces[WALL_LEFT], faces[WALL_RIGHT], z0, min(z1, top)))
                     for z0, z1 in bounds])


def depth_figure(history, snaps, bounds, title, band_bounds=None):
    """Pore pressure and porosity by depth over time: the block-mean U (history) and the porosity
    change of the same bands since t = 0 (the snapshots ``snaps``) as colour over time and height,
    both centred on 0, and the porosity profile at t = 0. ``bounds``: the blocks' [z0, z1] [m].
    With the bands' r_u in the history (ru_band*) and their ``band_bounds`` [m], a fourth panel:
    r_u by height over time (``draw_ru_by_depth``)."""
    s0 = snaps[0]
    mobile = s0["group"] == 0
    top = max(float(np.max(s0["xz"][mobile, 1] + s0["r"][mobile])), bounds[-1][0] + 1e-9)  # the bed's top at t = 0
    edges = 1e3 * np.array([b[0] for b in bounds] + [min(bounds[-1][1], top)])
    U = np.column_stack([history[c] for c in block_columns(history)])
    n = np.array([band_porosity(s, bounds, top) for s in snaps])
    ts = np.array([float(s["t"]) for s in snaps]) * 1e3
    t_edges = np.r_[ts[0], 0.5 * (ts[1:] + ts[:-1]), ts[-1]] if len(ts) > 1 else np.r_[ts, ts + 1]
    ru = band_bounds is not None and "ru_band1" in history
    fig, axes = plt.subplots(1, 4 if ru else 3, figsize=(19 if ru else 14, 5.6), sharey=True, layout="constrained",
                             gridspec_kw={"width_ratios": (1.4, 1.4, 0.7) + ((1.4,) if ru else ())})
    t_end = float(history["t"][-1]) * 1e3
    lim = max(float(np.nanpercentile(np.abs(U), 99)), 1e-9)  # the surface block's rare spikes saturate
    im = axes[0].pcolormesh(history["t"] * 1e3, edges, U[:-1].T if len(U) > 1 else U.T, cmap="RdBu_r",
                            vmin=-lim, vmax=lim, shading="flat")
    fig.colorbar(im, ax=axes[0], extend="both", location="bottom", shrink=0.9,
                 label=f"block-mean excess pore pressure U [N/m]\n(beyond ±{lim:.0f}: the end colours; max |U| "
                       f"{np.nanmax(np.abs(U)):.0f})")
    dn = n - n[0]
    dlim = max(float(np.nanmax(np.abs(dn[:, :-1] if dn.shape[1] > 1 else dn))), 1e-9)  # the bands below the surface
    im = axes[1].pcolormesh(t_edges, edges, dn.T, cmap="RdBu_r",  # a cell about each snapshot's time
                            vmin=-dlim, vmax=dlim, shading="flat")
    fig.colorbar(im, ax=axes[1], extend="both", location="bottom", shrink=0.9,
                 label="porosity change since t = 0 [-], a cell about each snapshot\n"
                       f"(scaled to the bands below the surface; max |Δn| {np.nanmax(np.abs(dn)):.3f})")
    axes[2].step(np.r_[n[0], n[0][-1]], edges, where="post", color="k")
    axes[2].set_xlabel("porosity at t = 0 [-]\n(top band: to the highest disc)", fontsize=9)
    for ax, what in zip(axes[:2], ("pore pressure", "porosity (at the snapshots)")):
        ax.set_xlabel("t [ms]")
        ax.set_xlim(0.0, max(t_end, t_edges[-1]))  # both panels over the run's whole time
        ax.set_title(f"{what} by height", fontsize=9)
    axes[0].set_ylabel("z [mm]")
    if ru:
        draw_ru_by_depth(fig, axes[3], history, band_bounds)
        axes[3].set_xlim(0.0, max(t_end, t_edges[-1]))
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"{title}: pore pressure and porosity by depth over time")
    return fig


RU_CMAP = "viridis"  # sequential: dark r_u <= 0, bright r_u >= 1 (the contacts carry nothing)
RU_RANGE = (-0.2, 1.2)  # the colour scale of r_u: 0 and 1 inside it, beyond it the end colours


def draw_ru_by_depth(fig, ax, history, band_bounds):
    """The bands' pore-pressure ratio r_u (history.csv's ru_band*, engines.model.effective_stress) as
    colour over time and height on ``ax`` on the scale RU_RANGE with 0 and 1 marked on the colour
    bar and the contour r_u = 1 drawn (a black line: where the contacts carry nothing)."""
    cols = sorted((c for c in history if c.startswith("ru_band")), key=lambda c: int(c[len("ru_band"):]))
    ru = np.column_stack([history[c] for c in cols])
    t = history["t"] * 1e3
    edges = 1e3 * np.array([b[0] for b in band_bounds] + [band_bounds[-1][1]])
    finite = ru[np.isfinite(ru)]
    low, top = RU_RANGE
    im = ax.pcolormesh(t, edges, ru[:-1].T if len(ru) > 1 else ru.T, cmap=RU_CMAP, vmin=low, vmax=top, shading="flat")
    mids = 0.5 * (edges[1:] + edges[:-1])
    if finite.size and np.nanmax(ru) >= 1.0 and len(t) > 1 and len(mids) > 1:
        ax.contour(t, mids, np.where(np.isfinite(ru), ru, 0.0).T, levels=[1.0], colors="k", linewidths=1.0)
    bar = fig.colorbar(im, ax=ax, extend="both", location="bottom", shrink=0.9,
                       label=f"pore-pressure ratio r_u = U / σ'_v0 [-], black line: r_u = 1\n(range {finite.min():.2f} "
                             f"to {finite.max():.2f}; beyond {low:g}, {top:g}: the end colours)"
                       if finite.size else "pore-pressure ratio r_u [-] (no pore in any band)")
    for level, colour in ((0.0, "white"), (1.0, "red")):
        bar.ax.axvline(level, color=colour, lw=2.0)
    ax.set_xlabel("t [ms]")
    ax.set_title("pore-pressure ratio by height (bands of the bed)", fontsize=9)


def run_figures(run_dir):
    """Draw blocks.png of a wet run (``blocks_figure``) and, with two snapshots or more, depth.png
    (``depth_figure``); returns the paths written."""
    summary = read_summary(run_dir)
    history = read_history(os.path.join(run_dir, "history.csv"))
    params = summary.get("parameters", {})
    if len(history.get("t", [])) < 2 or not params.get("water", {}).get("enabled", False):
        return []
    snap_files = snapshot_files(run_dir)
    snap0 = read_snapshot(snap_files[0]) if snap_files and float(read_snapshot(snap_files[0])["t"]) == 0.0 else None
    fig = blocks_figure(history, summary.get("scene", run_dir), summary.get("block_bounds_m"), snap0)
    paths = [os.path.join(run_dir, "blocks.png")]
    files.save_figure(fig, paths[-1], dpi=110)
    plt.close(fig)
    bounds = summary.get("block_bounds_m")
    if len(snap_files) > 1 and bounds:
        fig = depth_figure(history, [read_snapshot(f) for f in snap_files], bounds, summary.get("scene", run_dir),
                           summary.get("band_bounds_m"))
        paths.append(os.path.join(run_dir, "depth.png"))
        files.save_figure(fig, paths[-1], dpi=110)
        plt.close(fig)
    return paths


# -- the study ----------------------------------------------------------------------------------------
def end_mean(t, y, window=PERIOD):
    """Mean of y over the last ``window`` seconds (one input period: the oscillation averages out)."""
    sel = (t >= t[-1] - window) & np.isfinite(y)
    return float(np.mean(y[sel])) if sel.any() else float("nan")


def dominant_period(t, y, t_from=PERIOD):
    """Period [s] of the largest Fourier peak of y (mean and linear trend removed) after t_from."""
    sel = (t >= t_from) & np.isfinite(y)
    if sel.sum() < 16:
        return float("nan")
    tt, yy = t[sel], y[sel]
    yy = yy - np.polyval(np.polyfit(tt, yy, 1), tt)
    power = np.abs(np.fft.rfft(yy)) ** 2
    freq = np.fft.rfftfreq(len(yy), tt[1] - tt[0])
    k = 1 + int(np.argmax(power[1:]))
    return float(1.0 / freq[k])


def compaction_correlation(n, U):
    """Pearson correlation of U with the window's compaction n_0 - n over a run: near 1 when U is
    the water squeezed by the settling bed (eq 32: U = E_w (W - A)/W rises as the voids A shrink)."""
    ok = np.isfinite(n) & np.isfinite(U)
    if ok.sum() < 3 or np.std(n[ok]) == 0 or np.std(U[ok]) == 0:
        return float("nan")
    return float(np.corrcoef(n[0] - n[ok], U[ok])[0, 1])


def case_summary(run_dir):
    """The study's numbers of one run (see the module docstring); None when the run is missing."""
    summary = read_summary(run_dir)
    hist_path = os.path.join(run_dir, "history.csv")
    if not summary or not os.path.exists(hist_path):
        return None
    h = read_history(hist_path)
    t, n = h["t"], h["porosity"]
    out = {"scene": summary["scene"], "status": summary["status"], "t_end": float(t[-1]), "steps": summary["steps"],
           "wall_seconds": summary["wall_seconds"], "cpu_seconds": summary.get("cpu_seconds"),
           "us_per_step": summary["us_per_step"],
           "porosity_initial": float(n[0]), "porosity_end": end_mean(t, n),
           "porosity_change": end_mean(t, n) - float(n[0]), "porosity_min": float(np.nanmin(n)),
           "porosity_max": float(np.nanmax(n)),
           "base_peak_acc": float(np.abs(h["base_acc"]).max()) if "base_acc" in h else 0.0,
           "base_disp_range": [float(h["base_disp"].min()), float(h["base_disp"].max())] if "base_disp" in h
           else [0.0, 0.0],
           "side_wall_shift_max": float(np.nanmax(np.abs(np.r_[h["side_left_dx"], h["side_right_dx"]])))
           if "side_left_dx" in h and np.isfinite(h["side_left_dx"]).any() else None,
           "bed_top_change": float(h["bed_top"][-1] - h["bed_top"][0])}
    wb = summary.get("water_balance")
    if wb:
        U = {}
        for c in block_columns(h):
            y = h[c]
            ok = np.isfinite(y)
            U[c] = {"mean": float(np.mean(y[ok])), "mean_last_period": end_mean(t, y), "max": float(np.max(y[ok])),
                    "min": float(np.min(y[ok])), "peak_abs": float(np.max(np.abs(y[ok]))),
                    "empty_fraction": float(1 - ok.mean())}
        low = np.nanmean(np.column_stack([h[c] for c in block_columns(h)[:LOW_BLOCKS]]), axis=1)
        out.update(U_blocks=U, U_low_mean=float(np.nanmean(low)), U_low_abs_mean=float(np.nanmean(np.abs(low))),
                   U_low_std=float(np.nanstd(low)), U_low_end=end_mean(t, low),
                   U_low_rise_first_period=end_mean(t[t <= PERIOD], low[t <= PERIOD], PERIOD / 4) - float(low[0]),
                   U_low_dominant_period=dominant_period(t, low),
                   U_low_vs_compaction_corr=compaction_correlation(n, low),
                   transfer=summary["parameters"]["water"]["transfer"],
                   water_initial=wb["initial"], remesh_water_change=wb["remesh_change"],
                   remesh_water_change_rel=wb["remesh_change"] / wb["initial"],
                   remesh_excess_change=wb.get("remesh_excess_change"),
                   remesh_excess_change_rel=wb["remesh_excess_change"] / wb["initial"]
                   if "remesh_excess_change" in wb else None,
                   remesh_excess_edge=wb.get("remesh_excess_edge"),
                   side_outflow=wb["side_outflow"], surface_outflow=wb["surface_outflow"],
                   water_balance_error=summary["water_balance_error"], n_rebuilds=summary["n_rebuilds"])
    return out


def _wet(runs):
    return [k for k, (_, s, _) in runs.items() if s.get("parameters", {}).get("water", {}).get("enabled")]


def _drawn(run, col):
    """The values a figure draws of a column of ``run`` (history, summary, band): the line and its band."""
    history, _, band = run
    return np.concatenate([history[col], *(band[col] if band is not None else ())])


def porosity_figure(runs, title, n_lim=None, u_lim=None):
    """Porosity of the cases together (top), then the block pressures of each wet case; ``runs``
    {case: (history, summary, band)}: an ensemble's history is its means over the starts, drawn with
    its 95 % band (band {column: (low, high)}; None for one run). n_lim (low, high) and u_lim (U
    from -u_lim to u_lim) give several figures the same axes."""
    wet = _wet(runs)
    fig, axes = plt.subplots(1 + len(wet), 1, figsize=(9, 3.2 + 2.3 * len(wet)), sharex=True,
                             gridspec_kw={"height_ratios": [1.4] + [1] * len(wet)}, layout="constrained")
    axes = np.atleast_1d(axes)

    def draw(ax, h, band, col, **style):
        line, = ax.plot(h["t"] * 1e3, h[col], **style)
        if band is not None:
            ax.fill_between(h["t"] * 1e3, *band[col], color=line.get_color(), alpha=0.25, lw=0)

    for k, (h, _, band) in runs.items():
        draw(axes[0], h, band, "porosity", label=f"case {k}: {CASES[k]}" + (" (mean over the starts, 95 % band)"
                                                                            if band is not None else ""))
    axes[0].set_ylabel("porosity of the window [-]")
    axes[0].legend(fontsize=8)
    axes[0].set_title(title)
    if n_lim:
        axes[0].set_ylim(*n_lim)
    lim = u_lim or max([np.nanmax(np.abs(_drawn(runs[k], c))) for k in wet for c in block_columns(runs[k][0])] + [1e-9])
    for ax, k in zip(axes[1:], wet):
        h, _, band = runs[k]
        ax.set_ylim(-1.05 * lim, 1.05 * lim)  # one scale for the wet cases, centred on U = 0
        for b, c in enumerate(block_columns(h)):
            draw(ax, h, band, c, color=f"C{b}", lw=0.7, label=block_label(b, len(block_columns(h))))
        ax.axhline(0.0, color="0.3", lw=0.6)
        ax.set_ylabel(f"case {k}: U [N/m]")
        ax.legend(fontsize=7, ncol=3, loc="upper left")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [ms]")
    return fig


def transfer_figure(pairs):
    """Paper against conserving transfer: block 1-4 mean U and the cumulative re-meshing water
    change, per case of ``pairs`` {case: (history paper, history conserving)}."""
    fig, axes = plt.subplots(2, len(pairs), figsize=(6 * len(pairs), 6.5), sharex=True, sharey="row", squeeze=False,
                             layout="constrained")
    for col, (k, (hp, hc)) in enumerate(pairs.items()):
        for h, name, style in ((hp, "paper", "-"), (hc, "conserving", "--")):
            low = np.nanmean(np.column_stack([h[c] for c in block_columns(h)[:LOW_BLOCKS]]), axis=1)
            axes[0, col].plot(h["t"] * 1e3, low, style, lw=0.8, label=f"transfer = {name}")
            axes[1, col].plot(h["t"] * 1e3, h["remesh_change"] / h["total_water"][0], style, label=f"transfer = {name}")
        axes[0, col].set_title(f"case {k}: {CASES[k]}", fontsize=9)
        axes[0, col].set_ylabel("mean U of blocks 1-4 [N/m]")
        axes[1, col].set_ylabel("re-meshing water change / initial water\n(cumulative, edges included)")
        axes[1, col].set_xlabel("t [ms]")
        for ax in axes[:, col]:
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
            ax.axhline(0.0, color="0.3", lw=0.6)
    return fig


def trends_markdown(rows):
    """The trends as a table: per condition its estimate, 95 % interval, criterion and verdict."""
    lines = ["| trend | the paper | quantity: estimate [95 % interval] (holds if) → verdict | starts | verdict |",
             "|---|---|---|---|---|"]
    for r in rows:
        cells = "; ".join(f"{c['quantity']}: {c['estimate']:.3g} [{c['ci95'][0]:.3g}, {c['ci95'][1]:.3g}] "
                          f"({c['holds_if']}) → {c['verdict']}" for c in r["conditions"])
        if r.get("note"):
            cells += f"; {r['note']}"
        starts = ", ".join(f"{n} (case {k})" for k, n in r["starts"].items())
        lines.append(f"| {r['trend']} | {r['paper']} | {cells} | {starts} | {r['verdict']} |")
    return "\n".join(lines) + "\n"


def _case_runs(path):
    """([case_summary of each completed start], (history, summary, band)) of the run or ensemble in
    ``path`` (history: an ensemble's means over its starts, band: their 95 % intervals per column,
    None for one run), or None when nothing has completed there."""
    starts = [s for s in (case_summary(d) for d in run_folders(path)) if s is not None and s["status"] == "completed"]
    if not starts:
        return None
    if run_folders(path) == [path]:
        return starts, (read_history(os.path.join(path, "history.csv")), read_summary(path), None)
    history, band = ensemble_history(path)
    if history is None:
        return None
    return starts, (history, read_summary(run_folders(path)[0]), band)


def study(root):
    """Summaries, trends and the study figures of the runs under ``root``; returns the paths written."""
    cases, runs, written = {}, {}, []
    for k in CASES:
        got = _case_runs(os.path.join(root, f"case{k}"))
        if got is not None:
            cases[k], runs[k] = got
    conserving, conserving_runs = {}, {}
    for k in TRANSFER_CASES:
        got = _case_runs(os.path.join(root, f"case{k}-conserving"))
        if got is not None:
            conserving[k], conserving_runs[k] = got
    drain = os.path.join(root, "drainage.json")
    drainage = json.load(open(drain)) if os.path.exists(drain) else None
    rows = trends(cases, drainage)
    out = {"cases": {f"case{k}": v for k, v in cases.items()}, "starts": {f"case{k}": len(v) for k, v in cases.items()},
           "drainage": drainage,
           "conserving": {f"case{k}": v for k, v in conserving.items()},
           "trends": rows, "paper_cpu_minutes": 330,
           "notes": {"porosity_end": f"mean over the last {PERIOD:g} s (one input period)",
                     "U_low": f"mean of the block means of blocks 1-{LOW_BLOCKS} (below the two surface blocks)"}}
    path = os.path.join(root, "summary.json")
    files.write_json(path, out, indent=1)
    written.append(path)
    path = os.path.join(root, "trends.md")
    files.write_text(path, trends_markdown(rows))
    written.append(path)
    n_all = np.concatenate([_drawn(r, "porosity") for r in runs.values()]) if runs else np.zeros(1)
    pad = 0.05 * (np.nanmax(n_all) - np.nanmin(n_all) + 1e-9)
    n_lim = (np.nanmin(n_all) - pad, np.nanmax(n_all) + pad)  # Fig. 40, 41, 46 on the same axes
    u_lim = max([np.nanmax(np.abs(_drawn(runs[k], c))) for k in _wet(runs) for c in block_columns(runs[k][0])] + [1e-9])
    for name, (title, ks) in STUDY_FIGURES.items():
        have = {k: runs[k] for k in ks if k in runs}
        if have:
            fig = porosity_figure(have, title, n_lim, u_lim)
            written.append(os.path.join(root, name))
            files.save_figure(fig, written[-1], dpi=110)
            plt.close(fig)
    pairs = {k: (runs[k][0], conserving_runs[k][0]) for k in conserving if k in runs}  # the (mean) histories
    if pairs:
        fig = transfer_figure(pairs)
        written.append(os.path.join(root, "transfer_comparison.png"))
        files.save_figure(fig, written[-1], dpi=110)
        plt.close(fig)
    return written


def _cases_of(summary):
    """{case: [case_summary of each start]} of a study's summary.json."""
    return {int(k[len("case"):]): v for k, v in summary["cases"].items()}


def reconstruction(out, baseline, packings=None):
    """The trends on each variant of engines.studies.reconstruction (its ``judged``): its cases'
    ensembles under OUT/runs, the study's own from BASELINE/summary.json. ``packings``: {variant:
    facts of its deposit} (engines.run.reconstruction.packing_facts). Writes OUT/reconstruction.json,
    reconstruction.md and reconstruction.png; returns the JSON's dict."""
    with open(os.path.join(baseline, "summary.json")) as f:
        base = _cases_of(json.load(f))
    runs = {}
    for name, v in VARIANTS.items():
        got = {k: _case_runs(ensemble_path(os.path.join(out, "runs"), name, k)) for k in v.cases}
        runs[name] = {k: None if g is None else g[0] for k, g in got.items()}
    doc = {"baseline": os.path.abspath(baseline), **judged(base, runs, packings)}
    files.write_json(os.path.join(out, "reconstruction.json"), doc, indent=1)
    files.write_text(os.path.join(out, "reconstruction.md"), reconstruction_markdown(doc))
    fig = reconstruction_figure(doc)
    files.save_figure(fig, os.path.join(out, "reconstruction.png"), dpi=110)
    plt.close(fig)
    return doc


MARK = {"holds": "✓", "fails": "✗", "undecided": "?"}  # a condition's verdict in the table


def _rows(doc):
    """[(label, trend rows, the cases changed)]: the study's presets first (None), then each variant."""
    return [("the presets (make liquefaction)", doc["reference"], None)] + [
        (name, v["trends"], set(v["changed"])) for name, v in doc["variants"].items()]


def _unchanged(row, changed):
    """A trend row of a variant none of whose cases the variant changed (the presets' own numbers)."""
    return changed is not None and not changed & set(row["cases"])


def reconstruction_markdown(doc):
    """The reconstruction table: per variant (rows) each trend's (columns T1..) quantities with
    their intervals and verdicts (MARK), the trend's verdict in bold ("as the presets" where the
    variant changes none of its cases); the trends' key, the variants' reasons and their cases' means."""
    names = [t[0] for t in TRENDS]
    lines = ["| variant | " + " | ".join(f"T{i + 1}" for i in range(len(names))) + " |",
             "|---" * (len(names) + 1) + "|"]
    for label, rows, changed in _rows(doc):
        by = {r["trend"]: r for r in rows}
        cells = []
        for t in names:
            r = by.get(t)
            cells.append("–" if r is None else "as the presets" if _unchanged(r, changed) else "; ".join(
                f"{c['estimate']:.3g} [{c['ci95'][0]:.3g}, {c['ci95'][1]:.3g}] {MARK[c['verdict']]}"
                for c in r["conditions"]) + f" **{r['verdict']}**")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines += ["", "Trends (each quantity's criterion in brackets):", ""]
    for i, (trend, _, _, conditions) in enumerate(TRENDS):
        lines.append(f"- T{i + 1}: {trend}: " + "; ".join(f"{q} ({holds_if(lo, hi)})" for q, _, lo, hi in conditions))
    lines += ["", "| variant | unknown | why a candidate | cases run (starts) | packing | "
              "case means: porosity at t = 0, Δn, U_low mean [N/m] |", "|---|---|---|---|---|---|"]
    for name, v in doc["variants"].items():
        pk = v["packing"]
        packing = "–" if not pk else (f"bed top {pk['bed_top_mm']:.1f} mm, contacts carry "
                                      f"{pk['dense_top_support']:.2f} of the dense top's weight")
        means = "; ".join(f"case {k}: " + ", ".join(f"{m[key]:.3g}" for key in ("porosity_initial", "porosity_change",
                                                                                 "U_low_mean") if key in m)
                          for k, m in v["case_means"].items())
        starts = ", ".join(f"{k} ({n})" for k, n in v["starts"].items())
        missing = [k for k in v["cases"] if k not in v["done"]]
        lines.append(f"| {name} | {v['unknown']} | {v['reason']} | {starts}"
                     + (f"; not yet: {missing}" if missing else "") + f" | {packing} | {means} |")
    return "\n".join(lines) + "\n"


def reconstruction_figure(doc):
    """One panel per criterion of TRENDS: its estimate and 95 % interval for the presets and each
    variant, the region where it holds shaded."""
    conditions = [(t, c) for t, _, _, cs in TRENDS for c in cs]
    labels = _rows(doc)
    ncol = 5
    nrow = -(-len(conditions) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.3 * ncol, 3.6 * nrow), layout="constrained", squeeze=False)
    for ax, (trend, (quantity, _, low, high)) in zip(axes.flat, conditions):
        for y, (_, rows, changed) in enumerate(labels):
            row = next((r for r in rows if r["trend"] == trend), None)
            if row is None:
                continue
            c = next(c for c in row["conditions"] if c["quantity"] == quantity)
            lo, hi = c["ci95"]
            colour = {"holds": "tab:green", "fails": "tab:red"}.get(c["verdict"], "tab:grey")
            same = _unchanged(row, changed)
            ax.errorbar([c["estimate"]], [y], xerr=[[c["estimate"] - lo], [hi - c["estimate"]]], fmt="o",
                        color=colour, ms=4, capsize=2, mfc="none" if same else colour, alpha=0.4 if same else 1)
        edges = [v for v in (low, high) if np.isfinite(v)]  # the thresholds in view
        x0, x1 = min(ax.get_xlim()[0], *edges), max(ax.get_xlim()[1], *edges)
        x0, x1 = x0 - 0.05 * (x1 - x0), x1 + 0.05 * (x1 - x0)
        ax.axvspan(max(low, x0) if np.isfinite(low) else x0, min(high, x1) if np.isfinite(high) else x1,
                   color="tab:green", alpha=0.12, lw=0)
        ax.set_xlim(x0, x1)
        ax.set_yticks(range(len(labels)), [lab if y else "presets" for y, (lab, _, _) in enumerate(labels)], fontsize=7)
        ax.invert_yaxis()
        ax.set_title(f"T{[t[0] for t in TRENDS].index(trend) + 1}: {quantity}", fontsize=7)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(conditions):]:
        ax.axis("off")
    fig.suptitle(f"The trends on the variants: estimate and {100 * CONFIDENCE:g} % interval (green: holds, "
                 "red: fails, grey: undecided; open: the variant changes none of the trend's cases; shaded: where "
                 "the criterion holds)", fontsize=10)
    return fig


if __name__ == "__main__":
    from engines.files.inputs import ArgumentParser
    ap = ArgumentParser(prog="python3 -m postproc.liquefaction",
                                 description="Redraw seismic runs' blocks.png and depth.png, or (--study ROOT) the "
                                             "study of `make liquefaction`'s ensembles: summary.json, trends.md, "
                                             "Fig. 40, 41, 46.")
    what = ap.add_mutually_exclusive_group(required=True)
    what.add_argument("runs", nargs="*", type=run_dir, metavar="RUN_DIR", default=[], help="a run's --out folder")
    what.add_argument("--study", metavar="ROOT", help="the folder of make liquefaction (case1 ... case7)")
    args = ap.parse_args()
    if args.study:
        found = [k for k in CASES if _case_runs(os.path.join(args.study, f"case{k}")) is not None]
        if not found:
            ap.error(f"--study {args.study}: no finished case (case1 ... case7 with their summary.json); "
                     "run `make liquefaction` first")
        paths = study(args.study)
    else:
        paths = [p for run in args.runs for p in run_figures(run)]
    print("\n".join(paths))
