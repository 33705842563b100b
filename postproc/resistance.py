"""The liquefaction resistance curve's figure (make resistance; engines.studies.resistance): CSR
against N_L on a log axis, as laboratory curves are drawn.

Per amplitude and packing: the median N_L of the starts with its interval (horizontal bar) and the
mean CSR with its 95 % interval (vertical bar), filled; a censored median (more than half the
starts not liquefied within the runs' cycles) open at the runs' end with an arrow to the right;
the simplified CSR (0.65 a_max/g sigma_v/sigma'_v0) of the same row as a small grey mark at the same
N_L. Loose: circles; dense: squares. The 10,000-disc ground's one run, when the document has it:
a star, open with an arrow when censored, without bars (one run has no interval). The key sits below the axes.
"""
import numpy as np

from engines.files import save_figure
from engines.studies.resistance import read_rows
from postproc.plots import plt

STYLE = {"loose": ("o", "C0"), "dense": ("s", "C3")}


def resistance_figure(doc, path):
    """Draw ``doc`` (engines.run.resistance.analyse's document) to ``path``."""
    cycles = doc["cycles"]
    fig, ax = plt.subplots(figsize=(6.4, 5.0))
    for name, p in doc["packings"].items():
        marker, colour = STYLE.get(name, ("^", "C2"))
        label = f"{name} (e = {p['void_ratio']:.3f})"
        for r in read_rows(p):
            n_l, csr = r["n_l"], r["csr"]
            censored = n_l["median"] is None
            x = cycles if censored else n_l["median"]
            lo = cycles if n_l["low"] is None else n_l["low"]
            hi = cycles if n_l["high"] is None else n_l["high"]
            y = csr["mean"]
            yerr = np.array([[y - csr["ci95_low"]], [csr["ci95_high"] - y]]) if np.isfinite(csr["ci95_low"]) else None
            ax.errorbar([x], [y], xerr=[[x - lo], [hi - x]], yerr=yerr, fmt=marker, color=colour, ms=7, capsize=3,
                        mfc="white" if censored else colour, label=label + (" censored" if censored else ""))
            if censored or n_l["high"] is None:
                ax.annotate("", xy=(x * 1.6, y), xytext=(x, y), arrowprops=dict(arrowstyle="->", color=colour))
            ax.plot([x], [r["csr_simplified"]["mean"]], marker, color="0.55", ms=4, mfc="none",
                    label="grey: simplified CSR 0.65 a_max/g σv/σ'v0")
    g = doc.get("ground")
    if g:
        x = cycles if g["censored"] else g["n_l"]
        ax.plot([x], [g["csr"]], "*", color="C2", ms=13, mfc="white" if g["censored"] else "C2",
                label=f"{g['n_particles']:,}-disc ground, one run (e = {g['void_ratio']:.3f})"
                      + (" censored" if g["censored"] else ""))
        if g["censored"]:
            ax.annotate("", xy=(x * 1.6, g["csr"]), xytext=(x, g["csr"]), arrowprops=dict(arrowstyle="->", color="C2"))
    ax.set_xscale("log")
    ax.set_xlim(0.8, 3 * cycles)
    ax.axvline(cycles, color="0.7", lw=0.8, ls=":")
    ax.set_xlabel("cycles to liquefaction N_L (cycle-mean r_u ≥ %g)" % doc["ru_liquefied"])
    ax.set_ylabel("CSR = amplitude of σ'_xz / σ'_v0")
    ax.set_title(("PILOT: " if doc.get("pilot") else "") + "resistance curve, seismic box (case 1),\n"
                 f"{doc['frequency_Hz']:g} Hz, runs of {cycles:g} cycles", fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    keep = dict(zip(labels, handles))  # one entry per label
    ax.legend(keep.values(), keep.keys(), fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2,
              frameon=False)
    fig.text(0.01, 0.01, "bars: N_L interval of the median (order statistics), CSR 95 % interval; open + arrow: "
             f"censored (N_L > {cycles:g})", fontsize=7)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    save_figure(fig, path, dpi=130)
    plt.close(fig)
    return path
