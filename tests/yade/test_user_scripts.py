"""Scripts a YADE user writes from README.md, run as `yade -n -x` processes (marked ``check``): each
runs physically or is refused in one line naming the cause and a remedy."""
import os
import subprocess
import textwrap

import pytest

from engines import ROOT

pytestmark = pytest.mark.check

HEAD = """
from yade import O
from engines.model.pore_water import WaterSettings
from engines.yade.water_engine import WaterEngine
from yade_scripts.examples import viscel_column as ex
bottom, left, right, grains = ex.build_column()
O.engines = ex.engines()
O.dt = 1e-6
walls = {"bottom": bottom, "left": left, "right": right}
"""


def run(tmp_path, body):
    path = tmp_path / "user_script.py"
    path.write_text(textwrap.dedent(HEAD) + textwrap.dedent(body))
    return subprocess.run(["yade", "-n", "-x", str(path)], capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, PYTHONPATH=ROOT), cwd=tmp_path)


def test_a_stiff_water_at_the_readmes_water_interval_is_refused_up_front_naming_water_interval(tmp_path):
    """E_w = 2.4e5 N/m with water every 100 steps: refused at construction, before any step, with the
    largest stable water_interval and a margin; the margin then runs with every U within +-E_w."""
    p = run(tmp_path, """
        water = WaterEngine(bottom + left + right + grains, walls=walls, settings=WaterSettings(E_w=2.4e5, q_w=5e-4),
                            l_m=1.3e-4, water_interval=100)
        """)
    assert p.returncode != 0
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith("engines.model.limits.WaterStiffnessError: water step 0.0001 s (WaterEngine "
                           "water_interval= 100 x O.dt 1e-06 s) exceeds the water-stiffness limit"), last
    largest, margin = (int(v) for v in last.split("water_interval= <= ")[1].split(" (")[0:1] +
                       [last.split(" leaves a margin")[0].split("(")[-1]])
    assert 1 <= margin == largest // 2
    p = run(tmp_path, f"""
        water = WaterEngine(bottom + left + right + grains, walls=walls, settings=WaterSettings(E_w=2.4e5, q_w=5e-4),
                            l_m=1.3e-4, water_interval={margin})
        water.drive(3000)
        U = water.pressures()
        print("U/E_w", U.min() / 2.4e5, U.max() / 2.4e5, "balance", water.model.water.balance_error())
        """)
    assert p.returncode == 0, p.stderr[-2000:]
    line = next(ln for ln in p.stdout.splitlines() if ln.startswith("U/E_w"))
    lo, hi, err = (float(v) for v in line.split()[1:3] + line.split()[4:])
    assert -1 <= lo and hi <= 1 and err < 1e-12


def test_buoyancy_under_a_strong_gravity_is_that_gravity(tmp_path):
    """NewtonIntegrator(gravity = 50 g): the buoyancy on each grain is rho_w pi r^2 x 50 g."""
    p = run(tmp_path, """
        O.engines[-1].gravity = (0, 0, -50 * 9.81)
        water = WaterEngine(bottom + left + right + grains, walls=walls, settings=WaterSettings(), l_m=1.3e-4)
        import math
        r = O.bodies[grains[0]].shape.radius
        print("ratio", water.F_const[:, 1].max() / (1000.0 * math.pi * r**2 * 50 * 9.81))
        """)
    assert p.returncode == 0, p.stderr[-2000:]
    assert abs(float(next(ln for ln in p.stdout.splitlines() if ln.startswith("ratio")).split()[1]) - 1) < 1e-12


def test_a_periodic_scene_is_refused_in_one_line(tmp_path):
    p = run(tmp_path, """
        O.periodic = True
        water = WaterEngine(bottom + left + right + grains, walls=walls, settings=WaterSettings(), l_m=1.3e-4)
        """)
    assert p.returncode != 0
    assert p.stderr.strip().splitlines()[-1].startswith("engines.yade.contract.ContractError: O.periodic is True")
