"""Seed 003's judged points without YADE: the intervals, the pooled scatter, the table and the
criteria from synthetic runs of known φ, and the conditioning of E50 in kn."""
import json
import math

import numpy as np
import pytest
from scipy import stats

from engines.seeds.biaxial.calibration import Calibration
from engines.studies import biaxial_judged as bj
from tests.figures import assert_drawn
from tests.seeds.test_calibration import fake_run


def test_interval_is_students_t_on_the_mean():
    v = [21.0, 23.5, 22.0, 26.0, 24.5]
    half = stats.t.ppf(0.975, 4) * np.std(v, ddof=1) / math.sqrt(5)
    st = bj.interval(v + [float("nan"), None])
    assert st["n"] == 5 and st["mean"] == pytest.approx(23.4)
    assert (st["low"], st["high"]) == (pytest.approx(23.4 - half), pytest.approx(23.4 + half))
    one = bj.interval([3.0])
    assert one["mean"] == 3.0 and one["low"] is None and bj.interval([])["mean"] is None


def test_welch_difference_bounds_are_the_5_percent_level_of_welchs_test():
    a, b = [24.0, 26.5, 25.0, 27.0, 23.5], [15.0, 17.5, 16.0, 14.0, 18.5, 16.5]
    d = bj.difference(a, b)
    assert d["mean"] == pytest.approx(np.mean(a) - np.mean(b))
    # a moved by either bound differs from b exactly at the 5 % level of Welch's test
    for bound in (d["low"], d["high"]):
        assert stats.ttest_ind(np.subtract(a, bound), b, equal_var=False).pvalue == pytest.approx(0.05)
    assert bj.difference([1.0], b)["low"] is None


def test_pooled_log_sd():
    """Groups scattered by the same factors around different means pool to that s.d. of ln."""
    f = np.exp([-0.2, 0.0, 0.2])
    assert bj.log_sd([1e4 * f, 3e4 * f, [5e4]]) == pytest.approx(0.2)
    assert bj.log_sd([[1e4], [2e4]]) is None


def q_f(sigma3, phi_deg):
    """Peak deviator of a cohesionless Mohr–Coulomb ground: 2 σ3 sin φ / (1 − sin φ)."""
    s = math.sin(math.radians(phi_deg))
    return 2 * sigma3 * s / (1 - s)


def test_judged_table_from_synthetic_runs(tmp_path):
    """Five packings at φe = 15° with φ = 26–28° (mean 27°) and E50 = 60 σ3 scattered by a known
    factor, four at 5° with φ = 19.5–20.5°: the table gives φ* and c* = 0 back with Student-t
    intervals, the peaks, E50, porosity, the eq 4 fit (m = 0: E50 ∝ σ3), the criteria (φ* within
    3° of 27.4°, the peaks against 330 and 140 Pa, φ* rising) and the Calibration's scatter; a
    failed job is listed and left out."""
    phis = {15.0: [26.0, 27.5, 26.5, 28.0, 27.0], 5.0: [19.5, 20.0, 20.5, 20.0]}
    factor = [0.8, 1.25, 1.0, 0.9, 1.1]
    s3 = np.array(bj.JUDGED_SIGMA3)
    for p, values in phis.items():
        for seed, phi in enumerate(values, start=1):
            fake_run(str(tmp_path), bj.judged_name(p, seed), s3, [q_f(s, phi) for s in s3], 60 * s3 * factor[seed - 1],
                     0.85)
    failed = tmp_path / bj.judged_name(5.0, 5)
    failed.mkdir()
    (failed / "job.json").write_text('{"status": "failed"}')
    res, cal = bj.analyse_judged(str(tmp_path))
    rows = {r["phi_e_deg"]: r for r in res["rows"]}
    r15, r5 = rows[15.0], rows[5.0]
    assert r15["phi_star_deg"]["n"] == 5 and r5["phi_star_deg"]["n"] == 4
    assert r15["phi_star_deg"]["values"] == pytest.approx(phis[15.0], abs=1e-9)
    half = stats.t.ppf(0.975, 4) * np.std(phis[15.0], ddof=1) / math.sqrt(5)
    assert r15["phi_star_deg"]["high"] == pytest.approx(27.0 + half, abs=1e-9)
    assert max(abs(c) for c in r15["c_star_pa"]["values"]) < 1e-9
    assert r15["per_sigma3"]["200"]["peak_pa"]["mean"] == pytest.approx(np.mean([q_f(200, p) for p in phis[15.0]]))
    assert r15["per_sigma3"]["200"]["e50_pa"]["mean"] == pytest.approx(60 * 200 * np.mean(factor), rel=1e-3)
    assert r15["porosity"]["mean"] == pytest.approx(0.15)
    assert r15["eq4"]["m"] == pytest.approx(0.0, abs=1e-3) and r15["e50_log_sd"] == pytest.approx(
        np.std(np.log(factor), ddof=1), rel=1e-3)
    assert res["jobs_failed"] == [bj.judged_name(5.0, 5)]
    met = [c["met"] for c in res["criteria"]]
    # φ* 27.0° within 3° of 27.4°; q_f(200 Pa) 333 Pa within 25 % of 330; 5°: 208 Pa, not within 25 % of 140
    assert [c["what"][:12] for c in res["criteria"]] == ["φ* at φe = 1", "peak q at σ3", "peak q at σ3", "φ* rising wi"]
    assert met == [True, True, False, True]
    assert [c["paper_inside"] for c in res["criteria"]] == [
        bj.inside(27.4, r15["phi_star_deg"]), bj.inside(330.0, r15["per_sigma3"]["200"]["peak_pa"]), False, None]
    assert bj.inside(27.4, {"low": 26.0, "high": 28.0}) and not bj.inside(30.0, {"low": 26.0, "high": 28.0})
    assert cal.phi_e == [5.0, 15.0] and cal.phi_star == pytest.approx([20.0, 27.0])
    assert cal.packings == [4, 5] and cal.e50_log_sd[1] == pytest.approx(r15["e50_log_sd"])
    table = bj.write_judged(res, str(tmp_path / "j.json"), str(tmp_path / "j.md"))
    assert f"| 15° | 27.4 | 27.0° [{27 - half:.1f}, {27 + half:.1f}] (n = 5) |" in table


def test_conditioning_of_e50_in_kn():
    """eq 6 turns the E50 interval of n packings into a kn factor exp(t s/√n / |m|); the packings
    needed for E50 within 25 % are the fewest with t(n − 1) s/√n <= ln 1.25."""
    cal = Calibration([5.0, 15.0], [16.0, 24.0], [50.0, 80.0], [-0.1, -0.3], 1e8, 0.25,
                      e50_log_sd=[0.2, 0.4], phi_star_sd=[1.0, 2.0], packings=[5, 5])
    c = bj.conditioning(cal, 10.0, 5)
    half = stats.t.ppf(0.975, 4) * 0.3 / math.sqrt(5)
    assert c["m"] == pytest.approx(-0.2) and c["dlnE50_dlnkn"] == pytest.approx(0.2)
    assert c["e50_half_width"] == pytest.approx(math.exp(half) - 1)
    assert c["kn_factor"] == pytest.approx(math.exp(half / 0.2))
    assert c["phi_star_half_width"] == pytest.approx(stats.t.ppf(0.975, 4) * 1.5 / math.sqrt(5))
    n = c["packings_for_e50"]
    t = lambda k: stats.t.ppf(0.975, k - 1) * 0.3 / math.sqrt(k)  # noqa: E731
    assert t(n) <= math.log(1.25) < t(n - 1)
    assert "factor" in bj.conditioning_text(c)
    assert bj.conditioning(Calibration([5.0, 15.0], [16.0, 24.0], [50.0, 80.0], [-0.1, -0.3], 1e8, 0.25), 10.0) is None


def test_judged_part_with_its_calibration_round_trip_from_synthetic_runs(tmp_path):
    """run_judged on synthetic runs (nothing run): the judged fit (φ* 20° at 5°, 27° at 15°;
    E50 = 60 σ3 (σ3/200 Pa)^−0.3 scattered, m = −0.3), the round trip's verification runs answering with φ = 23.5° and
    E50 10 % above the target, are reported with the conditioning of E50 in kn; the figure is drawn."""
    from engines.run import biaxial_study as st

    runs = tmp_path / "runs"
    s3 = np.array(bj.JUDGED_SIGMA3)
    factor = [0.8, 1.25, 1.0, 0.9, 1.1]
    for p, phi in ((15.0, 27.0), (5.0, 20.0)):
        for seed in bj.JUDGED_SEEDS:
            fake_run(str(runs), bj.judged_name(p, seed), s3, [q_f(s, phi + 0.2 * seed) for s in s3],
                     60 * s3 * (s3 / 200) ** -0.3 * factor[seed - 1], 0.85)
    _, cal = bj.analyse_judged(str(runs))
    assert cal.m == pytest.approx([-0.3, -0.3], rel=1e-3)
    target, (phi_e, kn), jobs = st.calibration_jobs(cal, bj.JUDGED_SEEDS)
    for j in jobs:
        v = sorted({*st.VERIFY_SIGMA3, target[2]})
        fake_run(str(runs), j.name, v, [q_f(s, 23.5) for s in v], [1.1 * target[1] / target[2] * s for s in v], 0.85)
    table = st.run_judged(str(tmp_path), str(runs), run=lambda jobs: None)
    res = json.loads((tmp_path / "judged.json").read_text())
    v = res["calibration"]["verified"]
    assert v["phi_star_deg"]["mean"] == pytest.approx(23.5, abs=1e-6)
    assert v["e50_error"] == pytest.approx(0.1, rel=1e-3)
    c = res["calibration"]["conditioning"]
    assert c["packings"] == 5 and c["m"] == pytest.approx(-0.3, rel=1e-3)
    assert c["kn_factor"] == pytest.approx(math.exp(math.log(1 + c["e50_half_width"]) / 0.3), rel=1e-3)
    assert "Calibration round trip" in table and "+10.0 %" in table and "fixes kn only within a factor" in table
    assert_drawn(str(tmp_path / "fig_judged.png"))
    assert Calibration.load(str(tmp_path / "judged_fit.json")).packings == [5, 5]


def test_the_judged_figure_s_key_covers_no_panel(monkeypatch):
    """docs/biaxial/fig_judged.png from its committed record: one key, under the three panels."""
    import os

    from engines import ROOT, files
    from postproc.biaxial_plots import plot_judged
    drawn = []
    monkeypatch.setattr(files, "save_figure", lambda fig, path, **kw: drawn.append(fig))
    plot_judged(json.load(open(os.path.join(ROOT, "docs", "biaxial", "judged.json"))), "unused.png")
    (fig,) = drawn
    fig.canvas.draw()
    (key,) = fig.legends
    assert [t.get_text() for t in key.get_texts()] == ["one packing", "paper", "model: mean, 95 % interval"]
    box = key.get_window_extent()
    for ax in fig.axes:
        panel = ax.get_window_extent()
        assert box.y1 <= panel.y0 or box.x1 <= panel.x0 or panel.x1 <= box.x0


def test_the_shipped_fit_is_the_calibration_of_the_committed_judged_record():
    """docs/biaxial/judged_fit.json (calibrate.py --fit on a fresh tree) is what run_judged saves
    from the runs of docs/biaxial/judged.json: the same rows and eq 4 fits."""
    import os
    from dataclasses import asdict

    from engines import ROOT
    rec = json.load(open(os.path.join(ROOT, "docs", "biaxial", "judged.json")))
    cal = bj.calibration(rec["rows"], {r["phi_e_deg"]: (r["eq4"]["A"], r["eq4"]["m"]) for r in rec["rows"] if "eq4" in r})
    shipped = Calibration.load(os.path.join(ROOT, "docs", "biaxial", "judged_fit.json"))
    assert asdict(shipped) == asdict(cal) and shipped.phi_e == [5.0, 10.0, 15.0]
