"""Figures of an ensemble (engines.run.ensemble): the mean over the starts with its 95 % band.

``figures(out_dir)`` reads OUT/ensemble.json (and the first start's summary.json for the title,
E_w and whether the scene is wet) and draws

    ensemble_pressure_blocks.png   the block-mean excess pore pressure, a panel per block
    ensemble_history.png           the panels of a run's history_panels.png

``compare(dirs, figure, times)`` sets ensembles of one scene from starts of different sizes side
by side: the spread of the starts (their standard deviation, standard_error x sqrt(n)) of the
bed top, porosity and block pressures against time, the mean heave time marked, and a markdown
table of the spreads at ``times`` (how a scene's default size is chosen, docs/SWEEPS.md);
``differences(dirs, window)`` the speed/accuracy study's metrics (engines.studies.tradeoffs.
systematic: block pressures, porosity change, and the change of the bed top in place of the
mean height) between each two of them over the first ``window`` seconds.

    /usr/bin/python3 -m postproc.ensemble OUT_DIR [OUT_DIR ...]          # redraw their figures
    /usr/bin/python3 -m postproc.ensemble --compare OUT_DIR ... --figure F.png [--times S ...] [--window S]
"""
import argparse
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from engines import files  # noqa: E402
from engines.studies.tradeoffs import systematic  # noqa: E402
from postproc.plots import HISTORY_PANELS  # noqa: E402
from postproc.run_files import read_history, read_summary  # noqa: E402


def _band(ax, t_ms, stats, colour, scale=1.0):
    """The mean (a line) and its 95 % interval (a band) of one column's statistics."""
    mean, lo, hi = (np.array(stats[k], float) * scale for k in ("mean", "ci95_low", "ci95_high"))
    ax.fill_between(t_ms, lo, hi, color=colour, alpha=0.3, linewidth=0, label="95 % interval")
    ax.plot(t_ms, mean, color=colour, label="mean")


def read(out_dir):
    with open(os.path.join(out_dir, "ensemble.json")) as f:
        return json.load(f)


def figures(out_dir):
    """Draw the ensemble's figures (module docstring); returns the paths written."""
    doc = read(out_dir)
    first = read_summary(os.path.join(out_dir, doc["starts"][0]))
    water = first.get("parameters", {}).get("water", {})
    title = f"{doc['scene']}: {doc['n_starts']} starts perturbed by {doc['perturbation_m']:g} m, their mean and its 95 % interval"
    cols, t_ms = doc["history"]["columns"], np.array(doc["history"]["t"]) * 1e3
    written = []
    blocks = sorted((c for c in cols if c.startswith("U_block")), key=lambda c: int(c[len("U_block"):]))
    if len(t_ms) >= 2 and water.get("enabled", False) and blocks:
        # one panel per block, the surface block on top (as Fig. 35/37 stack them)
        fig, axes = plt.subplots(len(blocks), 1, figsize=(7.5, 1.2 + 1.3 * len(blocks)), sharex=True, sharey=True,
                                 squeeze=False)  # one U axis: the blocks compared at a glance
        for ax, (k, name) in zip(axes[:, 0], reversed(list(enumerate(blocks)))):
            where = " (bottom)" if k == 0 else " (surface)" if k == len(blocks) - 1 else ""
            _band(ax, t_ms, cols[name], f"C{k}")
            ax.axhline(0.0, color="0.3", lw=0.6)
            ax.set_ylabel(f"U, block {k + 1}{where}\n[N/m]", fontsize=8)
            ax.grid(alpha=0.3)
        axes[0, 0].legend(fontsize=7, loc="upper left")
        axes[-1, 0].set_xlabel("t [ms]")
        fig.suptitle(f"{title}\nblock-mean excess pore pressure (E_w = {water['E_w']:g} N/m bounds it, eq 32)",
                     fontsize=9)
        fig.tight_layout()
        written.append(os.path.join(out_dir, "ensemble_pressure_blocks.png"))
        files.save_figure(fig, written[-1], dpi=110)
        plt.close(fig)
    if len(t_ms) >= 2:
        fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
        for ax, (col, label, scale) in zip(axes.ravel(), HISTORY_PANELS):
            if col in cols:
                _band(ax, t_ms, cols[col], "C0", scale)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        for ax in axes[1]:
            ax.set_xlabel("t [ms]")
        axes[0, 0].legend(fontsize=7)
        fig.suptitle(title, fontsize=10)
        fig.tight_layout()
        written.append(os.path.join(out_dir, "ensemble_history.png"))
        files.save_figure(fig, written[-1], dpi=120)
        plt.close(fig)
    return written


SPREAD_COLUMNS = (("bed_top", "bed top [m]"), ("porosity", "porosity [-]"), ("U_block1", "U, block 1 [N/m]"),
                  ("U_block2", "U, block 2 [N/m]"))


def spread(stats):
    """The standard deviation of the starts of one column's statistics (standard_error x sqrt(n))."""
    return np.array(stats["standard_error"], float) * np.sqrt(np.array(stats["n"], float))


def compare(dirs, figure, times):
    """The spreads of the ensembles in ``dirs`` (module docstring): draws ``figure``, returns the
    table (markdown lines)."""
    docs = [read(d) for d in dirs]
    fig, axes = plt.subplots(2, 2, figsize=(9, 6.5), sharex=True)
    rows = ["| perturbation [m] | starts | heave time [ms] | " +
            " | ".join(f"spread of {c} at {1e3 * t:g} ms" for c, _ in SPREAD_COLUMNS[:2] for t in times) + " |",
            "|---" * (3 + 2 * len(times)) + "|"]
    for k, doc in enumerate(docs):
        t = np.array(doc["history"]["t"])
        heave = doc["results"].get("heave_time_s", {})
        for ax, (col, label) in zip(axes.ravel(), SPREAD_COLUMNS):
            if col in doc["history"]["columns"]:
                ax.semilogy(t * 1e3, spread(doc["history"]["columns"][col]), color=f"C{k}",
                            label=f"{doc['perturbation_m']:g} m, {doc['n_starts']} starts")
                if heave.get("mean") is not None:
                    ax.axvline(heave["mean"] * 1e3, color=f"C{k}", ls=":", lw=0.8)
            ax.set_ylabel(f"spread of the starts: {label}")
            ax.grid(alpha=0.3, which="both")
        at = [int(np.argmin(np.abs(t - x))) for x in times]
        cells = [f"{spread(doc['history']['columns'][c])[i]:.2g}" for c, _ in SPREAD_COLUMNS[:2] for i in at]
        when = "never" if heave.get("mean") is None else f"{1e3 * heave['mean']:.2f} ± {1e3 * (heave['standard_error'] or 0):.2f}"
        rows.append(f"| {doc['perturbation_m']:g} | {doc['n_starts']} | {when} | " + " | ".join(cells) + " |")
    for ax in axes[1]:
        ax.set_xlabel("t [ms] (dotted: the mean heave time)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"{docs[0]['scene']}: standard deviation of the starts against time, by perturbation size", fontsize=10)
    fig.tight_layout()
    files.save_figure(fig, figure, dpi=110)
    plt.close(fig)
    return rows


def _study_run(out_dir, window):
    """The starts of an ensemble as the study's run dict (t, U, porosity, height = bed top) up to ``window`` [s]."""
    doc = read(out_dir)
    hs = [read_history(os.path.join(out_dir, s, "history.csv")) for s in doc["starts"]]
    keep = hs[0]["t"] <= window * (1 + 1e-9)
    blocks = sorted((c for c in hs[0] if c.startswith("U_block")), key=lambda c: int(c[len("U_block"):]))
    return {"t": hs[0]["t"][keep], "U": np.array([np.column_stack([h[b] for b in blocks])[keep] for h in hs]),
            "porosity": np.array([h["porosity"][keep] for h in hs]), "height": np.array([h["bed_top"][keep] for h in hs])}


def differences(dirs, window):
    """Markdown lines: the study's metrics (measured, floor, systematic +- sigma, %) between each two ensembles."""
    runs = [_study_run(d, window) for d in dirs]
    sizes = [f"{read(d)['perturbation_m']:g} m" for d in dirs]
    rows = [f"| first {1e3 * window:g} ms | pressures | porosity change | bed-top change |", "|---|---|---|---|"]
    for i in range(len(dirs)):
        for j in range(i + 1, len(dirs)):
            m = systematic(runs[j], runs[i], n_boot=200)
            cells = [f"{100 * m[k]['systematic']:.1f} ± {100 * m[k]['sigma']:.1f} %"
                     for k in ("pressure_rms", "porosity_change", "settlement")]
            rows.append(f"| {sizes[j]} against {sizes[i]} | " + " | ".join(cells) + " |")
    return rows


def ensemble_dir(path):
    """argparse type of an ensemble folder: ``path`` if it holds ensemble.json, else one line."""
    if not os.path.isfile(os.path.join(path, "ensemble.json")):
        raise argparse.ArgumentTypeError(f"{path}: not an ensemble folder (no ensemble.json; give the --out folder "
                                         "of a run with --starts N)")
    return path


if __name__ == "__main__":
    from engines.files.inputs import ArgumentParser
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+", type=ensemble_dir, help="ensemble folders (holding ensemble.json)")
    ap.add_argument("--compare", action="store_true", help="their spreads side by side (needs --figure)")
    ap.add_argument("--figure", help="the comparison's figure")
    ap.add_argument("--times", type=float, nargs="+", default=[0.002, 0.004, 0.006, 0.01], help="[s]")
    ap.add_argument("--window", type=float, nargs="+", default=[], help="the differences' windows [s]")
    a = ap.parse_args()
    if a.compare:
        if not a.figure:
            ap.error("--compare needs --figure")
        print("\n".join(compare(a.dirs, a.figure, a.times)))
        for w in a.window:
            print("\n" + "\n".join(differences(a.dirs, w)))
    else:
        for d in a.dirs:
            for path in figures(d):
                print(path)
