"""Ensembles: the perturbed starts, the statistics across starts (against their definitions and
a Monte-Carlo coverage), the results' entries and the common time grid (no YADE run)."""
import numpy as np
import pytest

from engines.run import scene as scenes
from engines.studies import ensemble as en
from engines.yade.deposition import scene_packing


def test_perturbed_starts_move_only_the_particles_by_about_the_size():
    pk = scene_packing(scenes.preset("quicksand_case1"))
    assert en.perturbed(pk, 0, 1e-9) is pk
    a, b = en.perturbed(pk, 1, 1e-9), en.perturbed(pk, 2, 1e-9)
    d = a.xz - pk.xz
    assert np.all(d[~pk.mobile] == 0) and 0.3e-9 < np.std(d[pk.mobile]) < 3e-9
    assert not np.allclose(a.xz, b.xz, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(en.perturbed(pk, 1, 1e-9).xz, a.xz)  # reproducible
    c = en.perturbed(pk, 1, 1e-7)  # the same draw, scaled
    np.testing.assert_allclose(c.xz - pk.xz, 100 * d, rtol=1e-6, atol=1e-18)


def test_statistics_of_known_samples():
    """Three starts 1, 2, 6: mean 3, sample std sqrt(7), SE sqrt(7/3), t(0.975, 2) = 4.3027."""
    s = en.statistics([[1.0, 5.0], [2.0, np.nan], [6.0, 7.0]])
    assert s["n"].tolist() == [3, 2]
    assert s["mean"].tolist() == pytest.approx([3.0, 6.0])
    assert s["standard_error"].tolist() == pytest.approx([np.sqrt(7 / 3), 1.0])
    assert s["ci95_high"][0] - s["mean"][0] == pytest.approx(4.302653 * np.sqrt(7 / 3), rel=1e-6)
    assert s["ci95_high"][1] - s["mean"][1] == pytest.approx(12.7062, rel=1e-4)  # t(0.975, 1) SE
    assert s["mean"][0] - s["ci95_low"][0] == pytest.approx(s["ci95_high"][0] - s["mean"][0])
    one = en.statistics([[4.0], [np.nan]])  # one value: a mean, no spread
    assert one["mean"][0] == 4.0 and np.isnan(one["standard_error"][0]) and np.isnan(one["ci95_low"][0])
    assert np.isnan(en.statistics([[np.nan], [np.nan]])["mean"][0])


def test_the_95_percent_interval_covers_the_mean_95_percent_of_the_time():
    rng = np.random.default_rng(7)
    samples = rng.normal(2.0, 3.0, size=(4, 20000))  # 20000 ensembles of 4 starts
    s = en.statistics(samples)
    covered = np.mean((s["ci95_low"] <= 2.0) & (2.0 <= s["ci95_high"]))
    assert abs(covered - 0.95) < 0.006  # 3.5 binomial standard deviations
    assert np.mean(s["standard_error"]) == pytest.approx(3.0 / 2 * 0.9213, rel=0.02)  # E[s] = c4 sigma, n = 4


def test_every_number_of_the_results_is_an_entry():
    """Nested entries by dotted names; None (no heave, a block without pores) counts as no value,
    also where another start has numbers under that name."""
    one = {"peak_block_pressures": {"U_block1": {"U_max_N_per_m": 3, "t_s": 0.1}, "U_block2": None},
           "heave_time_s": None, "porosity_end": 0.4, "note": "text", "flag": True}
    two = {"peak_block_pressures": {"U_block1": {"U_max_N_per_m": 5, "t_s": 0.3}, "U_block2": {"U_max_N_per_m": 1,
                                                                                               "t_s": 0.2}},
           "heave_time_s": 0.01, "porosity_end": 0.6, "note": "text", "flag": False}
    flat = en.flat_results(one)
    assert set(flat) == {"peak_block_pressures.U_block1.U_max_N_per_m", "peak_block_pressures.U_block1.t_s",
                         "peak_block_pressures.U_block2", "heave_time_s", "porosity_end"}
    assert np.isnan(flat["heave_time_s"]) and flat["porosity_end"] == 0.4
    t = np.arange(3.0)
    res = en.ensemble_statistics([{"t": t, "y": t}] * 2, [one, two])["results"]
    assert set(res) == {"peak_block_pressures.U_block1.U_max_N_per_m", "peak_block_pressures.U_block1.t_s",
                        "peak_block_pressures.U_block2.U_max_N_per_m", "peak_block_pressures.U_block2.t_s",
                        "heave_time_s", "porosity_end"}
    assert res["peak_block_pressures.U_block1.U_max_N_per_m"]["mean"] == 4.0
    assert res["heave_time_s"]["n"] == 1 and res["heave_time_s"]["mean"] == 0.01
    assert res["peak_block_pressures.U_block2.t_s"]["values"][1] == 0.2


def test_histories_on_a_common_grid():
    t = np.arange(0, 1.0001, 0.1)
    a = {"t": t, "y": 2 * t}
    b = {"t": t[:-2], "y": 3 * t[:-2]}          # a shorter start: the grid ends with it
    c = {"t": t * 0.95, "y": 4 * t * 0.95}        # other times (another dt): interpolated
    grid, cols = en.on_common_grid([a, b, c])
    np.testing.assert_array_equal(grid, t[:-2])
    np.testing.assert_allclose(cols["y"], [2 * grid, 3 * grid, np.minimum(4 * grid, 4 * 0.95)], rtol=1e-12)
    doc = en.ensemble_statistics([a, b, c], [{"x": 1.0}, {"x": 2.0}, {"x": None}])
    assert doc["results"]["x"]["n"] == 2 and doc["results"]["x"]["mean"] == 1.5
    assert doc["history"]["t"] == grid.tolist()
    assert doc["history"]["columns"]["y"]["mean"] == pytest.approx((9 * grid / 3).tolist())
