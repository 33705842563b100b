"""Saito & Fujiwara §4: uniaxial tests on a particle-potential specimen (seed 002).

    /usr/bin/python3 yade_scripts/particle_potential.py --out out/particle-potential [--alpha 1 2]

Layout (half model by symmetry; the paper's Fig. 5 numbering in brackets): square lattice,
spacing 1 m, the full specimen spans x = 0..6 m, z = 0..12 m (7 columns × 13 rows); we keep its
left half, columns x = 0, 1, 2, 3 with the symmetry axis at x = 3:
  * rows z = 1..12 of columns x = 0, 1, 2: 36 free particles [1–36];
  * rows z = 1..12 of the axis x = 3: 12 vertical-only particles [37–48];
  * row z = 0: 4 fixed boundary points [49–52].
For forced top displacement the top row z = 12 (three free particles and the axis particle)
becomes 4 moving boundary points, as the paper does with particles 1, 2, 3 and 37.

Pairs: every pair within DL counts once with full weight, as eq 6 sums them over the model's
particles; the paper's model *is* the half specimen ("左右の対称性を考慮して、土粒子の配列は、
左半分だけを考えている", §4), so the vertical pairs of the axis column count fully too (a
mirror-symmetric full specimen would share them between its halves and weight them 1/2; the
paper does not, and its E ≈ 300 t/m² is that of the half model as it states it). A top load σ is
applied as σ times the tributary width (0.5 m at the free edge x = 0 and for our half of the axis
column, 1 m elsewhere: 3 m in all).

Yield (§4: "載荷応力 26t/m² (ヒズミにして8.5%) で降伏"): the limit load under top-load control, where
the equilibrium followed from the unloaded state stops existing; found by marching the load and
halving the increment from the last stable state until the yield load moves by < 2 %
(engines.seeds.particle_potential.limit_load), so it depends on neither the increment nor the trust box.

Stress is the applied top stress (load control) or the top reaction over the 3 m half width
(displacement control), positive in compression; strain is the tributary-weighted mean top
settlement over the 12 m height. Outputs are in t/m² as in the paper (SI inside).
"""
import json
import os
import sys
from dataclasses import dataclass

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from engines.run.preflight import ArgumentParser, number, output_dir
from engines.seeds.particle_potential import (
    TONNE_FORCE,
    Kind,
    Model,
    Potential,
    SolverSettings,
    Step,
    find_pairs,
    limit_load,
    pa_to_tf_m2,
    pair_stiffness_at_well,
    run_path,
    tf_m2_to_pa,
)

SPACING = 1.0      # m
HALF_COLUMNS = 3   # columns x = 0..3, axis at x = 3
ROWS = 12          # rows z = 0..12
HEIGHT = ROWS * SPACING
DL = 1.8           # m, influence radius of §3
SEARCH_MAX = 80.0  # t/m², largest load of the yield searches
MAX_INCREMENTS = 100_000  # per path: a smaller increment would run for hours


@dataclass(frozen=True)
class Specimen:
    """The half specimen: its model and the index sets and widths the loading needs.

    Attributes:
        model: the particle model.
        top, bottom: indices of the top row (z = 12) and bottom row (z = 0).
        top_width: (len(top),) width [m] each top particle's load acts on.
        half_width: total loaded width of the half model [m].
    """

    model: Model
    top: np.ndarray
    bottom: np.ndarray
    top_width: np.ndarray
    half_width: float


def build_specimen(potential, moving_top):
    """Half specimen of §4; `moving_top` makes the top row moving boundary points."""
    x, z = np.meshgrid(np.arange(HALF_COLUMNS + 1) * SPACING, np.arange(ROWS + 1) * SPACING)
    reference = np.column_stack([x.ravel(), z.ravel()])
    on_axis = np.isclose(reference[:, 0], HALF_COLUMNS * SPACING)
    top = np.flatnonzero(np.isclose(reference[:, 1], HEIGHT))
    bottom = np.flatnonzero(np.isclose(reference[:, 1], 0.0))
    kinds = np.where(on_axis, Kind.Z_ONLY, Kind.FREE)
    kinds[bottom] = Kind.FIXED
    if moving_top:
        kinds[top] = Kind.MOVING
    edge = on_axis[top] | np.isclose(reference[top, 0], 0.0)
    top_width = np.where(edge, 0.5, 1.0) * SPACING
    model = Model(reference, kinds, potential)
    return Specimen(model, top, bottom, top_width, float(top_width.sum()))


def top_settlement(spec, positions):
    """Tributary-weighted mean downward displacement of the top row [m]."""
    dz = positions[spec.top, 1] - spec.model.reference[spec.top, 1]
    return -float(np.sum(spec.top_width * dz) / spec.half_width)


def bottom_stress(spec, inc):
    """Mean vertical reaction of the bottom row over the loaded width [Pa], compression > 0."""
    return float(inc.reactions[spec.bottom, 1].sum() / spec.half_width)


def top_load(spec):
    """(step_at(σ), measure) of top-load control: σ [Pa] (compression > 0) times the tributary widths."""
    ref = spec.model.reference

    def step_at(sigma):
        forces = np.zeros_like(ref)
        forces[spec.top, 1] = -sigma * spec.top_width
        return Step(forces, ref)

    def measure(inc):
        return top_settlement(spec, inc.positions) / HEIGHT, -inc.forces[spec.top, 1].sum() / spec.half_width

    return step_at, measure


def load_path(spec, stresses_pa, settings):
    """Top load control: stresses [Pa] (compression > 0) applied in turn."""
    step_at, measure = top_load(spec)
    return run_path(spec.model, [step_at(s) for s in stresses_pa], settings, measure)


def yield_search(spec, settings, dload_pa, max_pa, rel_tol=0.02):
    """The converged limit load of top-load control (compression for max_pa > 0, tension < 0)."""
    step_at, measure = top_load(spec)
    return limit_load(spec.model, step_at, measure, settings, np.sign(max_pa) * dload_pa, max_pa, rel_tol)


def displacement_path(spec, settlements, settings):
    """Forced top displacement: settlements [m] (downward > 0) applied in turn."""
    ref = spec.model.reference

    def step(d):
        prescribed = ref.copy()
        prescribed[spec.top, 1] -= d
        return Step(np.zeros_like(ref), prescribed)

    def measure(inc):
        return (top_settlement(spec, inc.positions) / HEIGHT,
                -inc.reactions[spec.top, 1].sum() / spec.half_width)

    return run_path(spec.model, [step(d) for d in settlements], settings, measure)


def ramp(end, increment):
    """end/increment equal steps from increment to end (end may be negative)."""
    n = max(1, int(round(abs(end) / increment)))
    return np.linspace(end / n, end, n)


PAPER = {1.0: {"E_t_m2": 300.0, "yield_stress_t_m2": 26.0, "yield_strain": 0.085},
         2.0: {"E_t_m2": 1200.0, "yield_stress_t_m2": None, "yield_strain": None}}   # §4, Fig. 8


def run_all(alpha, C=2.0, Am=1.0, load_max=22.0, dload=0.25, disp_max=0.9, ddisp=0.01,
            search_max=SEARCH_MAX, settings=SolverSettings()):
    """All §4 runs for one parameter set. Loads in t/m², displacements in m, A_m in tf·m/m.

    Returns a dict: the specimens 'loaded' and 'pushed', the `Path`s 'load' (top load to load_max)
    and 'displacement' (forced top displacement to disp_max), and the `LimitLoad`s 'compression'
    and 'tension' (yield under top-load control, searched up to ±search_max).
    """
    pot = Potential(A_m=Am * TONNE_FORCE, alpha=alpha, C=C, DL=DL)
    loaded = build_specimen(pot, moving_top=False)
    pushed = build_specimen(pot, moving_top=True)
    return {
        "loaded": loaded,
        "pushed": pushed,
        "load": load_path(loaded, tf_m2_to_pa(ramp(load_max, dload)), settings),
        "compression": yield_search(loaded, settings, tf_m2_to_pa(dload), tf_m2_to_pa(search_max)),
        "tension": yield_search(loaded, settings, tf_m2_to_pa(dload), -tf_m2_to_pa(search_max)),
        "displacement": displacement_path(pushed, ramp(disp_max, ddisp), settings),
    }


def _yield_point(limit):
    """(stress t/m², strain) at yield, or (None, None) when none was found."""
    if not limit.found:
        return None, None
    return float(pa_to_tf_m2(limit.load)), limit.strain


def summarise(runs, params):
    """JSON-ready numbers in t/m² (stresses), t per m depth (forces) and - (strains), with the
    paper's values for α = 1, 2 beside ours."""
    comp, load, disp = runs["compression"], runs["load"], runs["displacement"]
    loaded, pushed = runs["loaded"], runs["pushed"]
    k = pair_stiffness_at_well(SPACING, loaded.model.potential)
    yield_stress, yield_strain = _yield_point(comp)
    tension_stress, tension_strain = _yield_point(runs["tension"])
    iload, idisp = load.last_stable(), disp.last_stable()
    final = load.increments[iload]
    applied = -final.forces[loaded.top, 1].sum()
    E = float(pa_to_tf_m2(load.stress[0] / load.strain[0]))
    return {
        **params,
        "E_apparent_t_m2": E,
        "E_apparent_displacement_control_t_m2": float(pa_to_tf_m2(disp.stress[0] / disp.strain[0])),
        "E_secant_at_load_t_m2": float(pa_to_tf_m2(load.stress[iload] / load.strain[iload])),
        "pair_stiffness_t_per_m": float(k / TONNE_FORCE),
        "E_lattice_plane_stress_t_m2": float(pa_to_tf_m2(1.5 * k)),
        "E_lattice_uniaxial_strain_t_m2": float(pa_to_tf_m2(2.0 * k)),
        "yield_stress_t_m2": yield_stress,
        "yield_strain": yield_strain,
        "yield_reason": comp.reason,
        "yield_refinements_t_m2": [[float(pa_to_tf_m2(h)), float(pa_to_tf_m2(y))] for h, y in comp.refinements],
        "tension_yield_stress_t_m2": tension_stress,
        "tension_yield_strain": tension_strain,
        "load_reached_t_m2": float(pa_to_tf_m2(load.stress[iload])),
        "strain_at_load": float(load.strain[iload]),
        "bottom_reaction_at_load_t_m2": float(pa_to_tf_m2(bottom_stress(loaded, final))),
        "reaction_balance_error_t": float((final.reactions[:, 1].sum() - applied) / TONNE_FORCE),
        "reaction_balance_relative": float(abs(final.reactions[:, 1].sum() - applied) / applied),
        "displacement_reached_m": float(top_settlement(pushed, disp.increments[idisp].positions)),
        "top_reaction_at_displacement_t_m2": float(pa_to_tf_m2(disp.stress[idisp])),
        "bottom_reaction_at_displacement_t_m2": float(pa_to_tf_m2(bottom_stress(pushed, disp.increments[idisp]))),
        "displacement_reason": disp.reason,
        "paper": PAPER.get(float(params["alpha"])),
    }


def comparison_table(summaries):
    """Markdown rows: E, yield stress and strain of each run beside the paper's (§4)."""
    def fmt(v, f, unit=""):
        return "—" if v is None else format(v, f) + unit
    rows = ["| α | E ours [t/m²] | E paper | yield ours [t/m²] | yield paper | yield strain ours | yield strain paper |",
            "|---|---|---|---|---|---|---|"]
    for s in summaries:
        p = s["paper"] or {}
        rows.append(f"| {s['alpha']:g} | {s['E_apparent_t_m2']:.0f} | {fmt(p.get('E_t_m2'), '.0f')} | "
                    f"{fmt(s['yield_stress_t_m2'], '.1f')} | {fmt(p.get('yield_stress_t_m2'), '.0f')} | "
                    f"{fmt(s['yield_strain'] and 100 * s['yield_strain'], '.1f', ' %')} | "
                    f"{fmt(p.get('yield_strain') and 100 * p['yield_strain'], '.1f', ' %')} |")
    return "\n".join(rows)


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
    fig.savefig(path, dpi=120)
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
    fig.savefig(path, dpi=120)
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
    fig.savefig(path, dpi=120)
    plt.close(fig)


def parse_args(argv=None):
    """Command line; bad values are refused in one line naming the argument and its limit."""
    ap = ArgumentParser(description=__doc__.split("\n")[0])
    positive = number(lo=0, lo_open=True)
    ap.add_argument("--alpha", type=positive, nargs="+", default=[1.0, 2.0], help="potential parameter(s) α [-]")
    ap.add_argument("--C", type=positive, default=2.0, help="potential exponent C [-]")
    ap.add_argument("--Am", type=positive, default=1.0, help="potential amplitude A_m [tf·m per m depth]")
    ap.add_argument("--load-max", type=positive, default=22.0, help="top load of Fig. 6 [t/m²]")
    ap.add_argument("--dload", type=positive, default=0.25, help="first load increment of the yield search [t/m²]")
    ap.add_argument("--disp-max", type=positive, default=0.9, help="forced top displacement of Fig. 7 [m]")
    ap.add_argument("--ddisp", type=positive, default=0.01, help="displacement increment [m]")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory (one subfolder per α)")
    args = ap.parse_args(argv)
    for end, step, name, unit in ((max(args.load_max, SEARCH_MAX), args.dload, "--dload", "t/m²"),
                                  (args.disp_max, args.ddisp, "--ddisp", "m")):
        if end / step > MAX_INCREMENTS:
            ap.error(f"argument {name}: {step:g} {unit} gives {end / step:.0f} increments up to {end:g} {unit} "
                     f"(limit {MAX_INCREMENTS})")
    return args


def run_one(alpha, args):
    """Every §4 run for one α, its figures and summary.json in out/alpha<α>; returns the summary."""
    out = os.path.join(args.out, f"alpha{alpha:g}")
    os.makedirs(out, exist_ok=True)
    runs = run_all(alpha, C=args.C, Am=args.Am, load_max=args.load_max, dload=args.dload,
                   disp_max=args.disp_max, ddisp=args.ddisp)
    params = {"A_m_tf_m": args.Am, "alpha": alpha, "C": args.C, "DL_m": DL,
              "spacing_m": SPACING, "height_m": HEIGHT, "half_width_m": runs["loaded"].half_width,
              "dload_t_m2": args.dload, "ddisp_m": args.ddisp, "trust_box_m": SolverSettings().max_step}
    summary = summarise(runs, params)
    with open(os.path.join(out, "summary.json"), "w") as fh:
        json.dump(summary, fh, indent=2)
    plot_stress_strain(runs, summary, os.path.join(out, "fig8_stress_strain.png"))
    plot_top_vs_bottom(runs, os.path.join(out, "fig9_top_vs_bottom.png"))
    load, disp = runs["load"], runs["displacement"]
    plot_deformed(runs["loaded"], load.increments[load.last_stable()],
                  f"top load {summary['load_reached_t_m2']:.1f} t/m²", os.path.join(out, "fig6_top_load.png"))
    plot_deformed(runs["pushed"], disp.increments[disp.last_stable()],
                  f"forced top displacement {100 * summary['displacement_reached_m']:.0f} cm",
                  os.path.join(out, "fig7_forced_displacement.png"))
    return summary


def main(argv=None):
    args = parse_args(argv)
    summaries = [run_one(alpha, args) for alpha in args.alpha]
    table = comparison_table(summaries)
    with open(os.path.join(args.out, "comparison.md"), "w") as fh:
        fh.write(table + "\n")
    print(json.dumps(summaries, indent=2))
    print(table)


if __name__ == "__main__":
    main()
