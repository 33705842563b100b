"""Saito & Fujiwara §4: uniaxial tests on the half specimen of the particle-potential model
(seed 002, engines.seeds.particle_potential.model), by top load and by forced top displacement.

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
(engines.seeds.particle_potential.model.limit_load), so it depends on neither the increment nor the trust box.

Stress is the applied top stress (load control) or the top reaction over the 3 m half width
(displacement control), positive in compression; strain is the tributary-weighted mean top
settlement over the 12 m height. Outputs are in t/m² as in the paper (SI inside).

postproc/particle_potential.py draws the figures; yade_scripts/particle_potential.py is the command line.
"""
import os
from dataclasses import dataclass

import numpy as np

from engines import files
from engines.seeds.particle_potential.model import (
    TONNE_FORCE,
    Kind,
    Model,
    Potential,
    SolverSettings,
    Step,
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


def run_one(alpha, out, *, C, Am, load_max, dload, disp_max, ddisp, figures=None):
    """Every §4 run for one α (the other arguments: run_all's), summary.json in out/alpha<α>, then
    ``figures(runs, summary, that folder)`` (postproc.particle_potential.figures); returns the summary."""
    out = os.path.join(out, f"alpha{alpha:g}")
    os.makedirs(out, exist_ok=True)
    runs = run_all(alpha, C=C, Am=Am, load_max=load_max, dload=dload, disp_max=disp_max, ddisp=ddisp)
    params = {"A_m_tf_m": Am, "alpha": alpha, "C": C, "DL_m": DL,
              "spacing_m": SPACING, "height_m": HEIGHT, "half_width_m": runs["loaded"].half_width,
              "dload_t_m2": dload, "ddisp_m": ddisp, "trust_box_m": SolverSettings().max_step}
    summary = summarise(runs, params)
    files.write_json(os.path.join(out, "summary.json"), summary, indent=2)
    if figures:
        figures(runs, summary, out)
    return summary


def run_study(alphas, out, figures=None, **options):
    """run_one for each of ``alphas`` (``options``: its keywords), then out/comparison.md;
    returns (the summaries, the comparison table)."""
    summaries = [run_one(alpha, out, figures=figures, **options) for alpha in alphas]
    table = comparison_table(summaries)
    files.write_text(os.path.join(out, "comparison.md"), table + "\n")
    return summaries, table
