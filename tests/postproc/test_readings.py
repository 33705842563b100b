"""The quick-sand reading's record (postproc.readings) from an ensemble's files."""
import json

import numpy as np
import pytest

from postproc.readings import quick_condition, quicksand_ru, weight_carried


def _stats(mean, lo, hi):
    return {"n": 8, "mean": mean, "ci95_low": lo, "ci95_high": hi, "standard_error": 0.1, "values": []}


def _snapshot(push):
    """A particle on a wall disc pushed up by ``push`` [N/m]; rho 2000, density factor 1."""
    return {"t": 0.0, "xz": np.array([[0.0, 1e-3], [0.0, 0.0]]), "r": np.array([5e-4, 5e-4]), "group": np.array([0, 1]),
            "density_factor": np.ones(2), "pairs": np.array([[0, 1]]), "f_n": np.array([push]), "f_s": np.zeros(1)}


def test_weight_carried_is_the_walls_push_over_the_buoyant_weight():
    weight = (2000.0 - 1000.0) * 10.0 * np.pi * 25e-8
    assert weight_carried(_snapshot(0.5 * weight), 2000.0, 1000.0, 10.0) == pytest.approx(0.5)


@pytest.mark.parametrize("ru, holds", [((1.0, 0.9, 1.1), True), ((3.7, 3.5, 3.9), False), ((1.0, 0.7, 1.3), False)])
def test_the_record_says_whether_the_interval_lies_within_0_8_to_1_2(tmp_path, ru, holds):
    (tmp_path / "start_0").mkdir()
    json.dump({"scene": "qs", "n_starts": 8, "perturbation_m": 1e-8, "interval": "95 %", "seeds": [0],
               "results": {"bands.band1.ru_at_heave": _stats(*ru), "bands.band1.ru_max": _stats(4.0, 3.8, 4.2),
                           "heave_time_s": _stats(0.01, 0.009, 0.011)}}, open(tmp_path / "ensemble.json", "w"))
    json.dump({"band_sigma_v0_Pa": [50.0], "band_overburden_Pa": [100.0], "band_bounds_m": [[0.0, 1e-3]],
               "parameters": {"material": {"rho": 2000.0, "rho_w": 1000.0, "g": 10.0}, "contact": {"mu": 0.0}},
               "provenance": {"git_commit": "abc", "git_dirty": False}}, open(tmp_path / "start_0" / "summary.json", "w"))
    np.savez(tmp_path / "start_0" / "snapshot_000.00ms.npz", **_snapshot(0.01))
    (tmp_path / "start_0" / "history.csv").write_text("t,sv_band1,ru_band1\n0,50,0\n0.001,6,0.9\n0.002,4,1.1\n")
    rec = quicksand_ru(str(tmp_path))
    assert rec["holds"] is holds and rec["band1"]["ru_at_heave"]["mean"] == ru[0]
    assert rec["band1"]["U_over_overburden_at_heave"] == pytest.approx(ru[0] * 0.5)
    quick = rec["band1"]["quick_condition"]
    assert (quick["t_s"]["n"], quick["t_s"]["mean"], quick["ru"]["mean"]) == (1, 0.002, 1.1)
    assert quick["U_over_overburden"] == pytest.approx(1.1 * 0.5) and rec["mu"] == 0.0


def test_the_quick_condition_is_the_first_row_below_a_tenth_of_the_start():
    history = {"t": np.array([0.0, 1.0, 2.0, 3.0]), "sv_band1": np.array([50.0, 5.5, 4.9, 0.0]),
               "ru_band1": np.array([0.0, 0.8, 0.95, 1.3]), "sv_band2": np.array([50.0, 40.0, 30.0, 20.0]),
               "ru_band2": np.zeros(4)}
    assert quick_condition(history) == (2.0, 0.95)
    assert quick_condition(history, fraction=0.2) == (1.0, 0.8)
    assert all(np.isnan(quick_condition(history, band=2)))
