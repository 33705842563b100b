"""The bulk-I/O bridge (engines/yade/yadebulk) against YADE's per-body Python API: exact agreement of
every function, bit-identical trajectories, refused ids and arrays, a probe that leaves the user's
scene alone and rejects a wrong layout."""
import os
import subprocess
import sys

import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing: make test installs it)
from yade import O, Vector3, utils
from yade.wrapper import (
    Bo1_Box_Aabb,
    Bo1_Sphere_Aabb,
    ForceResetter,
    FrictMat,
    Ig2_Box_Sphere_ScGeom,
    Ig2_Sphere_Sphere_ScGeom,
    InsertionSortCollider,
    InteractionLoop,
    Ip2_FrictMat_FrictMat_FrictPhys,
    Law2_ScGeom_FrictPhys_CundallStrack,
    NewtonIntegrator,
    PyRunner,
)

import __main__
from engines import ROOT
from engines.yade import yadebulk
from engines.yade.yadebulk import probe


@pytest.fixture(scope="module")
def bulk():
    if not yadebulk.available():
        if os.environ.get("YADEBULK_REQUIRED") == "1":
            pytest.fail(f"engines.yade.yadebulk is not available: {yadebulk.reason()}")
        pytest.skip(f"engines.yade.yadebulk is not available: {yadebulk.reason()}")
    return yadebulk


def _discs(n, seed=1):
    """A fresh scene: n free discs (random radii, positions, velocities, spins) in the x-z plane."""
    O.reset()
    rng = np.random.default_rng(seed)
    O.bodies.append([utils.sphere((rng.uniform(-1, 1), 0.0, rng.uniform(-1, 1)), rng.uniform(0.01, 0.02))
                     for _ in range(n)])
    for b in O.bodies:
        b.state.vel = Vector3(*rng.normal(size=3))
        b.state.angVel = Vector3(*rng.normal(size=3))
    return np.arange(n, dtype=np.int64)


def _xz(vectors):
    return np.array([(v[0], v[2]) for v in vectors])


def test_reads_equal_the_python_api(bulk):
    ids = _discs(50)[::-1][::3].copy()  # a reversed, strided subset
    xz, y = np.empty((len(ids), 2)), np.empty(len(ids))
    bulk.get_pos_xz(ids, xz)
    assert np.array_equal(xz, _xz(O.bodies[int(i)].state.pos for i in ids))
    bulk.get_vel_xz(ids, xz)
    assert np.array_equal(xz, _xz(O.bodies[int(i)].state.vel for i in ids))
    bulk.get_angvel_y(ids, y)
    assert np.array_equal(y, [O.bodies[int(i)].state.angVel[1] for i in ids])


def test_set_vel_is_read_back_by_the_python_api(bulk):
    ids = _discs(20)[[3, 17, 0, 9]]
    V = np.random.default_rng(2).normal(size=(4, 2))
    bulk.set_vel_xz(ids, V)
    assert [tuple(O.bodies[int(i)].state.vel) for i in ids] == [(vx, 0.0, vz) for vx, vz in V]
    assert tuple(O.bodies[1].state.vel) != (0.0, 0.0, 0.0)  # bodies not named keep theirs


def test_forces_equal_those_of_o_forces(bulk):
    """Bodies n..2n-1 get through the bridge what bodies 0..n-1 get through O.forces (twice, to
    accumulate); the synchronised sums, torques and permanent forces must be equal bit for bit."""
    n = 8
    _discs(2 * n)
    rng = np.random.default_rng(3)
    F, P, T = rng.normal(size=(n, 2)), rng.normal(size=(n, 2)), rng.normal(size=n)
    twins = np.arange(n, 2 * n, dtype=np.int64)
    for _ in range(2):
        for i in range(n):
            O.forces.addF(i, Vector3(F[i, 0], 0.0, F[i, 1]))
            O.forces.addT(i, Vector3(0.0, T[i], 0.0))
        bulk.add_force_xz(twins, F)
        bulk.add_torque_y(twins, T)
    for i in range(n):
        O.forces.setPermF(i, Vector3(P[i, 0], 0.0, P[i, 1]))
    bulk.set_perm_force_xz(twins, P)
    for i in range(n):
        assert tuple(O.forces.f(n + i, True)) == tuple(O.forces.f(i, True))
        assert tuple(O.forces.t(n + i, True)) == tuple(O.forces.t(i, True))
        assert tuple(O.forces.permF(n + i)) == tuple(O.forces.permF(i)) == (P[i, 0], 0.0, P[i, 1])
    assert tuple(O.forces.f(0, True)) != (0.0, 0.0, 0.0)


_HOOK = None  # the force callback of the running trajectory, called by a PyRunner


def _apply_hook():
    _HOOK()


def _box_of_discs(n=40, seed=4):
    """Discs in a box under gravity with YADE's collider and Cundall-Strack law, and a PyRunner
    (after the contact law) that calls _HOOK every step."""
    O.reset()
    rng = np.random.default_rng(seed)
    O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2600))
    walls = [utils.box(c, e, fixed=True) for c, e in (((0, 0, -0.05), (0.5, 0.1, 0.05)),
                                                      ((-0.45, 0, 0.5), (0.05, 0.1, 0.5)),
                                                      ((0.45, 0, 0.5), (0.05, 0.1, 0.5)))]
    O.bodies.append(walls)
    for k in range(n):
        b = utils.sphere((-0.35 + 0.1 * (k % 8) + rng.uniform(-0.01, 0.01), 0, 0.1 + 0.1 * (k // 8)),
                         rng.uniform(0.03, 0.045))
        b.state.blockedDOFs = "yXZ"
        O.bodies.append(b)
    hook = f"__import__('sys').modules[{__name__!r}]._apply_hook()"
    O.engines = [ForceResetter(),
                 InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                                 [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()],
                                 ompThreads=1),  # one thread: contact forces summed in a fixed order
                 PyRunner(command=hook, iterPeriod=1, updateGlobals=False),
                 NewtonIntegrator(damping=0.1, gravity=(0, 0, -9.81))]
    O.dt = 0.5 * utils.PWaveTimeStep()
    return np.arange(len(walls), len(walls) + n, dtype=np.int64)


def _forces(xz, v, w, it):
    """A state-dependent push: a spring to a moving centre, drag, spin damping; permanent forces
    refreshed every 7 steps (N, N m)."""
    c = np.array([0.1 * np.sin(0.01 * it), 0.3])
    return -50.0 * (xz - c) - 0.3 * v, -1e-3 * w, (it % 7 == 0), 2.0 * (xz[:, ::-1] - c)


def _trajectory(ids, bridge, steps=300, nudge=None):
    """Run `steps` steps with the forces of _forces applied through the bridge (module) or O.forces
    (None); return every disc's final pos, vel, angVel, ori. nudge = (step, index): that force
    component 1e-12 larger (relative) at that step."""
    global _HOOK
    n = len(ids)
    xz, v, w = np.empty((n, 2)), np.empty((n, 2)), np.empty(n)

    def hook():
        it = O.iter
        if bridge:
            bridge.get_pos_xz(ids, xz)
            bridge.get_vel_xz(ids, v)
            bridge.get_angvel_y(ids, w)
        else:
            xz[:] = _xz(O.bodies[int(i)].state.pos for i in ids)
            v[:] = _xz(O.bodies[int(i)].state.vel for i in ids)
            w[:] = [O.bodies[int(i)].state.angVel[1] for i in ids]
        F, T, refresh, P = _forces(xz, v, w, it)
        if nudge and nudge[0] == it:
            F[nudge[1], 0] *= 1 + 1e-12
        if bridge:
            bridge.add_force_xz(ids, F)
            bridge.add_torque_y(ids, T)
            if refresh:
                bridge.set_perm_force_xz(ids, P)
        else:
            for k, i in enumerate(ids.tolist()):
                O.forces.addF(i, Vector3(F[k, 0], 0.0, F[k, 1]))
                O.forces.addT(i, Vector3(0.0, T[k], 0.0))
                if refresh:
                    O.forces.setPermF(i, Vector3(P[k, 0], 0.0, P[k, 1]))
    _HOOK = hook
    try:
        O.run(steps, True)
    finally:
        _HOOK = None
    return np.array([[*b.state.pos, *b.state.vel, *b.state.angVel, *b.state.ori] for b in (O.bodies[int(i)]
                                                                                             for i in ids)])


def test_trajectories_with_bridge_forces_equal_those_with_o_forces_bit_for_bit(bulk):
    runs = {}
    for name, bridge, nudge in (("python", None, None), ("python again", None, None), ("bridge", bulk, None),
                                ("bridge, 1e-12 off", bulk, (5, 7))):
        ids = _box_of_discs()
        runs[name] = _trajectory(ids, bridge, nudge=nudge)
    assert np.array_equal(runs["python"], runs["python again"])  # YADE is deterministic here
    assert np.array_equal(runs["bridge"], runs["python"])
    assert not np.array_equal(runs["bridge, 1e-12 off"], runs["python"])  # the test sees a 1e-12 nudge
    assert np.ptp(runs["python"][:, 2]) > 0.1  # the discs moved and touched: a real trajectory


def test_steps_equal_o_step_bit_for_bit(bulk):
    """yadebulk.steps(n) (Scene::moveToNextTimeStep from C++) is n O.step() calls: the same
    trajectory to the bit, O.iter and O.time; a PyRunner inside the steps still runs."""
    global _HOOK
    calls = []
    runs = []
    for step in (lambda n: [O.step() for _ in range(n)], bulk.steps):
        ids = _box_of_discs()
        _HOOK = lambda: calls.append(O.iter)  # noqa: E731
        try:
            step(300)
        finally:
            _HOOK = None
        runs.append((O.iter, O.time, np.array([[*b.state.pos, *b.state.vel, *b.state.angVel, *b.state.ori]
                                               for b in (O.bodies[int(i)] for i in ids)])))
    assert runs[0][:2] == runs[1][:2] and runs[0][0] == 300
    assert np.array_equal(runs[0][2], runs[1][2]) and np.ptp(runs[0][2][:, 2]) > 0.01
    assert calls == list(range(1, 300)) * 2  # the PyRunner, from step 1 (initRun=False)


def test_steps_raise_what_an_engine_threw(bulk):
    global _HOOK
    _box_of_discs()

    def fail():
        if O.iter == 3:
            raise ValueError("boom at step 3")
    _HOOK = fail
    try:
        with pytest.raises(RuntimeError, match="boom at step 3"):
            bulk.steps(10)
        assert O.iter == 3  # as O.step(): the step that threw did not count
    finally:
        _HOOK = None
        O.reset()  # YADE leaves a step that threw half done


def test_bad_ids_are_refused_and_nothing_is_done(bulk):
    ids = _discs(10)
    O.bodies.erase(4)
    for i in (0, 1, 2):  # known forces (YADE's O.forces.permF crashes if none was ever set)
        O.forces.addF(i, Vector3(1.0, 2.0, 3.0))
        O.forces.setPermF(i, Vector3(4.0, 5.0, 6.0))
    F = np.ones((3, 2))
    vel0 = tuple(O.bodies[0].state.vel)
    out = np.full((3, 2), 7.0)
    for bad, k in (([0, 1, 10], 2), ([0, -1, 2], 1), ([0, 4, 2], 1), ([0, 2, 2**40], 2)):  # 4 is erased
        bad = np.array(bad, dtype=np.int64)
        for fn, arr in ((bulk.add_force_xz, F), (bulk.set_perm_force_xz, F), (bulk.set_vel_xz, F),
                        (bulk.get_pos_xz, out)):
            with pytest.raises(IndexError, match=f"ids\\[{k}\\]"):
                fn(bad, arr)
    assert all(tuple(O.forces.f(i, True)) == (5.0, 7.0, 9.0) for i in (0, 1, 2))
    assert all(tuple(O.forces.permF(i)) == (4.0, 5.0, 6.0) for i in (0, 1, 2))
    assert tuple(O.bodies[0].state.vel) == vel0 and np.all(out == 7.0)
    bulk.get_pos_xz(ids[:3], out)  # good ids still work after refusals


def test_unsynced_force_writes_refuse_ids_out_of_range_only(bulk):
    """add_force_unsynced_xz checks the ids against the body range, not body by body: an id out of
    range is refused, naming its place, and an erased body's slot takes its force (the compiled
    steps read the positions of the same bodies first, and that read refuses it)."""
    _discs(10)
    O.bodies.erase(4)
    F = np.ones((3, 2))
    for bad, k in (([0, 1, 10], 2), ([0, -1, 2], 1), ([0, 2, 2**40], 2)):
        with pytest.raises(IndexError, match=f"ids\\[{k}\\]"):
            bulk.add_force_unsynced_xz(np.array(bad, dtype=np.int64), F)
    bulk.add_force_unsynced_xz(np.array([0, 4, 2], dtype=np.int64), F)
    with pytest.raises(IndexError, match="ids\\[1\\]"):
        bulk.get_pos_xz(np.array([0, 4, 2], dtype=np.int64), np.empty((3, 2)))


def test_bad_arrays_are_refused(bulk):
    ids = _discs(6)
    xz = np.empty((6, 2))
    with pytest.raises(TypeError):
        bulk.get_pos_xz(ids.astype(np.int32), xz)
    with pytest.raises(TypeError):
        bulk.get_pos_xz(ids[::2], np.empty((3, 2)))  # not contiguous
    with pytest.raises(TypeError):
        bulk.get_pos_xz(ids, np.empty((6, 2), dtype=np.float32))
    with pytest.raises(TypeError):
        bulk.get_pos_xz(ids, np.empty((5, 2)))
    with pytest.raises(TypeError):
        bulk.get_angvel_y(ids, np.empty((6, 2)))
    with pytest.raises(TypeError):
        bulk.add_force_xz(ids, np.empty((2, 6)).T)  # Fortran order
    with pytest.raises(TypeError):
        bulk.add_force_xz(list(ids), xz)
    xz.flags.writeable = False
    with pytest.raises(ValueError):
        bulk.get_vel_xz(ids, xz)


def test_an_njit_function_calls_the_ctypes_functions(bulk):
    numba = pytest.importorskip("numba")
    get_pos, add_force = bulk.c_get_pos_xz, bulk.c_add_force_xz

    @numba.njit
    def pull_to_origin(ids, xz):
        rc = get_pos(ids.ctypes.data, ids.size, xz.ctypes.data)
        F = -3.0 * xz
        return rc, add_force(ids.ctypes.data, ids.size, F.ctypes.data)

    ids = _discs(12)[::-1].copy()
    xz = np.empty((12, 2))
    assert pull_to_origin(ids, xz) == (0, 0)
    assert np.array_equal(xz, _xz(O.bodies[int(i)].state.pos for i in ids))
    assert [tuple(O.forces.f(int(i), True)) for i in ids] == [(-3.0 * x, 0.0, -3.0 * z) for x, z in xz]
    assert pull_to_origin(np.array([12], dtype=np.int64), np.empty((1, 2))) == (1, 1)  # bad ids[0]


def _user_scene():
    """A user's scene in the middle of a run: bodies, engines, iterations, forces."""
    ids = _box_of_discs(16)
    O.engines = O.engines[:3] + O.engines[4:]
    O.run(20, True)
    O.forces.addF(int(ids[0]), Vector3(1.0, 2.0, 3.0))
    for i in range(len(O.bodies)):  # on every body: YADE's O.forces.permF reads past the end otherwise
        O.forces.setPermF(i, Vector3(4.0, 5.0, i))
    return ids


def _snapshot():
    """The user's scene, its forces, and the names of __main__ (where a PyRunner can write)."""
    return (O.sceneToString(), O.thisScene, O.iter, O.time, O.dt,
            [(tuple(O.forces.f(i, True)), tuple(O.forces.permF(i))) for i in range(len(O.bodies))],
            {k: id(v) for k, v in vars(__main__).items()})


def test_the_probe_leaves_the_user_scene_untouched(bulk):
    _user_scene()
    before = _snapshot()
    assert probe.run(bulk._lib, bulk) == {k: bulk.layout()[k] for k in ("forces", "force_data", "bodies", "state",
                                                                         "pos", "vel", "angvel")}
    assert _snapshot() == before


def _next_vector(find):
    """``find`` of a data pointer, moved to the next std::vector's (24 bytes on): plausible, wrong."""
    return lambda *args: find(*args) + 24


def _swapped(find):
    """``find`` of the State offsets with pos and vel exchanged: unique, plausible, wrong."""
    def swapped(*args):
        state, pos, vel, angvel = find(*args)
        return state, vel, pos, angvel
    return swapped


@pytest.mark.parametrize("finder, fix, failed", [
    ("_find_state_offsets", _swapped, "get_pos_xz reads what the Python API wrote"),
    ("_find_force_data_offset", _next_vector, "O.forces.f adds what add_force_unsynced_xz added")])
def test_the_probe_rejects_a_wrong_layout_and_switches_the_bridge_off(bulk, monkeypatch, finder, fix, failed):
    ids = _user_scene()
    before = _snapshot()
    monkeypatch.setattr(probe, finder, fix(getattr(probe, finder)))
    try:
        with pytest.raises(probe.ProbeError, match=failed):
            probe.run(bulk._lib, bulk)
        assert _snapshot() == before
        with pytest.raises(RuntimeError, match="not configured"):
            bulk.get_pos_xz(ids, np.empty((len(ids), 2)))
    finally:
        monkeypatch.undo()
        probe.run(bulk._lib, bulk)  # the real layout back for the other tests
    bulk.get_pos_xz(ids, np.empty((len(ids), 2)))


def test_without_the_summed_forces_pointer_the_bridge_adds_through_yade(bulk, monkeypatch):
    """A YADE whose summed forces the probe cannot find uniquely: the probe still passes (its checks
    of add_force_unsynced_xz and the Newton twins run through ForceContainer::addForceUnsynced)."""
    def not_found(*args):
        raise probe.ProbeError("summed forces' data pointer in ForceContainer: 0 candidates")
    monkeypatch.setattr(probe, "_find_force_data_offset", not_found)
    try:
        assert probe.run(bulk._lib, bulk)["force_data"] == -1
    finally:
        monkeypatch.undo()
        probe.run(bulk._lib, bulk)  # the real layout back for the other tests


def test_the_probe_refuses_to_run_during_a_simulation(bulk):
    _user_scene()
    O.run(20000)  # about a second in the background (O.pause() would not wait for the thread)
    try:
        with pytest.raises(probe.ProbeError, match="running"):
            probe.run(bulk._lib, bulk)
    finally:
        O.wait()
    assert O.thisScene == 0 and O.iter == 20020


def test_the_bridge_follows_the_current_scene(bulk):
    _discs(5, seed=8)
    a = np.empty((5, 2))
    bulk.get_pos_xz(np.arange(5, dtype=np.int64), a)
    ids = _discs(30, seed=9)
    b = np.empty((30, 2))
    bulk.get_pos_xz(ids, b)
    assert np.array_equal(b, _xz(bod.state.pos for bod in O.bodies)) and not np.array_equal(a, b[:5])
    with pytest.raises(IndexError):
        bulk.get_pos_xz(np.array([30], dtype=np.int64), np.empty((1, 2)))


def test_an_unlisted_libyade_is_refused_unless_unpinned(bulk, tmp_path):
    """In a fresh process: with KNOWN_LIBYADE emptied the bridge refuses; YADEBULK_UNPINNED=1
    probes anyway; YADEBULK=0 switches it off."""
    script = tmp_path / "pin.py"
    script.write_text(
        "import os, sys\n"
        "sys.path.append('/usr/lib/x86_64-linux-gnu/yade-double/py')\n"
        "from engines.yade import yadebulk\n"
        "yadebulk.KNOWN_LIBYADE.clear()\n"
        "print(yadebulk.available(), 'KNOWN_LIBYADE' in yadebulk.reason())\n"
        "os.environ['YADEBULK_UNPINNED'] = '1'\n"
        "yadebulk._final = False\n"
        "print(yadebulk.available(), yadebulk.reason())\n")
    env = dict(os.environ, PYTHONPATH=ROOT)
    env.pop("YADEBULK_UNPINNED", None)
    out = subprocess.run([sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=300)
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith(("True", "False"))]
    assert lines == ["False True", "True probe passed"], out.stdout + out.stderr
    env["YADEBULK"] = "0"
    off = subprocess.run([sys.executable, "-c", "from engines.yade import yadebulk; print(yadebulk.reason())"],
                         env=env, capture_output=True, text=True, timeout=300)
    assert off.stdout.strip() == "switched off by YADEBULK=0", off.stdout + off.stderr
