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


def _ground_run(folder, status="completed", ru=0.95):
    """A run folder like one of make resistance-ground: the synthetic history of
    tests/studies/test_resistance.py, band 3 at a constant cycle-mean r_u of ``ru``."""
    import numpy as np

    from tests.studies.test_resistance import F, history, summary
    h = history(lambda k, t: np.full(len(t), ru if k == 2 else 0.2))
    h["porosity"] = np.full(len(h["t"]), 0.2)
    os.makedirs(folder)
    with open(os.path.join(folder, "history.csv"), "w") as f:
        f.write(",".join(h) + "\n" + "\n".join(",".join(repr(float(h[k][i])) for k in h) for i in range(len(h["t"]))))
    s = summary()
    s["parameters"]["loading"] = {"type": "cosine", "amplitude": 7.5, "amplitude_scale": 2.0, "frequency": F}
    s.update(status=status, scene="ground-10000", n_particles=10000, cpu_seconds=3600.0)
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump(s, f)
    return folder


def test_the_ground_run_is_read_like_a_start_at_its_own_amplitude_and_a_run_not_completed_is_refused(tmp_path):
    from engines.run.resistance import ground_reading
    from engines.studies.resistance import void_ratio
    g = ground_reading(_ground_run(str(tmp_path / "ground")), 30)
    assert g["amplitude_m_s2"] == 15.0 and g["a_max_g"] == pytest.approx(15.0 / 9.81)  # amplitude x its scale
    assert g["n_l"] == pytest.approx(1.0, abs=0.01) and g["band"] == 3 and not g["censored"]  # 0.95 from the first cycle
    assert g["void_ratio"] == pytest.approx(void_ratio(0.2)) and g["n_particles"] == 10000
    assert ground_reading(_ground_run(str(tmp_path / "low"), ru=0.5), 30)["censored"]
    with pytest.raises(ValueError, match=r"^\S+: the ground run is 'running', not completed: make resistance-ground"):
        ground_reading(_ground_run(str(tmp_path / "stopped"), status="running"), 30)
