"""yade_scripts/deposit.py writes into out/ unless asked to replace the scene's packing file."""
import hashlib
import os
import subprocess

import numpy as np
import pytest

from engines import ROOT
from engines.run import scene as scenes

PRESET = os.path.join(scenes.SCENE_DIR, "quicksand_case1.toml")
SMALL = ('[scene]\nname = "small"\n[packing]\nsource = "deposit"\nfile = "mine.csv"\nn_particles = 8\n'
         'n_bottom = 6\nn_side = 5\nsettle_time = 0.02\ncut_extra = 0.0\n')


def deposit(cwd, *args):
    return subprocess.run(["yade", "-n", "-x", os.path.join(ROOT, "yade_scripts/deposit.py"), *args], cwd=cwd,
                          env=dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg"), capture_output=True,
                          text=True, timeout=300)


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


@pytest.mark.check
def test_default_goes_to_out_and_replace_overwrites_the_scenes_file(tmp_path):
    scene = tmp_path / "small.toml"
    scene.write_text(f'extends = "{os.path.relpath(PRESET, tmp_path)}"\n' + SMALL)
    preset_packing = os.path.join(scenes.SCENE_DIR, "quicksand_packing.csv")
    before = digest(preset_packing)
    run = deposit(tmp_path, "--scene", str(scene))
    assert run.returncode == 0, run.stderr
    written = tmp_path / "out" / "packings" / "small.csv"
    assert f"-> out/packings/small.csv" in run.stdout and "--replace overwrites it" in run.stdout
    assert written.exists() and not (tmp_path / "mine.csv").exists()
    assert np.loadtxt(written, delimiter=",", skiprows=1, ndmin=2).shape[0] == 8 + 6 + 2 * 4
    run = deposit(tmp_path, "--scene", str(scene), "--replace")
    assert run.returncode == 0 and f"-> {tmp_path / 'mine.csv'}" in run.stdout, run.stderr
    assert digest(preset_packing) == before


def test_replace_without_a_file_and_an_unwritable_out_are_refused(tmp_path):
    scene = tmp_path / "nofile.toml"
    scene.write_text('[scene]\nname = "nofile"\n')
    run = deposit(tmp_path, "--scene", str(scene), "--replace")
    assert run.returncode != 0 and "--replace: the scene names no [packing] file" in run.stderr
    run = deposit(tmp_path, "--scene", str(scene), "--out", "/proc/x/p.csv")
    assert run.returncode != 0 and "--out" in run.stderr and "Traceback" not in run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nofile.toml"]


@pytest.mark.check
def test_set_changes_the_deposit_and_is_refused_with_replace(tmp_path):
    """--set as in the run scripts: a wider box (8 bottom discs instead of 6) holds the same 8 discs;
    a changed scene never replaces the preset's packing file."""
    scene = tmp_path / "small.toml"
    scene.write_text(f'extends = "{os.path.relpath(PRESET, tmp_path)}"\n' + SMALL)
    run = deposit(tmp_path, "--scene", str(scene), "--set", "packing.n_bottom=8", "--out", "wide.csv")
    assert run.returncode == 0, run.stderr
    rows = np.loadtxt(tmp_path / "wide.csv", delimiter=",", skiprows=1, ndmin=2)
    assert rows.shape[0] == 8 + 8 + 2 * 4
    run = deposit(tmp_path, "--scene", str(scene), "--set", "packing.n_bottom=8", "--replace")
    assert run.returncode != 0 and "--replace with --set" in run.stderr and "Traceback" not in run.stderr
    assert not (tmp_path / "mine.csv").exists()
    run = deposit(tmp_path, "--scene", str(scene), "--set", "packing.n_bottom=1", "--out", "bad.csv")
    assert run.returncode != 0 and "n_bottom" in run.stderr and "Traceback" not in run.stderr
