"""The study's measures (postproc/liquefaction.py) on signals with known answers."""
import numpy as np
import pytest

from postproc.liquefaction import compaction_correlation, dominant_period, end_mean, trends

t = np.arange(0, 0.18, 1e-4)


def test_dominant_period_of_a_ramped_cosine_is_its_period():
    y = 40 * t / 0.18 + 10 * np.cos(2 * np.pi * 50 * t) + 3 * np.cos(2 * np.pi * 170 * t)
    assert dominant_period(t, y) == pytest.approx(0.02, rel=0.02)


def test_end_mean_averages_the_last_period():
    y = 5.0 + np.sin(2 * np.pi * 50 * t)
    assert end_mean(t, y) == pytest.approx(5.0, abs=0.01)


def test_compaction_correlation():
    n = 0.47 - 0.02 * (1 - np.exp(-t / 0.05))
    assert compaction_correlation(n, 2400 * (n[0] - n) / 0.25) == pytest.approx(1.0)  # U from compaction
    assert abs(compaction_correlation(n, 50 * np.sin(2 * np.pi * 50 * t))) < 0.2  # U oscillating alone


def _case(mean, std, dn):
    return {"U_low_mean": mean, "U_low_abs_mean": abs(mean), "U_low_std": std, "porosity_change": dn,
            "U_blocks": {"U_block1": {"min": -std}}, "U_low_vs_compaction_corr": 0.0,
            "U_low_rise_first_period": mean / 2, "U_low_end": mean, "U_low_dominant_period": 0.02}


def test_trends_judge_the_elastic_and_drained_rows():
    rows = {r["trend"][:20]: r for r in trends({1: _case(140, 40, -0.02), 2: _case(0, 0, -0.05),
                                                3: _case(10, 20, -0.03), 4: _case(5, 30, -0.002),
                                                5: _case(0, 0, -0.003)},
                                               {"case3": {"1": {"tau": [0.476]}}})}
    assert rows["elastic springs: U o"]["holds"]
    assert rows["drained sides with h"]["holds"] and "476 ms" in rows["drained sides with h"]["ours"]
    rows = {r["trend"][:20]: r for r in trends({1: _case(140, 40, -0.02), 3: _case(120, 30, -0.03),
                                                4: _case(100, 40, -0.02)})}
    assert not rows["elastic springs: U o"]["holds"] and not rows["drained sides with h"]["holds"]
