"""A WaterEngine's water through YADE's own save and restore (O.save/O.load, O.saveTmp/O.loadTmp).

YADE saves the scene (bodies, engines, O.tags) but no Python object: the engine's water travels
as a string in ``O.tags[TAG + key]``, in the checkpoint's format (engines.yade.checkpoint.pack:
the JSON header and named arrays of an .npz, as base64 text; sections ``recipe``: the engine's
constructor arguments, ``state``: its CHECKPOINT_FIELDS, engines.model.state; ``yade``: O.iter).
Nothing in it is executed or unpickled.

* ``install()`` (called by ``WaterEngine.runner()``) wraps ``Omega.save`` and ``Omega.saveTmp``:
  just before YADE writes, every WaterEngine whose runner is in O.engines writes its tag; and
  ``Omega.load`` and ``Omega.loadTmp``: after YADE read, every engine of this process restores its
  water from the loaded tags: those whose runner is in the loaded O.engines at once (a RestoreError
  raised by the load), the others when they are called.
* YADE saves no permanent force: the runners are saved due at the next step, where the
  restored engine sets its forces again and puts its runner back on its schedule.
* The runner's command imports engines.yade.water_engine (RUNNER_MODULE, which gives this module
  its class, ENGINE_CLASS) and calls ``call(key)``: the engine of that key (this process), or one
  made again from the tag's recipe (a new process: ``O.load`` then ``O.run``).
  Its water is restored from the tag (saved at step k, valid up to the engine's next water step:
  O.iter in k ... k + water_interval); no tag, or a tag of another step, stops the run in one line
  naming what to do. An engine called at a step before its last water step (the scene
  went back without the wrappers) restores from the tags the same way, never running on with
  water of another state.
* ``engine(label)`` gives the script the engine of a loaded scene (to read its pores); a new
  engine's runner made while a loaded runner with saved water is in O.engines says, on stderr,
  that its water starts afresh.
"""
import base64
import binascii
import dataclasses
import io
import sys

import numpy as np

from engines.model import state as named_state
from engines.yade import checkpoint, yade_io

TAG = "pore_water:"  # O.tags key of an engine's saved water: TAG + its runner's key
ENGINES = {}  # {key: WaterEngine} of this process's runners
_STALE = set()  # keys whose water is to be restored from O.tags at the next call (after a load)
_LOADED = set()  # keys restored from O.tags whose runner has not been called since


RUNNER_MODULE = "engines.yade.water_engine"  # the runners' command imports it; it re-exports ``call``
ENGINE_CLASS = None  # WaterEngine, set by RUNNER_MODULE at its import (this module does not import it)


class RestoreError(RuntimeError):
    """A saved scene whose water cannot be restored; the message names what to do, in one line."""


def runner(engine, label):
    """The PyRunner of ``engine`` (WaterEngine.runner): every water_interval steps, ``call`` by key."""
    from yade import O
    from yade.wrapper import PyRunner
    install()
    saved = [k for k in (t[len(TAG):] for t in O.tags.keys() if t.startswith(TAG))
             if (k not in ENGINES or k in _LOADED) and _runs_here(k)]  # loaded, not yet run on
    if saved:
        print(f"WaterEngine: the scene's runner(s) {saved} hold saved water (a loaded scene); this new engine's water "
              "starts afresh (U = 0): to go on with the saved water, keep the loaded runner in O.engines "
              "(engines.yade.scene_save.engine(label) gives its engine)", file=sys.stderr, flush=True)
    key = yade_io.new_key(label)
    ENGINES[key] = engine
    return PyRunner(command=yade_io.runner_command(RUNNER_MODULE, key), iterPeriod=int(engine.model.schedule.water_interval),
                    initRun=True, label=label)


def call(key):
    """The runner's command: the water step of the engine ``key``, its water restored first when
    the scene was loaded (module docstring). An error pauses YADE (engines.yade.yade_io.guarded)."""
    yade_io.guarded(lambda: _step(key))()


def _step(key):
    from yade import O
    water = ENGINES.get(key)
    if water is None or key in _STALE or O.iter < water.k:
        water = restore(key)
    if key in _LOADED:  # the first call after a load (``install``): the forces are set again (restore);
        _LOADED.discard(key)  # the water step only where the saved runner's call was due
        runner = _runners(key)[0]
        if O.iter < water.k + runner.iterPeriod:
            runner.iterLast = water.k
            return
    water()


def set_period(water, period, first):
    """The runners of the engine ``water`` call it every ``period`` steps from step ``first`` on."""
    for key in [k for k, e in ENGINES.items() if e is water]:
        for r in _runners(key):
            r.iterPeriod, r.iterLast = int(period), int(first) - int(period)


def _runners(key):
    """The PyRunners of ``key`` among O.engines."""
    from yade import O
    from yade.wrapper import PyRunner
    return [e for e in O.engines if isinstance(e, PyRunner) and repr(key) in e.command]


def _runs_here(key):
    """Is the runner of ``key`` among O.engines?"""
    return bool(_runners(key))


def engine(label="water"):
    """The WaterEngine of the runner labelled ``label`` in O.engines, its water restored when the
    scene was loaded (in a new process: made again from O.tags)."""
    from yade import O
    from yade.wrapper import PyRunner
    runners = [e for e in O.engines if isinstance(e, PyRunner) and e.label == label and f"{RUNNER_MODULE} " in e.command]
    if len(runners) != 1:
        raise RestoreError(f"{len(runners)} WaterEngine runners labelled {label!r} in O.engines; give the label of one")
    key = runners[0].command.rsplit("call(", 1)[1].rstrip(")").strip("'\"")
    water = ENGINES.get(key)
    return restore(key) if water is None or key in _STALE else water


# -- the tag ----------------------------------------------------------------------------------------
def recipe(arguments):
    """The constructor arguments of a WaterEngine (WaterEngine.arguments) as data: settings as the
    dict of its fields, flat_walls' ids as strings, arrays of numbers as arrays."""
    out = {}
    for name, value in arguments.items():
        if dataclasses.is_dataclass(value):
            value = dataclasses.asdict(value)
        elif name == "flat_walls" and value:
            value = {str(int(i)): kind for i, kind in value.items()}
        elif name == "walls" and value:
            value = {k: [int(i) for i in ids] for k, ids in value.items()}
        elif name in ("disc_ids", "radii") and value is not None:
            value = np.asarray(value, np.int64 if name == "disc_ids" else float)
        out[name] = value
    return out


def arguments(stored):
    """The WaterEngine's constructor arguments of a stored ``recipe``."""
    from engines.model.pore_water import WaterSettings
    out = dict(stored)
    out["settings"] = WaterSettings(**out["settings"])
    out["disc_ids"] = np.asarray(out["disc_ids"]).tolist()
    if out.get("flat_walls"):
        out["flat_walls"] = {int(i): kind for i, kind in out["flat_walls"].items()}
    return out


def encode(water, step):
    """The saved water of ``water`` at DEM step ``step``, as the text of its tag."""
    members = checkpoint.pack(step, {"what": "WaterEngine"}, {
        "recipe": recipe(water.arguments), "state": named_state.state_of(water), "yade": {"iter": int(step)}})
    buf = io.BytesIO()
    np.savez(buf, **members)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def decode(where, text):
    """The Checkpoint in the tag text ``text`` (named ``where`` in the messages); CheckpointError."""
    try:
        data = base64.b64decode(text.encode("ascii"), validate=True)
    except (binascii.Error, UnicodeEncodeError):
        raise checkpoint.CheckpointError(f"{where}: not base64 text of a saved water") from None
    return checkpoint.load_bytes(where, data)


def save_tags():
    """Write O.tags[TAG + key] for every engine of this process whose runner is in O.engines."""
    from yade import O
    for key, water in ENGINES.items():
        if key not in _STALE and _runs_here(key):
            O.tags[TAG + key] = encode(water, O.iter)


def restore(key):
    """The engine ``key`` with its water from O.tags (this process's engine, set in place, or one
    made again from the tag's recipe); RestoreError in one line naming what to do."""
    from yade import O
    where = f"O.tags[{TAG + key!r}]"
    remedy = ("make the WaterEngine again and put its runner() in O.engines in place of this PyRunner (its water "
              "starts afresh), or load a scene saved with the engine's runner in O.engines")
    if TAG + key not in O.tags.keys():
        raise RestoreError(f"the scene at step {O.iter} holds no saved water of WaterEngine {key} ({where}): {remedy}")
    try:
        ck = decode(where, O.tags[TAG + key])
    except checkpoint.CheckpointError as e:
        raise RestoreError(f"{e}: {remedy}") from None
    interval = ck.recipe.get("water_interval")
    if not (ck.yade == {"iter": ck.step} and type(interval) is int and 0 <= O.iter - ck.step <= interval):
        raise RestoreError(f"{where} holds the water of step {ck.step}, the scene is at step {O.iter} (the scene went "
                           f"back or forward without O.load): {remedy}")
    water = ENGINES.get(key)
    if water is None:
        water = ENGINE_CLASS(**arguments(ck.recipe))
    try:
        named_state.restore_all(water, ck.state)
    except named_state.StateError as e:
        raise RestoreError(f"{where}: {e}: {remedy}") from None
    if water.model.F is not None:
        water.write_forces()
    ENGINES[key] = water
    _STALE.discard(key)
    _LOADED.add(key)
    return water


# -- YADE's save and load, wrapped ------------------------------------------------------------------
def install():
    """Wrap Omega.save, saveTmp (the tags written first) and load, loadTmp (the engines' water
    restored from the loaded tags at their next call); once per process."""
    from yade import O
    from yade.wrapper import Omega
    if getattr(Omega.save, "_pore_water", False):
        return

    def before(method):
        def wrapped(self, *args, **kwargs):
            save_tags()
            # saved due at the next step: after a load (in a new process, where nothing of the project
            # runs before it) the runner restores the water and the permanent forces YADE does not save
            runners = [(r, r.iterLast) for key in ENGINES for r in _runners(key)]
            for r, last in runners:
                r.iterLast = O.iter - r.iterPeriod
            try:
                return method(self, *args, **kwargs)
            finally:
                for r, last in runners:
                    r.iterLast = last
        wrapped._pore_water = True
        return wrapped

    def after(method):
        def wrapped(self, *args, **kwargs):
            out = method(self, *args, **kwargs)
            _STALE.update(ENGINES)
            for key in list(ENGINES):
                if _runs_here(key):
                    restore(key)
            return out
        wrapped._pore_water = True
        return wrapped

    Omega.save, Omega.saveTmp = before(Omega.save), before(Omega.saveTmp)
    Omega.load, Omega.loadTmp = after(Omega.load), after(Omega.loadTmp)
