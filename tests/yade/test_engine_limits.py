"""What the WaterEngine reads of a YADE scene and refuses up front (docs/ENGINE.md, the contract):
the water step against the water-stiffness limit (at construction and when O.dt changes), gravity
from the NewtonIntegrator, periodic cells, repeated, erased and clumped discs, lengths in the
wrong unit, drained flat walls that pass no water."""
import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing)

from engines.model.limits import WaterStiffnessError
from engines.model.pore_water import WaterSettings
from engines.yade.contract import ContractError

STIFF = WaterSettings(E_w=2.4e6, k1=200.0, k2=2.0, q_w=5e-4)  # at dt = 1e-6 s: a few water steps of 1e-6 s only


def column(settings=STIFF, water_interval=1, **kw):
    """viscel_column's column (dt = 1e-6 s) with a WaterEngine over all its discs."""
    from yade import O

    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    O.engines = ex.engines()
    O.dt = 1e-6
    ids = kw.pop("ids", bottom + left + right + grains)
    if kw.pop("ids_drop_first", False):
        ids = ids[1:]
    walls = {"bottom": bottom, "left": left, "right": right, **kw.pop("walls_extra", {})}
    return WaterEngine(ids, walls=walls, settings=settings,
                       l_m=kw.pop("l_m", 1.3e-4), water_interval=water_interval, **kw)


def test_a_water_step_above_the_stiffness_limit_is_refused_naming_the_largest_water_interval():
    with pytest.raises(WaterStiffnessError, match=r"water-stiffness limit .* at construction") as e:
        column(water_interval=200)
    largest = int(str(e.value).split("water_interval= <= ")[1].split()[0])
    assert 1 <= largest < 200
    water = column(water_interval=largest)  # the remedy it names works
    with pytest.raises(WaterStiffnessError):
        column(water_interval=largest + 1)
    assert water.model.schedule.water_interval == largest


def test_a_larger_o_dt_is_checked_at_the_next_water_step():
    from yade import O
    water = column(water_interval=1)
    water.drive(5, lambda: False)
    O.dt = 50 * O.dt
    with pytest.raises(WaterStiffnessError, match=r"O.dt changed.*set WaterEngine water_interval= <= 0|reduce O.dt"):
        water.drive(5, lambda: False)


def test_water_interval_set_on_a_live_engine_is_checked_and_the_runner_follows():
    """water.water_interval = M between steps: above the stiffness limit refused naming the largest
    stable value (the old interval kept); a stable M takes effect at the next water step, the
    PyRunner then calls every M steps; not an integer >= 1: refused."""
    from yade import O
    water = column(water_interval=1)
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
    O.run(3, True)
    with pytest.raises(WaterStiffnessError, match=r"when water_interval was set at step 3 .*water_interval= <= "):
        water.water_interval = 200
    assert water.water_interval == 1
    with pytest.raises(WaterStiffnessError) as e:
        water.water_interval = 200
    largest = int(str(e.value).split("water_interval= <= ")[1].split()[0])
    assert largest >= 2
    water.water_interval = largest
    assert water.model.schedule.k_water == 3 and water.arguments["water_interval"] == largest
    calls = []
    seen = water.__class__.__call__

    def counted(self):
        calls.append(O.iter)
        seen(self)
    water.__class__.__call__ = counted
    try:
        O.run(2 * largest + 1, True)
    finally:
        water.__class__.__call__ = seen
    assert calls == [3, 3 + largest, 3 + 2 * largest]
    for bad in (0, 2.5, True):
        with pytest.raises(ValueError, match="water_interval = .*integer >= 1"):
            water.water_interval = bad


def test_buoyancy_follows_the_newton_integrators_gravity():
    from yade import O
    water = column(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), water_interval=1)
    lift = water.F_const[:, 1].copy()
    assert np.all(lift > 0) and np.all(water.F_const[:, 0] == 0)
    newton = O.engines[-1]
    newton.gravity = (1.0, 0.0, -2 * 9.81)  # a ramp's later value, tilted
    water.drive(1, lambda: False)
    np.testing.assert_allclose(water.F_const[:, 1], 2 * lift, rtol=1e-12)
    np.testing.assert_allclose(water.F_const[:, 0], -lift / 9.81, rtol=1e-12)  # -rho_w pi r^2 g_x
    newton.gravity = (0.0, 1.0, -9.81)
    with pytest.raises(ContractError, match="y component"):
        water.drive(1, lambda: False)


def test_no_integrator_and_no_gravity_given_is_refused():
    from yade import O
    with pytest.raises(ContractError, match="no NewtonIntegrator .* gravity=9.81"):
        _without_newton()
    water = _without_newton(gravity=9.81)
    assert water.F_const[:, 1].min() > 0
    assert O.dt > 0


def _without_newton(**kw):
    from yade import O

    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    O.engines = ex.engines()[:-1]
    O.dt = 1e-6
    return WaterEngine(bottom + left + right + grains, walls={"bottom": bottom}, settings=WaterSettings(E_w=240.0),
                       l_m=1.3e-4, **kw)


def test_a_periodic_cell_is_refused():
    from yade import O
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    O.engines = ex.engines()
    O.dt = 1e-6
    O.periodic = True
    from engines.yade.water_engine import WaterEngine
    with pytest.raises(ContractError, match="O.periodic is True.*O.periodic = False"):
        WaterEngine(bottom + grains, walls={"bottom": bottom}, settings=WaterSettings(), l_m=1.3e-4)


def test_repeated_and_erased_discs_are_refused_with_the_remedy():
    from yade import O
    with pytest.raises(ContractError, match="listed twice.*sorted\\(set\\(disc_ids\\)\\)"):
        column(ids=[0, 1, 1, 2])
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    O.bodies.erase(grains[0])
    from engines.yade.water_engine import WaterEngine
    O.engines = ex.engines()
    O.dt = 1e-6
    with pytest.raises(ContractError, match=f"body {grains[0]}: not in O.bodies \\(erased.*drop it"):
        WaterEngine(bottom + grains, walls={"bottom": bottom}, settings=WaterSettings(), l_m=1.3e-4)


def test_clumps_are_refused_naming_their_members_and_mass():
    from yade import O, utils
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    y = O.bodies[grains[0]].state.pos[1]
    clump, members = O.bodies.appendClumped([utils.sphere((0.05, y, 0.05), 5e-4), utils.sphere((0.051, y, 0.05), 5e-4)])
    O.engines = ex.engines()
    O.dt = 1e-6
    from engines.yade.water_engine import WaterEngine
    with pytest.raises(ContractError, match=f"a member of clump {clump} \\(members \\[{members[0]}, {members[1]}\\], "
                                            f"the clump's mass .* kg"):
        WaterEngine(bottom + grains + members, walls={"bottom": bottom}, settings=WaterSettings(), l_m=1.3e-4)


@pytest.mark.parametrize("l_m, eps_m, match", [(0.13, 0.0, "l_m = 0.13 m is .* x the median disc radius .* units"),
                                               (1e-9, 0.0, "outside 0.01-2 x it"),
                                               (1e-4, 2e-4, "eps_m = 0.0002 m exceeds l_m")])
def test_lengths_out_of_range_are_refused(l_m, eps_m, match):
    with pytest.raises(ValueError, match=match):
        column(WaterSettings(E_w=240.0), l_m=l_m, eps_m=eps_m)


def test_a_drained_flat_wall_without_k3_is_refused():
    from yade import O, utils
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    wall = O.bodies.append(utils.box((0.0, 0.0, -0.01), (0.1, 0.01, 0.005), fixed=True))
    O.engines = ex.engines()
    O.dt = 1e-6
    from engines.yade.water_engine import WaterEngine
    with pytest.raises(ContractError, match=f"body {wall}: a drained flat wall with k3 = 0.*k3 > 0.*'undrained'"):
        WaterEngine(grains, walls={}, settings=WaterSettings(), l_m=1.3e-4, flat_walls={wall: "drained"})


def _watched(path, monkeypatch, steps=800, water_interval=40):
    """(worst max |dA| / A, lowest U / E_w) the accuracy watch saw on viscel_column's column driven
    ``steps`` steps with water every ``water_interval`` steps on one path of WaterEngine."""
    from engines.yade import water_engine, yade_io
    if path in ("drive", "chunks") and yade_io.BACKEND != "yadebulk":
        pytest.skip("the compiled drive needs the bulk bridge (make ext)")
    if path == "kernel":
        monkeypatch.setattr(water_engine, "water_path", lambda compiled, bridge=False: "kernel")
    water = column(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), water_interval=water_interval,
                   compiled=path != "python", accept_inaccurate=True)
    water.drive(steps, None if path == "chunks" else (lambda: False))
    monkeypatch.undo()
    return water.model.watch.worst, water.model.watch.lowest


def test_the_accuracy_watch_sees_every_water_step_on_every_path(monkeypatch):
    """The NumPy model (Python at each water step), kernels.water_step between Python's reads and
    writes, the compiled drive one water step a call (a PyRunner's path) and in chunks of many
    water steps: the watch sees the same largest area change and lowest U (the chunks' water steps
    compared one with the next inside the kernel, kernels.watch_areas)."""
    worst, lowest = _watched("python", monkeypatch)
    assert 1e-4 < worst < 0.5
    for path in ("kernel", "drive", "chunks"):
        got = _watched(path, monkeypatch)
        np.testing.assert_allclose(got, (worst, lowest), rtol=1e-6, atol=1e-12, err_msg=path)


def test_the_compiled_drive_stops_at_an_area_change_above_the_stop_threshold():
    """A water step far too long for the discs' motion, run in the compiled drive's chunks: stopped
    by the watch (AccuracyError naming water_interval) unless accepted."""
    from engines.model.limits import AccuracyError
    from engines.yade import yade_io
    if yade_io.BACKEND != "yadebulk":
        pytest.skip("the compiled drive needs the bulk bridge (make ext)")
    water = column(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), water_interval=10)
    water.model.watch.warn = water.model.watch.stop = 1e-5
    with pytest.raises(AccuracyError, match="in one water step of 1e-05 s .*water_interval"):
        water.drive(400)


def test_unknown_wall_groups_walls_outside_disc_ids_and_no_o_dt_are_refused():
    from yade import O
    with pytest.raises(ValueError, match=r"walls: unknown group 'top'; known: \['bottom', 'left', 'right'\]"):
        column(WaterSettings(E_w=240.0), walls_extra={"top": [0]})
    with pytest.raises(ValueError, match=r"walls\['bottom'\]: ids \[0\] are not among disc_ids"):
        column(WaterSettings(E_w=240.0), ids_drop_first=True)
    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    O.engines = ex.engines()
    O.dt = 0.0
    with pytest.raises(ValueError, match="set O.dt before creating the WaterEngine"):
        WaterEngine(bottom + grains, walls={"bottom": bottom}, settings=WaterSettings(E_w=240.0), l_m=1.3e-4)
