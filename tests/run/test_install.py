"""`make deps` installs the project for Debian's python3: a script outside the tree imports it."""
import os
import subprocess

import pytest

from engines import ROOT, __version__


@pytest.mark.check
def test_a_script_outside_the_tree_imports_the_engine_without_pythonpath(tmp_path):
    script = tmp_path / "mine.py"
    script.write_text("import engines, packing, postproc\n"
                      "from engines.yade.water_engine import WaterEngine\n"
                      "print('ROOT', engines.ROOT, engines.__version__)\n")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run(["yade", "-n", "-x", str(script)], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-1500:]
    assert f"ROOT {ROOT} {__version__}" in out.stdout, "make install: another checkout is installed, or none"
