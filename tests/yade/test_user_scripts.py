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


CHECKS = """
from engines.yade.yade_io import raise_pending
from yade_scripts.examples import report
raise_pending()
checks = report(water, grains, walls)
print("CHECKS", checks["pores"], float(water.pressures().min()) / checks["E_w"], checks["max_U"] / checks["E_w"],
      checks["balance"], checks["outside"])
"""


def script(*parts):
    """The parts of a script, each dedented."""
    return "\n".join(textwrap.dedent(part) for part in parts)


def physical(p):
    """The script ran and its checks (yade_scripts.examples.report) are physical: pores, every U
    within +-E_w, the water balance at round-off, no grain out of the box."""
    assert p.returncode == 0, p.stderr[-3000:]
    line = next(ln for ln in p.stdout.splitlines() if ln.startswith("CHECKS")).split()[1:]
    pores, lo, hi, balance, outside = int(line[0]), *(float(v) for v in line[1:4]), int(line[4])
    assert pores > 0 and -1 <= lo and hi <= 1 and balance < 1e-11 and outside == 0, line
    return p


def refused(p, start):
    """The script was refused in one line (the last of stderr) beginning with ``start``."""
    assert p.returncode != 0
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith(start), p.stderr[-3000:]
    return last


def test_the_readmes_snippet_runs_physically_with_its_own_numbers(tmp_path):
    """README.md's WaterEngine lines as they stand (O.dt = 1e-6 s, E_w = 240 N/m, water_interval = 10,
    O.run(20000)) on viscel_column's column."""
    physical(run(tmp_path, script("""
        from engines.yade.yade_io import raise_pending
        bottom_ids, left_ids, right_ids, disc_ids = bottom, left, right, bottom + left + right + grains
        O.dt = 1e-6
        water = WaterEngine(disc_ids, walls={"bottom": bottom_ids, "left": left_ids, "right": right_ids},
                            settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4, transfer="conserving"),
                            l_m=1.3e-4, water_interval=10)
        O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
        O.run(20000, True)
        raise_pending()
        """, CHECKS)))


def engine(settings="E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4", extra=""):
    """A user's WaterEngine on the column with its runner in O.engines."""
    return f"""
        water = WaterEngine(bottom + left + right + grains, walls=walls, settings=WaterSettings({settings}),
                            l_m=1.3e-4{extra})
        O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
        """


def test_savetmp_loadtmp_reruns_the_same_steps(tmp_path):
    p = physical(run(tmp_path, script(engine(), """
        import numpy as np
        O.run(500, True)
        O.saveTmp("a")
        O.run(300, True)
        later = water.io.positions()
        O.loadTmp("a")
        O.run(300, True)
        print("SAME", np.array_equal(later, water.io.positions()))
        """, CHECKS)))
    assert "SAME True" in p.stdout


def test_o_dt_changed_by_the_script_runs_physically(tmp_path):
    physical(run(tmp_path, script(engine(extra=", water_interval=4"), """
        O.run(1000, True)
        O.dt = 0.5 * O.dt
        O.run(2000, True)
        O.dt = 2e-6
        O.run(1000, True)
        """, CHECKS)))


def test_a_global_stiffness_time_stepper_runs_physically_or_is_refused_in_one_line(tmp_path):
    """YADE's GlobalStiffnessTimeStepper sets O.dt as the run goes: the engine follows each change
    (its limits checked again); this column runs physically."""
    physical(run(tmp_path, script("""
        from yade.wrapper import GlobalStiffnessTimeStepper
        O.engines = O.engines[:1] + [GlobalStiffnessTimeStepper(timestepSafetyCoefficient=0.8,
                                                                timeStepUpdateInterval=50)] + O.engines[1:]
        """ + engine(), """
        O.run(3000, True)
        print("dt", O.dt)
        """, CHECKS)))


def test_a_gravity_ramp_is_followed_and_runs_physically(tmp_path):
    p = physical(run(tmp_path, script("""
        from yade.wrapper import PyRunner
        O.engines = O.engines[:-1] + [PyRunner(command="O.engines[-1].gravity = (0, 0, -9.81 * min(1.0, 0.2 + O.iter / 2000))",
                                               iterPeriod=100, initRun=True), O.engines[-1]]
        O.engines[-1].gravity = (0, 0, -0.2 * 9.81)
        """ + engine(), """
        import math
        O.run(3000, True)
        r = O.bodies[grains[0]].shape.radius
        print("RATIO", water.F_const[:, 1].max() / (1000.0 * math.pi * r**2 * 9.81))
        """, CHECKS)))
    assert abs(float(next(ln for ln in p.stdout.splitlines() if ln.startswith("RATIO")).split()[1]) - 1) < 1e-12


def test_inflow_velocity_runs_physically(tmp_path):
    physical(run(tmp_path, script(engine("E_w=240.0, k1=200.0, k2=2.0, inflow_velocity=0.05"), """
        O.run(3000, True)
        print("INFLOW", water.model.water.balance.inflow)
        """, CHECKS)))


def test_radii_in_millimetres_are_refused_in_one_line(tmp_path):
    refused(run(tmp_path, """
        from engines.yade.contract import set_disc_mass
        for i in bottom + left + right + grains:  # the column typed in millimetres as metres
            b = O.bodies[i]
            b.state.pos, b.shape.radius = 1e3 * b.state.pos, 1e3 * b.shape.radius
            set_disc_mass(b, b.material.density)
        water = WaterEngine(bottom + left + right + grains, walls=walls, settings=WaterSettings(), l_m=1.3e-4)
        """), "ValueError: l_m = 0.00013 m is 0.000289 x the median disc radius 0.45 m")


def test_a_disc_listed_twice_is_refused_in_one_line(tmp_path):
    refused(run(tmp_path, """
        water = WaterEngine(bottom + left + right + grains + grains[:1], walls=walls, settings=WaterSettings(),
                            l_m=1.3e-4)
        """), "engines.yade.contract.ContractError: body ")


def test_a_drained_flat_wall_without_k3_is_refused_in_one_line(tmp_path):
    refused(run(tmp_path, """
        from yade import utils
        box = O.bodies.append(utils.box((0.0, 0.0, -0.01), (0.1, 0.01, 0.005), fixed=True))
        water = WaterEngine(left + right + grains, walls={"left": left, "right": right}, settings=WaterSettings(),
                            l_m=1.3e-4, flat_walls={box: "drained"})
        """), "engines.yade.contract.ContractError: body ")
