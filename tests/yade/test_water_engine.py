"""The public engines in YADE scenes: WaterEngine with YADE's own laws, law = "yade" scenes."""
import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing)

from engines.model import pores as pg
from engines.model.pore_dem import side_wall_ties
from engines.reference.model import simulate_reference
from engines.run import scene as scenes
from engines.yade.coupling import YadeCoupling, simulate
from engines.yade.deposition import scene_packing
from packing.packing import Packing


@pytest.fixture(scope="module")
def packing():
    return scene_packing(scenes.preset("quicksand_case1"))


def test_example_script_inflow_raises_the_bottom_pressure():
    """yade_scripts/examples/viscel_column.py: YADE's collider and ViscEl law, water every 10 steps."""
    from yade import O

    from yade_scripts.examples.viscel_column import main
    water = main(["--steps", "3000"])
    net, U = water.model.water.net, water.pressures()
    assert O.iter == 3000 and water.k == 2990  # the runner ran every 10 steps, the last at 2990
    assert U[net.pore_touches["bottom"]].mean() > 10 * max(abs(U[net.pore_surface].mean()), 1e-3)
    assert water.model.water.balance_error() < 1e-12
    # pressure forces plus buoyancy are held as permanent forces on the grains only
    grain = water._dynamic[0]
    bid = int(water.io.ids[grain])
    r = O.bodies[bid].shape.radius
    expected = water.model.F[grain] + [0.0, 1000.0 * np.pi * r**2 * 9.81]
    np.testing.assert_allclose([O.forces.permF(bid)[0], O.forces.permF(bid)[2]], expected, rtol=1e-12, atol=1e-15)
    assert O.forces.permF(int(water.io.ids[0])).norm() == 0  # a wall disc


def test_the_engine_replaces_a_users_permanent_forces_on_its_dynamic_discs():
    """On its dynamic discs the engine sets the permanent force (docs/ENGINE.md): a user's own
    setPermF there is replaced at the next water step, y component included; on its fixed discs
    (walls) it is kept."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    water = column_engine(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), 1000, 1)
    grain = water._dynamic[0]
    bid = int(water.io.ids[grain])
    O.forces.setPermF(bid, (1.0, 2.0, 3.0))
    O.step()
    water()
    O.step()  # YADE's permanent forces are read back after a step
    r = O.bodies[bid].shape.radius
    F = water.model.F[grain] + [0.0, 1000.0 * np.pi * r**2 * 9.81]
    P = O.forces.permF(bid)
    np.testing.assert_allclose([P[0], P[1], P[2]], [F[0], 0.0, F[1]], rtol=1e-12, atol=1e-15)
    assert O.forces.permF(int(water.io.ids[0])).norm() == 0  # a wall disc: the engine leaves it alone
    O.forces.setPermF(int(water.io.ids[0]), (1.0, 2.0, 3.0))
    water()
    O.step()
    assert tuple(O.forces.permF(int(water.io.ids[0]))) == (1.0, 2.0, 3.0)


def test_water_engine_with_frictmat_cundallstrack(packing):
    """The engine does not care which YADE law moves the discs."""
    from yade import O, utils
    from yade.wrapper import (
        Bo1_Sphere_Aabb,
        ForceResetter,
        FrictMat,
        Ig2_Sphere_Sphere_ScGeom,
        InsertionSortCollider,
        InteractionLoop,
        Ip2_FrictMat_FrictMat_FrictPhys,
        Law2_ScGeom_FrictPhys_CundallStrack,
        NewtonIntegrator,
    )

    from engines.model.pore_water import WaterSettings
    from engines.yade.contract import set_disc_mass
    from engines.yade.water_engine import WaterEngine
    O.reset()
    mat = O.materials.append(FrictMat(young=3e9, poisson=0.25, frictionAngle=0.5, density=2700))
    ids = []
    for (x, z), r, mob in zip(packing.xz, packing.r, packing.mobile):
        b = utils.sphere((x, 0, z), r, fixed=not mob, material=mat)
        set_disc_mass(b, 2700)
        if mob:
            b.state.blockedDOFs = "yXZ"
        ids.append(O.bodies.append(b))
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                                 [Law2_ScGeom_FrictPhys_CundallStrack()]), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 1e-6
    groups = {name: [i for i, g in zip(ids, packing.group) if g == code] for name, code in
              (("bottom", 1), ("left", 2), ("right", 3))}
    water = WaterEngine(ids, groups, WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), l_m=1.3e-4, water_interval=5)
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
    for _ in range(1000):
        O.step()
    U = water.pressures()
    net = water.model.water.net
    assert U[net.pore_touches["bottom"]].mean() > 20.0
    assert water.model.water.balance_error() < 1e-12



def column_engine(settings, rebuild_interval, water_interval, rebuild_distance=0.0):
    """viscel_column's column in a fresh scene (dt = 1e-6 s) with a WaterEngine over all its discs
    (rebuilt every rebuild_interval steps only, unless rebuild_distance [m] > 0)."""
    from yade import O

    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    O.engines = ex.engines()
    O.dt = 1e-6
    return WaterEngine(bottom + left + right + grains, walls={"bottom": bottom, "left": left, "right": right},
                       settings=settings, l_m=1.3e-4, rebuild_interval=rebuild_interval, water_interval=water_interval,
                       rebuild_distance=rebuild_distance)


def run_as(water, how, n):
    """n steps with the engine as a PyRunner under O.run ("runner"), or by drive from Python
    ("python": a stop function keeps it there) or compiled between rebuilds ("compiled")."""
    from yade import O
    if how == "runner":
        O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
        O.run(n, True)
    else:
        water.drive(n, (lambda: False) if how == "python" else None)


@pytest.mark.parametrize("water_interval, smoothing, k1, k3", [(10, False, 200.0, 100.0), (1, True, 5.8e5, 0.0)])
def test_drive_is_the_runner_without_the_pyrunner(water_interval, smoothing, k1, k3):
    """WaterEngine.drive(n) (the engine before O.step on its steps), in Python and compiled between
    rebuilds (kernels.water_drive_bulk_io), and the PyRunner with O.run(n) give the same run bit for
    bit: viscel_column's column with two rebuilds; water every 10 steps with drained sides, or
    every step with the eq 45-46 smoothing and a k1 at which one water step needs sub-steps."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    from engines.yade import yade_io
    runs = []
    for how in ("runner", "python", "compiled"):
        water = column_engine(WaterSettings(E_w=240.0, k1=k1, k2=2.0, k3=k3, q_w=5e-4, smoothing=smoothing, substep=True,
                                            sides="drained" if k3 else "undrained"), 500, water_interval)
        chunks = []
        if how == "compiled":
            compiled = water._drive_compiled
            water._drive_compiled = lambda n: chunks.append(n) or compiled(n)
        run_as(water, how, 1205)
        b = water.model.water.balance
        runs.append((O.iter, water.k, water.model.n_rebuilds, water.model.substeps_total, water.io.positions(),
                     water.model.water.W.copy(), (b.inflow, b.surface_outflow, b.side_outflow), water.model.last_limit))
    last = 1200 if water_interval == 10 else 1204
    assert runs[0][:3] == (1205, last, 2)
    if k1 > 1e3:
        assert runs[0][3] > 0  # some water steps were sub-stepped
    assert min(runs[0][6]) > 0 if k3 else runs[0][6][2] == 0  # every balance term counts
    for other in runs[1:]:
        assert other[:4] == runs[0][:4]
        assert np.array_equal(other[4], runs[0][4]) and np.array_equal(other[5], runs[0][5])
        assert other[6:] == runs[0][6:]
    if yade_io.BACKEND == "yadebulk":
        assert len(chunks) >= 3  # the compiled loop ran between the rebuilds


def test_dry_yade_law_scene_runs_no_python_engine(packing):
    from yade import O
    from yade.wrapper import PyRunner
    sc = scenes.preset("quicksand_case1", {"contact": {"law": "yade", "spring": "a"}, "water": {"enabled": False}})
    YadeCoupling(sc, packing)
    assert not any(isinstance(e, PyRunner) for e in O.engines)
    wet = scenes.preset("quicksand_case1", {"contact": {"law": "yade", "spring": "a"},
                                            "numerics": {"water_interval": 10}})
    cp = YadeCoupling(wet, packing)  # the water engine is called before O.step on its steps
    assert not any(isinstance(e, PyRunner) for e in O.engines)
    asked = []
    assert cp.run(35, stop=lambda: asked.append(O.iter) and False)  # a stop is asked between compiled calls
    assert cp.water_engine.k == 30 and O.iter == 35 and asked and asked[-1] <= 35
    cp.run(35)  # compiled between rebuilds with the bridge: the same water steps
    assert cp.water_engine.k == 60 and O.iter == 70
    assert not cp.run(5000, stop=lambda: O.iter > 70) and 70 < O.iter < 5070  # and ends the run early


def test_yade_law_refuses_springs_c_and_d():
    with pytest.raises(scenes.SceneError, match=r"\[contact\] spring = 'c'.*law = 'yade'"):
        scenes.preset("quicksand_case1", {"contact": {"law": "yade"}})


def test_yade_law_head_on_collision_matches_the_paper_law():
    """Where the two laws coincide (spring a, two discs, g = 0, no separation adjustment), YADE's
    ViscEl law with the mapped constants follows the reference to 1e-3 of a radius (measured
    2.5e-4) while the discs touch: YADE clamps the normal force at zero where eq 6 lets the dashpot
    pull (YADE: e = 0.798, eq 4-6: 0.789, analytic 0.790), so the restitutions agree to 2 % only. A wrong factor 2 in the kn/eta_n mapping
    moves e by > 5 % and the path by far more."""
    from engines.run.crosscheck import R, contact_scene, launcher_packing, restitution
    sc = contact_scene("head_on_yade", spring="a", separation_adjustment=False).with_overrides({"contact": {"law": "yade"}})
    pk = launcher_packing()
    ty = simulate(sc, pk, 2500, 10)
    tr = simulate_reference(sc, pk, 2500, 10)
    x_y, x_r = ty.arrays()[1], tr.arrays()[1]
    gap = x_r[:, 2, 0] - x_r[:, 1, 0] - 2 * R
    touched = np.flatnonzero(gap < 0)
    assert len(touched) > 5
    before = slice(0, touched[-1])  # up to the last sample with A and B in contact
    assert np.max(np.abs(x_y[before] - x_r[before])) / R < 1e-3
    assert abs(restitution(ty) - restitution(tr)) < 0.02 * restitution(tr)


def _fused_and_general(sc, packing, n=200):
    """The same run of n steps through PaperLawEngine.drive four ways: many steps in one compiled
    call where it can (kernels.dem_drive_bulk_io), the same with the forces held as permanent
    forces (ForceResetter first in the engine list, as a user's script may have it), one compiled
    call a step (the drive with n = 1, as with hooks) and the general path only: (x, v, omega, pair-list builds, W,
    O.iter) of each, the steps the first three made in compiled calls, and the pair lists that
    the first one's compiled calls rebuilt themselves (kernels.near_pairs inside the drive)."""
    from yade import O
    from yade.wrapper import ForceResetter

    from engines.yade import yade_io
    runs, compiled_steps, kernel_lists = [], [], 0
    for how in ("many", "held", "one", "general"):
        cp = YadeCoupling(sc, packing)
        assert yade_io.forces_reset_after_newton(O.engines)  # the coupling's list: no permanent forces
        if how == "held":
            newton = O.engines[0]
            newton.warnNoForceReset = True
            O.engines = [ForceResetter(), newton]
            assert not yade_io.forces_reset_after_newton(O.engines)
        cp.core.contact.skin = 1e-11  # pair lists rebuilt often, the bed at rest too (the skin changes no force)
        counted = 0
        if how == "general":
            cp.core.kernel_drive_args = lambda rows, held, n: None
        else:
            drive = cp.engine._drive_dem

            def many(*args):
                nonlocal counted, kernel_lists
                out = drive(*args)
                counted += out[0]
                kernel_lists += out[5] if how == "many" else 0
                return out
            cp.engine._drive_dem = many
        if how == "one":  # a hook: one step a compiled call, its O.step() made after the hook
            cp.engine.hooks.append(lambda: None)
        cp.run(n)
        runs.append((cp.positions(), cp.velocities(), cp.core.omega.copy(), cp.core.contact.list_builds,
                     None if cp.water is None else cp.water.W.copy(), O.iter))
        compiled_steps.append(counted)
    return runs, compiled_steps[:3], kernel_lists


def _assert_same_runs(runs, n=200):
    x0, v0, w0, b0, W0, k0 = runs[-1]
    for x1, v1, w1, b1, W1, k1 in runs[:-1]:
        assert k1 == k0 == n and b1 == b0 > 5
        np.testing.assert_array_equal(x1, x0)
        np.testing.assert_array_equal(v1, v0)
        np.testing.assert_array_equal(w1, w0)
        if W0 is not None:
            np.testing.assert_array_equal(W1, W0)


@pytest.mark.parametrize("law_override", [{}, {"water": {"enabled": False}}])
def test_paper_law_compiled_steps_equal_the_general_path(packing, law_override):
    """PaperLawEngine.drive runs many steps in one compiled call (kernels.dem_drive_bulk_io), or
    one step a call (with hooks) where it can; the general path
    (PoreDEM.step between yade_io calls) gives the same run, bit for bit, through pair-list and
    pore rebuilds and steps without water, and so do the forces held as permanent forces."""
    over = {"numerics": {"rebuild_interval": 60, "water_interval": 3}}
    over.update(law_override)
    runs, compiled_steps, kernel_lists = _fused_and_general(scenes.preset("quicksand_case1", over), packing)
    _assert_same_runs(runs)
    assert kernel_lists == runs[0][3] - 1  # every list but the first step's rebuilt inside the compiled calls
    assert min(compiled_steps) > 150


def test_seismic_compiled_steps_with_side_wall_ties_equal_the_general_path():
    """The seismic box (liquefaction_case1: base shaken, side walls on the springs of Fig. 27)
    takes the compiled steps too (kernels.tie_forces, the base motion and the walls' velocity
    inside dem_drive_bulk_io), and the run is bit for bit that of the general path
    (SideWallTies.forces in NumPy, BaseMotion in Python), the side walls and the base moving."""
    sc = scenes.preset("liquefaction_case1", {"numerics": {"rebuild_interval": 60, "water_interval": 3}})
    packing = Packing.load(sc.packing.file)
    runs, compiled_steps, kernel_lists = _fused_and_general(sc, packing)
    _assert_same_runs(runs)
    assert kernel_lists == runs[0][3] - 1  # every list but the first step's rebuilt inside the compiled calls
    assert min(compiled_steps) > 150
    side = side_wall_ties(sc.settings, packing).moving
    assert np.all(runs[0][0][side, 0] != packing.xz[side, 0]) and np.all(runs[0][1][side, 0] != 0)
    bottom = packing.group == pg.WALL_BOTTOM
    assert np.all(runs[0][0][bottom, 0] > packing.xz[bottom, 0])


def test_compiled_steps_leave_a_disc_set_free_to_the_velocity_adjustment():
    """The head-on collision with the eq 18-24 adjustment: the compiled runs of steps adjust the
    velocities of the discs the separation sets free (kernels.separation_velocities, -Vn''/Vn = e)
    without leaving the compiled call, and the run is bit for bit that of the other paths (the
    NumPy adjustment)."""
    from engines.run.crosscheck import contact_scene, launcher_packing
    sc = contact_scene("head_on_adjusted", spring="a", separation_adjustment=True)
    runs, compiled_steps, kernel_lists = _fused_and_general(sc, launcher_packing(), n=2500)
    _assert_same_runs(runs, n=2500)
    assert kernel_lists == runs[0][3] - 1  # every list but the first step's rebuilt inside the compiled calls
    assert min(compiled_steps) > 2000
    assert compiled_steps[0] == 2499  # all but the first step (du = 0): none finished in Python
    v = runs[0][1]
    assert v[2, 0] > v[1, 0] > 0  # B ahead of A, both on their way after the collision


def test_the_engine_rebuilds_on_the_schedule_of_the_paper_law():
    """Water every 3 steps, pores every 10: the engine rebuilds at the first water step at or after
    each multiple of 10 (12, 21, 30, 42, 51, 60; the schedule does not drift by the 2 steps a
    rebuild comes late), run by the PyRunner, by drive in Python and by drive compiled."""

    from engines.model.pore_water import WaterSettings
    expected = [min(k for k in range(0, 100, 3) if k >= 10 * n) for n in range(1, 7)]
    assert expected == [12, 21, 30, 42, 51, 60]
    for how in ("runner", "python", "compiled"):
        water = column_engine(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), 10, 3)
        built, rebuild = [], water.model.rebuild
        water.model.rebuild = lambda xz, k=None: built.append(k) or rebuild(xz, k)
        run_as(water, how, 63)
        assert built == expected, how


def test_rebuilds_by_displacement_are_the_same_run_by_the_runner_and_by_drive():
    """With a rebuild_distance d of 1 um (the column settles by several d in 1205 steps) and no
    interval within reach: the pores are rebuilt at water steps at which a disc is farther than d
    from its built centre, and the PyRunner, drive in Python and drive compiled (stopping before
    those steps) give the same run bit for bit."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    from engines.yade import yade_io
    d, runs, chunks = 1e-6, [], []
    for how in ("runner", "python", "compiled"):
        water = column_engine(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), 10**6, 5, rebuild_distance=d)
        if how == "compiled":
            compiled = water._drive_compiled
            water._drive_compiled = lambda n: chunks.append(n) or compiled(n)
        built, rebuild = [], water.model.rebuild
        water.model.rebuild = lambda xz, k=None: built.append((k, water.model.max_sq_moved(xz))) or rebuild(xz, k)
        run_as(water, how, 1205)
        runs.append(([k for k, _ in built], O.iter, water.io.positions(), water.model.water.W.copy()))
        assert all(moved > d * d and (k - water.model.schedule.k0) % 5 == 0 for k, moved in built), how
    assert len(runs[0][0]) >= 3
    if yade_io.BACKEND == "yadebulk":
        assert len(chunks) > len(runs[0][0])  # the compiled loop ran, stopped before each of them
    for other in runs[1:]:
        assert other[:2] == runs[0][:2]
        assert np.array_equal(other[2], runs[0][2]) and np.array_equal(other[3], runs[0][3])


def test_a_void_area_out_of_range_rebuilds_the_same_in_the_runner_and_in_drive():
    """A grain pushed by hand 0.4 of its radius into its neighbour after the engine is made (a void
    area below 0; d = 1 m is not reached): the first water step rebuilds the pores, in the PyRunner,
    drive in Python and drive compiled (kernels.water_step answers AREAS_OUT_OF_RANGE and the
    compiled loop stops before it), to the same run bit for bit, every area in range after."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    from engines.model.schedule import areas_in_range
    runs = []
    for how in ("runner", "python", "compiled"):
        water = column_engine(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), 10**6, 5, rebuild_distance=1.0)
        grain = O.bodies[int(water.io.ids[-1])]
        pos = grain.state.pos
        pos[0] -= 0.4 * grain.shape.radius
        grain.state.pos = pos
        m = pg.measure(water.model.water.net, water.io.positions(), water.model.r)
        assert not areas_in_range(m.void_area, m.polygon_area)
        built, rebuild = [], water.model.rebuild
        water.model.rebuild = lambda xz, k=None: built.append(k) or rebuild(xz, k)
        k0 = O.iter
        run_as(water, how, 50)
        m = pg.measure(water.model.water.net, water.io.positions(), water.model.r)
        assert built[:1] == [k0] and areas_in_range(m.void_area, m.polygon_area), how
        runs.append((built, water.io.positions(), water.model.water.W.copy()))
    for other in runs[1:]:
        assert other[0] == runs[0][0]
        assert np.array_equal(other[1], runs[0][1]) and np.array_equal(other[2], runs[0][2])


@pytest.mark.parametrize("law", ["paper", "yade"])
def test_the_scene_option_rebuild_distance_rebuilds_by_displacement_in_both_laws(packing, law):
    """[numerics] rebuild_distance d > 0 with no interval within reach: the pores are rebuilt,
    each time with a disc farther than d from its built centre; d = 0 (the presets): never."""
    for d in (1e-8, 0.0):
        sc = scenes.preset("quicksand_case1", {"contact": {"law": law, "spring": "a"},
                                               "numerics": {"rebuild_interval": 10**6, "rebuild_distance": d}})
        cp = YadeCoupling(sc, packing)
        model = cp.core.water_model if law == "paper" else cp.water_engine.model
        moved, rebuild = [], model.rebuild
        model.rebuild = lambda xz, k=None: moved.append(model.max_sq_moved(xz)) or rebuild(xz, k)
        cp.run(300)
        assert (len(moved) >= 2 and min(moved) > d * d) if d else moved == [], (law, d, moved)


def test_forces_are_added_unheld_only_where_the_engine_list_resets_them_after_newton():
    """forces_reset_after_newton: the engine writes the next step's forces unheld (no permanent
    forces) only when no ForceResetter runs before the one NewtonIntegrator, so a user's list
    with ForceResetter first keeps its forces held (the runs above: bit for bit the same)."""
    from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner

    from engines.yade.yade_io import forces_reset_after_newton
    fr, newton, other = ForceResetter, NewtonIntegrator, lambda: PyRunner(command="pass")
    assert forces_reset_after_newton([newton(), fr()])
    assert forces_reset_after_newton([other(), newton(), other(), fr()])
    assert not forces_reset_after_newton([fr(), newton()])
    assert not forces_reset_after_newton([fr(), newton(), fr()])
    assert not forces_reset_after_newton([newton()])
    assert not forces_reset_after_newton([newton(), newton(), fr()])


def test_the_python_backend_writes_the_forces_of_each_step_as_the_bridge_does(monkeypatch):
    """Without the bulk bridge (yade_io's Python backend: O.forces.addF into the forces reset after
    NewtonIntegrator, or O.forces.setPermF with ForceResetter first), the seismic box runs bit for
    bit as with it, through a pore rebuild."""
    from yade import O
    from yade.wrapper import ForceResetter

    from engines.yade import yade_io
    sc = scenes.preset("liquefaction_case1", {"numerics": {"rebuild_interval": 30}})
    packing = Packing.load(sc.packing.file)
    runs = []
    for backend, held in (("yadebulk", False), ("python", False), ("python", True)):
        if backend == "python":
            monkeypatch.setattr(yade_io, "_BULK", None)
            monkeypatch.setattr(yade_io, "BACKEND", "python")
        cp = YadeCoupling(sc, packing)
        if held:
            O.engines = [ForceResetter(), O.engines[0]]
        assert yade_io.forces_reset_after_newton(O.engines) != held
        cp.run(60)
        runs.append((cp.positions(), cp.velocities(), cp.water_model.n_rebuilds))
    for x, v, built in runs[1:]:
        np.testing.assert_array_equal(x, runs[0][0])
        np.testing.assert_array_equal(v, runs[0][1])
        assert built == runs[0][2] >= 1
    assert np.abs(runs[0][0] - packing.xz).max() > 0


def test_newtons_damping_pass_switched_off_changes_no_bit_of_a_run():
    """engines.yade.coupling.undamped: with NewtonIntegrator's damping 0 the scenes switch its
    per-body damping pass off (State.isDamped), and the seismic box runs bit for bit as with it;
    with a damping that acts the pass stays on, and a damping set after the build is refused."""
    from yade import O
    sc = scenes.preset("liquefaction_case1", {"numerics": {"rebuild_interval": 30}})
    packing = Packing.load(sc.packing.file)
    runs = []
    for damped in (False, True):
        cp = YadeCoupling(sc, packing)
        assert not any(b.state.isDamped for b in O.bodies)
        if damped:
            for b in O.bodies:
                b.state.isDamped = True
        cp.run(60)
        runs.append((cp.positions(), cp.velocities()))
    np.testing.assert_array_equal(runs[1][0], runs[0][0])
    np.testing.assert_array_equal(runs[1][1], runs[0][1])
    YadeCoupling(sc, packing, newton_damping=0.2)  # a damping that acts: every body keeps it
    assert all(b.state.isDamped for b in O.bodies)
    cp = YadeCoupling(sc, packing)
    O.engines[0].damping = 0.2  # set after the build, it would not act: refused in one line
    with pytest.raises(ValueError, match="newton_damping"):
        cp.run(1)


def test_the_water_engine_follows_a_change_of_o_dt():
    """O.dt halved by the script after 100 steps: the model's dt follows at its next water step, the
    next 100 steps let in half the water (q_w per inflow pore x water_interval x O.dt, no rebuild),
    and the runner, drive from Python and drive's compiled calls make the same run."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    from engines.yade import yade_io
    runs = []
    for how in ("runner", "python", "compiled"):
        water = column_engine(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), 10**6, 5)
        b = water.model.water.balance
        if how == "runner":
            O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
        first = []
        for dt in (1e-6, 0.5e-6):
            O.dt = dt
            if how == "runner":
                O.run(100, True)
                yade_io.raise_pending()
            else:
                water.drive(100, (lambda: False) if how == "python" else None)
            first.append(b.inflow - sum(first))
            assert water.model.dt == dt, how
        assert water.model.n_rebuilds == 0
        np.testing.assert_allclose(first[1], 0.5 * first[0], rtol=1e-12)
        runs.append((water.model.water.W.copy(), water.io.positions()))
    for W, xz in runs[1:]:
        assert np.array_equal(W, runs[0][0]) and np.array_equal(xz, runs[0][1])


def test_the_paper_law_engine_follows_a_change_of_o_dt(packing):
    """A run whose script sets O.dt = dt2 after the scene was built at dt1 is, bit for bit, the run
    built at dt2 (the law's du / dt, dashpots and spin, and the water step follow O.dt); a dt
    above eq 52 is refused at the next step."""
    from yade import O
    runs = []
    for built, run in ((1e-6, 0.5e-6), (0.5e-6, 0.5e-6)):
        cp = YadeCoupling(scenes.preset("quicksand_case1", {"numerics": {"dt": built, "water_interval": 2}}), packing)
        O.dt = run
        cp.run(300)
        assert cp.core.dt == cp.core.law.dt == cp.core.water_model.dt == run
        runs.append((cp.positions(), cp.core.omega.copy(), cp.water.W.copy()))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)
    O.dt = 1.0
    with pytest.raises(ValueError, match="eq 52"):
        cp.run(1)


def test_the_engines_choose_their_path_in_one_place():
    """step_path: the compiled drive for the compiled PoreDEM with the bridge, else the general
    step (the NumPy PoreDEM, no bridge); water_path: the drive, water_step, the NumPy model."""
    from engines.compiled.pore_dem import PoreDEM as CompiledPoreDEM
    from engines.model.pore_dem import PoreDEM as NumpyPoreDEM
    from engines.yade.paper_law_engine import step_path
    from engines.yade.water_engine import water_path
    from tests.model.test_pore_dem import scene, wet_box
    s, pk = scene(numerics={"dt": 1e-6}), wet_box()
    compiled, numpy_core = CompiledPoreDEM(s.settings, pk), NumpyPoreDEM(s.settings, pk)
    assert [step_path(compiled, True), step_path(compiled, False), step_path(numpy_core, True)] == [
        "drive", "python", "python"]
    assert [water_path(True, True), water_path(True, False), water_path(False, True)] == ["drive", "kernel", "python"]
