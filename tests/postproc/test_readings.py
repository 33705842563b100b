"""The quick-sand reading's record (postproc.readings) from an ensemble's files."""
import json

import numpy as np
import pytest

from postproc.readings import quicksand_ru, weight_carried


def _stats(mean, lo, hi):
    return {"n": 8, "mean": mean, "ci95_low": lo, "ci95_high": hi, "standard_error": 0.1, "values": []}


def _snapshot(push):
    """A particle on a wall disc pushed up by ``push`` [N/m]; rho 2000, density factor 1."""
    return {"t": 0.0, "xz": np.array([[0.0, 1e-3], [0.0, 0.0]]), "r": np.array([5e-4, 5e-4]), "group": np.array([0, 1]),
            "density_factor": np.ones(2), "pairs": np.array([[0, 1]]), "f_n": np.array([push]), "f_s": np.zeros(1)}


def test_weight_carried_is_the_walls_push_over_the_buoyant_weight():
    weight = (2000.0 - 1000.0) * 10.0 * np.pi * 25e-8
    assert weight_carried(_snapshot(0.5 * weight), 2000.0, 1000.0, 10.0) == pytest.approx(0.5)


def _ensemble(tmp_path, ru, surface=True):
    """An ensemble folder of one start whose statistics give r_u = ``ru`` (mean, low, high) at the onset."""
    (tmp_path / "start_0").mkdir()
    results = {"bands.band1.ru_at_quick": _stats(*ru), "bands.band1.t_quick_s": _stats(0.001, 0.0009, 0.0011),
               "bands.band1.ru_max": _stats(4.0, 3.8, 4.2),
               "peak_block_pressures.U_block1.U_max_N_per_m": _stats(230.0, 220.0, 240.0)}
    if surface:
        results.update({"bands.band1.ru_at_heave": _stats(2.0, 1.9, 2.1), "heave_time_s": _stats(0.01, 0.009, 0.011)})
    json.dump({"scene": "qs", "n_starts": 8, "perturbation_m": 1e-8, "interval": "95 %", "seeds": [0],
               "results": results}, open(tmp_path / "ensemble.json", "w"))
    json.dump({"band_sigma_v0_Pa": [50.0], "band_overburden_Pa": [100.0], "band_bounds_m": [[0.0, 1e-3]],
               "results": {"heave_rise_m": 4.5e-4},
               "parameters": {"material": {"rho": 2000.0, "rho_w": 1000.0, "g": 10.0}, "contact": {"mu": 0.0},
                              "water": {"E_w": 240.0}},
               "provenance": {"git_commit": "abc", "git_dirty": False}}, open(tmp_path / "start_0" / "summary.json", "w"))
    np.savez(tmp_path / "start_0" / "snapshot_000.00ms.npz", **_snapshot(0.01))


@pytest.mark.parametrize("ru, holds", [((1.0, 0.9, 1.1), True), ((3.7, 3.5, 3.9), False), ((1.0, 0.7, 1.3), False)])
def test_the_record_says_whether_the_interval_at_the_onset_lies_within_0_8_to_1_2(tmp_path, ru, holds):
    """Judged at the heave's onset (the bottom band's contacts let go), the surface's heave beside it."""
    _ensemble(tmp_path, ru)
    rec = quicksand_ru(str(tmp_path))
    onset, surface = rec["band1"]["heave_onset"], rec["band1"]["surface_heave"]
    assert rec["holds"] is holds and onset["ru"]["mean"] == ru[0] and onset["t_s"]["mean"] == 0.001
    assert onset["U_over_overburden"] == pytest.approx(ru[0] * 0.5) and rec["mu"] == 0.0
    assert surface["ru"]["mean"] == 2.0 and surface["U_over_overburden"] == pytest.approx(1.0)
    assert surface["t_s"]["mean"] == 0.01 and "0.00045 m" in surface["definition"]
    assert rec["block1_U_max_N_per_m"]["mean"] == 230.0 and rec["E_w_N_per_m"] == 240.0
    assert rec["weight_carried_at_start"] == pytest.approx(0.01 / ((2000.0 - 1000.0) * 10.0 * np.pi * 25e-8))


def test_a_run_ended_before_the_surface_heaved_has_no_surface_reading(tmp_path, capsys):
    """The onset is judged; the surface's heave, never reached, is none, not an error."""
    _ensemble(tmp_path, (1.0, 0.9, 1.1), surface=False)
    rec = quicksand_ru(str(tmp_path))
    surface = rec["band1"]["surface_heave"]
    assert rec["holds"] and surface["ru"]["n"] == 0 and surface["ru"]["mean"] is None and surface["U_over_overburden"] is None
    from postproc.readings import main
    main([str(tmp_path), str(tmp_path / "r.json")])
    assert "at the surface's heave (none) r_u none" in capsys.readouterr().out
