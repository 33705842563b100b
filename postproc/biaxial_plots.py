"""Figures of seed 003's biaxial tests (Murakami et al. Fig. 4–21), from what the runs write."""
import os

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from engines import files  # noqa: E402
from engines.seeds.biaxial.specimen import mohr_coulomb_fit  # noqa: E402
from engines.seeds.biaxial.study import KN, PAPER, SENS_PHI, SENS_SIGMA3, SMALL_DISCS  # noqa: E402

PHI_COLOURS = {5.0: "C0", 10.0: "C1", 15.0: "C2"}


def _save(fig, path):
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


def plot_deviator_strain(curves, path, title):
    """Fig. 4(A)/9(A): deviator σ1 − σ3 against axial strain, one line per σ3, the peak and the
    E50 secant marked; volumetric strain below. ``curves``: engines.seeds.biaxial.specimen.Curve list."""
    fig, (ax, axv) = plt.subplots(2, 1, figsize=(6.5, 6.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    for k, c in enumerate(sorted(curves, key=lambda c: c.sigma3)):
        col = f"C{k}"
        ax.plot(100 * c.strain, c.deviator, color=col, lw=1, label=f"σ3 = {c.sigma3:g} Pa")
        eps_f, q_f = c.peak()
        ax.plot(100 * eps_f, q_f, "o", color=col, ms=4)
        e50 = c.e50()
        if np.isfinite(e50):
            ax.plot([0, 100 * q_f / e50], [0, q_f], ":", color=col, lw=0.8)
        axv.plot(100 * c.strain, 100 * c.volumetric_strain, color=col, lw=1)
    ax.set(ylabel="deviator σ1 − σ3 [Pa]", title=title)
    ax.plot([], [], "ko", ms=4, label="peak (σ1 − σ3)_f")
    ax.plot([], [], "k:", lw=0.8, label="E50 secant (to half the peak, extended)")
    ax.set_ylim(bottom=min(0, ax.get_ylim()[0]))
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    axv.axhline(0, color="0.5", lw=0.6)
    axv.set(xlabel="axial strain [%]", ylabel="volumetric strain [%]\n(contraction > 0)")
    axv.grid(alpha=0.3)
    _save(fig, path)


def plot_mohr(sigma3, sigma1, phi_deg, c_pa, path, title):
    """Fig. 4(B)/9(B): Mohr circles at the peak and the failure line τ = c* + σ tan φ*."""
    s3, s1 = np.asarray(sigma3, float), np.asarray(sigma1, float)
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    th = np.linspace(0, np.pi, 200)
    for k, (a, b) in enumerate(sorted(zip(s3, s1))):
        centre, radius = (a + b) / 2, (b - a) / 2
        ax.plot(centre + radius * np.cos(th), radius * np.sin(th), color=f"C{k}", label=f"σ3 = {a:g} Pa")
    smax = 1.05 * s1.max()
    x = np.array([0, smax])
    ax.plot(x, c_pa + x * np.tan(np.radians(phi_deg)), "k-", lw=1.2,
            label=f"failure line: φ* = {phi_deg:.1f}°, c* = {c_pa:.1f} Pa")
    ax.set(xlabel="normal stress σ [Pa]", ylabel="shear stress τ [Pa]", title=title, xlim=(0, smax), ylim=(0, None),
           aspect="equal")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    _save(fig, path)


def plot_phi_star(rows, paper, path):
    """Fig. 12: φ* against φe, every packing and the mean, the paper's values for reference.
    rows: list of {"phi_e_deg", "phi_star_deg"}; paper: {φe: φ*}."""
    fig, ax = plt.subplots(figsize=(5, 4))
    pe = np.array([r["phi_e_deg"] for r in rows])
    ps = np.array([r["phi_star_deg"] for r in rows])
    ax.plot(pe, ps, "o", color="0.6", ms=4, label="one packing (4 σ3)")
    u = np.unique(pe)
    ax.errorbar(u, [ps[pe == v].mean() for v in u], yerr=[ps[pe == v].std(ddof=1) if (pe == v).sum() > 1 else 0
                                                        for v in u], fmt="s-", color="C3", capsize=3, label="mean ± s.d.")
    if paper:
        ax.plot(list(paper), list(paper.values()), "k*", ms=10, label="paper (φ* from its Fig. 9–11)")
    ax.plot([0, 20], [0, 20], color="0.8", lw=0.8, label="φ* = φe")
    ax.set(xlabel="inter-element friction angle φe [°]", ylabel="model ground φ* [°]", xlim=(0, 20), ylim=(0, None),
           title="φ* against φe (Fig. 12)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    _save(fig, path)


def plot_e50_sigma3(points, path):
    """Fig. 15: E50 against σ3 (log–log), per φe; points: list of {"phi_e_deg", "sigma3_pa", "e50_pa"}."""
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    for pe in sorted({p["phi_e_deg"] for p in points}):
        sel = [p for p in points if p["phi_e_deg"] == pe]
        s3 = np.array([p["sigma3_pa"] for p in sel])
        e = np.array([p["e50_pa"] for p in sel])
        col = PHI_COLOURS.get(pe, None)
        ax.plot(s3, e, "o", color=col, ms=3, alpha=0.5)
        u = np.unique(s3)
        ax.plot(u, [np.exp(np.mean(np.log(e[s3 == v]))) for v in u], "-", color=col, label=f"φe = {pe:g}° (geometric mean)")
    ax.set(xscale="log", yscale="log", xlabel="σ3 [Pa]", ylabel="E50 [Pa]", title="E50 against σ3 (Fig. 15)")
    s3_all = sorted({p["sigma3_pa"] for p in points})
    ax.set_xticks(s3_all, [f"{v:g}" for v in s3_all])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    _save(fig, path)


def plot_eq4(points, fits, path, extra=()):
    """Fig. 19: E50/σ3 against σ3/kn (log–log) with the eq 4 regression line per φe.
    points: {"phi_e_deg", "sigma3_pa", "kn", "e50_pa"}; fits: {φe: (A, m)}; ``extra``: points of
    other kn (not fitted), drawn open: on the line if E50/σ3 depends on σ3/kn only (Fig. 18)."""
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    for k, p in enumerate(extra):
        ax.plot(p["sigma3_pa"] / p["kn"], p["e50_pa"] / p["sigma3_pa"], "D", mfc="none", ms=5,
                color=PHI_COLOURS.get(p["phi_e_deg"]), label=f"φe = {p['phi_e_deg']:g}°, kn ≠ 1e8, other specimen (not fitted)" if k == 0 else None)
    for pe, (A, m) in sorted(fits.items()):
        sel = [p for p in points if p["phi_e_deg"] == pe]
        x = np.array([p["sigma3_pa"] / p["kn"] for p in sel])
        y = np.array([p["e50_pa"] / p["sigma3_pa"] for p in sel])
        col = PHI_COLOURS.get(pe, None)
        ax.plot(x, y, "o", color=col, ms=3, alpha=0.6)
        xx = np.geomspace(x.min() / 1.2, x.max() * 1.2, 20)
        ax.plot(xx, A * xx ** m, "-", color=col, label=f"φe = {pe:g}°: A = {A:.3g}, m = {m:.3f}")
    ax.set(xscale="log", yscale="log", xlabel="σ3 / kn [m]", ylabel="E50 / σ3 [-]", title="eq 4 fit (Fig. 19)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    _save(fig, path)


def plot_A_m(fits, path):
    """Fig. 20–21: A(φe) and m(φe) of eq 4."""
    pe = sorted(fits)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(8, 3.5))
    a1.plot(pe, [fits[p][0] for p in pe], "o-")
    a1.set(yscale="log", xlabel="φe [°]", ylabel="A(φe) [m^-m]", title="A (Fig. 20)")
    a2.plot(pe, [fits[p][1] for p in pe], "s-", color="C1")
    a2.set(xlabel="φe [°]", ylabel="m(φe) [-]", title="m (Fig. 21)")
    for a in (a1, a2):
        a.grid(alpha=0.3, which="both")
    _save(fig, path)


def plot_sensitivity(groups, path, title, label, failed=None):
    """Fig. 5/6/8/13/14: deviator–strain curves for each value of one knob (one line per packing,
    the same colour per value), and peak deviator and E50 against the knob with the scatter.
    groups: {value: [Curve, ...]}; label: the knob's name and unit; failed: {value: runs that
    did not finish} (named in the title)."""
    fig, (ax, ap, ae) = plt.subplots(1, 3, figsize=(13, 4), gridspec_kw={"width_ratios": [2, 1, 1]})
    values = sorted(groups)
    for k, v in enumerate(values):
        for j, c in enumerate(groups[v]):
            ax.plot(100 * c.strain, c.deviator, color=f"C{k}", lw=0.8, alpha=0.8, label=f"{label} = {v:g}" if j == 0 else None)
        peaks = [c.peak()[1] for c in groups[v]]
        e50s = [c.e50() for c in groups[v]]
        ap.plot([v] * len(peaks), peaks, "o", color=f"C{k}", ms=4)
        ae.plot([v] * len(e50s), e50s, "o", color=f"C{k}", ms=4)
    ap.plot(values, [np.mean([c.peak()[1] for c in groups[v]]) for v in values], "k-", lw=0.8)
    ae.plot(values, [np.mean([c.e50() for c in groups[v]]) for v in values], "k-", lw=0.8)
    if failed:
        title += "\n" + ", ".join(f"{label} = {v:g}: {n} run(s) failed (no rest)" for v, n in failed.items())
    ax.set(xlabel="axial strain [%]", ylabel="deviator σ1 − σ3 [Pa]", title=title)
    ax.legend(fontsize=8)
    ap.set(xlabel=label, ylabel="peak deviator [Pa]", ylim=(0, None), title="peak (each packing, mean)")
    ae.set(xlabel=label, ylabel="E50 [Pa]", ylim=(0, None), title="E50 (each packing, mean)")
    for a in (ap, ae):
        a.set_xscale("log")
        a.set_xticks(values, [f"{v:g}" for v in values])
        a.minorticks_off()
    for a in (ax, ap, ae):
        a.grid(alpha=0.3)
    _save(fig, path)


def plot_study_curves(per_phi_e, path):
    """Fig. 9–11: for each φe the deviator–strain curves of every packing (one colour per σ3)
    and the Mohr circles at the peaks with the failure line of each packing."""
    phis = sorted(per_phi_e)
    fig, axes = plt.subplots(2, len(phis), figsize=(4.6 * len(phis), 8), squeeze=False)
    th = np.linspace(0, np.pi, 100)
    for col, pe in enumerate(phis):
        ax, am = axes[0, col], axes[1, col]
        smax = 0
        for seed, curves in sorted(per_phi_e[pe]["curves"].items()):
            s3, s1 = [], []
            for k, (sig3, c) in enumerate(sorted(curves.items())):
                ax.plot(100 * c.strain, c.deviator, color=f"C{k}", lw=0.7, alpha=0.8,
                        label=f"σ3 = {sig3:g} Pa" if seed == min(per_phi_e[pe]["curves"]) else None)
                q = c.peak()[1]
                s3.append(sig3)
                s1.append(sig3 + q)
                am.plot((2 * sig3 + q) / 2 + q / 2 * np.cos(th), q / 2 * np.sin(th), color=f"C{k}", lw=0.7, alpha=0.8)
            if len(s3) >= 2:
                phi, c_star = mohr_coulomb_fit(s3, s1)
                smax = max(smax, max(s1))
                x = np.array([0, 1.05 * max(s1)])
                am.plot(x, c_star + x * np.tan(np.radians(phi)), color="k", lw=0.8, ls=("-", "--", ":", "-.")[seed % 4],
                        label=f"seed {seed}: φ* = {phi:.1f}°, c* = {c_star:.1f} Pa")
        ax.set(xlabel="axial strain [%]", ylabel="deviator σ1 − σ3 [Pa]", title=f"φe = {pe:g}° (Fig. 9–11 A)")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        am.set(xlabel="σ [Pa]", ylabel="τ [Pa]", aspect="equal", xlim=(0, 1.05 * smax or None), ylim=(0, None),
               title=f"φe = {pe:g}°: Mohr circles (Fig. 9–11 B)")
        am.legend(fontsize=7, loc="upper left")
        am.grid(alpha=0.3)
    _save(fig, path)


def plot_sigma3_kn_collapse(pairs, path):
    """Fig. 18: q/σ3 against axial strain for tests at equal σ3/kn but different kn, one panel per
    σ3/kn. pairs: {σ3/kn [m]: {label: [Curve, ...]}}."""
    fig, axes = plt.subplots(1, len(pairs), figsize=(5.2 * len(pairs), 4), squeeze=False)
    for ax, (ratio, groups) in zip(axes[0], sorted(pairs.items())):
        for k, (label, curves) in enumerate(sorted(groups.items())):
            for j, c in enumerate(curves):
                ax.plot(100 * c.strain, c.deviator / c.sigma3, color=f"C{k}", lw=0.8, alpha=0.8,
                        label=label if j == 0 else None)
        ax.set(xlabel="axial strain [%]", ylabel="(σ1 − σ3) / σ3 [-]", title=f"σ3 / kn = {ratio:.0e} m (Fig. 18)")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    _save(fig, path)


def study_figures(out, main, sens):
    """The study's figures into ``out`` (yade_scripts/biaxial_study.py lists them), from
    engines.seeds.biaxial.study's analyse_main (``main``) and analyse_sensitivity (``sens``)."""
    if main["rows"]:
        plot_phi_star(main["rows"], PAPER["phi_star_deg"], os.path.join(out, "fig12_phi_star.png"))
        plot_e50_sigma3(main["points"], os.path.join(out, "fig15_e50_sigma3.png"))
        plot_study_curves(main["per_phi_e"], os.path.join(out, "fig09_11_curves.png"))
    if main["fits"]:
        kn_points = [{"phi_e_deg": SENS_PHI, "sigma3_pa": SENS_SIGMA3, "kn": float(k), "e50_pa": e}
                     for k, c in sens["kn_pa_per_m"].items() for e in c["e50_pa"] if float(k) != KN]
        plot_eq4(main["points"], main["fits"], os.path.join(out, "fig19_eq4.png"), extra=kn_points)
        plot_A_m(main["fits"], os.path.join(out, "fig20_21_A_m.png"))
    pairs = {}  # Fig. 18: the kn runs at σ3 = 200 Pa against the main grid's φe = 10° at the same σ3/kn
    for kn, s3 in ((2e8, 100.0), (0.5e8, 400.0)):
        main_curves = [c[s3] for c in main["per_phi_e"].get(SENS_PHI, {}).get("curves", {}).values() if s3 in c]
        kn_curves = sens["kn_pa_per_m"].get(kn, {}).get("curves", [])
        if main_curves and kn_curves:
            pairs[s3 / KN] = {f"kn = {KN:.0e}, σ3 = {s3:g} Pa, 1000 discs": main_curves,
                              f"kn = {kn:.0e}, σ3 = {SENS_SIGMA3:g} Pa, {SMALL_DISCS} discs": kn_curves}
    if pairs:
        plot_sigma3_kn_collapse(pairs, os.path.join(out, "fig18_sigma3_over_kn.png"))
    for key, fname, title, label in [
            ("strain_rate_pct_min", "fig05_strain_rate.png", "axial strain rate, 1000 discs (Fig. 5)", "strain rate [%/min]"),
            ("dt_s", "fig06_dt.png", f"time step, {SMALL_DISCS} discs (Fig. 6)", "Δt [s]"),
            ("n_discs", "fig08_discs.png", "number of discs (Fig. 8)", "discs"),
            ("kn_pa_per_m", "fig13_kn.png", f"kn, {SMALL_DISCS} discs (Fig. 13)", "kn [Pa/m]"),
            ("ks_ratio", "fig14_ks.png", f"ks/kn, {SMALL_DISCS} discs (Fig. 14)", "ks/kn")]:
        groups = {float(v): c["curves"] for v, c in sens[key].items() if c["curves"]}
        failed = {float(v): len(c["failed"]) for v, c in sens[key].items() if c["failed"]}
        if groups:
            plot_sensitivity(groups, os.path.join(out, fname),
                             f"φe = {SENS_PHI:g}°, σ3 = {SENS_SIGMA3:g} Pa: {title}", label, failed)


def plot_judged(res, path):
    """The judged points (engines.studies.biaxial_judged.analyse_judged's record): φ*, peak q at
    σ3 = 200 Pa and E50 at 200 Pa against φe, every packing and the mean with its 95 % interval,
    beside the paper's values."""
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    panels = ((lambda r: r["phi_star_deg"], "φ* [°]", PAPER["phi_star_deg"], "φ* against φe (Fig. 12)"),
              (lambda r: r["per_sigma3"]["200"]["peak_pa"], "peak deviator q_f at σ3 = 200 Pa [Pa]",
               PAPER["peak_deviator_200_pa"], "peak q at σ3 = 200 Pa (Fig. 9–11)"),
              (lambda r: r["per_sigma3"]["200"]["e50_pa"], "E50 at σ3 = 200 Pa [Pa]", {}, "E50 at σ3 = 200 Pa (Fig. 16)"))
    n = sorted({r["phi_star_deg"]["n"] for r in res["rows"]})
    for ax, (get, ylabel, paper, title) in zip(axes, panels):
        for k, r in enumerate(res["rows"]):
            st, p = get(r), r["phi_e_deg"]
            ax.plot(np.full(len(st["values"]), p - 0.4), st["values"], "o", color="0.6", ms=4,
                    label="one packing" if k == 0 else None)
            if st["low"] is not None:
                ax.errorbar([p], [st["mean"]], yerr=[[st["mean"] - st["low"]], [st["high"] - st["mean"]]], fmt="s",
                            color="C3", capsize=4, label="model: mean, 95 % interval" if k == 0 else None)
        if paper:
            ax.plot(list(paper), list(paper.values()), "k*", ms=11, label="paper")
        ax.set(xlabel="inter-element friction angle φe [°]", ylabel=ylabel, xlim=(0, 20), ylim=(0, None), title=title)
        ax.grid(alpha=0.3)
    axes[2].text(0.98, 0.02, "the paper: figures only", transform=axes[2].transAxes, ha="right", fontsize=8, color="0.4")
    fig.suptitle(f"Judged points on the default reading: 1000 discs, σ3 = 100, 200, 300 Pa, "
                 f"n = {'/'.join(map(str, n))} packings per φe", fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 1))  # one key for the three panels, under them: it covers no point
    fig.legend(*axes[1].get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8.5, frameon=False)
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)
