"""Ensembles of the scene scripts (--starts): the start folders, ensemble.json against the starts'
own files, the same numbers from the same command (locally and on a Dask cluster), resume per
start, and the refusals before anything is written. Short runs."""
import json
import os
import subprocess

import numpy as np
import pytest

from engines import ROOT
from engines.run.ensemble import start_argv
from postproc.run_files import read_history
from yade_scripts import liquefaction, quicksand


def script(name, *args, cwd):
    return subprocess.run(["yade", "-n", "-x", os.path.join(ROOT, "yade_scripts", name), *args], cwd=cwd,
                          env=dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg"), capture_output=True, text=True,
                          timeout=900)


def numbers(out):
    """The statistics of ensemble.json (results and history), without the timings."""
    doc = json.loads((out / "ensemble.json").read_text())
    return {k: doc[k] for k in ("seeds", "perturbation_m", "results", "history")}


@pytest.mark.check
def test_the_seismic_box_ensemble_and_the_same_numbers_again(tmp_path):
    args = ["--case", "1", "--duration", "0.002", "--starts", "3"]
    for name in ("a", "b"):
        run = script("liquefaction.py", *args, "--out", name, cwd=tmp_path)
        assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    a, b = tmp_path / "a", tmp_path / "b"
    doc = json.loads((a / "ensemble.json").read_text())
    assert doc["status"] == "completed" and doc["seeds"] == [0, 1, 2] and doc["perturbation_m"] == 1e-7
    histories = []
    for k in range(3):
        d = a / f"start_{k}"
        for f in ("history.csv", "summary.json", "checkpoint.npz", "blocks.png"):
            assert (d / f).exists(), (d, f)
        summary = json.loads((d / "summary.json").read_text())
        assert summary["status"] == "completed" and summary["start"] == {"seed": k, "perturbation_m": 1e-7}
        histories.append(read_history(str(d / "history.csv")))
    assert not np.array_equal(histories[0]["U_block1"], histories[1]["U_block1"])  # the starts differ
    assert numbers(a) == numbers(b)
    # the statistics are those of the starts' own files: the last row of U_block1, a result
    u = np.array([h["U_block1"][-1] for h in histories])
    col = doc["history"]["columns"]["U_block1"]
    assert doc["history"]["t"] == histories[0]["t"].tolist()
    assert col["mean"][-1] == pytest.approx(u.mean(), rel=1e-12)
    assert col["standard_error"][-1] == pytest.approx(u.std(ddof=1) / np.sqrt(3), rel=1e-9)
    assert col["ci95_high"][-1] - col["mean"][-1] == pytest.approx(4.302653 * u.std(ddof=1) / np.sqrt(3), rel=1e-6)
    ends = [json.loads((a / f"start_{k}" / "summary.json").read_text())["results"]["porosity_end"] for k in range(3)]
    assert doc["results"]["porosity_end"]["values"] == ends
    assert doc["results"]["porosity_end"]["mean"] == pytest.approx(np.mean(ends), rel=1e-12)
    assert {"peak_block_pressures.U_block6.U_max_N_per_m", "heave_time_s", "t_last_row_s"} <= set(doc["results"])
    assert (a / "ensemble_pressure_blocks.png").exists() and (a / "ensemble_history.png").exists()


@pytest.mark.check
def test_quick_sand_ensemble_on_dask_and_resumed_per_start_locally_gives_the_same_numbers(tmp_path):
    """An ensemble continued to a later end, and then with a start that never began, gives the
    numbers of the ensemble run at once on a Dask cluster's workers."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        run = script("quicksand.py", "--case", "1", "--starts", "2", "--duration", "0.004", "--scheduler",
                     cluster.scheduler_address, "--out", "whole", cwd=tmp_path)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    run = script("quicksand.py", "--case", "1", "--starts", "2", "--jobs", "2", "--duration", "0.002", "--out", "parts",
                 cwd=tmp_path)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    run = script("quicksand.py", "--resume", "parts", "--duration", "0.004", cwd=tmp_path)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert numbers(tmp_path / "parts") == numbers(tmp_path / "whole")
    for path in (tmp_path / "parts" / "start_1").iterdir():  # start 1 never began
        path.unlink()
    (tmp_path / "parts" / "start_1").rmdir()
    run = script("quicksand.py", "--resume", "parts", cwd=tmp_path)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert "1 jobs, 0 already ok, 1 to run" in run.stdout
    assert numbers(tmp_path / "parts") == numbers(tmp_path / "whole")


@pytest.mark.parametrize("args,match", [
    (["--starts", "2", "--perturbation", "0.01"], "start 1 (perturbed by 0.01 m)"),  # discs outside the box
    (["--starts", "1"], "--starts"),
    (["--starts", "2", "--start", "1"], "--start"),
    (["--perturbation", "1e-7"], "--perturbation needs --starts"),
    (["--jobs", "2"], "--jobs needs --starts"),
    (["--starts", "2", "--jobs", "2", "--scheduler", "tcp://127.0.0.1:1"], "not allowed with"),
    (["--starts", "2", "--dt", "1e-3"], "[numerics] dt"),
])
def test_bad_ensembles_are_refused_in_one_line(tmp_path, capsys, args, match):
    with pytest.raises(SystemExit) as ex:
        quicksand.main(["--case", "1"] + args + ["--out", str(tmp_path / "bad")])
    message = str(ex.value.code) if isinstance(ex.value.code, str) else capsys.readouterr().err
    assert ex.value.code != 0 and match in message and len(message.strip().splitlines()) == 1, message
    assert not (tmp_path / "bad").exists()


def test_a_start_gets_the_scripts_arguments_without_the_ensembles():
    ap = liquefaction.parser()
    argv = ["--case", "1", "--starts", "3", "--jobs=2", "--pert", "1e-7", "--set", "water.k1=20", "--overwrite",
            "--out", "o", "--duration", "0.01", "--scheduler-f", "s.json"]
    assert start_argv(ap, argv) == ["--case", "1", "--set", "water.k1=20", "--duration", "0.01"]


def test_an_ensembles_resume_is_refused_in_one_line_before_anything_runs(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("sys.argv", [os.path.join(ROOT, "yade_scripts", "quicksand.py")])  # the script typed
    out = tmp_path / "ens"
    out.mkdir()
    plan = {"scene": "quicksand-case1", "script": os.path.join(ROOT, "yade_scripts", "quicksand.py"), "n_starts": 2,
            "seeds": [0, 1], "perturbation_m": 1e-8, "perturbation": "", "start_argv": ["--case", "1"],
            "starts": ["start_0", "start_1"], "status": "running"}
    (out / "ensemble.json").write_text(json.dumps(plan))
    for args, match in ((["--starts", "2"], "--starts cannot be given"), (["--start", "0"], "--start cannot be given"),
                        (["--duration", "0.01"], "start 0 never began")):
        with pytest.raises(SystemExit) as ex:
            quicksand.main(["--resume", str(out)] + args)
        message = str(ex.value.code) if isinstance(ex.value.code, str) else capsys.readouterr().err
        assert ex.value.code != 0 and match in message and len(message.strip().splitlines()) == 1, message
    assert sorted(p.name for p in out.iterdir()) == ["ensemble.json"]
