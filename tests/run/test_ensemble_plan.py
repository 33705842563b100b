"""ensemble.json never chooses what runs: --resume of an ensemble runs the script it was started
with, and a plan that is not one the project writes (its script elsewhere, seeds that are paths,
start_argv with --out or options of no script) is refused in one line before anything runs."""
import json
import os

import pytest

from engines import ROOT
from engines.run import ensemble
from engines.run.preflight import InputError
from engines.run.sweep import YADE
from yade_scripts import liquefaction, quicksand

TYPED = os.path.join(ROOT, "yade_scripts", "quicksand.py")


def plan(**change):
    doc = {"scene": "quicksand-case1", "script": TYPED, "n_starts": 2, "seeds": [0, 1], "perturbation_m": 1e-8,
           "perturbation": "", "start_argv": ["--case", "1", "--set", "water.k1=20", "--dt", "-1e-6"],
           "starts": ["start_0", "start_1"], "status": "running"}
    doc.update(change)
    return doc


def resume(tmp_path, doc, script=TYPED, parser=quicksand.parser):
    out = tmp_path / "ens"
    out.mkdir(exist_ok=True)
    (out / "ensemble.json").write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return ensemble.resume_jobs(parser(), str(out), None, script)


def test_the_starts_run_the_script_typed_never_the_plans(tmp_path):
    jobs, kept = resume(tmp_path, plan(script="/elsewhere/quicksand.py"))
    assert [j.name for j in jobs] == ["start_0", "start_1"]
    for k, job in enumerate(jobs):
        assert job.argv == (*YADE, "-x", TYPED, "--case", "1", "--set", "water.k1=20", "--dt", "-1e-6",
                            "--start", str(k), "--perturbation", "1e-08", "--out", "{out}")
    assert kept["script"] == TYPED


@pytest.mark.parametrize("change, match", [
    ({"script": "/tmp/evil.py"}, "this ensemble was run by 'evil.py' (ensemble.json); resume it with that script"),
    ({"seeds": ["../../x", 1]}, "seeds must be a list of distinct integers >= 0"),
    ({"seeds": [0, True]}, "seeds must be a list of distinct integers >= 0"),
    ({"starts": ["start_0", "../start_1"]}, "n_starts and starts do not match the seeds"),
    ({"n_starts": 3}, "n_starts and starts do not match the seeds"),
    ({"perturbation_m": "1e-8"}, "perturbation_m must be a number > 0"),
    ({"start_argv": "--case 1"}, "start_argv a list of strings"),
    ({"start_argv": ["--case", "1", "--out", "/tmp/x"]}, "start_argv holds '--out', which the ensemble gives"),
    ({"start_argv": ["--case", "1", "--ov"]}, "start_argv holds '--ov', which the ensemble gives"),
    ({"start_argv": ["--resume=/tmp/x"]}, "start_argv holds '--resume=/tmp/x', which the ensemble gives"),
    ({"start_argv": ["-x", "/tmp/evil.py"]}, "start_argv holds '-x', which is not an option of this script"),
    ({"scene": None, "seeds": None}, None),
])
def test_a_crafted_plan_is_refused_in_one_line(tmp_path, change, match):
    doc = plan(**change)
    if match is None:  # a key missing
        del doc["seeds"]
        match = "no seeds"
    with pytest.raises(InputError) as e:
        resume(tmp_path, doc)
    assert match in str(e.value) and "\n" not in str(e.value)
    assert sorted(p.name for p in (tmp_path / "ens").iterdir()) == ["ensemble.json"]


def test_a_plan_that_is_no_json_object_is_refused(tmp_path):
    for text, match in (("[1, 2]", "not a JSON object"), ("{", "cannot be read as JSON"), ("[" * 100000, "JSON")):
        with pytest.raises(InputError, match=match):
            resume(tmp_path, text)


def test_the_other_scripts_resume_is_refused_by_the_script_itself(tmp_path, capsys, monkeypatch):
    """quicksand.py's ensemble resumed with liquefaction.py: one line, nothing runs."""
    monkeypatch.setattr("sys.argv", [os.path.join(ROOT, "yade_scripts", "liquefaction.py")])
    out = tmp_path / "ens"
    out.mkdir()
    (out / "ensemble.json").write_text(json.dumps(plan()))
    with pytest.raises(SystemExit) as e:
        liquefaction.main(["--resume", str(out)])
    assert "run by 'quicksand.py' (ensemble.json); resume it with that script, not liquefaction.py" in str(e.value.code)
    assert sorted(p.name for p in out.iterdir()) == ["ensemble.json"]


def test_a_scheduler_file_goes_with_starts_only(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        quicksand.main(["--case", "1", "--scheduler-file", str(tmp_path / "s.json"), "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--scheduler-file needs --starts N" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        quicksand.main(["--case", "1", "--starts", "2", "--jobs", "2", "--scheduler-file", "s.json", "--out", "o"])
    assert "not allowed with" in capsys.readouterr().err
    assert ensemble.start_argv(quicksand.parser(), ["--case", "1", "--scheduler-file", "s.json"]) == ["--case", "1"]
