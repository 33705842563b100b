"""Saito & Fujiwara §4: uniaxial tests on a particle-potential specimen (seed 002, issue 5).

    /usr/bin/python3 yade_scripts/particle_potential.py --alpha 1 --out out/pp-alpha1

Layout (half model by symmetry; the paper's Fig. 5 numbering in brackets): square lattice,
spacing 1 m, the full specimen spans x = 0..6 m, z = 0..12 m (7 columns × 13 rows); we keep its
left half, columns x = 0, 1, 2, 3 with the symmetry axis at x = 3:
  * rows z = 1..12 of columns x = 0, 1, 2: 36 free particles [1–36];
  * rows z = 1..12 of the axis x = 3: 12 vertical-only particles [37–48];
  * row z = 0: 4 fixed boundary points [49–52].
For forced top displacement the top row z = 12 (three free particles and the axis particle)
becomes 4 moving boundary points, as the paper does with particles 1, 2, 3 and 37.

Symmetry: the half model carries half of the full energy, so the vertical pairs on the axis
(shared by both halves) count 1/2, and a top load σ is applied as σ times the tributary width
(0.5 m at the free edge x = 0 and for our half of the axis column, 1 m elsewhere: 3 m in all).
`--paper-literal` instead counts axis pairs fully and loads every top particle with σ × 1 m
(what eq 9–10's remark "reactions equal stresses for unit spacing" suggests the paper did).

Stress is the applied top stress (load control) or the top reaction over the 3 m half width
(displacement control), positive in compression; strain is the tributary-weighted mean top
settlement over the 12 m height. Outputs are in t/m² as in the paper (SI inside).
"""
import json
import os
import sys
from dataclasses import dataclass, replace

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from engines.particle_potential import (  # noqa: E402
    Kind, Model, Potential, SolverSettings, Step, TONNE_FORCE, find_pairs, pa_to_tf_m2,
    pair_stiffness_at_well, run_path, tf_m2_to_pa)
from engines.preflight import ArgumentParser, number, output_dir  # noqa: E402

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


def build_specimen(potential, moving_top, paper_literal=False):
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
    top_width = np.ones(len(top)) if paper_literal else np.where(edge, 0.5, 1.0) * SPACING
    model = Model(reference, kinds, potential, on_axis & (not paper_literal))
    return Specimen(model, top, bottom, top_width, float(top_width.sum()))


def top_settlement(spec, positions):
    """Tributary-weighted mean downward displacement of the top row [m]."""
    dz = positions[spec.top, 1] - spec.model.reference[spec.top, 1]
    return -float(np.sum(spec.top_width * dz) / spec.half_width)


def bottom_stress(spec, inc):
    """Mean vertical reaction of the bottom row over the loaded width [Pa], compression > 0."""
    return float(inc.reactions[spec.bottom, 1].sum() / spec.half_width)


def load_path(spec, stresses_pa, settings):
    """Top load control: stresses [Pa] (compression > 0) applied in turn."""
    ref = spec.model.reference

    def step(sigma):
        forces = np.zeros_like(ref)
        forces[spec.top, 1] = -sigma * spec.top_width
        return Step(forces, ref)

    def measure(inc):
        return top_settlement(spec, inc.positions) / HEIGHT, -inc.forces[spec.top, 1].sum() / spec.half_width

    return run_path(spec.model, [step(s) for s in stresses_pa], settings, measure)


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


def run_all(alpha, C=2.0, Am=1.0, load_max=22.0, dload=0.25, disp_max=0.9, ddisp=0.01,
            search_max=SEARCH_MAX, paper_literal=False, settings=SolverSettings()):
    """All §4 runs for one parameter set. Loads in t/m², displacements in m, A_m in tf·m/m.

    Returns a dict: the specimens 'loaded' and 'pushed', and the `Path`s 'load' (top load to
    load_max), 'compression' and 'tension' (load control until yield, at most ±search_max),
    'collapse' (compression continued through the first snaps with a 2× larger trust box until no
    equilibrium is found: post-yield, for comparison with the paper's 26 t/m² only; a larger box
    lets the minimiser's first step leave the current well, so this number is box-dependent) and 'displacement' (forced top
    displacement to disp_max).
    """
    pot = Potential(A_m=Am * TONNE_FORCE, alpha=alpha, C=C, DL=DL)
    loaded = build_specimen(pot, moving_top=False, paper_literal=paper_literal)
    pushed = build_specimen(pot, moving_top=True, paper_literal=paper_literal)
    wide = replace(settings, max_step=2 * settings.max_step)
    return {
        "loaded": loaded,
        "pushed": pushed,
        "load": load_path(loaded, tf_m2_to_pa(ramp(load_max, dload)), settings),
        "compression": load_path(loaded, tf_m2_to_pa(ramp(search_max, dload)), settings),
        "tension": load_path(loaded, tf_m2_to_pa(ramp(-search_max, dload)), settings),
        "collapse": load_path(loaded, tf_m2_to_pa(ramp(search_max, dload)), wide),
        "displacement": displacement_path(pushed, ramp(disp_max, ddisp), settings),
    }


def _yield_point(path):
    """(stress t/m², strain) at yield, or (None, None) when the path did not yield."""
    if not path.yielded:
        return None, None
    strain, stress = path.peak()
    return float(pa_to_tf_m2(stress)), strain


def summarise(runs, params):
    """JSON-ready numbers in t/m² (stresses), t per m depth (forces) and - (strains)."""
    comp, load, disp = runs["compression"], runs["load"], runs["displacement"]
    loaded, pushed = runs["loaded"], runs["pushed"]
    k = pair_stiffness_at_well(SPACING, loaded.model.potential)
    yield_stress, yield_strain = _yield_point(comp)
    tension_stress, tension_strain = _yield_point(runs["tension"])
    collapse_stress, collapse_strain = _yield_point(runs["collapse"])
    iload, idisp = load.last_stable(), disp.last_stable()
    final = load.increments[iload]
    applied = -final.forces[loaded.top, 1].sum()
    return {
        **params,
        "E_apparent_t_m2": float(pa_to_tf_m2(comp.stress[0] / comp.strain[0])),
        "E_apparent_displacement_control_t_m2": float(pa_to_tf_m2(disp.stress[0] / disp.strain[0])),
        "E_secant_at_load_t_m2": float(pa_to_tf_m2(load.stress[iload] / load.strain[iload])),
        "pair_stiffness_t_per_m": float(k / TONNE_FORCE),
        "E_lattice_plane_stress_t_m2": float(pa_to_tf_m2(1.5 * k)),
        "E_lattice_uniaxial_strain_t_m2": float(pa_to_tf_m2(2.0 * k)),
        "yield_stress_t_m2": yield_stress,
        "yield_strain": yield_strain,
        "yield_reason": comp.reason,
        "tension_yield_stress_t_m2": tension_stress,
        "tension_yield_strain": tension_strain,
        "collapse_stress_t_m2": collapse_stress,
        "collapse_strain": collapse_strain,
        "load_reached_t_m2": float(pa_to_tf_m2(load.stress[iload])),
        "strain_at_load": float(load.strain[iload]),
        "bottom_reaction_at_load_t_m2": float(pa_to_tf_m2(bottom_stress(loaded, final))),
        "reaction_balance_error_t": float((final.reactions[:, 1].sum() - applied) / TONNE_FORCE),
        "reaction_balance_relative": float(abs(final.reactions[:, 1].sum() - applied) / applied),
        "displacement_reached_m": float(top_settlement(pushed, disp.increments[idisp].positions)),
        "top_reaction_at_displacement_t_m2": float(pa_to_tf_m2(disp.stress[idisp])),
        "bottom_reaction_at_displacement_t_m2": float(pa_to_tf_m2(bottom_stress(pushed, disp.increments[idisp]))),
        "displacement_reason": disp.reason,
    }


def plot_stress_strain(runs, summary, path):
    """Fig. 8: stress–strain curves (compression and tension by load, compression by displacement)."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for key, label in [("compression", "top load, compression"), ("tension", "top load, tension"),
                       ("collapse", "top load, through snaps (post-yield)"),
                       ("displacement", "forced top displacement")]:
        p = runs[key]
        ax.plot(100 * np.r_[0, p.strain], np.r_[0, pa_to_tf_m2(p.stress)], marker=".", ms=2, label=label,
                ls=":" if key == "collapse" else "-")
    if summary["yield_stress_t_m2"] is not None:
        ax.plot(100 * summary["yield_strain"], summary["yield_stress_t_m2"], "rx", ms=10, label="yield")
    eps = np.linspace(-0.1, 0.1, 3)
    ax.plot(100 * eps, summary["E_apparent_t_m2"] * eps, "k--", lw=0.8,
            label=f"E = {summary['E_apparent_t_m2']:.0f} t/m²")
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
    for key, spec_key, label in [("compression", "loaded", "top load"),
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
    ap.add_argument("--alpha", type=positive, required=True, help="potential parameter α [-]")
    ap.add_argument("--C", type=positive, default=2.0, help="potential exponent C [-]")
    ap.add_argument("--Am", type=positive, default=1.0, help="potential amplitude A_m [tf·m per m depth]")
    ap.add_argument("--load-max", type=positive, default=22.0, help="top load of Fig. 6 [t/m²]")
    ap.add_argument("--dload", type=positive, default=0.25, help="load increment [t/m²]")
    ap.add_argument("--disp-max", type=positive, default=0.9, help="forced top displacement of Fig. 7 [m]")
    ap.add_argument("--ddisp", type=positive, default=0.01, help="displacement increment [m]")
    ap.add_argument("--paper-literal", action="store_true",
                    help="full-weight axis pairs and σ × 1 m on every top particle (see module doc)")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory")
    args = ap.parse_args(argv)
    for end, step, name, unit in ((max(args.load_max, SEARCH_MAX), args.dload, "--dload", "t/m²"),
                                  (args.disp_max, args.ddisp, "--ddisp", "m")):
        if end / step > MAX_INCREMENTS:
            ap.error(f"argument {name}: {step:g} {unit} gives {end / step:.0f} increments up to {end:g} {unit} "
                     f"(limit {MAX_INCREMENTS})")
    return args


def main(argv=None):
    args = parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    runs = run_all(args.alpha, C=args.C, Am=args.Am, load_max=args.load_max, dload=args.dload,
                   disp_max=args.disp_max, ddisp=args.ddisp, paper_literal=args.paper_literal)
    params = {"A_m_tf_m": args.Am, "alpha": args.alpha, "C": args.C, "DL_m": DL,
              "spacing_m": SPACING, "height_m": HEIGHT, "half_width_m": runs["loaded"].half_width,
              "dload_t_m2": args.dload, "ddisp_m": args.ddisp, "paper_literal": args.paper_literal,
              "trust_box_m": SolverSettings().max_step}
    summary = summarise(runs, params)
    with open(os.path.join(args.out, "summary.json"), "w") as fh:
        json.dump(summary, fh, indent=2)
    plot_stress_strain(runs, summary, os.path.join(args.out, "fig8_stress_strain.png"))
    plot_top_vs_bottom(runs, os.path.join(args.out, "fig9_top_vs_bottom.png"))
    load, disp = runs["load"], runs["displacement"]
    plot_deformed(runs["loaded"], load.increments[load.last_stable()],
                  f"top load {summary['load_reached_t_m2']:.1f} t/m²", os.path.join(args.out, "fig6_top_load.png"))
    plot_deformed(runs["pushed"], disp.increments[disp.last_stable()],
                  f"forced top displacement {100 * summary['displacement_reached_m']:.0f} cm",
                  os.path.join(args.out, "fig7_forced_displacement.png"))
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
