"""The seismic study's verdicts (engines/studies/liquefaction.py): the paper's trends on ensembles of
starts of known means."""
import numpy as np
import pytest

from engines.studies.liquefaction import trends


def _case(mean, std, dn):
    return {"U_low_mean": mean, "U_low_abs_mean": abs(mean), "U_low_std": std, "porosity_change": dn,
            "U_low_rise_first_period": mean / 2, "U_low_end": mean, "U_low_dominant_period": 0.02}


def _ensemble(rng, n, mean, std, dn, spread=0.1):
    """n starts whose U mean and porosity change scatter by ``spread`` (relative) about the given values."""
    return [_case(mean * (1 + spread * rng.standard_normal()), std, dn * (1 + spread * rng.standard_normal()))
            for _ in range(n)]


def _rows(cases, drainage=None):
    return {r["trend"][:20]: r for r in trends(cases, drainage)}


def test_trends_on_ensembles_hold_fail_or_are_undecided_by_their_interval():
    rng = np.random.default_rng(1)
    base = {1: _ensemble(rng, 8, 140, 40, -0.02), 2: _ensemble(rng, 8, 0, 1, -0.05), 4: _ensemble(rng, 8, 5, 30, -0.002),
            5: _ensemble(rng, 8, 0, 1, -0.003)}
    # drained |U| at 7 %, 50 % and 86 % of the undrained: holds (interval below 0.5), undecided, fails
    for u3, verdict in ((10, "holds"), (70, "undecided"), (120, "fails")):
        rows = _rows({**base, 3: _ensemble(rng, 8, u3, 20, -0.03)}, {"case3": {"1": {"tau": [0.476]}}})
        row = rows["drained sides with h"]
        (cond,) = row["conditions"]
        lo, hi = cond["ci95"]
        assert row["verdict"] == cond["verdict"] == verdict, (u3, cond)
        assert lo < cond["estimate"] < hi and cond["holds_if"] == "< 0.5" and "476 ms" in row["note"]
        assert row["starts"] == {1: 8, 3: 8}
    # the elastic rows: both conditions of case 4 hold; the porosity ratio max(0.002, 0.003) / 0.05 too
    assert rows["elastic springs: U o"]["verdict"] == "holds" and len(rows["elastic springs: U o"]["conditions"]) == 2
    assert rows["elastic springs keep"]["verdict"] == "holds"
    assert rows["drained case lies be"]["verdict"] == "holds"  # (0.03 - 0.02) / (0.05 - 0.02) = 1/3
    # dry -0.05 against saturated -0.02: the ratio 2.5 with 10 % scatter straddles the criterion's 2
    assert rows["dry settles more tha"]["conditions"][0]["estimate"] == pytest.approx(2.5, rel=0.15)


def test_trend_interval_covers_the_ratio_of_the_true_means():
    """Starts drawn about known means: the 95 % interval of the drained ratio holds the ratio of the
    true means (90 / 150), and narrows as 1 / sqrt(starts)."""
    rng = np.random.default_rng(2)
    width = {}
    for n in (8, 32):
        cond = _rows({1: _ensemble(rng, n, 150, 40, -0.02, 0.2), 3: _ensemble(rng, n, 90, 20, -0.03, 0.2)}
                     )["drained sides with h"]["conditions"][0]
        lo, hi = cond["ci95"]
        assert lo < 90 / 150 < hi
        width[n] = hi - lo
    assert width[32] == pytest.approx(width[8] / 2, rel=0.35)


def test_one_run_per_case_decides_no_trend():
    rows = _rows({1: _case(140, 40, -0.02), 3: _case(10, 20, -0.03)})
    row = rows["drained sides with h"]
    assert row["verdict"] == "undecided" and np.isnan(row["conditions"][0]["ci95"]).all()
    assert row["conditions"][0]["estimate"] == pytest.approx(10 / 140)
