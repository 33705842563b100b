"""make resistance SHORT=1 (check: it starts YADE processes): the pipeline end to end (a dense
deposit, two packings at two amplitudes, ensembles of two starts, resistance.json and its figure),
and a second make that finds every run done and redoes none."""
import json
import os
import subprocess

import pytest

from engines import ROOT
from engines.run.resistance import short_plan
from engines.studies.resistance import PACKINGS


def _make(out):
    # -o deps: the test runs the study's recipe, not the installation (make deps installs this checkout)
    return subprocess.run(["make", "-s", "-o", "deps", "resistance", "SHORT=1", f"OUT={out}", "LIQ_JOBS=2"],
                          cwd=ROOT, capture_output=True, text=True, timeout=1800)


@pytest.mark.check
def test_make_resistance_short_writes_the_curve_and_resumes_without_redoing_runs(tmp_path):
    p = _make(tmp_path)
    assert p.returncode == 0, p.stderr[-2000:]
    study = tmp_path / "resistance-short"
    doc = json.loads((study / "resistance.json").read_text())
    plan = short_plan()
    assert set(doc["packings"]) == set(PACKINGS) and doc["cycles"] == pytest.approx(plan.cycles)
    for p_ in doc["packings"].values():
        assert [r["amplitude_m_s2"] for r in p_["rows"]] == list(plan.amplitudes) and p_["void_ratio"] > 0
        for r in p_["rows"]:  # runs of 0.1 cycle liquefy nowhere: every one is censored
            assert r["n_starts"] == plan.starts and r["n_l"]["median"] is None and r["liquefied"]["fraction"] == 0
            assert r["csr_simplified"]["mean"] > 0
    assert (study / "resistance.png").exists()  # what it draws: tests/postproc/test_resistance_figure.py
    runs = study / "runs"
    stamp = {d: os.path.getmtime(runs / d / "ensemble" / "ensemble.json") for d in os.listdir(runs) if d.endswith("gal")}
    assert len(stamp) == 2 * len(plan.amplitudes)
    again = _make(tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    assert "1 jobs, 1 already ok, 0 to run" in again.stdout  # the deposit kept; no ensemble left to run
    assert {d: os.path.getmtime(runs / d / "ensemble" / "ensemble.json") for d in stamp} == stamp
