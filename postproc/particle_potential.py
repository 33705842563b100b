"""The figures of the particle-potential study (engines.seeds.particle_potential.specimen):
Fig. 6–7 (the deformed specimen), Fig. 8 (stress against strain), Fig. 9 (top against bottom)."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from engines import files  # noqa: E402
from engines.seeds.particle_potential.model import find_pairs, pa_to_tf_m2  # noqa: E402
from engines.seeds.particle_potential.specimen import HALF_COLUMNS, SPACING, bottom_stress  # noqa: E402


def plot_stress_strain(runs, summary, path):
    """Fig. 8: stress–strain curves (compression and tension by load, compression by displacement)."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    curves = [("compression", "top load, compression (to the limit load)"),
              ("tension", "top load, tension (to the limit load)")]
    for key, label in curves:
        lim = runs[key]
        ax.plot(100 * np.r_[0, lim.strain_path], np.r_[0, pa_to_tf_m2(lim.stress_path)], marker=".", ms=2, label=label)
    disp = runs["displacement"]
    ax.plot(100 * np.r_[0, disp.strain], np.r_[0, pa_to_tf_m2(disp.stress)], marker=".", ms=2,
            label="forced top displacement")
    if summary["yield_stress_t_m2"] is not None:
        ax.plot(100 * summary["yield_strain"], summary["yield_stress_t_m2"], "rx", ms=10, label="yield (ours)")
    paper = summary["paper"] or {}
    if paper.get("yield_stress_t_m2"):
        ax.plot(100 * paper["yield_strain"], paper["yield_stress_t_m2"], "ks", mfc="none", ms=9, label="yield (paper)")
    eps = np.linspace(-0.1, 0.1, 3)
    ax.plot(100 * eps, summary["E_apparent_t_m2"] * eps, "k--", lw=0.8,
            label=f"E = {summary['E_apparent_t_m2']:.0f} t/m² (paper ≈ {paper.get('E_t_m2', float('nan')):.0f})")
    ax.set(xlabel="strain (mean top settlement / 12 m) [%]", ylabel="stress [t/m²] (compression > 0)",
           title=f"A_m = {summary['A_m_tf_m']}, α = {summary['alpha']}, C = {summary['C']}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


def plot_top_vs_bottom(runs, path):
    """Fig. 9: applied or top stress against the mean bottom reaction."""
    fig, ax = plt.subplots(figsize=(4.5, 4.5))
    for key, spec_key, label in [("load", "loaded", "top load"),
                                 ("displacement", "pushed", "forced displacement")]:
        p, spec = runs[key], runs[spec_key]
        ok = [k for k, inc in enumerate(p.increments) if inc.converged]
        bottom = [bottom_stress(spec, p.increments[k]) for k in ok]
        ax.plot(pa_to_tf_m2(p.stress[ok]), pa_to_tf_m2(np.array(bottom)), "o", ms=3, label=label)
    top = ax.get_xlim()
    ax.plot(top, top, "k--", lw=0.8, label="45°")
    ax.set(xlabel="top stress [t/m²]", ylabel="bottom reaction [t/m²]", aspect="equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


def plot_deformed(spec, inc, title, path):
    """Fig. 6–7: deformed lattice (mirrored to the full width) with bottom and top reactions
    drawn as bars in t/m² (reaction over tributary width)."""
    ref, pos = spec.model.reference, inc.positions
    axis_x = HALF_COLUMNS * SPACING
    pairs = find_pairs(ref, spec.model)
    fig, ax = plt.subplots(figsize=(5, 8))
    for sign in (1, -1):
        mirror = lambda p: np.column_stack([axis_x + sign * (p[:, 0] - axis_x), p[:, 1]])
        r, q = mirror(ref), mirror(pos)
        ax.plot(r[:, 0], r[:, 1], "o", color="0.8", ms=3)
        ax.plot(*np.stack([q[pairs.i], q[pairs.j]]).transpose(2, 0, 1), color="C0", lw=0.5)
        ax.plot(q[:, 0], q[:, 1], "o", color="C0", ms=3)
        for rows, out in [(spec.bottom, -1), (spec.top, 1)]:
            stress = pa_to_tf_m2(-out * inc.reactions[rows, 1] / spec.top_width)  # compression > 0
            for (x, z), s in zip(q[rows], stress):
                if s != 0:
                    ax.plot([x, x], [z + out * 0.2, z + out * (0.2 + s / 40)], color="C3", lw=3)
                    if sign == 1:
                        ax.annotate(f"{s:.1f}", (x, z + out * (0.45 + s / 40)), ha="center",
                                    va="center", fontsize=6, color="C3")
    ax.set(aspect="equal", xlabel="x [m]", ylabel="z [m]", title=title)
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


def figures(runs, summary, out):
    """Fig. 6–9 of one α's runs (engines.seeds.particle_potential.specimen.run_all) into ``out``."""
    plot_stress_strain(runs, summary, os.path.join(out, "fig8_stress_strain.png"))
    plot_top_vs_bottom(runs, os.path.join(out, "fig9_top_vs_bottom.png"))
    load, disp = runs["load"], runs["displacement"]
    plot_deformed(runs["loaded"], load.increments[load.last_stable()],
                  f"top load {summary['load_reached_t_m2']:.1f} t/m²", os.path.join(out, "fig6_top_load.png"))
    plot_deformed(runs["pushed"], disp.increments[disp.last_stable()],
                  f"forced top displacement {100 * summary['displacement_reached_m']:.0f} cm",
                  os.path.join(out, "fig7_forced_displacement.png"))
