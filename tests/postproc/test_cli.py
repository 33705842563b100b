"""python3 -m postproc.<module>: --help works, and a folder that is not a run is refused in one line."""
import os
import subprocess
import sys

import pytest

from engines import ROOT


def run(*args):
    env = {**os.environ, "PYTHONPATH": ROOT, "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", *args], capture_output=True, text=True, env=env, timeout=120)


@pytest.mark.parametrize("module", ["postproc.plots", "postproc.vtk", "postproc.liquefaction", "postproc.ensemble"])
def test_help_and_a_folder_that_is_not_a_run(module, tmp_path):
    out = run(module, "--help")
    assert out.returncode == 0 and "usage:" in out.stdout and not out.stderr
    out = run(module, str(tmp_path))
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert out.stderr.strip().splitlines()[-1].endswith(("(no history.csv; give the --out folder of a run)",
                                                          "of a run with --starts N)")), out.stderr


def test_the_study_of_an_empty_folder_is_refused(tmp_path):
    out = run("postproc.liquefaction", "--study", str(tmp_path))
    assert out.returncode == 2 and "no finished case" in out.stderr and "make liquefaction" in out.stderr
    assert os.listdir(tmp_path) == []
