"""What a run tells its user: history columns the scene produces, with units; a row and a
snapshot at the end; the end lines with the results' units; --quiet; the ETA from measured steps."""
import io
import contextlib
import json
import math

import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing: make test installs it)

from engines.run import history, scene as scenes, talk
from engines.run.runner import Recorder, Run, done_line
from engines.studies.ensemble import ensemble_statistics
from engines.yade.deposition import scene_packing
from postproc.run_files import read_history, snapshot_files

STEPS = 1050  # not a multiple of the history interval (100): the end's row is an extra one
RESULTS = {"peak_block_pressures": {"U_block1": {"U_max_N_per_m": 221.9, "t_s": 0.0281}},
           "heave_rise_m": 4.5e-4, "bed_top_initial_m": 0.0102, "bed_top_max_m": 0.0112, "heave_time_s": None,
           "porosity_last_row": 0.5, "t_last_row_s": 0.06, "porosity_end": 0.508}


def run(name, tmp_path, overrides=None):
    sc = scenes.preset(name, {"output": {"snapshot_times": [0.0]}, **(overrides or {})})
    r = Run(sc, scene_packing(sc), str(tmp_path), STEPS)
    return r, r.go(figures=False)


def test_a_quick_sand_history_has_only_its_columns_a_row_and_a_snapshot_at_the_end(tmp_path):
    r, summary = run("quicksand_case1", tmp_path)
    h = read_history(str(tmp_path / "history.csv"))
    assert list(h) == ["t", "U_block1", "U_block2", "porosity", "kinetic_energy", "water_balance_error", "total_water",
                       "n_pores", "fn_bottom_mean", "bed_top", "remesh_change"] + \
        [f"{q}_band{k}" for q in ("sv", "p", "q", "sxz", "ru") for k in range(1, 9)]  # no base motion, no side springs
    for name, values in h.items():  # a band above the top pore has no pore and no r_u
        assert not np.all(np.isnan(values)) or name.startswith("ru_band"), name
    assert np.isfinite(h["ru_band1"]).all() and h["ru_band1"][0] == 0 and h["sv_band1"][0] > 0
    bands = summary["results"]["bands"]
    assert bands["band1"]["ru_max"] == pytest.approx(np.max(h["ru_band1"]), rel=1e-6) and bands["band1"]["p_ratio_min"] > 0
    assert summary["band_sigma_v0_Pa"] == pytest.approx([h[f"sv_band{k}"][0] for k in range(1, 9)], rel=1e-6)
    assert summary["history_units"]["sv_band1"] == "Pa" and summary["history_units"]["ru_band8"] == "1"
    assert summary["history_units"]["sxz_band1"] == "Pa" and np.all(np.abs(h["sxz_band1"]) <= h["q_band1"] * (1 + 1e-6))
    assert h["t"][-1] == pytest.approx(STEPS * r.scene.numerics.dt, rel=1e-9) and len(h["t"]) == STEPS // 100 + 2
    assert [f.rsplit("/", 1)[-1] for f in snapshot_files(str(tmp_path))] == ["snapshot_000.00ms.npz",
                                                                              "snapshot_001.05ms.npz"]
    with open(tmp_path / "summary.json") as f:
        assert json.load(f)["history_units"] == history.units(list(h)) == summary["history_units"]
    assert summary["history_units"]["U_block1"] == "N/m" and summary["history_units"]["t"] == "s"


def test_a_seismic_history_has_the_base_motion_and_the_side_wall_shifts(tmp_path):
    run_, _ = run("liquefaction_case1", tmp_path)
    h = read_history(str(tmp_path / "history.csv"))
    assert {"base_acc", "base_vel", "base_disp", "side_left_dx", "side_right_dx"} <= set(h)
    assert np.any(h["base_disp"] != 0) and np.all(np.isfinite(h["side_left_dx"]))


def test_every_column_has_a_unit_and_an_unknown_one_is_named():
    assert history.units(["t", "U_block6", "wall_left_water", "n_pores"]) == \
        {"t": "s", "U_block6": "N/m", "wall_left_water": "N/m", "n_pores": "1"}
    with pytest.raises(KeyError, match="'speed'"):
        history.units(["speed"])


def test_the_end_lines_give_the_results_with_units_and_the_figures():
    text = done_line({"steps": 60000, "wall_seconds": 5.0, "us_per_step": 83.0, "water_balance_error": 1e-15,
                      "results": RESULTS}, ["out/pressure_blocks.png"])
    lines = text.splitlines()
    assert lines[0].startswith("done: 60000 steps in 5.0 s")
    assert lines[1:] == ["  U_block1 peak 221.9 N/m at 28.1 ms", "  heave_time none", "  porosity_end 0.508",
                         "  figure out/pressure_blocks.png"]


def test_an_ensemble_says_each_mean_with_its_interval():
    other = {**RESULTS, "porosity_end": 0.51, "heave_time_s": 0.0105}
    stats = ensemble_statistics([{"t": np.arange(2.0), "porosity": np.ones(2)}] * 2, [RESULTS, other])["results"]
    lines = talk.interval_lines(stats)
    assert "porosity_end 0.509 (95 % interval 0.4963 to 0.5217, 2 starts)" in lines
    assert "U_block1 U_max 221.9 N/m (95 % interval 221.9 to 221.9, 2 starts)" in lines
    assert not any(line.startswith("bed_top") for line in lines)


def test_a_sweep_table_lists_each_run_with_its_headline_results():
    table = talk.results_table([("k1=20", RESULTS), ("k1=200", {**RESULTS, "heave_time_s": 0.0105})]).splitlines()
    assert table[0].split("  ")[0] == "run" and "U_block1 U_max [N/m]" in table[0] and "heave_time [ms]" in table[0]
    assert table[1].split()[0] == "k1=20" and "none" in table[1].split() and "10.5" in table[2].split()


def test_quiet_says_nothing_but_verbose_says_more():
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            talk.set_level(quiet=True)
            talk.say("progress")
            talk.set_level(verbose=True)
            talk.say("cache folder", talk.VERBOSE)
            talk.set_level()
            talk.say("cache folder again", talk.VERBOSE)
    finally:
        talk.set_level()
    assert out.getvalue() == "cache folder\n"


def test_the_eta_is_measured_from_the_first_progress_line_on():
    rec = Recorder.__new__(Recorder)
    rec.n_steps, rec.k_ref, rec.t_ref = 10000, None, None
    assert rec.eta(100.0, 10) == ""  # the first line: after a compile of 100 s, no estimate
    assert rec.eta(101.0, 1010) == ", about 9 s left"  # 1000 steps a second from there: 8990 steps
    assert rec.eta(102.0, 2010) == ", about 8 s left"
    assert math.isclose(rec.t_ref, 100.0)


def test_a_sweep_ends_with_the_results_of_the_jobs_that_wrote_a_summary(tmp_path):
    from engines.run.sweep import format_summary
    (tmp_path / "k1=20").mkdir()
    (tmp_path / "k1=20" / "summary.json").write_text(json.dumps({"results": RESULTS}))
    (tmp_path / "other").mkdir()  # a job of another kind: no summary.json
    records = [{"name": "k1=20", "status": "ok", "returncode": 0, "wall_s": 3.0},
               {"name": "other", "status": "ok", "returncode": 0, "wall_s": 1.0}]
    lines = format_summary(records, str(tmp_path)).splitlines()
    assert lines[4] == "the results of the jobs that wrote a summary.json:"
    assert lines[5].startswith("run    U_block1 U_max [N/m]") and lines[6].split()[:2] == ["k1=20", "221.9"]
    assert len(lines) == 7 and "results" not in format_summary(records)


def test_n_bands_sets_the_band_columns_and_their_sigma_v0(tmp_path):
    """[output] n_bands = 3: three equal bands from the bottom wall to the bed's top, each with its columns."""
    r, summary = run("quicksand_case1", tmp_path, {"output": {"snapshot_times": [0.0], "n_bands": 3}})
    h = read_history(str(tmp_path / "history.csv"))
    assert [c for c in h if c.startswith("sv_band")] == ["sv_band1", "sv_band2", "sv_band3"] and "ru_band3" in h
    (z0, _), (_, z1) = summary["band_bounds_m"][0], summary["band_bounds_m"][-1]
    assert len(summary["band_bounds_m"]) == len(summary["band_sigma_v0_Pa"]) == 3 and list(summary["results"]["bands"]) == \
        ["band1", "band2", "band3"]
    assert z1 == pytest.approx(r.cp.packing.bed_top) and z0 < z1


def test_the_results_give_the_porosity_change():
    from postproc.run_files import headline_results
    h = {"t": np.array([0.0, 0.01]), "porosity": np.array([0.47, 0.45]), "bed_top": np.array([0.01, 0.01]),
         "U_block1": np.array([0.0, 5.0])}
    res = headline_results(h, 4.5e-4)
    assert res["porosity_change"] == pytest.approx(-0.02) and "porosity_change -0.02" in talk.result_lines(res)


def test_each_band_says_when_its_contacts_let_go_and_its_r_u_there():
    """t_quick_s: the first row whose sigma'_v < QUICK x the first row's; r_u at it and at the heave's row."""
    from postproc.run_files import QUICK, band_results
    t = np.array([0.0, 1.0, 2.0, 3.0])
    h = {"t": t, "sv_band1": np.array([50.0, 50 * QUICK, 50 * QUICK - 1e-9, 0.0]), "p_band1": np.array([40.0, 20.0, 10.0, 5.0]),
         "ru_band1": np.array([0.0, 0.8, 0.95, 1.3]), "sv_band2": np.array([50.0, 40.0, 30.0, 20.0]),
         "p_band2": np.array([40.0, 30.0, 20.0, 10.0]), "ru_band2": np.array([0.0, 0.1, 0.2, 0.3])}
    b = band_results(h, heave_row=3)
    assert (b["band1"]["t_quick_s"], b["band1"]["ru_at_quick"], b["band1"]["ru_at_heave"]) == (2.0, 0.95, 1.3)
    assert b["band2"]["t_quick_s"] is None and b["band2"]["ru_at_quick"] is None
    assert b["band1"]["p_ratio_min"] == 0.125 and b["band1"]["t_ru_0p9_s"] == 2.0
    dry = {k: v for k, v in h.items() if not k.startswith("ru_")}
    assert band_results(dry)["band1"] == {"p_ratio_min": 0.125, "t_quick_s": 2.0}
