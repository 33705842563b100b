"""Never delete what the project did not write (issue 37, item 5): the manifest of a run folder,
--overwrite removing only its names (an older folder without one: the known output names), the
rest kept and named in one line, an ensemble's start folders only those its ensemble.json lists,
and a folder holding anything else refused without --overwrite."""
import json
import os
import subprocess

import pytest

from engines import ROOT
from engines.run import manifest
from engines.run.preflight import InputError, check_fresh_output


def make(folder, names):
    """Files (and folders, names ending in /) in ``folder``."""
    for name in names:
        path = folder / name
        if name.endswith("/"):
            path.mkdir(parents=True, exist_ok=True)
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(name)


def tree(folder):
    return sorted(os.path.relpath(os.path.join(d, n), folder) for d, dirs, files in os.walk(folder) for n in dirs + files)


def test_an_older_run_without_a_manifest_its_known_outputs_go_the_rest_is_kept(tmp_path, capsys):
    make(tmp_path, ["history.csv", "summary.json", "checkpoint.pkl", "snapshot_000.02ms.npz", "snapshots.png",
                    ".checkpoint-abc.yade.gz", "vtk/discs_00000.vtp", "vtk/discs.pvd", "vtk/my_state.pvsm",
                    "notes.txt", "start_notes/a.txt", "history.csv.bak"])
    kept = manifest.clear(str(tmp_path))
    assert tree(tmp_path) == ["history.csv.bak", "notes.txt", "start_notes", "start_notes/a.txt", "vtk",
                              "vtk/my_state.pvsm"]
    assert kept == ["history.csv.bak", "notes.txt", "start_notes", "vtk/my_state.pvsm"]
    assert capsys.readouterr().out == (f"kept in {tmp_path} (not written by this project): history.csv.bak, notes.txt, "
                                       f"start_notes, vtk/my_state.pvsm\n")


def test_with_a_manifest_only_its_names_go(tmp_path):
    make(tmp_path, ["history.csv", "summary.json", "snapshot_000.02ms.npz", "vtk/discs_00000.vtp"])
    manifest.claim(str(tmp_path), ["history.csv", "snapshot_000.02ms.npz", "vtk"])
    assert manifest.read(str(tmp_path)) == ["history.csv", "snapshot_000.02ms.npz", "vtk", "manifest.json"]
    manifest.claim(str(tmp_path), ["history.csv"])  # once each
    assert manifest.read(str(tmp_path)).count("history.csv") == 1
    manifest.clear(str(tmp_path), log=None)
    assert tree(tmp_path) == ["summary.json"]  # not listed: not this run's


def test_a_crafted_manifest_cannot_reach_outside_the_folder(tmp_path):
    run, victim = tmp_path / "run", tmp_path / "victim.txt"
    make(tmp_path, ["victim.txt", "run/history.csv", "run/.hidden"])
    (run / "manifest.json").write_text(json.dumps({"files": ["../victim.txt", "/etc/passwd", ".hidden", "..", 3,
                                                             "history.csv"]}))
    with pytest.raises(ValueError, match="manifest.json: entry = '../victim.txt' holds a path separator"):
        manifest.claim(str(run), ["../victim.txt"])
    assert manifest.read(str(run)) == ["history.csv"]
    manifest.clear(str(run), log=None)
    assert victim.exists() and tree(run) == [".hidden"]


def test_a_name_of_ours_of_the_wrong_kind_is_kept(tmp_path):
    make(tmp_path, ["history.csv/mine.txt", "start_3"])  # a folder where a run writes a file, a file named like a start
    (tmp_path / "ensemble.json").write_text(json.dumps({"starts": ["start_3"]}))
    manifest.clear(str(tmp_path), log=None)
    assert tree(tmp_path) == ["history.csv", "history.csv/mine.txt", "start_3"]


def test_an_ensemble_removes_only_the_starts_its_ensemble_json_lists(tmp_path):
    make(tmp_path, ["start_0/history.csv", "start_1/summary.json", "start_2/x", "start_notes/plan.txt",
                    "ensemble_history.png", "sweep.json"])
    (tmp_path / "ensemble.json").write_text(json.dumps({"starts": ["start_0", "start_1", "../elsewhere", ".."]}))
    kept = manifest.clear(str(tmp_path), log=None)
    assert kept == ["start_2", "start_notes"] and tree(tmp_path) == ["start_2", "start_2/x", "start_notes",
                                                                     "start_notes/plan.txt"]


@pytest.mark.parametrize("names,message", [
    (["notes.txt"], "holds files this project did not write (notes.txt): give --overwrite to write there anyway "
                    "(they are kept), or name a new or empty folder"),
    (["history.csv", "notes.txt"], "holds another run's outputs (history.csv) and files this project did not write "
                                   "(notes.txt): give --overwrite to replace the outputs (the other files are kept)"),
    (["vtk/discs_00000.vtp"], "holds another run's outputs (vtk): give --overwrite to replace them"),
    (["snapshot_000.02ms.npz"], "holds another run's outputs (snapshot_000.02ms.npz): give --overwrite"),
])
def test_a_fresh_run_refuses_a_folder_holding_anything(tmp_path, names, message):
    make(tmp_path, names)
    with pytest.raises(InputError) as e:
        check_fresh_output(str(tmp_path))
    assert str(e.value).startswith(f"--out {tmp_path} {message}"), str(e.value)
    assert tree(tmp_path) == sorted(set(tree(tmp_path)))  # nothing touched
    check_fresh_output(str(tmp_path / "new"))


# -- a run, end to end --------------------------------------------------------------------------------
ENV = dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg")
RUN = ["yade", "-n", "-x", "yade_scripts/quicksand.py", "--duration", "2e-4", "--set", "output.snapshot_times=[1e-4]",
       "--set", "output.vtk_interval=100", "--vtk"]


@pytest.mark.check
def test_a_run_lists_every_file_it_writes_and_overwrite_keeps_the_users(tmp_path):
    out = tmp_path / "run"
    run = subprocess.run(RUN + ["--out", str(out)], cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    listed = set(manifest.read(str(out)))
    assert set(os.listdir(out)) <= listed, set(os.listdir(out)) - listed
    assert {"history.csv", "summary.json", "snapshot_000.10ms.npz", "vtk", "snapshots.png"} <= set(os.listdir(out))
    make(out, ["notes.txt", "vtk/view.pvsm"])
    run = subprocess.run(RUN + ["--out", str(out)], cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=600)
    assert run.returncode == 1 and [line for line in run.stderr.splitlines() if "error" in line] == [
        f"error: --out {out} holds another run's outputs ({', '.join(sorted(set(os.listdir(out)) - {'notes.txt'})[:6])}"
        f"{', ...' if len(os.listdir(out)) > 7 else ''}) and files this project did not write (notes.txt): give "
        f"--overwrite to replace the outputs (the other files are kept), or --resume {out} to continue that run"]
    run = subprocess.run(RUN + ["--out", str(out), "--overwrite"], cwd=ROOT, env=ENV, capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stderr
    assert f"kept in {out} (not written by this project): notes.txt, vtk/view.pvsm" in run.stdout.splitlines()
    assert (out / "notes.txt").read_text() == "notes.txt" and (out / "vtk" / "view.pvsm").exists()
    assert '"status": "completed"' in (out / "summary.json").read_text()
