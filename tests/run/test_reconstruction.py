"""The reconstruction study's jobs (engines/run/reconstruction.py): each variant's cases carry its
changes on the preset's own values, a packing variant's cases run on its deposit."""
import json
import os

import pytest

from engines.run import scene as scenes
from engines.run.reconstruction import study_jobs
from engines.studies.reconstruction import VARIANTS, packing_path


def _sets(job):
    a = list(job.argv)
    return {a[i + 1].split("=", 1)[0]: json.loads(a[i + 1].split("=", 1)[1]) for i in range(len(a)) if a[i] == "--set"}


@pytest.fixture(scope="module")
def jobs():
    deposits, cases = study_jobs("/runs")
    return {j.name: j for j in deposits}, {j.name: j for j in cases}


def test_every_variant_runs_each_of_its_cases_once(jobs):
    deposits, cases = jobs
    assert sorted(cases) == sorted(f"{n}_case{k}" for n, v in VARIANTS.items() for k in v.cases)
    assert sorted(deposits) == sorted(f"{n}_packing" for n, v in VARIANTS.items() if v.deposit)
    assert all("--starts" in j.argv and j.argv[j.argv.index("--starts") + 1] == "8" for j in cases.values())


@pytest.mark.parametrize("name,case,field,factor", [("k_x10", 3, "k1", 10), ("k_x30", 3, "k2", 30),
                                                    ("E_w_x3", 6, "E_w", 3), ("E_w_x10", 1, "E_w", 10)])
def test_scaled_fields_are_the_presets_values_times_the_factor(jobs, name, case, field, factor):
    preset = getattr(scenes.preset(f"liquefaction_case{case}").water, field)
    assert _sets(jobs[1][f"{name}_case{case}"])[f"water.{field}"] == pytest.approx(factor * preset)


def test_a_packing_variant_deposits_once_and_runs_its_cases_on_it(jobs):
    deposits, cases = jobs
    assert _sets(deposits["box_narrow_packing"]) == {"packing.n_bottom": 17, "packing.n_side": 16}
    for k in VARIANTS["box_narrow"].cases:
        sets = _sets(cases[f"box_narrow_case{k}"])
        assert sets == {"packing.source": "file", "packing.file": packing_path("/runs", "box_narrow")}
    # the cases whose fast numerics passed the validation run with them, as make liquefaction does
    assert "liquefaction_case2_fast.toml" in " ".join(cases["box_wide_case2"].argv)
    assert "--case" in cases["box_wide_case6"].argv and "--scene" not in cases["box_wide_case6"].argv


def test_a_case_begun_continues_its_ensemble(tmp_path):
    """A study stopped during a case: the re-run's job resumes that case's ensemble (its finished
    starts kept); a case not begun starts afresh; a completed one has no job."""
    from engines.studies.reconstruction import ensemble_path
    for name, status in (("k_x10", "running"), ("k_x30", "completed")):
        os.makedirs(ensemble_path(str(tmp_path), name, 3))
        with open(os.path.join(ensemble_path(str(tmp_path), name, 3), "ensemble.json"), "w") as f:
            json.dump({"status": status}, f)
    _, cases = study_jobs(str(tmp_path))
    job = {j.name: j for j in cases}
    assert job["k_x10_case3"].argv[-4:] == ("--resume", ensemble_path(str(tmp_path), "k_x10", 3), "--jobs", "1")
    assert "--starts" in job["k_x3_case3"].argv  # not begun
    assert "k_x30_case3" not in job  # completed: nothing to run
