"""The reconstruction's table (postproc.liquefaction.reconstruction) on starts of known means."""
import numpy as np
import pytest

from postproc.liquefaction import TRENDS, reconstruction_figure, reconstruction_markdown, trends, variant_cases
from tests.figures import assert_drawn
from tests.postproc.test_liquefaction_study import _ensemble


def _base(rng):
    return {1: _ensemble(rng, 8, 140, 40, -0.03), 2: _ensemble(rng, 8, 0, 1, -0.05),
            3: _ensemble(rng, 8, 110, 30, -0.035), 4: _ensemble(rng, 8, 70, 40, -0.01),
            5: _ensemble(rng, 8, 0, 1, -0.01), 6: _ensemble(rng, 8, 100, 30, -0.04), 7: _ensemble(rng, 8, 0, 1, -0.05)}


def _verdict(rows, start):
    (row,) = [r for r in rows if r["trend"].startswith(start)]
    return row["verdict"], row["conditions"][0]["estimate"]


def test_a_variant_changes_only_its_cases_and_its_trends():
    """Case 3 drained 10x better: the drained row turns from fails to holds, the rows without
    case 3 are the baseline's to the last digit."""
    rng = np.random.default_rng(3)
    base = _base(rng)
    ref = trends(base)
    assert _verdict(ref, "drained sides")[0] == "fails"
    rows = trends(variant_cases(base, (3,), {3: _ensemble(rng, 8, 11, 5, -0.035)}))
    verdict, est = _verdict(rows, "drained sides")
    assert verdict == "holds" and est == pytest.approx(11 / 140, rel=0.15)
    same = [r["trend"] for r in ref if 3 not in r["cases"]]
    assert same and all(r in rows for r in ref if r["trend"] in same)


def test_a_changed_case_not_yet_run_is_never_taken_from_the_baseline():
    rng = np.random.default_rng(4)
    base = _base(rng)
    cases = variant_cases(base, (1, 3, 4, 6), {1: _ensemble(rng, 8, 140, 40, -0.01)})
    assert set(cases) == {1, 2, 5, 7} and cases[2] is base[2]
    need = {tuple(r["cases"]) for r in trends(cases)}
    assert need == {(1, 2), (1,)}  # every row with case 3, 4 or 6 is left out
    assert _verdict(trends(cases), "dry settles more than saturated-undrained (cosine")[1] == pytest.approx(5, rel=0.1)


def test_the_table_and_figure_show_each_variant_against_the_presets(tmp_path):
    rng = np.random.default_rng(5)
    base = _base(rng)
    doc = {"reference": trends(base), "variants": {"k_x10": {
        "unknown": "k x10", "reason": "r", "cases": [3], "done": [3], "changed": [3], "starts": {3: 8}, "packing": None,
        "case_means": {3: {"porosity_initial": 0.47, "porosity_change": -0.03, "U_low_mean": 11.0}},
        "trends": trends(variant_cases(base, (3,), {3: _ensemble(rng, 8, 11, 5, -0.035)}))}}}
    table = reconstruction_markdown(doc).splitlines()
    ref, var = table[2], table[3]  # columns: variant, T1 ... (T3: the drained sides)
    assert ref.startswith("| the presets") and var.startswith("| k_x10 |")
    assert ref.split("|")[4].strip().endswith("✗ **fails**") and var.split("|")[4].strip().endswith("✓ **holds**")
    assert len(ref.split("|")) == len(var.split("|")) == 2 + len(TRENDS) + 1
    fig = reconstruction_figure(doc)
    fig.savefig(tmp_path / "r.png")
    assert assert_drawn(str(tmp_path / "r.png")) is None
