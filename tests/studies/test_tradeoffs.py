"""The speed/accuracy study: its error metrics on statistics, their chaos floors,
the Pareto front and the study's bookkeeping, on synthetic runs (no YADE)."""
import json
import os
import warnings

import numpy as np
import pytest

from engines.run import scene as scenes
from engines.studies import ensemble as ens
from engines.studies import tradeoffs as tr
from tests.figures import assert_drawn


def _run(U, porosity, height, t=None):
    U = np.asarray(U, float)
    t = np.arange(U.shape[1]) * 1e-3 if t is None else t
    return {"t": t, "U": U, "porosity": np.asarray(porosity, float), "height": np.asarray(height, float)}


def _pressure_metric(U, U_ref, t=None, t_ref=None):
    """(measured, floor) of the study's pressure_rms metric (tr.systematic) of block pressure
    histories U (starts, times, blocks) against U_ref; porosity and height change alike in every start."""
    def run(u, tt):
        n = len(u)
        return _run(u, np.tile([0.30, 0.31], (n, 1)), np.tile([1e-2, 0.9e-2], (n, 1)), tt)
    r = tr.systematic(run(U, t), run(U_ref, t_ref), n_boot=2)["pressure_rms"]
    return r["measured"], r["floor"]


def test_pressure_error_is_the_rms_of_the_ensemble_mean_difference():
    rng = np.random.default_rng(1)
    U_ref = rng.normal(100.0, 30.0, (5, 40, 3))
    assert _pressure_metric(U_ref, U_ref)[0] == 0.0
    # every start 10 % higher: the error is 0.1 whatever the spread between starts
    assert _pressure_metric(1.1 * U_ref, U_ref)[0] == pytest.approx(0.1, rel=1e-12)
    # a run offset by c in one block of three: RMS over blocks and times = c / sqrt(3) over the reference's RMS
    off = U_ref.copy()
    off[:, :, 1] += 7.0
    expected = 7.0 / np.sqrt(3) / np.sqrt(np.mean(U_ref.mean(axis=0) ** 2))
    assert _pressure_metric(off, U_ref)[0] == pytest.approx(expected, rel=1e-12)


def test_pressure_error_interpolates_onto_the_reference_times_and_skips_empty_blocks():
    t_ref = np.linspace(0, 1, 11)
    U_ref = np.stack([np.column_stack([1 + t_ref, np.full(11, np.nan)])] * 2)  # block 2 holds no pore
    t = np.linspace(0, 1, 5)
    U = np.stack([np.column_stack([1 + t, np.full(5, np.nan)])] * 3)
    with warnings.catch_warnings():   # the empty block has no spread: nan, left out
        warnings.simplefilter("ignore", RuntimeWarning)
        assert _pressure_metric(U, U_ref, t, t_ref)[0] == pytest.approx(0.0, abs=1e-15)  # linear: exact


def test_floors_follow_the_spread_between_starts():
    # starts = mean +- sigma (alternating), n = 4: std (ddof 1) = sigma sqrt(4/3)
    n, sigma = 4, 3.0
    z = np.array([1, -1, 1, -1], float)
    U = 50.0 + sigma * z[:, None, None] * np.ones((1, 20, 2))
    floor = np.sqrt(2 / n) * sigma * np.sqrt(4 / 3) / 50.0
    assert tr.pressure_floor(U) == pytest.approx(floor, rel=1e-12)
    x = 2e-4 + 1e-5 * z
    assert tr.change_floor(x) == pytest.approx(np.sqrt(2 / n) * 1e-5 * np.sqrt(4 / 3) / 2e-4, rel=1e-12)
    assert tr.change_error(x * 1.2, x) == pytest.approx(0.2, rel=1e-12)


def test_noise_floor_of_two_ensembles_adds_both_variances_over_their_sizes():
    # run: 4 starts at 50 +- 3 (alternating), reference: 8 starts at 50 +- 1
    za, zb = np.array([1, -1] * 2, float), np.array([1, -1] * 4, float)
    U = 50.0 + 3.0 * za[:, None, None] * np.ones((1, 20, 2))
    U_ref = 50.0 + 1.0 * zb[:, None, None] * np.ones((1, 20, 2))
    var_a, var_b = 9.0 * 4 / 3, 1.0 * 8 / 7  # ddof 1
    t = np.arange(20)
    assert _pressure_metric(U, U_ref, t, t)[1] == pytest.approx(np.sqrt(var_a / 4 + var_b / 8) / 50.0, rel=1e-12)
    # the same ensembles at the reference: the chaos floor of two sets of n (the reference's floor)
    assert _pressure_metric(U_ref, U_ref, t, t)[1] == pytest.approx(tr.pressure_floor(U_ref), rel=1e-12)
    x, x_ref = 2e-4 + 3e-5 * za, 2e-4 + 1e-5 * zb
    assert tr.change_noise(x, x_ref) == pytest.approx(np.sqrt(9e-10 * 4 / 3 / 4 + 1e-10 * 8 / 7 / 8) / 2e-4, rel=1e-12)
    assert tr.corrected(0.05, 0.03) == pytest.approx(0.04) and tr.corrected(0.03, 0.05) == 0.0


@pytest.mark.parametrize("bias", [0.0, 0.04, 0.10])
def test_systematic_error_recovers_a_known_bias_through_the_chaos(bias):
    """Histories with a 20 % spread between starts and a relative bias: with 20 starts the raw
    metric is inflated by the chaos; the noise-corrected estimate finds the bias within 3 sigma."""
    rng = np.random.default_rng(7)
    t = np.arange(60) * 5e-4
    shape = 100 * np.sin(2 * np.pi * 50 * t)[:, None] * np.array([1.0, 0.5, -0.8])

    def ensemble(n, scale):
        U = scale * shape[None] + 20.0 * rng.standard_normal((n, len(t), 3))
        d_por = scale * (-0.0175) * (1 + 0.2 * rng.standard_normal(n))
        d_h = scale * 1.5e-4 * (1 + 0.2 * rng.standard_normal(n))
        return _run(U, np.outer(np.ones(n), [0.3, 0.3]) + np.column_stack([0 * d_por, d_por]),
                    np.outer(np.ones(n), [1e-2, 1e-2]) - np.column_stack([0 * d_h, d_h]), t)

    run, ref = ensemble(20, 1.0 + bias), ensemble(20, 1.0)
    res = tr.systematic(run, ref, n_boot=200)
    for key in ("pressure_rms", "porosity_change", "settlement"):
        r = res[key]
        assert r["systematic"] <= r["measured"] and r["sigma"] > 0
        assert abs(r["systematic"] - bias) < 3 * r["sigma"] + 0.01, (key, r)
    # the pressures' chaos alone (bias 0) reads as ~10 % raw; the correction removes most of it
    # (what remains is the scatter of measured^2 - floor^2 over 180 samples, ~0.3 floor)
    if bias == 0.0:
        assert res["pressure_rms"]["measured"] > 0.05 and res["pressure_rms"]["systematic"] < 0.5 * res["pressure_rms"]["measured"]


def test_errors_use_porosity_change_and_settlement():
    U = np.ones((2, 3, 2)) + [[[0.0], [0.1], [0.2]], [[0.1], [0.0], [0.3]]]   # starts differ: a floor > 0
    ref = _run(U, [[0.30, 0.31, 0.32], [0.30, 0.30, 0.34]], [[1.0, 0.9, 0.8], [1.0, 0.9, 0.6]])
    run = _run(U, [[0.30, 0.31, 0.33], [0.30, 0.30, 0.36]], [[1.0, 0.9, 0.8], [1.0, 0.9, 0.8]])
    e = {k: v["measured"] for k, v in tr.systematic(run, ref, n_boot=2).items()}
    assert e["pressure_rms"] == 0.0
    assert e["porosity_change"] == pytest.approx((0.045 - 0.03) / 0.03)  # mean change 0.045 against 0.03
    assert e["settlement"] == pytest.approx(abs(0.2 - 0.3) / 0.3)
    assert set(tr.floors(ref)) == set(e)


def test_block_means_are_judged_on_the_scenes_pressure_scale_and_dry_runs_have_no_pressure_metrics():
    rng = np.random.default_rng(3)
    t = np.arange(40) * 5e-4
    shape = np.column_stack([100 * np.sin(2 * np.pi * 50 * t) + 60, 0 * t + 1.0])  # block 2: mean ~0
    ref = _run(shape + rng.normal(0, 5, (8, 40, 2)), np.tile([0.30, 0.31], (8, 1))[:, [0] * 20 + [1] * 20],
               np.tile([1e-2, 0.9e-2], (8, 1))[:, [0] * 20 + [1] * 20], t)
    run = {**ref, "U": ref["U"] + [0.0, 3.0]}  # block 2 higher by 3 N/m in every start and sample
    res = tr.systematic(run, ref, n_boot=20, blocks=True)
    scale = np.sqrt(np.mean(ref["U"].mean(axis=0) ** 2))
    assert res["block_mean_1"]["measured"] == pytest.approx(0.0, abs=1e-12)
    assert res["block_mean_2"]["measured"] == pytest.approx(3.0 / scale, rel=1e-9)  # not 3 / 1 = 300 %
    # the same starts: the two ensembles' floor is sqrt(2 var / n) of the block's time means
    x = ref["U"][:, :, 1].mean(axis=1)
    assert res["block_mean_2"]["floor"] == pytest.approx(np.sqrt(2 * np.var(x, ddof=1) / 8) / scale, rel=1e-9)
    assert "block_mean_1" not in tr.systematic(run, ref, n_boot=2)  # only with blocks
    dry = {**ref, "U": np.full_like(ref["U"], np.nan)}
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no mean of an empty slice
        res = tr.systematic(dry, dry, n_boot=2, blocks=True)
    assert set(res) == set(tr.floors(dry)) == {"porosity_change", "settlement"}


def test_pareto_front():
    cost = [1, 2, 3, 4, 5, 0.5]
    err = [0.5, 0.1, 0.2, 0.05, 0.3, np.nan]
    assert tr.pareto_front(cost, err) == [0, 1, 3]
    assert tr.pareto_front([1, 1], [0.2, 0.1]) == [1]  # the same cost: the lower error only


def test_study_points_and_jobs():
    from engines.run import tradeoffs as study
    pts = tr.points()
    assert pts[0] == ("liquefaction_case1", "reference", tr.REFERENCE_DT)
    assert ("liquefaction_case1", "dt", tr.PAPER_DT) in pts
    cases = [c for c, _, _ in pts]
    assert cases.index("liquefaction_case4") > max(i for i, c in enumerate(cases) if c != "liquefaction_case4")
    # the dt sweep keeps the rebuild period at 1 ms, the paper's 1000 steps of 1e-6 s
    for dt in (5e-7, 1e-6, 2e-5, 1e-4):
        over, _ = study.settings_of("liquefaction_case1", "dt", dt)
        assert over["numerics.rebuild_interval"] * dt == pytest.approx(1e-3)
    over, prog = study.settings_of("liquefaction_case1", "E_w_scale", 10.0)
    assert over["water.E_w"] == 24000.0 and over["water.substep"] and prog == "yade"
    assert study.settings_of("liquefaction_case1", "precision", "longdouble")[1] == "yade-longdouble"
    jobs, meta = study.study_jobs()
    assert len({j.name for j in jobs}) == len(jobs) == len(pts)
    argv = dict(zip(jobs[0].argv, jobs[0].argv[1:]))
    assert argv["--case"] == "liquefaction_case1" and argv["--window"] == "0.04"
    # the rows judged against 5 % get 20 starts (floor / 2), the other knobs STARTS
    starts = {meta[j.name][1]: dict(zip(j.argv, j.argv[1:]))["--starts"] for j in jobs if meta[j.name][0] == "liquefaction_case1"}
    assert starts["reference"] == starts["dt"] == starts["defaults"] == "20"
    assert starts["water_interval"] == starts["smoothing"] == str(tr.STARTS)
    # the seismic starts are perturbed by 1e-7 m: with 1e-9 m the ensemble means still depend on the size
    # (docs/TRADEOFFS.md); the knob "perturbation" runs the other sizes, every other case keeps PERTURBATION
    size = {(meta[j.name][1], meta[j.name][2] if meta[j.name][1] == "perturbation" else None):
            float(dict(zip(j.argv, j.argv[1:]))["--perturbation"]) for j in jobs if meta[j.name][0] == "liquefaction_case1"}
    assert size[("reference", None)] == size[("dt", None)] == size[("defaults", None)] == 1e-7
    assert {v: size[("perturbation", v)] for v in (1e-9, 1e-8, 3e-7)} == {1e-9: 1e-9, 1e-8: 1e-8, 3e-7: 3e-7}
    assert {float(dict(zip(j.argv, j.argv[1:]))["--perturbation"]) for j in jobs
            if meta[j.name][0] == "quicksand_case1"} == {tr.PERTURBATION}
    sub, sub_meta = study.study_jobs(["liquefaction_case1"], knobs=["reference", "defaults"])
    assert {sub_meta[j.name][1] for j in sub} == {"reference", "defaults"}


def _fake_result(path, case, over, dt, cpu, scale, rng, n=5, ok=True):
    t = np.arange(0, 0.0105, 5e-4)
    starts = []
    for s in range(n):
        U = scale * (100 * np.sin(2 * np.pi * 100 * t)[:, None] * np.ones(2) + rng.normal(0, 0.2, (len(t), 2)))
        starts.append({"seed": s, "status": "ok" if ok else "refused", "t": list(t), "U": U.tolist(),
                       "porosity": list(0.3 + scale * 0.01 * t / t[-1]), "height": list(1e-2 - scale * 1e-4 * t / t[-1]),
                       "kinetic_energy": list(0 * t), "cpu_s": cpu, "message": "" if ok else "refused: eq 52"})
    os.makedirs(path, exist_ok=True)
    with open(os.path.join(path, "result.json"), "w") as f:
        json.dump({"case": case, "overrides": over, "dt": dt, "window": 0.01, "cpu_s": cpu, "wall_s": 2 * cpu,
                   "starts": starts}, f)


def test_analyse_writes_the_issue_format(tmp_path):
    from engines.run.sweep import Job
    from postproc.tradeoffs import analyse
    rng = np.random.default_rng(0)
    case = "liquefaction_case1"
    spec = [("ref", "reference", 5e-7, 5e-7, 100.0, 1.0, True), ("paper", "dt", 1e-6, 1e-6, 50.0, 1.0, True),
            ("fast", "dt", 2e-5, 2e-5, 2.5, 1.02, True), ("bad", "dt", 2e-4, 2e-4, 0.1, 1.0, False),
            ("def", "defaults", {"name": "fast", "numerics.dt": "auto"}, 2e-5, 2.0, 1.03, True),
            ("pert", "perturbation", 3e-7, 2e-5, 2.5, 1.0, True)]
    jobs, meta = [], {}
    for name, knob, value, dt, cpu, scale, ok in spec:
        _fake_result(str(tmp_path / "runs" / name), case, {"numerics": {"dt": dt}}, dt, cpu, scale, rng, ok=ok)
        jobs.append(Job(name, ("true",)))
        meta[name] = (case, knob, value)
    doc = analyse(str(tmp_path), jobs, meta, log=None)
    on_disk = json.loads((tmp_path / "tradeoffs.json").read_text())
    assert set(on_disk) >= {"reference", "runs", "defaults"}
    runs = {r["value"] if not isinstance(r["value"], dict) else "def": r for r in doc["runs"]}
    assert runs[1e-6]["speedup"] == pytest.approx(1.0) and runs[2e-5]["speedup"] == pytest.approx(20.0)
    assert runs[2e-5]["error"]["pressure_rms"] == pytest.approx(0.02, rel=0.1)  # 2 % higher everywhere
    assert runs[2e-4]["error"] is None and "eq 52" in runs[2e-4]["messages"][0]
    d = on_disk["defaults"]
    assert d["speedup"] == pytest.approx(25.0)
    assert set(d["error"]) == {"pressure_rms", "porosity_change", "settlement", "pressure_rms_below_surface"}
    # 3 % higher everywhere, a small spread: the systematic estimate is the 3 %, within 5 %, at 25x
    assert d["systematic"]["pressure_rms"]["systematic"] == pytest.approx(0.03, rel=0.1)
    assert d["within_target"] and d["target_met"]
    assert_drawn(str(tmp_path / f"tradeoffs_{case}.png"))
    assert_drawn(str(tmp_path / f"perturbation_{case}.png"))  # the reference and the perturbation row
    assert "| liquefaction_case1 | dt | 2e-05 |" in (tmp_path / "table.md").read_text()


def test_validation_runs_the_fast_setting_against_the_papers_numerics_on_every_preset():
    from engines.run import tradeoffs as study
    presets = sorted(os.path.basename(p)[:-5] for p in os.listdir(scenes.SCENE_DIR)
                     if p.startswith(("quicksand_case", "liquefaction_case")) and p[:-5].split("case")[1].isdigit())
    assert sorted(tr.VALIDATION) == presets
    assert not any(c in tr.VALIDATION_CASES for c, _, _ in tr.points())  # not in the trade study's default
    jobs, meta = study.study_jobs(list(tr.VALIDATION_CASES))
    seismic_scenes = [p for p in presets if p.startswith("liquefaction")]
    assert len(jobs) == 2 * len(presets) + len(seismic_scenes)  # and a candidate setting on the seismic box
    for j in jobs:
        case, knob, value = meta[j.name]
        argv = dict(zip(j.argv, j.argv[1:]))
        scene = scenes.preset(tr.CASES[case]["preset"])
        assert argv["--case"] == tr.CASES[case]["preset"] and float(argv["--window"]) == scene.numerics.duration
        assert argv["--starts"] == "20"
        seismic = tr.CASES[case]["preset"].startswith("liquefaction")
        assert float(argv["--perturbation"]) == (ens.SEISMIC_PERTURBATION if seismic else ens.QUICKSAND_PERTURBATION)
        sets = {a.split("=", 1)[0]: json.loads(a.split("=", 1)[1]) for a in j.argv if "=" in a and a.startswith("numerics.")}
        named = {"reference": tr.ACCURATE, "defaults": tr.FAST, "candidate": tr.VALIDATION_CANDIDATE}[knob]
        assert sets == {k: v for k, v in named.items() if k != "name"}, (j.name, sets)


def _fake_validation(path, scale, spread, rng, wet=True, n=20):
    t = np.arange(0, 0.0405, 5e-4)
    starts = []
    for s in range(n):
        U = scale * (100 * np.sin(2 * np.pi * 50 * t)[:, None] * [1.0, 0.6] + 50) + rng.normal(0, spread, (len(t), 2))
        d = 1 + 0.05 * rng.standard_normal()
        starts.append({"seed": s, "status": "ok", "t": list(t), "U": U.tolist() if wet else np.full_like(U, np.nan).tolist(),
                       "porosity": list(0.3 - scale * d * 0.01 * t / t[-1]), "height": list(1e-2 - scale * d * 1e-4 * t / t[-1]),
                       "kinetic_energy": list(0 * t), "cpu_s": 1.0})
    os.makedirs(path, exist_ok=True)
    with open(os.path.join(path, "result.json"), "w") as f:
        json.dump({"case": "x", "overrides": {}, "dt": 1e-6, "window": 0.04, "cpu_s": 10.0 / scale, "wall_s": 1.0,
                   "starts": starts}, f)


def test_validate_writes_every_metric_and_the_verdict(tmp_path):
    from engines.run.sweep import Job
    from postproc.tradeoffs import validate
    rng = np.random.default_rng(5)
    # case 1: the fast runs 1 % off (pass); quick sand: 10 % off (fail); case 2: dry, 1 % off (pass);
    # case 3: no runs yet
    spec = {"liquefaction_case1_full": (1.01, True), "quicksand_case1_full": (1.10, True),
            "liquefaction_case2_full": (1.01, False), "liquefaction_case3_full": None}
    jobs, meta = [], {}
    for case, what in spec.items():
        settings = [("reference", 1e-6), ("defaults", tr.FAST)] + [("candidate", v) for v in tr.CASES[case]["candidate"]]
        for knob, value in settings:
            name = tr.job_name(case, knob, value)
            if what is not None:  # a candidate 0.5 % off
                scale = {"reference": 1.0, "defaults": what[0], "candidate": 1.005}[knob]
                _fake_validation(str(tmp_path / "runs" / name), scale, 2.0, rng, what[1])
            jobs.append(Job(name, ("true",)))
            meta[name] = (case, knob, value)
    doc = validate(str(tmp_path), jobs, meta, log=None)
    assert json.loads((tmp_path / "validation.json").read_text())["scenes"].keys() == doc["scenes"].keys()
    v = {scene: e["verdict"] for scene, e in doc["scenes"].items()}
    assert v == {"liquefaction_case1": "pass", "quicksand_case1": "fail", "liquefaction_case2": "pass",
                 "liquefaction_case3": "not run"}
    wet, dry = doc["scenes"]["liquefaction_case1"], doc["scenes"]["liquefaction_case2"]
    assert set(wet["judged"]) == {"pressure_rms", "porosity_change", "settlement", "block_mean_1", "block_mean_2"}
    assert set(dry["judged"]) == {"porosity_change", "settlement"}
    assert wet["speedup"] == pytest.approx(1.01) and wet["starts"] == {"paper": 20, "fast": 20}
    # 10 % off everywhere: every metric's estimate near 10 %
    qs = doc["scenes"]["quicksand_case1"]["metrics"]
    assert qs["porosity_change"]["systematic"] == pytest.approx(0.10, abs=0.03)
    candidate = tr.VALIDATION_CANDIDATE["name"]
    assert wet["candidates"][candidate]["verdict"] == "pass" and "candidates" not in doc["scenes"]["quicksand_case1"]
    table = (tmp_path / "validation.md").read_text()
    assert "| quicksand_case1 | 20/20 |" in table and table.count("| fail |") == 1 and "| not run |" in table
    assert f"| liquefaction_case1, {candidate} | 20/20 |" in table


def test_a_row_not_resolved_states_the_starts_that_would_decide_it():
    from engines.studies.tradeoffs_judged import starts_needed
    m = lambda est, sigma: {"systematic": est, "sigma": sigma}  # noqa: E731
    # 3 % +- 1.5 %: 2 sigma = 3 % against 2 % left below 5 %: 20 (3/2)^2 = 45 starts
    assert starts_needed({"settlement": m(0.03, 0.015), "porosity_change": m(0.0, 0.01)}, 20) == 45
    assert starts_needed({"settlement": m(0.03, 0.015), "porosity_change": m(0.04, 0.01)}, 20) == 80  # 20 (2/1)^2
    assert starts_needed({"settlement": m(0.01, 0.01)}, 20) is None  # pass
    assert starts_needed({"settlement": m(0.06, 0.001), "porosity_change": m(0.03, 0.015)}, 20) is None  # fail
    assert starts_needed({"settlement": m(0.03, 0.015), "pressure_rms_below_surface": m(0.049, 0.1)}, 20) == 45  # judged only


def test_the_validation_gives_a_row_not_resolved_more_starts_and_reads_them_as_one_ensemble(tmp_path):
    from engines.run import tradeoffs as study
    from engines.studies.ensemble import MAX_STARTS
    from postproc.tradeoffs import validate
    rng = np.random.default_rng(5)
    case = "liquefaction_case7_full"  # dry: porosity change and settlement judged
    jobs, meta = study.study_jobs([case])
    assert [meta[j.name][1] for j in jobs] == ["reference", "defaults", "candidate"]
    for j in jobs:
        _fake_validation(str(tmp_path / "runs" / j.name), 1.0, 2.0, rng, wet=False)
    doc = {"scenes": {"liquefaction_case7": {"case": case, "verdict": "not resolved", "starts_needed": 45,
                                             "candidates": {"x": {"verdict": "pass"}}}}}
    more = study.more_starts_jobs(doc, jobs, meta)
    assert [j.name for j in more] == [f"{j.name}.starts20-44" for j in jobs]
    for j, base in zip(more, jobs):
        argv = list(j.argv)
        assert argv[argv.index("--starts") + 1] == "25" and argv[argv.index("--first-start") + 1] == "20"
        assert argv[argv.index("--out") - 2] == "--first-start" and meta[j.name] == meta[base.name]
        assert [a for a in argv if a not in ("--first-start", "20", "25")] == \
            [a for a in base.argv if a != "20"], "only the starts change"
    assert study.more_starts_jobs(doc, jobs + more, meta) == []  # they have the starts asked
    doc["scenes"]["liquefaction_case7"]["candidates"]["x"]["starts_needed"] = 500  # capped
    assert [j.name for j in study.more_starts_jobs(doc, jobs + more, meta)] == \
        [f"{j.name}.starts45-{MAX_STARTS - 1}" for j in jobs]
    # the more starts, 0.5 % off in every setting, read with the first 20 as one ensemble of 45
    for j in more:
        _fake_validation(str(tmp_path / "runs" / j.name), 1.0, 2.0, rng, wet=False, n=25)
    out = validate(str(tmp_path), jobs + more, meta, log=None)["scenes"]["liquefaction_case7"]
    assert out["starts"] == {"paper": 45, "fast": 45}
    assert out["cpu_s"]["paper"] == pytest.approx(10.0)  # the mean per start over both jobs
    assert validate(str(tmp_path), jobs, meta, log=None)["scenes"]["liquefaction_case7"]["starts"]["paper"] == 20
    (tmp_path / "runs" / more[0].name / "result.json").unlink()  # a missing part: that setting not read
    assert validate(str(tmp_path), jobs + more, meta, log=None)["scenes"]["liquefaction_case7"]["verdict"] == "not run"


def test_a_setting_runs_its_starts_from_the_first_asked(monkeypatch, tmp_path):
    from engines.run import tradeoffs as study
    seen = []
    monkeypatch.setattr(study, "_run_start", lambda sc, pk, seed, *a: seen.append((seed, pk.xz.copy())) or
                        {"seed": seed, "status": "ok", "cpu_s": 1.0, "wall_s": 1.0})
    res = study.run_setting("quicksand_case1", {"numerics": {"duration": 1e-4}}, 1e-4, 5e-5, 2, str(tmp_path),
                            1e-8, first=20)
    assert [s["seed"] for s in res["starts"]] == [20, 21]
    from engines.yade.deposition import scene_packing
    base = scene_packing(scenes.preset("quicksand_case1"))
    for seed, xz in seen:
        assert np.array_equal(xz, ens.perturbed(base, seed, 1e-8).xz)


def _numerics(setting):
    return {k.split(".", 1)[1]: v for k, v in setting.items() if k.startswith("numerics.")}


def test_fast_variants_are_the_validated_setting_on_scenes_that_pass():
    """Every scene offered a fast variant (``<scene>_fast.toml``) holds the numerics of a setting
    with the verdict "pass" on that scene in the committed validation (docs/tradeoffs/validation.json),
    and dt = "auto" names, per factor, exactly the scenes where its setting passes."""
    from engines import ROOT
    from engines.run.preflight import describe_auto_dt
    with open(os.path.join(ROOT, "docs", "tradeoffs", "validation.json")) as f:
        validation = json.load(f)
    assert validation["fast"] == {k: v for k, v in tr.FAST.items() if k != "name"}
    assert scenes.preset("liquefaction_case1").numerics.dt_auto_factor == tr.VALIDATED_FACTOR

    def passing(scene):
        """{dt_auto_factor: numerics} of the settings that pass on ``scene``."""
        e = validation["scenes"][scene]
        out = {tr.VALIDATED_FACTOR: _numerics(tr.FAST)} if e["verdict"] == "pass" else {}
        out.update({c["settings"]["numerics.dt_auto_factor"]: _numerics(c["settings"])
                    for c in e.get("candidates", {}).values() if c["verdict"] == "pass"})
        return out

    for factor, named in tr.VALIDATED_ON.items():
        assert sorted(named) == sorted(s for s in validation["scenes"] if factor in passing(s)), factor
        said = describe_auto_dt(1e-5, {"contact": 1e-5 / factor}, "contact", 1, factor)  # what dt = "auto" prints
        assert all(s in said for s in named) and "validated over the whole run on" in said
    assert "not validated" in describe_auto_dt(1e-5, {"contact": 2e-5}, "contact", 1, 0.5)
    for path in os.listdir(scenes.SCENE_DIR):
        if path.endswith("_fast.toml"):
            scene = path[:-len("_fast.toml")]
            num = scenes.preset(path[:-5]).numerics
            ok = passing(scene).get(num.dt_auto_factor)
            assert ok is not None, f"{path}: no setting at dt_auto_factor {num.dt_auto_factor} passes on {scene}"
            assert {k: getattr(num, k) for k in ok if k != "dt_auto_factor"} == {k: v for k, v in ok.items()
                                                                               if k != "dt_auto_factor"}, path


def test_speed_points_name_the_study_settings():
    from engines.run import tradeoffs as study
    assert tr.named_value("liquefaction_case1", "dt", "1e-06") == 1e-6
    fast = tr.named_value("liquefaction_case1", "defaults", "fast")
    assert fast is tr.CASES["liquefaction_case1"]["defaults"][0]
    over = tr.nested(study.settings_of("liquefaction_case1", "defaults", fast)[0])
    assert over["numerics"]["dt"] == "auto" and over["numerics"]["water_interval"] == fast["numerics.water_interval"]


def test_presets_are_the_study_defaults():
    """liquefaction_case1_accurate.toml holds the numerics the study measured under its name (a fast
    variant is offered only where the validation passes: the test above)."""
    for setting in [tr.ACCURATE]:
        num = scenes.preset(f"liquefaction_case1_{setting['name']}").numerics
        for key, value in setting.items():
            if key.startswith("numerics."):
                assert getattr(num, key.split(".", 1)[1]) == value, (setting["name"], key)


def test_verdict_passes_resolved_estimates_fails_one_above_the_target_and_ignores_the_diagnostic():
    from engines.studies.tradeoffs_judged import TARGET, verdict

    def m(estimate, sigma):
        return {"systematic": estimate, "sigma": sigma}
    assert verdict({"pressure_rms": m(0.01, 0.01), "block_mean_1": m(TARGET - 0.02, 0.01)}) == "pass"
    assert verdict({"pressure_rms": m(TARGET - 0.01, 0.01)}) == "not resolved"
    assert verdict({"settlement": m(TARGET + 0.01, 0.0), "porosity_change": m(0.0, 0.0)}) == "fail"
    assert verdict({"settlement": m(0.01, 0.0), "pressure_rms_below_surface": m(0.5, 0.1)}) == "pass"
