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
import argparse
import json
import os
import sys
from dataclasses import dataclass

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np  # noqa: E402

from engines.particle_potential import (  # noqa: E402
    Kind, Model, Potential, SolverSettings, Step, TONNE_FORCE, pa_to_tf_m2, pair_stiffness_at_well,
    run_path, tf_m2_to_pa)

SPACING = 1.0      # m
HALF_COLUMNS = 3   # columns x = 0..3, axis at x = 3
ROWS = 12          # rows z = 0..12
HEIGHT = ROWS * SPACING
DL = 1.8           # m, influence radius of §3


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
            search_max=80.0, paper_literal=False, settings=SolverSettings()):
    """All §4 runs for one parameter set. Loads in t/m², displacements in m, A_m in tf·m/m.

    Returns a dict of `Path`s and specimens: 'load' (top load to load_max), 'compression' and
    'tension' (load control until yield or ±search_max), 'displacement' (forced to disp_max).
    """
    pot = Potential(A_m=Am * TONNE_FORCE, alpha=alpha, C=C, DL=DL)
    loaded = build_specimen(pot, moving_top=False, paper_literal=paper_literal)
    pushed = build_specimen(pot, moving_top=True, paper_literal=paper_literal)
    return {
        "loaded": loaded,
        "pushed": pushed,
        "load": load_path(loaded, tf_m2_to_pa(ramp(load_max, dload)), settings),
        "compression": load_path(loaded, tf_m2_to_pa(ramp(search_max, dload)), settings),
        "tension": load_path(loaded, tf_m2_to_pa(ramp(-search_max, dload)), settings),
        "displacement": displacement_path(pushed, ramp(disp_max, ddisp), settings),
    }


def summarise(runs, alpha, C, Am, load_max, paper_literal):
    """Numbers of the run in t/m² (JSON-ready)."""
    comp, load = runs["compression"], runs["load"]
    e_first = pa_to_tf_m2(comp.stress[0] / comp.strain[0])
    peak = comp.peak()
    yielded = comp.yielded
    k = pair_stiffness_at_well(SPACING, runs["loaded"].model.potential)
    spec = runs["loaded"]
    final = load.increments[-1]
    applied = -final.forces[spec.top, 1].sum()
    tension_peak = runs["tension"].peak()
    disp = runs["displacement"]
    return {
        "A_m_tf_m": Am, "alpha": alpha, "C": C, "DL_m": DL, "paper_literal": paper_literal,
        "E_apparent_t_m2": float(e_first),
        "E_secant_at_load_max_t_m2": float(pa_to_tf_m2(load.stress[-1] / load.strain[-1])),
        "E_lattice_plane_stress_t_m2": float(pa_to_tf_m2(1.5 * k)),
        "E_lattice_uniaxial_strain_t_m2": float(pa_to_tf_m2(2.0 * k)),
        "pair_stiffness_t_per_m": float(k / TONNE_FORCE),
        "yield_stress_t_m2": float(pa_to_tf_m2(peak[1])) if yielded else None,
        "yield_strain": peak[0] if yielded else None,
        "compression_reason": comp.reason,
        "compression_max_stress_t_m2": float(pa_to_tf_m2(peak[1])),
        "tension_yield_stress_t_m2": float(pa_to_tf_m2(tension_peak[1])) if runs["tension"].yielded else None,
        "tension_yield_strain": tension_peak[0] if runs["tension"].yielded else None,
        "tension_reason": runs["tension"].reason,
        "load_max_t_m2": load_max,
        "strain_at_load_max": float(load.strain[-1]),
        "bottom_reaction_at_load_max_t_m2": float(pa_to_tf_m2(bottom_stress(spec, final))),
        "reaction_balance_error_t": float((final.reactions[:, 1].sum() - applied) / TONNE_FORCE),
        "reaction_balance_relative": float(abs(final.reactions[:, 1].sum() - applied) / applied),
        "forced_displacement_m": float(top_settlement(runs["pushed"], disp.increments[-1].positions)),
        "top_reaction_at_disp_max_t_m2": float(pa_to_tf_m2(disp.stress[-1])),
        "bottom_reaction_at_disp_max_t_m2": float(pa_to_tf_m2(bottom_stress(runs["pushed"], disp.increments[-1]))),
        "displacement_reason": disp.reason,
    }
