"""The reconstruction's verdicts (engines.studies.reconstruction): the trends on each variant's cases."""
import numpy as np
import pytest

from engines.studies.liquefaction import trends
from engines.studies.reconstruction import variant_cases
from tests.studies.test_liquefaction import _ensemble


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


def test_judged_builds_a_variant_on_the_one_it_is_on_and_leaves_out_variants_not_run():
    from engines.studies.reconstruction import judged
    rng = np.random.default_rng(6)
    base = _base(rng)
    e_w = {1: _ensemble(rng, 8, 200, 40, -0.03), 3: _ensemble(rng, 8, 110, 30, -0.035),
           4: _ensemble(rng, 8, 70, 40, -0.01), 6: _ensemble(rng, 8, 100, 30, -0.04)}
    runs = {"E_w_x10": e_w, "E_w_x10_k_x10": {3: _ensemble(rng, 8, 11, 5, -0.035)}, "k_x3": {3: None}}
    doc = judged(base, runs, {"E_w_x10": {"bed_top_mm": 1.0}})
    assert set(doc["variants"]) == {"E_w_x10", "E_w_x10_k_x10"} and doc["reference"] == trends(base)
    both = doc["variants"]["E_w_x10_k_x10"]
    assert both["done"] == [3] and both["changed"] == [1, 3, 4, 6] and both["starts"] == {3: 8}
    assert doc["variants"]["E_w_x10"]["packing"] == {"bed_top_mm": 1.0} and both["packing"] is None
    # its case 1 is E_w_x10's (U about 200), not the baseline's (140)
    assert _verdict(both["trends"], "drained sides")[1] == pytest.approx(11 / 200, rel=0.15)
