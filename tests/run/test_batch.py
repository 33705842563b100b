"""yade-batch: a table's columns become the script's options and scene fields, each job writes to
its own directory and records where it came from; the example table is valid."""
import importlib.util
import json
import os
import subprocess

import pytest

from engines import ROOT
from engines.run import scene as scenes
from engines.run.command_line import BATCH_OUT, job_argv, overrides_of
from engines.run.table import read_table

SCRIPT = os.path.join(ROOT, "yade_scripts", "quicksand.py")
TABLE = os.path.join(ROOT, "yade_scripts", "quicksand_sweep.table")


def quicksand():
    spec = importlib.util.spec_from_file_location("quicksand_script", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def job_args(monkeypatch, table, line):
    monkeypatch.setenv("YADE_BATCH", f"{table}:{line}")
    ap = quicksand().parser()
    return ap.parse_args(job_argv(ap, []))


def test_table_columns_become_options_and_scene_fields(tmp_path, monkeypatch):
    table = tmp_path / "t.table"
    table.write_text("# a comment\ncase duration water.k1 output.snapshot_times vtk\n"
                     "2    0.002    20       [0.001,0.002]          True\n")
    args = job_args(monkeypatch, table, 3)
    assert args.case == 2 and args.duration == 0.002 and args.vtk
    assert overrides_of(args) == {"water": {"k1": 20}, "output": {"snapshot_times": [0.001, 0.002], "vtk": True},
                                  "numerics": {"duration": 0.002}}
    assert args.out == os.path.join(BATCH_OUT, "case=2,duration=0.002,water.k1=20,output.snapshot_times=[0.001,0.002],vtk=True")
    monkeypatch.delenv("YADE_BATCH")
    assert job_argv(quicksand().parser(), ["--case", "1"]) == ["--case", "1"]  # outside yade-batch: argv as given


def test_under_the_sweep_runner_a_job_writes_into_its_job_directory(tmp_path, monkeypatch):
    table = tmp_path / "t.table"
    table.write_text("duration\n0.002\n")
    monkeypatch.setenv("SWEEP_JOB_DIR", str(tmp_path / "job"))
    assert job_args(monkeypatch, table, 2).out == str(tmp_path / "job")
    table.write_text("duration out\n0.002 'mine'\n")  # the table's own out column still wins
    assert job_args(monkeypatch, table, 2).out == "mine"


def test_an_unknown_column_is_refused_in_one_line(tmp_path, monkeypatch, capsys):
    table = tmp_path / "t.table"
    table.write_text("duraton\n0.002\n")
    with pytest.raises(SystemExit) as e:
        job_args(monkeypatch, table, 2)
    assert e.value.code == 2 and "column 'duraton'" in capsys.readouterr().err


def test_the_example_table_gives_valid_scenes(monkeypatch):
    lines = sorted(read_table(TABLE))
    assert len(lines) >= 2
    for line in lines:
        args = job_args(monkeypatch, TABLE, line)
        sc = scenes.preset(f"quicksand_case{args.case}", overrides_of(args))
        assert sc.numerics.duration == args.duration and sc.water.q_w > 0
        assert args.out.startswith(BATCH_OUT + os.sep)


@pytest.mark.check
def test_yade_batch_runs_a_table(tmp_path):
    table = tmp_path / "sweep.table"
    table.write_text("duration water.q_w\n3e-4 2.5e-4\n3e-4 1e-3\n")
    env = dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg")
    run = subprocess.run(["yade-batch", "-j", "2", "--log", str(tmp_path / "@.log"), str(table), SCRIPT],
                         cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0 and "All jobs finished" in run.stdout, run.stdout + run.stderr
    for line, q_w, name in ((2, 2.5e-4, "duration=3e-4,water.q_w=2.5e-4"), (3, 1e-3, "duration=3e-4,water.q_w=1e-3")):
        out = tmp_path / "out" / "batch" / name  # yade-batch's description of the job
        summary = json.load(open(out / "summary.json"))
        assert summary["status"] == "completed" and summary["steps"] == 300
        prov = summary["provenance"]
        assert prov["overrides"] == {"water": {"q_w": q_w}, "numerics": {"duration": 3e-4}}
        assert prov["yade_batch"] == f"{table}:{line}" and prov["yade_version"] and len(prov["git_commit"]) == 40
        assert summary["parameters"]["water"]["q_w"] == q_w and summary["results"]["peak_block_pressures"]["U_block1"]
