"""Bad input is refused before anything is written: one line naming the field or argument and its
limit, a non-zero exit, no output directory. The checks agree with the engine's own refusals."""
import argparse
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from engines import ROOT
from engines.compiled.pore_dem import PoreDEM
from engines.model.limits import DarcyStabilityError, critical_time_step
from engines.model.pore_dem import disc_masses
from engines.model.start import Start
from engines.run import scene as scenes
from engines.run.preflight import InputError, check_fresh_output, check_output_dir, check_packing, max_overlap, number, preflight
from engines.yade.checkpoint import NAME as CHECKPOINT
from engines.yade.deposition import scene_packing
from packing.packing import Packing

PRESET = os.path.join(scenes.SCENE_DIR, "quicksand_case1.toml")
RUN_OUTPUTS = ("summary.json", "history.csv", CHECKPOINT, "ensemble.json")  # each marks a run's folder
ENV = dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg")


@pytest.fixture(scope="module")
def packing():
    return scene_packing(scenes.preset("quicksand_case1"))


def user_scene(folder, body):
    """A scene file in ``folder`` that extends case 1 by a relative path from another folder."""
    path = folder / "mine.toml"
    path.write_text(f'extends = "{os.path.relpath(PRESET, folder)}"\n' + body)
    return str(path)


def refused(cmd, out, field, code=None):
    """Run ``cmd``; it must fail with exactly one error line naming ``field``, and write no ``out``."""
    run = subprocess.run(cmd, cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=120)
    errors = [line for line in run.stderr.splitlines() if "error" in line]
    assert run.returncode != 0 and (code is None or run.returncode == code), (run.returncode, run.stderr)
    assert "Traceback" not in run.stderr and len(errors) == 1, run.stderr
    assert field in errors[0], errors[0]
    assert not os.path.exists(out), f"{out} was created"
    return errors[0]


# -- quicksand.py: the checks run before YADE is imported, so Debian's python runs them quickly ----
QUICKSAND = [sys.executable, "yade_scripts/quicksand.py"]


@pytest.mark.parametrize("args,field", [
    (["--dt", "1e-3"], "[numerics] dt"),               # eq 52 with the preset's masses and kn
    (["--dt", "0"], "--dt"),
    (["--duration", "-1"], "--duration"),
    (["--dt", "1e-5", "--duration", "1e-6"], "[numerics] duration"),
    (["--case", "2", "--scene", PRESET], "--scene"),
    (["--case", "3"], "--case"),
])
def test_quicksand_refuses_bad_arguments(tmp_path, args, field):
    out = tmp_path / "run"
    msg = refused(QUICKSAND + args + ["--out", str(out)], out, field)
    if field == "[numerics] dt":   # the message states the limit of eq 52 from the preset's numbers
        sc, pk = scenes.preset("quicksand_case1"), scene_packing(scenes.preset("quicksand_case1"))
        mass = sc.material.rho * pk.density_factor * np.pi * pk.r**2
        limit = sc.numerics.dt_safety * 2 * np.sqrt(mass[pk.mobile].min() / sc.contact.kn)
        stated = [float(x) for x in re.findall(r"(\d[\d.]*(?:e[-+]?\d+)?) s\b", msg)]
        assert "eq 52" in msg and any(abs(x / limit - 1) < 5e-3 for x in stated), (limit, msg)


def test_quicksand_refuses_an_unwritable_output_path(tmp_path):
    refused(QUICKSAND + ["--out", "/proc/x"], "/proc/x", "--out")
    blocker = tmp_path / "file"
    blocker.write_text("")
    refused(QUICKSAND + ["--out", str(blocker / "run")], blocker / "run", "--out")


@pytest.mark.parametrize("body,field", [
    ("[water]\nk1 = 1e9\n", "Darcy limit"),                   # refused up front, not at step 1
    ('[loading]\ntype = "record"\nrecord = "no_such_record.txt"\n', "[loading] record"),
    ('[packing]\nfile = "no_such_packing.csv"\n', "[packing] file"),
])
def test_quicksand_refuses_bad_user_scenes_from_another_folder(tmp_path, body, field):
    out = tmp_path / "run"
    msg = refused(QUICKSAND + ["--scene", user_scene(tmp_path, body), "--out", str(out)], out, field)
    if "no_such" in body:  # resolved against the user's file, not the preset's folder
        assert str(tmp_path / "no_such") in msg


@pytest.mark.parametrize("args,field", [(["--dt", "0"], "--dt"), (["--dt", "1e-3"], "eq 52")])
def test_quicksand_under_yade_exits_in_one_line(tmp_path, args, field):
    out = tmp_path / "run"
    refused(["yade", "-n", "-x", "yade_scripts/quicksand.py"] + args + ["--out", str(out)], out, field)


# -- seed 002 and seed 004 scripts --------------------------------------------------------------
@pytest.mark.parametrize("args,field", [
    (["--alpha", "-1"], "--alpha"),
    (["--alpha", "1", "--C", "nan"], "--C"),
    (["--alpha", "1", "--load-max", "0"], "--load-max"),
    (["--alpha", "1", "--dload", "1e-7"], "--dload"),     # 8e8 increments
])
def test_particle_potential_refuses_bad_arguments(tmp_path, args, field):
    out = tmp_path / "run"
    refused([sys.executable, "yade_scripts/particle_potential.py"] + args + ["--out", str(out)], out, field, 2)


@pytest.mark.parametrize("args,field", [
    (["--realisations", "0"], "--realisations"),
    (["--seed", "-1"], "--seed"),
    (["--load-width", "27"], "--load-width"),
    (["--load-stress", "0"], "--load-stress"),
])
def test_sand_layer_refuses_bad_arguments(tmp_path, args, field):
    out = tmp_path / "run"
    refused([sys.executable, "yade_scripts/sand_layer.py"] + args + ["--out", str(out)], out, field, 2)


@pytest.mark.parametrize("script,args", [("particle_potential.py", ["--alpha", "1"]), ("sand_layer.py", [])])
def test_seed_scripts_refuse_an_unwritable_output_path(script, args):
    refused([sys.executable, f"yade_scripts/{script}"] + args + ["--out", "/proc/x"], "/proc/x", "--out", 2)


# -- the checks themselves, against the engine ---------------------------------------------------
def test_the_presets_pass_and_nothing_is_created(packing, tmp_path):
    for case in (1, 2):
        sc = scenes.preset(f"quicksand_case{case}", {"numerics": {"duration": 0.02}})
        notes = preflight(sc, scene_packing(sc), str(tmp_path / "a" / "b"))
        assert notes[0].startswith("estimate: ") and "0.04, 0.06" in notes[1]  # snapshots after the end are named
    assert list(tmp_path.iterdir()) == []


def test_eq52_check_agrees_with_the_engine(packing):
    sc = scenes.preset("quicksand_case1")
    m, _ = disc_masses(sc.settings, packing)
    limit = critical_time_step(m[packing.mobile], sc.contact.kn)
    for dt, ok in ((0.999 * limit, True), (1.001 * limit, False)):
        s = sc.with_overrides({"numerics": {"dt": dt}, "water": {"substep": True}})
        if ok:
            preflight(s, packing, "out")
            PoreDEM(s.settings, packing)
        else:
            with pytest.raises(InputError, match=r"\[numerics\] dt .*eq 52"):
                preflight(s, packing, "out")
            with pytest.raises(ValueError, match="eq 52"):
                PoreDEM(s.settings, packing)


def test_darcy_check_agrees_with_the_engine_at_step_0(packing):
    """Just below the start limit the engine's first water step passes, just above it raises."""
    sc = scenes.preset("quicksand_case1", {"water": {"k1": 1e5, "substep": False}})  # the strict mode
    limit = Start(sc.settings, packing).limits["darcy_check"] * sc.numerics.water_interval
    assert 1e-6 < limit < 1e-5
    for dt, ok in ((0.999 * limit, True), (1.001 * limit, False)):
        s = sc.with_overrides({"numerics": {"dt": dt}})
        core = PoreDEM(s.settings, packing)
        if ok:
            preflight(s, packing, "out")
            core.step(packing.xz.copy())
        else:
            with pytest.raises(InputError, match=r"\[numerics\] dt .*Darcy limit"):
                preflight(s, packing, "out")
            with pytest.raises(DarcyStabilityError):
                core.step(packing.xz.copy())
    s = sc.with_overrides({"numerics": {"dt": 2 * limit}, "water": {"substep": True}})
    preflight(s, packing, "out")  # sub-stepping (the default): 2 sub-steps, nothing to refuse
    assert scenes.preset("quicksand_case1").water.substep  # the default
    s = sc.with_overrides({"numerics": {"dt": 0.9 * limit, "water_interval": 6},   # a water step of 5.4 limits
                           "water": {"substep": True, "max_substeps": 5}})
    with pytest.raises(InputError, match=r"needs 6 sub-steps .*Darcy limit .*max_substeps = 5"):
        preflight(s, packing, "out")


@pytest.mark.parametrize("kind,lo,hi,lo_open,text,ok", [
    (float, 0, None, True, "1e-6", True), (float, 0, None, True, "0", False), (float, 0, None, True, "-1", False),
    (float, 0, None, True, "nan", False), (float, 0, None, True, "inf", False), (float, 0, None, True, "x", False),
    (int, 1, None, False, "1", True), (int, 1, None, False, "0", False), (int, 1, None, False, "2.5", False),
    (int, 1, 26, False, "26", True), (int, 1, 26, False, "27", False), (float, 0, None, False, "0", True),
])
def test_number_arguments(kind, lo, hi, lo_open, text, ok):
    convert = number(kind, lo, hi, lo_open)
    if ok:
        assert convert(text) == kind(text)
    else:
        with pytest.raises(argparse.ArgumentTypeError, match="must be|expected"):
            convert(text)


def test_output_dir_checks(tmp_path):
    check_output_dir(str(tmp_path / "new" / "deeper"))
    check_output_dir(str(tmp_path))
    (tmp_path / "f").write_text("")
    with pytest.raises(InputError, match="--out: .* is not a directory"):
        check_output_dir(str(tmp_path / "f" / "x"))
    with pytest.raises(InputError, match="--out"):
        check_output_dir("")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]


# -- packings and output folders -------------------------------------------------------------------
def test_every_preset_packing_file_passes():
    files = 0
    for name in sorted(os.listdir(scenes.SCENE_DIR)):
        if name.endswith(".toml"):
            sc = scenes.load(os.path.join(scenes.SCENE_DIR, name))
            if sc.packing.source == "file":
                check_packing(sc, scene_packing(sc))
                files += 1
    assert files >= 10  # the quick-sand and seismic presets


def _moved_towards_neighbour(packing, overlap):
    """The packing with particle 0 moved along the line to its nearest disc so that they overlap by ``overlap``."""
    xz = packing.xz.copy()
    d = np.linalg.norm(xz - xz[0], axis=1)
    d[0] = np.inf
    j = int(np.argmin(d))
    gap = d[j] - packing.r[0] - packing.r[j]
    xz[0] += (gap + overlap) * (xz[j] - xz[0]) / d[j]
    return Packing(xz, packing.r, packing.group, packing.density_factor, path="p.csv"), j


def test_the_overlap_tolerance_is_the_contact_laws_f_max_over_kn(packing):
    sc = scenes.preset("quicksand_case1")
    tol = max_overlap(sc.contact)
    assert tol == sc.contact.f_max / sc.contact.kn == pytest.approx(2.5 / 1.4e6)
    check_packing(sc, _moved_towards_neighbour(packing, 0.99 * tol)[0])
    deep, j = _moved_towards_neighbour(packing, 1.01 * tol)
    with pytest.raises(InputError, match=rf"^packing file p.csv, line 2: overlaps line {j + 2} by .* deeper than "
                                         rf"\[contact\] f_max / kn = 1.79e-06 m; raise \[contact\] f_max .* or redeposit the packing"):
        check_packing(sc, deep)
    check_packing(sc.with_overrides({"contact": {"f_max": 5.0}}), deep)  # a law that holds twice the force


def test_check_fresh_output(tmp_path):
    check_fresh_output(str(tmp_path / "new"))
    check_fresh_output(str(tmp_path))  # empty
    for name in ("job.json", "stdout.log", "stderr.log"):  # a sweep job's folder, before its run
        (tmp_path / name).write_text("")
    check_fresh_output(str(tmp_path))
    for name in RUN_OUTPUTS:
        (tmp_path / name).write_text("")
        with pytest.raises(InputError, match=rf"^--out {tmp_path} holds another run's outputs \(.*{name}.*\): "
                                             rf"give --overwrite to replace them$"):
            check_fresh_output(str(tmp_path))
        (tmp_path / name).unlink()


def _bad_packing_file(folder, edit):
    """The quick-sand preset's packing with ``edit(lines)`` applied, saved in ``folder``."""
    lines = open(os.path.join(scenes.SCENE_DIR, "quicksand_packing.csv")).read().splitlines()
    edit(lines)
    path = folder / "bad.csv"
    path.write_text("\n".join(lines) + "\n")
    return f'[packing]\nfile = "bad.csv"\n', str(path)


def _set(line_no, column, value):
    def edit(lines):
        cells = lines[line_no - 1].split(",")
        cells[column] = value
        lines[line_no - 1] = ",".join(cells)
    return edit


@pytest.mark.parametrize("edit,why", [
    (_set(3, 2, "nan"), "line 3: r = nan is not a number"),
    (_set(3, 2, "-1e-4"), "line 3: r = -0.0001 m: a radius must be > 0"),
    (_set(4, 3, "9"), "line 4: group = 9.0: not a group code"),
    (lambda lines: lines.append(lines[5]), "line 78: the same centre as line 6: a duplicated disc"),
    (_set(2, 0, "0.5"), "line 2: particle centre (x, z) = (0.5, "),      # 0.5 m outside the 12.6-mm box
    (_set(2, 1, "-0.5"), "line 2: particle centre (x, z) = ("),          # under the bottom
])
def test_quicksand_refuses_a_bad_packing_file_naming_it_and_the_line(tmp_path, edit, why):
    body, path = _bad_packing_file(tmp_path, edit)
    out = tmp_path / "run"
    msg = refused(QUICKSAND + ["--scene", user_scene(tmp_path, body), "--out", str(out)], out, why)
    assert f"packing file {path}, {why}" in msg


def test_quicksand_refuses_a_deep_overlap_in_the_packing_file(tmp_path, packing):
    """A 40 % overlap of the smaller radius (the issue's case), far above f_max / kn = 1.8 um."""
    _, j = _moved_towards_neighbour(packing, 0.0)
    deep, _ = _moved_towards_neighbour(packing, 0.4 * min(packing.r[0], packing.r[j]))
    deep.save(str(tmp_path / "bad.csv"))
    out = tmp_path / "run"
    msg = refused(QUICKSAND + ["--scene", user_scene(tmp_path, '[packing]\nfile = "bad.csv"\n'), "--out", str(out)],
                  out, "[contact] f_max / kn")
    assert f"packing file {tmp_path / 'bad.csv'}, line 2: overlaps line {j + 2} by " in msg and "(40.0% of" in msg


@pytest.mark.parametrize("name", RUN_OUTPUTS)
def test_a_scene_script_refuses_an_out_holding_another_runs_outputs(tmp_path, name):
    out = tmp_path / "run"
    out.mkdir()
    (out / name).write_text("another run's\n")
    run = subprocess.run(QUICKSAND + ["--out", str(out)], cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=120)
    assert run.returncode == 1 and run.stderr.splitlines() == [
        f"error: --out {out} holds another run's outputs ({name}): give --overwrite to replace them, "
        f"or --resume {out} to continue that run"], run.stderr
    assert os.listdir(out) == [name] and (out / name).read_text() == "another run's\n"


@pytest.mark.check
def test_overwrite_replaces_another_runs_outputs_and_the_folder_is_printed(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "summary.json").write_text("{}")
    (out / "snapshot_000.01ms.npz").write_text("")
    run = subprocess.run(["yade", "-n", "-x", "yade_scripts/quicksand.py", "--duration", "2e-5", "--overwrite",
                          "--out", str(out)], cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert f"output: {out}" in run.stdout.splitlines()
    assert '"status": "completed"' in (out / "summary.json").read_text()
    assert not (out / "snapshot_000.01ms.npz").exists()


@pytest.mark.parametrize("argv", [["sand_layer.py"], ["stability.py"], ["crosscheck.py"], ["biaxial_study.py"],
                                  ["tradeoffs.py", "study"], ["quicksand.py"],
                                  ["calibrate.py", "--phi-star", "25", "--e50", "8000", "--sigma3", "200"]])
def test_every_script_needs_an_explicit_out(tmp_path, argv):
    run = subprocess.run([sys.executable, os.path.join(ROOT, "yade_scripts", argv[0]), *argv[1:]], cwd=tmp_path, env=ENV,
                         capture_output=True, text=True, timeout=120)
    errors = [line for line in run.stderr.splitlines() if "error" in line]
    assert run.returncode == 2 and len(errors) == 1 and "--out" in errors[0] and "required" in errors[0], run.stderr
    assert list(tmp_path.iterdir()) == []


def test_sand_layer_keeps_another_runs_outputs(tmp_path):
    (tmp_path / "summary.json").write_text("{}")
    run = subprocess.run([sys.executable, "yade_scripts/sand_layer.py", "--out", str(tmp_path)], cwd=ROOT, env=ENV,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 1 and run.stderr.splitlines() == [
        f"error: --out {tmp_path} holds another run's outputs (summary.json): give --overwrite to replace them"]
    assert os.listdir(tmp_path) == ["summary.json"]


@pytest.mark.check
def test_the_sweep_runner_replaces_the_outputs_of_its_own_unfinished_job(tmp_path):
    """In the job directory the sweep runner gave it (SWEEP_JOB_DIR), a job it re-runs (only jobs
    that did not finish are) replaces that job's earlier outputs; any other folder stays refused."""
    job = tmp_path / "job"
    job.mkdir()
    (job / "history.csv").write_text("an unfinished attempt\n")
    argv = ["yade", "-n", "-x", "yade_scripts/quicksand.py", "--duration", "2e-5", "--out", str(job)]
    run = subprocess.run(argv, cwd=ROOT, env={**ENV, "SWEEP_JOB_DIR": str(job)}, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr
    assert '"status": "completed"' in (job / "summary.json").read_text()
    run = subprocess.run(argv, cwd=ROOT, env={**ENV, "SWEEP_JOB_DIR": str(tmp_path / "other")}, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 1 and "holds another run's outputs" in run.stderr
