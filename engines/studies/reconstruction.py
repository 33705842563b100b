"""The reconstruction of the seismic study (docs/LIQUEFACTION.md, "Reconstruction"): the unknowns
the paper leaves that could make a failing trend hold, each varied on ensembles of the cases it
touches, the other cases taken from the study's own ensembles (make liquefaction).

A variant scales fields of the case presets (``scale`` {table: {field: factor}}, applied to each
of its cases' own values; ``on`` another variant whose runs stand for the cases it does not run) or, for the packing's unknowns, a change to the deposition of the seismic box (``deposit``: the
[packing] fields of a fresh deposit of liquefaction_case1, on which all its cases then run).
``judged(base, runs)``: the trends (engines.studies.liquefaction) on each variant's cases.
The runs: engines.run.reconstruction; the table: postproc.liquefaction.reconstruction. No YADE.
"""
import os
from dataclasses import dataclass, field

import numpy as np

from engines.studies.ensemble import CONFIDENCE
from engines.studies.liquefaction import trends

STARTS = 8  # starts per case, as the study's ensembles (make liquefaction)
WET_CASES = (1, 3, 4, 6)  # the saturated cases of the failing trends
ALL_CASES = tuple(range(1, 8))
ENSEMBLE = "ensemble"  # a case job's ensemble folder, inside the job's own


@dataclass(frozen=True)
class Variant:
    """One unknown at one value: what it is, why it is a candidate, the cases it runs, the changes."""

    unknown: str
    reason: str
    cases: tuple
    scale: dict = field(default_factory=dict)
    deposit: dict = field(default_factory=dict)
    on: str = None  # another variant whose cases this one's trends take for the cases it does not run


def _permeability(factor):
    return Variant(
        f"case 3's k1, k2 x{factor:g}",
        "§6.2 says case 3's permeability was made considerably larger (gravel), Table 5 prints case 1's",
        (3,), {"water": {"k1": factor, "k2": factor}})


def _water_modulus(factor):
    return Variant(
        f"E_w x{factor:g}",
        "the water's modulus per unit thickness (Table 4) sets U for a given compaction and the water's "
        "resistance to it (not the drainage time: storage W/E_w over conductance k A_ij/E_w)",
        WET_CASES, {"water": {"E_w": factor}})


VARIANTS = {
    "k_x3": _permeability(3),
    "k_x10": _permeability(10),
    "k_x30": _permeability(30),
    "E_w_x3": _water_modulus(3),
    "E_w_x10": _water_modulus(10),
    "E_w_x10_k_x10": Variant(
        "E_w x10 and case 3's k1, k2 x10",
        "the two that make the most trends hold, together (case 3 run with both, cases 1, 4, 6 E_w_x10's)",
        (3,), {"water": {"E_w": 10, "k1": 10, "k2": 10}}, on="E_w_x10"),
    "box_wide": Variant(
        "box 1.5x wider, same 192 discs (37 bottom wall discs)",
        "the box (Fig. 26/28) is not in the OCR: its width is our reading; a wider box makes a "
        "shallower bed (a shorter path to the surface)",
        ALL_CASES, deposit={"n_bottom": 37}),
    "box_narrow": Variant(
        "box 0.65x as wide, same 192 discs (17 bottom, 16 side wall discs)",
        "as box_wide, the other way: a deeper bed with shorter paths to the drained sides",
        ALL_CASES, deposit={"n_bottom": 17, "n_side": 16}),
    "packing_frictionless": Variant(
        "a denser packing: deposited and cut without tangential springs (settle_ks = 0), then settled "
        "under its dense top",
        "the paper gives no porosity; ours (0.477 in the window) compacts under the input whatever "
        "the spring, and a denser bed compacts less",
        ALL_CASES, deposit={"settle_ks": 0.0}),
}


def packing_job(name):
    return f"{name}_packing"


def case_job(name, case):
    return f"{name}_case{case}"


def packing_path(runs, name):
    """The deposit of packing variant ``name`` in the study's sweep folder ``runs``."""
    return os.path.join(runs, packing_job(name), "packing.csv")


def ensemble_path(runs, name, case):
    """The ensemble of ``case`` of variant ``name`` in the study's sweep folder ``runs``."""
    return os.path.join(runs, case_job(name, case), ENSEMBLE)


def variant_cases(base, changed, runs):
    """The cases a variant's trends are evaluated on: ``runs`` {case: [start summaries]} of the
    ``changed`` cases that completed, the baseline's ``base`` for the cases the variant does not
    change; a changed case not in ``runs`` is left out (never taken from the baseline)."""
    return {**{k: r for k, r in base.items() if k not in changed}, **runs}


def judged(base, runs, packings=None):
    """The trends on each variant of VARIANTS: its cases' ensembles ``runs`` {variant: {case:
    [start summaries], or None where the case has not completed}} with the study's own ``base``
    {case: [start summaries]} (those of the variant it is ``on``) for the cases it does not change;
    a case it changes that has not completed drops the trends that need it. ``packings``: {variant:
    facts of its deposit}. Returns {confidence, reference: the trends on ``base``, variants}."""
    doc = {"confidence": CONFIDENCE, "reference": trends(base), "variants": {}}
    evaluated = {}  # the cases each variant's trends were evaluated on, for the variants built on it
    for name, v in VARIANTS.items():
        got = runs.get(name, {})
        done = [k for k in v.cases if got.get(k) is not None]
        if not done or (v.on and v.on not in evaluated):
            continue
        cases = variant_cases(evaluated[v.on] if v.on else base, v.cases, {k: got[k] for k in done})
        evaluated[name] = cases
        changed = sorted(set(done) | set(doc["variants"][v.on]["changed"] if v.on else ()))  # against the presets
        doc["variants"][name] = {
            "unknown": v.unknown, "reason": v.reason, "cases": list(v.cases), "done": done, "on": v.on,
            "changed": changed,
            "starts": {k: len(cases[k]) for k in done}, "packing": (packings or {}).get(name),
            "case_means": {k: {key: float(np.mean([r[key] for r in cases[k]]))
                               for key in ("porosity_initial", "porosity_change", "U_low_mean") if key in cases[k][0]}
                           for k in done},
            "trends": trends(cases)}
    return doc
