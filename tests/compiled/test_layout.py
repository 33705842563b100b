"""The kernels' arguments and buffers by name (engines.compiled.layout): the water buffers' lists
of names shuffled, and every kernel that reads them compiled again, give the same steps bit for
bit; a kernel passes its arrays on in the places of the callee's parameters of the same names; a
layout refuses a tuple with a name missing or unknown."""
import ast
import importlib
import inspect
import pkgutil

import numba
import numpy as np
import pytest

from engines.compiled import kernels
from engines.compiled.layout import Layout
from engines.compiled.pore_dem import PoreDEM
from engines.compiled.water_model import WaterModel
from engines.model import pores as pg
from engines.model.pore_water import WaterSettings
from engines.model.schedule import Schedule
from tests.model.test_pore_dem import R, fused_step, moving_positions, wet_box, wet_scene

BUFFERS = ("WATER_INTS", "WATER_FLOATS")


def modules():
    """The package engines.compiled.kernels and its modules."""
    return [kernels] + [importlib.import_module(f"{kernels.__name__}.{m.name}")
                        for m in pkgutil.iter_modules(kernels.__path__)]


def dispatchers():
    """{name: kernel} of every numba kernel of engines.compiled.kernels (its modules' too)."""
    return {n: f for m in modules() for n, f in vars(m).items() if isinstance(f, numba.core.registry.CPUDispatcher)}


def set_everywhere(monkeypatch, name, value):
    """The global ``name`` set to value in every module of the package that binds it (the kernels
    read their globals from their own module)."""
    for m in modules():
        if name in vars(m):
            monkeypatch.setattr(m, name, value)


def readers(names):
    """The kernels of engines.compiled.kernels whose code names one of the globals ``names``, and
    the kernels that call those, and so on."""
    found, named = set(), set(names)
    while True:
        new = {n for n, f in dispatchers().items() if n not in found and named & set(f.py_func.__code__.co_names)}
        if not new:
            return found
        found |= new
        named |= new


def shuffle_buffers(monkeypatch, seed=1):
    """The buffers' lists of names in a random order (not the first) and their readers compiled
    afresh (no cache: numba reads the layouts when it compiles)."""
    rng = np.random.default_rng(seed)
    for name in BUFFERS:
        names = getattr(kernels, name).names
        order = rng.permutation(len(names))
        assert np.any(order != np.arange(len(names)))
        set_everywhere(monkeypatch, name, Layout(name, [names[k] for k in order]))
    compiled_again = readers(BUFFERS)
    assert {"water_step", "dem_drive_bulk_io", "water_forces_step", "water_drive_bulk_io"} <= compiled_again
    for name in compiled_again:
        set_everywhere(monkeypatch, name, numba.njit(nogil=True)(dispatchers()[name].py_func))


def wet_box_steps(n=12):
    """PoreDEM on a wet box with side walls on springs, eq 45-46 smoothing and sub-steps, stepped
    by kernels.dem_drive_bulk_io where it can (tests.model.test_pore_dem.fused_step): the forces of every
    step and the state at the end."""
    s = wet_scene(q_w=1e-4, k1=2e6, smoothing=True, substep=True)
    s = s.with_overrides({"loading": {"type": "cosine", "amplitude": 0.0, "side_walls": "springs"},
                          "contact": {"ks_wall": 1e3, "eta_s_wall": 0.5}})
    pk = wet_box(jitter=0.05)
    core = PoreDEM(s.settings, pk)
    side = np.isin(pk.group, [pg.WALL_LEFT, pg.WALL_RIGHT])
    out, fused = [], 0
    for k in range(n):
        xz = moving_positions(pk, k)
        xz[side, 0] += 1e-3 * R * k * np.sin(np.arange(side.sum()))
        F, _, one_call = fused_step(core, xz)
        out.append(F.copy())
        fused += one_call
    w = core.water
    assert fused >= n // 2 and core.water_model.substeps_max > 1 and w.q_prev is not None
    return out + [w.W, w.q_prev, core.law.omega, core.law.contact.state,
                  [w.balance.inflow, w.balance.surface_outflow, w.balance.side_outflow]]


def water_engine_steps(n=10):
    """WaterModel stepped as the YADE water engine does it: kernels.water_forces_step between
    rebuilds (smoothing, sub-steps); the forces to write of every step and the water at the end."""
    rng = np.random.default_rng(4)
    pk = wet_box(jitter=0.05)
    m = WaterModel(WaterSettings(E_w=240.0, k1=2e6, k2=2e4, q_w=1e-4, smoothing=True, substep=True), pk.r, pk.group,
                   pk.xz, 0.0, 0.1 * R, 1e-6, Schedule(rebuild_interval=4), log=lambda message: None)
    rows = np.flatnonzero(pk.mobile)
    held = rng.standard_normal((len(rows), 2))
    F_out, xz, out = np.zeros_like(held), pk.xz, []
    for k in range(n):
        xz = xz + 1e-3 * R * rng.standard_normal(xz.shape) * pk.mobile[:, None]
        if m.rebuild_due(k):
            m.rebuild(xz, k)
        args = kernels.water_forces_step_args(rows, held, m.kernel_args(m.dt))
        _, n_sub = kernels.water_forces_step(xz, F_out, *args)
        m.finish_kernel_step(m.dt, n_sub)
        out.append(F_out.copy())
    assert m.n_rebuilds >= 2 and m.substeps_max > 1
    return out + [m.water.W, m.water.q_prev, [m.last_limit, m.water.balance.inflow, m.water.balance.surface_outflow]]


@pytest.mark.check  # the shuffled layouts compile the water kernels afresh (about a minute): make check
@pytest.mark.parametrize("run", [wet_box_steps, water_engine_steps])
def test_shuffled_buffer_layouts_give_the_same_steps(monkeypatch, run):
    before = run()
    u_at = kernels.WATER_FLOATS.U
    shuffle_buffers(monkeypatch)
    assert kernels.WATER_FLOATS.U != u_at
    after = run()
    assert len(after) == len(before)
    for k, (a, b) in enumerate(zip(after, before)):
        assert np.array_equal(np.asarray(a), np.asarray(b)), f"item {k} of {run.__name__}"


def test_a_layout_builds_its_tuple_by_name():
    lay = Layout("T", ("b", "a", "c"))
    assert (lay.a, lay.b, lay.c) == (1, 0, 2) and lay.values(a=1, c=2, b=0) == (0, 1, 2)
    buffer, at = lay.pack({"a": [3.0], "b": [[1.0, 2.0]], "c": []}, float)
    assert buffer.tolist() == [1.0, 2.0, 3.0] and lay.part(buffer, at, "a").tolist() == [3.0]
    with pytest.raises(KeyError):
        lay.values(a=1, c=2, d=0)
    with pytest.raises(TypeError):
        lay.values(a=1, c=2)
    for bad in (("a", "a"), ("a", "names"), ("pack", "b"), ("a",)):
        with pytest.raises(ValueError):
            Layout("T", bad)
    assert lay.check(("b",), Layout("U", ("a", "c"))) is lay
    with pytest.raises(TypeError):
        lay.check(("a", "b"), ("c",))
    assert Layout.of(numba.njit(lambda x, y, z: x), 1).names == ("y", "z")


def test_kernels_pass_their_arrays_on_under_the_callees_names():
    """Where a kernel calls another with a variable named like one of the callee's parameters
    (dem_drive_bulk_io's xz_prev ... T to law_step, water_step, tie_forces; the water drivers' to water_forces_step),
    the variable is in that parameter's place: a spelled-out call cannot shift its arguments."""
    params = {n: list(inspect.signature(f.py_func).parameters) for n, f in dispatchers().items()}
    wrong, checked = [], 0
    for fn in (f for m in modules() for f in ast.parse(inspect.getsource(m)).body):
        if not (isinstance(fn, ast.FunctionDef) and fn.name in params):
            continue
        for call in ast.walk(fn):
            if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id in params):
                continue
            callee = params[call.func.id]
            for k, arg in enumerate(call.args):
                if isinstance(arg, ast.Starred):
                    break
                if isinstance(arg, ast.Name) and arg.id in callee:
                    checked += 1
                    if k >= len(callee) or callee[k] != arg.id:
                        wrong.append(f"{fn.name} -> {call.func.id}: {arg.id} in place {k}")
    assert wrong == [] and checked > 150
