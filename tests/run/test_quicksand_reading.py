"""The quick sand's reading judged in docs/READINGS.md (E8), from a fresh ensemble: the bottom band's
r_u where its contacts let go (the heave's onset) lies in 0.8-1.2, its 95 % interval over 8 perturbed
starts; the same command as `make readings`, run to the onset only (4 ms), about a minute."""
import os
import subprocess

import pytest

from engines import ROOT
from postproc.readings import RU_HEAVE, quicksand_ru


@pytest.mark.check
def test_the_bottom_band_lets_go_at_r_u_near_1(tmp_path):
    out = tmp_path / "qs"
    done = subprocess.run(["yade", "-n", "-x", os.path.join(ROOT, "yade_scripts", "quicksand.py"), "--case", "1",
                           "--starts", "8", "--quiet", "--duration", "0.004",
                           "--out", str(out)], cwd=tmp_path, env=dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg"),
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    onset = quicksand_ru(str(out))["band1"]["heave_onset"]
    assert onset["t_s"]["n"] == 8 and onset["t_s"]["ci95_high"] < 0.004
    assert RU_HEAVE[0] <= onset["ru"]["ci95_low"] and onset["ru"]["ci95_high"] <= RU_HEAVE[1], onset["ru"]
