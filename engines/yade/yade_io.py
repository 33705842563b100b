"""All YADE body I/O of the engines, in bulk: positions and velocities in, forces and velocities out.

Discs are spheres kept in the x-z plane; arrays are (n, 2) [x, z] in the order of the ids given.
The backend is chosen once, at import:

* ``yadebulk``: the compiled bridge engines.yade.yadebulk (C and a little C++ without YADE's
  headers: it calls YADE's exported functions found in libyade.so, at data offsets probed and
  verified at first use), when it is importable and ``available()``; every call is one C loop over
  the ids.
* ``python``: YADE's Python API in its cheapest forms, measured on 240 spheres: positions by two
  ``utils.coordsAndDisplacements`` calls (one list per axis for all bodies), forces by
  ``map(O.forces.addF, ids, rows)`` over rows of a float buffer (0.35 us a body; building
  Vector3 objects first costs twice that). Velocities have no bulk read: per body. Call
  ``freeze_gc()`` once the scene is built (it keeps the garbage collector off the scene's objects).

Set the environment variable PORE_DEM_IO=python to force the Python backend (benchmarks, tests).
"""
import atexit
import ctypes
import gc
import os
import sys
import traceback
import uuid

import numpy as np
from yade import O, utils
from yade.wrapper import PyRunner

from engines.compiled import kernels


def _load_bulk():
    if os.environ.get("PORE_DEM_IO", "") == "python":
        return None
    try:
        from engines.yade import yadebulk
    except ImportError:
        return None
    return yadebulk if yadebulk.available() else None


_BULK = _load_bulk()
BACKEND = "yadebulk" if _BULK is not None else "python"
if _BULK is not None:  # addresses of the bridge's position read, force and velocity writes and step, for kernels
    _GET_POS, _SET_PERM, _ADD_UNSYNCED, _SET_VEL, _STEPS = (
        ctypes.cast(f, ctypes.c_void_p).value
        for f in (_BULK.c_get_pos_xz, _BULK.c_set_perm_force_xz, _BULK.c_add_force_unsynced_xz, _BULK.c_set_vel_xz,
                  _BULK.c_steps))
    _BRIDGE = kernels.BRIDGE.values(get_pos=_GET_POS, write_forces=_SET_PERM, set_vel=_SET_VEL, steps=_STEPS)
    _BRIDGE_RESET_LAST = kernels.BRIDGE.values(get_pos=_GET_POS, write_forces=_ADD_UNSYNCED, set_vel=_SET_VEL,
                                               steps=_STEPS)


def forces_reset_after_newton(engines):
    """Does the engine list reset the forces only after its one NewtonIntegrator ([...,
    NewtonIntegrator, ..., ForceResetter])? Then forces written between two steps reach the next
    step's integration as they are, and ``Bodies.write_forces`` adds them straight into YADE's
    summed forces (no permanent forces, whose sync() pass over all bodies costs every step)."""
    names = [type(e).__name__ for e in engines]
    if names.count("NewtonIntegrator") != 1 or "ForceResetter" not in names:
        return False
    return "ForceResetter" not in names[:names.index("NewtonIntegrator")]


# the remedy for a body of an engine erased after the engine was made
ERASED_HINT = ("(an engine's discs are fixed when it is made: erase bodies before making the WaterEngine, or make a "
               "new one with the discs left; its water starts again)")


class Bodies:
    """Bulk access to the bodies ``ids`` (any order; each id once)."""

    def __init__(self, ids):
        self.ids = np.ascontiguousarray(ids, np.int64)
        self.id_list = self.ids.tolist()
        self.n = len(self.ids)
        self._row = np.zeros((self.n, 3))  # x, y = 0, z rows for the Python API
        self._F = np.zeros((self.n, 2))  # forces being written
        self._all, self._zero = np.arange(self.n), np.zeros((self.n, 2))
        self._index = None  # position of each id in coordsAndDisplacements' lists
        self._n_listed = -1

    # -- reads -----------------------------------------------------------------------------------
    def positions(self):
        """Centres (n, 2) [m]; a new array."""
        out = np.empty((self.n, 2))
        if _BULK is not None:
            check(kernels.read_bulk_io(_GET_POS, self.ids, out), self.ids)
            return out
        x = utils.coordsAndDisplacements(0)[0]
        z = utils.coordsAndDisplacements(2)[0]
        if len(x) != self._n_listed:  # bodies were added or removed: the lists list the existing ones
            existing = np.array([b.id for b in O.bodies if b is not None], np.int64)
            self._index = np.searchsorted(existing, self.ids)
            gone = (self._index >= len(existing)) | (existing[np.minimum(self._index, len(existing) - 1)] != self.ids)
            if gone.any():
                raise IndexError(f"body id {self.ids[gone][0]} is out of range or erased; nothing was done "
                f"{ERASED_HINT}")
            self._n_listed = len(x)
        out[:, 0] = np.asarray(x)[self._index]
        out[:, 1] = np.asarray(z)[self._index]
        return out

    def velocities(self):
        """Velocities (n, 2) [m/s]."""
        out = np.empty((self.n, 2))
        if _BULK is not None:
            _BULK.get_vel_xz(self.ids, out)
            return out
        for k, i in enumerate(self.id_list):
            v = O.bodies[i].state.vel
            out[k, 0], out[k, 1] = v[0], v[2]
        return out

    def spins(self):
        """Angular velocities about y (n,) [rad/s] (counter-clockwise in the x-z plane is -y)."""
        out = np.empty(self.n)
        if _BULK is not None:
            _BULK.get_angvel_y(self.ids, out)
            return out
        for k, i in enumerate(self.id_list):
            out[k] = O.bodies[i].state.angVel[1]
        return out

    # -- writes ----------------------------------------------------------------------------------
    def _rows(self, F):
        self._row[:, 0] = F[:, 0]
        self._row[:, 2] = F[:, 1]
        return self._row.tolist()

    def add_forces(self, F):
        """O.forces.addF for every body, F (n, 2) [N] (reset by ForceResetter each step)."""
        if _BULK is not None:
            _BULK.add_force_xz(self.ids, np.ascontiguousarray(F, float))
        else:
            list(map(O.forces.addF, self.id_list, self._rows(F)))

    def set_permanent_forces(self, F, rows=None, add=None):
        """O.forces.setPermF for every body (held until set again): F (n, 2) [N], or with ``rows``
        (n,) F[rows] + add, F (m, 2) over some larger set of which these bodies are the rows."""
        self.write_forces(F, rows, add, False)

    def write_forces(self, F, rows, add, reset_last):
        """The forces of the next step, as ``set_permanent_forces``, or with ``reset_last`` (the
        engine list resets the forces after NewtonIntegrator: ``forces_reset_after_newton``) added
        to the reset forces: by the bridge's add_force_unsynced_xz, else O.forces.addF."""
        if rows is None:
            rows, add = self._all, self._zero
        if _BULK is not None:
            write = _ADD_UNSYNCED if reset_last else _SET_PERM
            check(kernels.write_rows_bulk_io(write, self.ids, np.ascontiguousarray(F, float), rows, add, self._F),
                  self.ids)
        else:
            np.add(F[rows], add, out=self._F)
            list(map(O.forces.addF if reset_last else O.forces.setPermF, self.id_list, self._rows(self._F)))


def drive_water(n, step_last, water_in, water_interval, totals, xz_built, moved2, reader, xz, writer, out, args):
    """kernels.water_drive_bulk_io through the bridge (BACKEND "yadebulk" only): n steps (the last
    one's O.step() left to the caller unless ``step_last``), the water
    steps among them (step water_in, then every water_interval) with their positions read from
    ``reader`` and forces out written to ``writer``
    (Bodies), args those of kernels.water_forces_step after (xz, out); it stops early before a
    water step at which a disc is farther than sqrt(moved2) [m] from xz_built (moved2 > 0). Returns
    its (steps, water steps, answer, error code)."""
    return kernels.water_drive_bulk_io(_BRIDGE, n, step_last, water_in, water_interval, totals, xz_built, moved2,
                                       reader.ids, xz,
                                       writer.ids, out, *args)


def drive_dem(k, step_last, drive, walls, wall_vel, reader, xz, writer, out, reset_last):
    """kernels.dem_drive_bulk_io through the bridge (BACKEND "yadebulk" only) with the
    engines.compiled.pore_dem.Drive ``drive``: up to drive.steps steps from step k (the last one's
    O.step() left to the caller unless ``step_last``; the water at step drive.water_in, then every
    drive.water_interval; drive.adjust: the eq 18-24 adjustment is on, with restitution drive.e and
    the discs' masses drive.mass (N,) [kg/m]; stale pair lists rebuilt with drive.skin [m]), the
    positions read from ``reader`` and the forces out written to ``writer`` (Bodies; held, or with
    ``reset_last`` added to the reset forces: ``Bodies.write_forces``), the velocities of the
    driven walls ``walls`` (Bodies; wall_vel (m, 2) scratch) set from the base motion drive.motion
    and its record (t_s, a_s) (kernels.base_step), drive.args those of dem_drive_bulk_io after
    F_out. Returns its (steps made, of them stepped, list stale, water answer, error code, pair
    lists built, pi, pj, state, lost)."""
    d = drive
    t_s, a_s = d.record
    return kernels.dem_drive_bulk_io(_BRIDGE_RESET_LAST if reset_last else _BRIDGE, d.steps, k, step_last, d.water_in,
                                     d.water_interval, d.adjust, d.e, d.mass, d.skin, d.totals, d.motion, t_s, a_s,
                                     walls.ids, wall_vel, reader.ids, xz, writer.ids, out, *d.args)


def check(rc, ids=None):
    """Raise on a bridge function's error code (engines.yade.yadebulk); nothing on 0."""
    if rc != 0:
        _BULK.raise_error(rc, ids)


def freeze_gc():
    """Collect garbage, then move every live object out of the garbage collector's reach
    (gc.freeze), undoing an earlier call first. Call it once a scene is built: the Python backend
    makes one small list per body per write, and the collections they trigger otherwise scan the
    whole scene each time (measured: a 10,000-body force write 14 -> 5 ms, 2,000 bodies -25 to -45 %)."""
    gc.unfreeze()
    gc.collect()
    gc.freeze()


def set_velocities(ids, V):
    """state.vel of a few bodies ``ids`` (k,) to V (k, 2) [m/s]."""
    if _BULK is not None:
        _BULK.set_vel_xz(np.ascontiguousarray(ids, np.int64), np.ascontiguousarray(V, float))
        return
    for i, (vx, vz) in zip(np.asarray(ids).tolist(), np.asarray(V, float).tolist()):
        O.bodies[i].state.vel = (vx, 0.0, vz)


ERRORS = []  # exceptions raised inside engine callbacks, first one first (raise_pending re-raises)


def guarded(callback):
    """``callback`` as an engine callback: an exception pauses YADE and is kept for ``raise_pending``."""
    def run():
        try:
            callback()
        except BaseException as e:  # stop YADE cleanly; raise_pending re-raises, else _exit_if_pending
            if not ERRORS:
                traceback.print_exc()
            ERRORS.append(e)
            O.pause()
    return run


def raise_pending():
    """Re-raise the first exception an engine callback raised since the last call."""
    if ERRORS:
        err = ERRORS[0]
        ERRORS.clear()
        raise err


@atexit.register
def _exit_if_pending():
    """At the interpreter's exit (the end of `yade -x script.py`), an engine error the script never
    raised (``raise_pending``) ends the process with status 1 and the error in one line on stderr."""
    if ERRORS:
        sys.stdout.flush()
        err = ERRORS[0]
        print(f"error inside a YADE engine, never raised by the script: {type(err).__name__}: "
              + " ".join(str(err).split()), file=sys.stderr, flush=True)
        os._exit(1)


CALLBACKS = {}  # {key: guarded callback} of the PyRunners made in this process (py_runner)
# A PyRunner's command imports its module (the project) and calls by key: nothing in builtins, so
# a scene saved by O.save and loaded by O.load, in this process or another, finds the module again
COMMAND = ("try:\n    import {module} as _pw\nexcept ImportError as e:\n    raise ImportError(\"this PyRunner "
           "calls the pore-water project ({module}), not importable here (\" + str(e) + \"): install it (make deps) "
           "or put its folder on sys.path before O.run\") from None\n_pw.call({key!r})")


def runner_command(module, key):
    """The command of a PyRunner that imports ``module`` (of the project) and calls its ``call(key)``."""
    return COMMAND.format(module=module, key=key)


def new_key(label):
    """A key for a PyRunner's callback, unique across processes (a saved scene keeps it)."""
    return f"{label or 'runner'}-{uuid.uuid4().hex[:12]}"


def py_runner(callback, iter_period=1, label=""):
    """A PyRunner that calls ``callback()`` every ``iter_period`` steps (its command imports this
    module and calls ``call`` with its key). An exception in the callback pauses YADE and is kept
    for ``raise_pending`` (never raised: the process exits with status 1)."""
    key = new_key(label)
    CALLBACKS[key] = guarded(callback)
    return PyRunner(command=runner_command(__name__, key), iterPeriod=int(iter_period), initRun=True, label=label)


def call(key):
    """The command of a PyRunner made by ``py_runner``: its callback, or (a scene loaded by O.load in
    another process) an error naming what to do."""
    callback = CALLBACKS.get(key)
    if callback is None:
        def callback():
            raise RuntimeError(f"PyRunner {key}: its engine was made in another process (a scene loaded by O.load); "
                               "make the engine again and put its runner() in O.engines in place of this PyRunner")
        callback = guarded(callback)
    callback()
