"""The figure of the stability map (engines.studies.stability; OUT/map.json of yade_scripts/stability.py)."""
import json
import os

import numpy as np

from engines import files
from engines.studies.stability import LIQ, QS

COLORS = {"bounded": "tab:green", "refused": "tab:orange", "unbounded": "tab:red"}
MARKERS = {QS: "o", LIQ: "s"}


def figure(points, path):
    """One panel per knob: the peak kinetic energy over its reference's (log), coloured by outcome;
    refused points drawn on the panel's top edge."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    knobs = list(dict.fromkeys(p["knob"] for p in points))
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5))
    for ax, knob in zip(axes.flat, knobs):
        sel = [p for p in points if p["knob"] == knob]
        ratios = [p.get("ke_ratio", np.nan) for p in sel if p["outcome"] != "refused"]
        top = max([r for r in ratios if np.isfinite(r)] + [10.0]) * 5
        for p in sel:
            x = max(p["value"], 1e-1 if knob in ("k1", "k2") else 0) if knob != "dt/dt_crit" else p["value"]
            y = top if p["outcome"] == "refused" else p.get("ke_ratio", np.nan)
            if not np.isfinite(y):
                y = top / 2
            ax.scatter(x, y, c=COLORS[p["outcome"]], marker=MARKERS[p["case"]], s=55, edgecolors="k", linewidths=0.5,
                       zorder=3)
            if p["overrides"].get("water", {}).get("substep") is False:
                ax.annotate("substep = false", (x, y), fontsize=7, xytext=(-30, -12), textcoords="offset points")
            elif "max_substeps" in p.get("reason", ""):
                ax.annotate("> max_substeps", (x, y), fontsize=7, xytext=(-50, -24), textcoords="offset points")
            elif p.get("substeps_max", 0) > 1:
                ax.annotate(f"{p['substeps_max']} sub-steps", (x, y), fontsize=7, xytext=(-20, -14), textcoords="offset points")
            if p["overrides"].get("numerics", {}).get("dt") == 1e-5 and knob == "E_w":
                ax.annotate("dt 1e-5", (x, y), fontsize=7, xytext=(4, 4), textcoords="offset points")
        ax.axhline(10, color="0.5", ls=":", lw=0.8)
        ax.set_yscale("log")
        if knob != "dt/dt_crit":
            ax.set_xscale("log")
        ax.set_xlabel({"dt/dt_crit": "dt / dt_crit (eq 52)", "E_w": "E_w [N/m]", "k1": "k1 [1/s] (0 drawn at 0.1)",
                       "k2": "k2 [1/s] (0 drawn at 0.1)", "eps_m": "eps_m [m]", "f_max": "f_max [N]"}[knob])
        ax.set_ylabel("peak kinetic energy / reference's")
        ax.set_title(knob + " (refused: top edge)", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes.flat[len(knobs):]:
        ax.axis("off")
    handles = [plt.Line2D([], [], ls="", marker="o", color=c, mec="k", label=o) for o, c in COLORS.items()]
    handles += [plt.Line2D([], [], ls="", marker=m, color="w", mec="k", label=c) for c, m in MARKERS.items()]
    handles += [plt.Line2D([], [], ls=":", color="0.5", label="bound: 10x the reference's (dt / 4; dt points: the preset)")]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=9)
    fig.suptitle("Stability map: short runs at the extremes (quick-sand case 1; dt also on the seismic box)")
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    files.save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path


def replot(out):
    """Redraw OUT/map.png from OUT/map.json; returns its path."""
    with open(os.path.join(out, "map.json")) as f:
        return figure(json.load(f)["points"], os.path.join(out, "map.png"))
