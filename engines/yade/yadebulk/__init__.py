"""Bulk body I/O for YADE: positions, velocities, forces and torques of many bodies in one call.

YADE 2023.02a's Python API moves one body per call (``O.forces.addF``, ``b.state.pos``, 1-2 us
each); these functions move arrays. They work in the x-z plane of our discs::

    from engines.yade import yadebulk
    if yadebulk.available():                 # first call probes YADE's layout (needs `import yade`)
        yadebulk.get_pos_xz(ids, xz)         # ids: int64 (n,); xz: float64 (n, 2), both C-contiguous
        yadebulk.add_force_xz(ids, F)        # = O.forces.addF(id, (Fx, 0, Fz)) for each id
    else:
        print(yadebulk.reason())             # and fall back to the per-body Python API

``add_force_xz``, ``add_torque_y`` and ``set_perm_force_xz`` call YADE's own ForceContainer
functions, the ones ``O.forces.addF``/``addT``/``setPermF`` call, so results are bit-identical to
those. The compiled part (``_yadebulk.so``, built by ``make ext`` from ``yadebulk.c`` and
``steps.cpp``) uses no YADE headers; it runs only on a libyade.so build listed in
``KNOWN_LIBYADE``, and the data offsets it needs are discovered and verified at first use by
``probe.py`` on a scratch scene (the user's scene is left untouched): nothing is read or written
before that succeeded. Call ``available()`` before ``O.run()``: the probe refuses to run during a
simulation.

``yadebulk.steps(n)`` is n O.step() calls, and ``c_steps`` lets a compiled loop step YADE between
its own work. For numba: ``c_get_pos_xz`` ... ``c_set_perm_force_xz`` and ``c_steps`` are the
ctypes function objects, ``(ids_ptr, n, array_ptr) -> int64`` with 0 for success, -1 not ready
(``available()`` not yet True), -2 no scene, -4 (STEP_THREW) when an engine threw in ``c_steps``
(``yb_error`` says what), -5 no memory for the lookup of the ids, k >= 1 when ``ids[k-1]`` is out
of range or erased. An ``@njit`` function calls them as
``c_add_force_xz(ids.ctypes.data, ids.size, F.ctypes.data)`` after ``available()``. Like YADE's
Python API, call them from the thread that runs the simulation (a PyRunner) or while it is stopped.
Set ``YADEBULK=0`` in the environment to switch the bridge off.
"""
import ctypes
import hashlib
import os
import sys

import numpy as np

SO_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_yadebulk.so")
# Builds of libyade.so (sha256) whose calling conventions the C part relies on were checked by
# disassembly: Omega::getScene and Body::byId return references (a by-value shared_ptr would be
# returned through a hidden pointer, and the call would write into Omega). The data layout is
# still probed at every load. YADEBULK_UNPINNED=1 probes an unlisted build anyway: if
# tests/yade/test_yadebulk.py then passes, add its hash here.
KNOWN_LIBYADE = {
    "6dab813fb5cb5be6adb80d973e52cc4ebc763a266317ebd1bab487264d8a391b": "Debian yade 2023.02a-1 amd64, yade-double",
}
STEP_THREW = -4  # c_steps: an engine threw; _lib.yb_error() holds its message
NAMES = ("get_pos_xz", "get_vel_xz", "set_vel_xz", "get_angvel_y", "add_torque_y", "add_force_xz",
         "set_perm_force_xz", "add_force_unsynced_xz", "steps")


def _open():
    """The compiled library with its ctypes signatures, or (None, why not)."""
    try:
        lib = ctypes.PyDLL(SO_PATH)  # keeps the GIL: the calls are short and touch no Python state
    except OSError as e:
        return None, f"the compiled part is not built ({e}); run `make ext`"
    lib.yb_open.argtypes, lib.yb_open.restype = [ctypes.c_char_p], ctypes.c_int
    lib.yb_error.restype = ctypes.c_char_p
    lib.yb_scene.restype = ctypes.c_void_p
    lib.yb_body_slot.argtypes, lib.yb_body_slot.restype = [ctypes.c_int], ctypes.c_void_p
    lib.yb_bodies_size.argtypes, lib.yb_bodies_size.restype = [ctypes.c_void_p], ctypes.c_int64
    lib.yb_bodies_at.argtypes, lib.yb_bodies_at.restype = [ctypes.c_void_p, ctypes.c_uint], ctypes.c_void_p
    lib.yb_configure.argtypes, lib.yb_configure.restype = [ctypes.c_int64] * 7 + [ctypes.c_int], None
    for name in NAMES:
        fn = getattr(lib, "yb_" + name)
        fn.argtypes, fn.restype = [ctypes.c_void_p, ctypes.c_int64, ctypes.c_void_p], ctypes.c_int64
    return lib, None


_lib, _reason = _open()
_ready = False       # the probe passed: the bulk functions may be called
_probing = False     # the probe is verifying through the wrappers
_final = False       # available() has its answer for this process
_layout = {}

c_get_pos_xz, c_get_vel_xz, c_set_vel_xz, c_get_angvel_y, c_add_torque_y, c_add_force_xz, \
    c_set_perm_force_xz, c_add_force_unsynced_xz, c_steps = (getattr(_lib, "yb_" + name) if _lib else None
                                                             for name in NAMES)


def available():
    """True once the layout probe has passed in this process (it runs on the first call)."""
    global _ready, _final, _reason, _probing
    if _ready or _final:
        return _ready
    if os.environ.get("YADEBULK", "1") == "0":
        _final, _reason = True, "switched off by YADEBULK=0"
        return False
    if _lib is None:
        _final = True
        return False
    try:
        import yade  # noqa: F401  (loads libyade.so and starts YADE's Omega)
    except ImportError as e:
        _final, _reason = True, f"YADE is not importable here ({e})"
        return False
    from . import probe
    try:
        path = probe.libyade_path()
        _layout.update(libyade=path, sha256=sha256(path))
        if _layout["sha256"] not in KNOWN_LIBYADE and os.environ.get("YADEBULK_UNPINNED") != "1":
            _final, _reason = True, (f"{path} (sha256 {_layout['sha256']}) is not a build listed in "
                                     "engines.yade.yadebulk.KNOWN_LIBYADE (YADEBULK_UNPINNED=1 probes it anyway)")
            return False
        if _lib.yb_open(path.encode()) != 0:
            raise probe.ProbeError(_lib.yb_error().decode())
        _probing = True
        _layout.update(probe.run(_lib, sys.modules[__name__]))
    except probe.ProbeError as e:
        _reason = f"layout probe failed: {e}"
        _final = "running" not in str(e)  # a probe refused during O.run() may be retried later
        return False
    except Exception as e:  # YADE refused a probe step: the caller falls back, reason() says why
        _final, _reason = True, f"layout probe stopped by {type(e).__name__}: {e}"
        return False
    finally:
        _probing = False
    _ready, _final, _reason = True, True, "probe passed"
    return True


def reason():
    """Why the bridge is (not) available, in words."""
    available()
    return _reason


def layout():
    """The verified offsets (bytes), the libyade.so they hold for and its sha256."""
    available()
    return dict(_layout)


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def raise_error(rc, ids=None):
    """Raise on a bulk function's error code."""
    if rc > 0:
        raise IndexError(f"body id {ids[rc - 1]} (ids[{rc - 1}]) is out of range or erased; nothing was done "
                         "(an engine's discs are fixed when it is made: erase bodies before making the WaterEngine, "
                         "or make a new one with the discs left; its water starts again)")
    if rc == STEP_THREW:
        raise RuntimeError(f"a YADE engine failed in the step: {_lib.yb_error().decode()}")
    if rc < 0:
        raise RuntimeError({-1: "the bridge is not configured", -2: "YADE has no current scene",
                            -5: "the bridge found no memory to look the bodies up"}.get(rc, rc))


def _call(fn, ids, arr, width, writes_arr):
    """Check the arrays and call one bulk function of the library."""
    if not (_ready or _probing or available()):
        raise RuntimeError(f"engines.yade.yadebulk is not available: {_reason}")
    if not (type(ids) is np.ndarray and ids.dtype == np.int64 and ids.ndim == 1 and ids.flags.c_contiguous):
        raise TypeError("ids must be a C-contiguous int64 array of shape (n,)")
    n = ids.shape[0]
    if not (type(arr) is np.ndarray and arr.dtype == np.float64 and arr.flags.c_contiguous
            and arr.shape == ((n, 2) if width == 2 else (n,))):
        shape = f"({n}, 2)" if width == 2 else f"({n},)"
        raise TypeError(f"the value array must be a C-contiguous float64 array of shape {shape}")
    if writes_arr and not arr.flags.writeable:
        raise ValueError("the output array is read-only")
    raise_error(fn(ids.ctypes.data, n, arr.ctypes.data), ids)


def get_pos_xz(ids, out):
    """out[k] = (x, z) of body ids[k]'s position (m)."""
    _call(c_get_pos_xz, ids, out, 2, True)


def get_vel_xz(ids, out):
    """out[k] = (vx, vz) of body ids[k]'s velocity (m/s)."""
    _call(c_get_vel_xz, ids, out, 2, True)


def set_vel_xz(ids, V):
    """Body ids[k]'s velocity = (V[k, 0], 0, V[k, 1]) (m/s), as b.state.vel = ... does."""
    _call(c_set_vel_xz, ids, V, 2, False)


def get_angvel_y(ids, out):
    """out[k] = y component of body ids[k]'s angular velocity (rad/s)."""
    _call(c_get_angvel_y, ids, out, 1, True)


def add_torque_y(ids, T):
    """O.forces.addT(ids[k], (0, T[k], 0)) for every k (N m), this step only."""
    _call(c_add_torque_y, ids, T, 1, False)


def add_force_xz(ids, F):
    """O.forces.addF(ids[k], (F[k, 0], 0, F[k, 1])) for every k (N), this step only."""
    _call(c_add_force_xz, ids, F, 2, False)


def set_perm_force_xz(ids, F):
    """O.forces.setPermF(ids[k], (F[k, 0], 0, F[k, 1])) for every k (N), held until changed."""
    _call(c_set_perm_force_xz, ids, F, 2, False)


def add_force_unsynced_xz(ids, F):
    """F[k] (N) added to body ids[k]'s summed force of this step, (F[k, 0], 0, F[k, 1]), without
    the sync() pass that O.forces.addF and setPermF lead to (ForceContainer::addForceUnsynced):
    for scenes whose ForceResetter runs after NewtonIntegrator, between steps."""
    _call(c_add_force_unsynced_xz, ids, F, 2, False)


def steps(n):
    """O.step() n times (YADE's Scene::moveToNextTimeStep; compiled loops call c_steps between
    their own work). An engine's exception stops it and is raised as RuntimeError with its message."""
    if not (_ready or _probing or available()):
        raise RuntimeError(f"engines.yade.yadebulk is not available: {_reason}")
    from yade import O
    if O.running:
        raise RuntimeError("steps() while the simulation is running (O.run): O.pause() first")
    raise_error(c_steps(None, int(n), None), None)

