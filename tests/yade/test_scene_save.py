"""A WaterEngine's water through YADE's O.save/O.load and O.saveTmp/O.loadTmp (engines.yade.scene_save)."""
import base64
import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing)

from engines.model import state as named_state
from engines.yade import checkpoint, scene_save, yade_io

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
COLUMN = """
import sys
sys.path.insert(0, {root!r})
import numpy as np
from yade import O
from engines.model.pore_water import WaterSettings
from tests.yade.test_water_engine import column_engine
water = column_engine(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4, transfer="conserving"), 1000, 10, 3e-5)
O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
"""


def column():
    from yade import O
    exec(COLUMN.format(root=ROOT), ns := {})
    return ns["water"], O


def test_savetmp_loadtmp_restores_the_water_and_the_run_repeats_bit_for_bit():
    """O.saveTmp between two water steps, 700 steps, O.loadTmp, the same 700 steps: the same centres and pressures (the
    engine's water restored from O.tags, not run on with the later water)."""
    water, O = column()
    O.run(505, True)  # between two water steps (every 10)
    O.saveTmp("sv")
    O.run(700, True)
    xz, U = water.io.positions(), water.pressures().copy()
    O.loadTmp("sv")
    assert O.iter == 505
    O.run(700, True)
    yade_io.raise_pending()
    np.testing.assert_array_equal(water.io.positions(), xz)
    np.testing.assert_array_equal(water.pressures(), U)
    assert water.model.water.balance_error() < 1e-12


def test_a_new_engine_on_a_loaded_scene_says_its_water_starts_afresh(capsys):
    from engines.yade.water_engine import WaterEngine
    water, O = column()
    O.run(100, True)
    O.saveTmp("afresh")
    capsys.readouterr()
    WaterEngine(**water.arguments).runner()  # a second engine beside a running one: nothing to say
    assert "starts afresh" not in capsys.readouterr().err
    O.loadTmp("afresh")
    WaterEngine(**water.arguments).runner()
    assert "hold saved water (a loaded scene); this new engine's water starts afresh" in capsys.readouterr().err


def test_a_scene_gone_back_without_a_load_is_refused_in_one_line():
    """O.iter set back (no load, no saved water of that step): the engine stops and names what to do."""
    water, O = column()
    O.run(300, True)
    O._sceneObj.updateAttrs({"iter": 100})
    O.run(20, True)
    with pytest.raises(scene_save.RestoreError, match=r"no saved water .* make the WaterEngine again") as e:
        yade_io.raise_pending()
    assert "\n" not in str(e.value)
    O.saveTmp("back")  # the tag of another step than the scene's: refused too
    O._sceneObj.updateAttrs({"iter": 50})
    O.loadTmp("back")
    O._sceneObj.updateAttrs({"iter": 40})
    O.run(20, True)
    with pytest.raises(scene_save.RestoreError, match=r"holds the water of step 10\d, the scene is at step 40"):
        yade_io.raise_pending()


def test_the_tag_is_the_checkpoint_format_and_a_pickle_is_refused_unread():
    water, O = column()
    O.run(30, True)
    text = scene_save.encode(water, O.iter)
    ck = scene_save.decode("tag", text)
    assert ck.step == O.iter and ck.info == {"what": "WaterEngine"} and ck.recipe["l_m"] == 1.3e-4
    stored = named_state.state_of(water)
    assert sorted(ck.state) == sorted(stored)
    for name, value in stored.items():
        np.testing.assert_array_equal(ck.state[name], value)
    evil = base64.b64encode(pickle.dumps({"a": 1})).decode()
    with pytest.raises(checkpoint.CheckpointError, match="not a checkpoint"):
        scene_save.decode("tag", evil)
    with pytest.raises(checkpoint.CheckpointError, match="not base64"):
        scene_save.decode("tag", "%%%")


def yade_script(tmp_path, name, text, env=None):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return subprocess.run(["yade", "-n", "-x", str(path)], capture_output=True, text=True, timeout=600, cwd=tmp_path,
                          env={**os.environ, "OMP_NUM_THREADS": "1", **(env or {})})


@pytest.mark.check
def test_o_load_in_a_new_process_restores_the_water(tmp_path):
    """A script saves its scene (O.save) and runs on; a new process O.load's it and runs the same
    steps: the same centres to the bit; with the tag emptied it stops in one line, exit status 1."""
    save = yade_script(tmp_path, "save.py", COLUMN.format(root=ROOT) + textwrap.dedent("""
        O.run(505, True)
        O.save("scene.yade.gz")
        O.run(300, True)
        np.save("xz.npy", water.io.positions())
        """))
    assert save.returncode == 0, save.stderr[-2000:]
    load = yade_script(tmp_path, "load.py", f"""
        import sys
        sys.path.insert(0, {ROOT!r})
        import numpy as np
        from yade import O
        O.load("scene.yade.gz")
        O.run(300, True)
        from engines.yade import scene_save, yade_io
        yade_io.raise_pending()
        water = scene_save.engine("water")
        assert np.array_equal(water.io.positions(), np.load("xz.npy"))
        assert water.model.water.balance_error() < 1e-12
        print("RESTORED")
        """)
    assert load.returncode == 0 and "RESTORED" in load.stdout, load.stderr[-2000:]
    lost = yade_script(tmp_path, "lost.py", f"""
        import sys
        sys.path.insert(0, {ROOT!r})
        from yade import O
        O.load("scene.yade.gz")
        for k in list(O.tags.keys()):
            if k.startswith("pore_water:"):
                O.tags[k] = ""  # (O.tags has no del)
        O.run(30, True)
        """)
    assert lost.returncode == 1
    assert lost.stderr.strip().splitlines()[-1].startswith("error inside a YADE engine, never raised by the script: "
                                                           "RestoreError: O.tags['pore_water:water-")
    assert "not a checkpoint (not a NumPy .npz file): make the WaterEngine again" in lost.stderr


def test_a_runner_whose_engine_is_not_in_this_process_stops_in_one_line():
    """A PyRunner of yade_io.py_runner (PaperLawEngine) loaded in another process: its key is unknown here."""
    yade_io.call("paper-law-0123456789ab")
    with pytest.raises(RuntimeError, match=r"made in another process .* make the engine again") as e:
        yade_io.raise_pending()
    assert "\n" not in str(e.value)


def test_a_py_runner_calls_its_callback_through_its_module():
    """yade_io.py_runner (PaperLawEngine's runner): the command imports the project's module, no builtins."""
    import builtins

    from yade import O
    O.reset()
    calls = []
    O.engines = [yade_io.py_runner(lambda: calls.append(O.iter), 2, "probe")]
    O.dt = 1e-6
    O.run(5, True)
    yade_io.raise_pending()
    assert calls == [0, 2, 4]
    assert "import engines.yade.yade_io as _pw" in O.engines[0].command
    assert not hasattr(builtins, "_pore_dem_engines")


def _driven():
    """viscel_column's column with a WaterEngine driven from Python (no runner, so no saved water)."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    from tests.yade.test_engine_limits import column as limits_column
    return limits_column(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), water_interval=10), O


@pytest.mark.parametrize("stop", [None, lambda: False], ids=["chunks", "python"])
def test_an_earlier_scene_loaded_without_the_engines_water_stops_drive_in_one_line(stop):
    """O.saveTmp, drive on, O.loadTmp: the engine (its water of the later step, no runner, no tag)
    stops at once naming the two ways out, whether drive steps from Python or in compiled chunks."""
    water, O = _driven()
    water.drive(50, stop)
    O.saveTmp("earlier")
    water.drive(50, stop)
    O.loadTmp("earlier")
    with pytest.raises(scene_save.RestoreError, match=r"went back from step 100 to step 50 .*scene_save.*make the "
                                                      r"WaterEngine again") as e:
        water.drive(10, stop)
    assert "\n" not in str(e.value) and O.iter == 50


def test_centres_that_jump_between_water_steps_stop_the_engine_but_a_dry_run_does_not():
    """A grain put 0.8 of its radius away between two water steps (drive, or the PyRunner: the error
    pauses YADE and raise_pending raises it) is refused naming it; steps run without the engine
    (more than a water interval) are not a jump."""
    water, O = _driven()
    water.drive(20)
    g = int(water.io.ids[water._dynamic[-1]])
    r = water.model.r[water._dynamic[-1]]
    p = O.bodies[g].state.pos
    O.bodies[g].state.pos = (p[0] + 0.8 * r, p[1], p[2])
    with pytest.raises(scene_save.RestoreError, match=f"body {g}: moved .* \\(0.8 of its radius\\) since the water "
                                                      f"step"):
        water.drive(5)
    O.bodies[g].state.pos = p
    water.drive(5)
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
    O.run(15, True)
    O.bodies[g].state.pos = (p[0], p[1], p[2] + 0.8 * r)
    O.run(20, True)
    with pytest.raises(scene_save.RestoreError, match=f"body {g}: moved"):
        yade_io.raise_pending()
    O.bodies[g].state.pos = p
    O.engines = [e for e in O.engines if type(e).__name__ != "PyRunner"]
    O.run(500, True)  # dry steps: the grains settle on without the water
    water.drive(10)
