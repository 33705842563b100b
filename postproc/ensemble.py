"""Figures of an ensemble (engines.run.ensemble): the mean over the starts with its 95 % band.

``figures(out_dir)`` reads OUT/ensemble.json (and the first start's summary.json for the title,
E_w and whether the scene is wet) and draws

    ensemble_pressure_blocks.png   the block-mean excess pore pressure of every block
    ensemble_history.png           the panels of a run's history_panels.png

    /usr/bin/python3 -m postproc.ensemble OUT_DIR      # redraw them
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from postproc.plots import BLOCK_NAMES, HISTORY_PANELS  # noqa: E402
from postproc.run_files import read_summary  # noqa: E402


def _band(ax, t_ms, stats, colour, label, scale=1.0):
    """The mean (a line) and its 95 % interval (a band) of one column's statistics."""
    mean, lo, hi = (np.array(stats[k], float) * scale for k in ("mean", "ci95_low", "ci95_high"))
    ax.fill_between(t_ms, lo, hi, color=colour, alpha=0.25, linewidth=0)
    return ax.plot(t_ms, mean, color=colour, label=label)[0]


def figures(out_dir):
    """Draw the ensemble's figures (module docstring); returns the paths written."""
    with open(os.path.join(out_dir, "ensemble.json")) as f:
        doc = json.load(f)
    first = read_summary(os.path.join(out_dir, doc["starts"][0]))
    water = first.get("parameters", {}).get("water", {})
    title = f"{doc['scene']}: mean of {doc['n_starts']} starts ({doc['perturbation_m']:g} m apart) with its 95 % band"
    cols, t_ms = doc["history"]["columns"], np.array(doc["history"]["t"]) * 1e3
    written = []
    blocks = sorted((c for c in cols if c.startswith("U_block")), key=lambda c: int(c[len("U_block"):]))
    if len(t_ms) >= 2 and water.get("enabled", False) and blocks:
        fig, ax = plt.subplots(figsize=(7.5, 4.9))
        for k, name in enumerate(blocks):
            _band(ax, t_ms, cols[name], f"C{k}", BLOCK_NAMES.get(name, name.replace("U_", "")))
        ax.axhline(water["E_w"], color="0.5", ls="--", lw=0.8, label=f"E_w = {water['E_w']:g} N/m (bound of eq 32)")
        ax.axhline(0.0, color="0.3", lw=0.6)
        ax.set_xlabel("t [ms]")
        ax.set_ylabel("block-mean excess pore pressure U [N/m]")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2)
        fig.tight_layout()
        written.append(os.path.join(out_dir, "ensemble_pressure_blocks.png"))
        fig.savefig(written[-1], dpi=120)
        plt.close(fig)
    if len(t_ms) >= 2:
        fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
        for ax, (col, label, scale) in zip(axes.ravel(), HISTORY_PANELS):
            if col in cols:
                _band(ax, t_ms, cols[col], "C0", label, scale)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        for ax in axes[1]:
            ax.set_xlabel("t [ms]")
        fig.suptitle(title, fontsize=10)
        fig.tight_layout()
        written.append(os.path.join(out_dir, "ensemble_history.png"))
        fig.savefig(written[-1], dpi=120)
        plt.close(fig)
    return written


if __name__ == "__main__":
    for d in sys.argv[1:]:
        for path in figures(d):
            print(path)
