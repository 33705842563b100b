"""A WaterEngine's water through YADE's own save and restore (O.save/O.load, O.saveTmp/O.loadTmp).

YADE saves the scene (bodies, engines, O.tags) but no Python object: the engine's water travels
as a string in ``O.tags[TAG + key]``, in the checkpoint's format (engines.yade.checkpoint.pack:
the JSON header and named arrays of an .npz, as base64 text; sections ``recipe``: the engine's
constructor arguments, ``state``: its CHECKPOINT_FIELDS, engines.model.state; ``yade``: O.iter).
Nothing in it is executed or unpickled.

* ``install()`` (made by ``WaterEngine.runner()``) wraps ``Omega.save`` and ``Omega.saveTmp``:
  just before YADE writes, every WaterEngine whose runner is in O.engines writes its tag; and
  ``Omega.load`` and ``Omega.loadTmp``: after YADE read, every engine of this process restores its
  water from the loaded tags at its next call.
* The runner's command imports this module and calls ``call(key)``: the engine of that key (this
  process), or one made again from the tag's recipe (a new process: ``O.load`` then ``O.run``).
  Its water is restored from the tag; no tag, or a tag of another step than O.iter, stops the run
  in one line naming what to do. An engine called at a step before its last water step (the scene
  went back without the wrappers) restores from the tags the same way, never running on with
  water of another state.
* ``engine(label)`` gives the script the engine of a loaded scene (to read its pores).
"""
import base64
import binascii
import dataclasses
import io

import numpy as np

from engines.model import state as named_state
from engines.yade import checkpoint, yade_io

TAG = "pore_water:"  # O.tags key of an engine's saved water: TAG + its runner's key
ENGINES = {}  # {key: WaterEngine} of this process's runners
_STALE = set()  # keys whose water is to be restored from O.tags at the next call (after a load)


class RestoreError(RuntimeError):
    """A saved scene whose water cannot be restored; the message names what to do, in one line."""


def runner(engine, label):
    """The PyRunner of ``engine`` (WaterEngine.runner): every water_interval steps, ``call`` by key."""
    from yade.wrapper import PyRunner
    install()
    key = yade_io.new_key(label)
    ENGINES[key] = engine
    return PyRunner(command=yade_io.runner_command(__name__, key), iterPeriod=int(engine.model.schedule.water_interval),
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
    water()


def _runs_here(key):
    """Is the runner of ``key`` among O.engines?"""
    from yade import O
    from yade.wrapper import PyRunner
    return any(isinstance(e, PyRunner) and repr(key) in e.command for e in O.engines)


def engine(label="water"):
    """The WaterEngine of the runner labelled ``label`` in O.engines, its water restored when the
    scene was loaded (in a new process: made again from O.tags)."""
    from yade import O
    from yade.wrapper import PyRunner
    runners = [e for e in O.engines if isinstance(e, PyRunner) and e.label == label and f"{__name__} " in e.command]
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

    from engines.yade.water_engine import WaterEngine
    where = f"O.tags[{TAG + key!r}]"
    remedy = ("make the WaterEngine again and put its runner() in O.engines in place of this PyRunner (its water "
              "starts afresh), or load a scene saved with the engine's runner in O.engines")
    if TAG + key not in O.tags.keys():
        raise RestoreError(f"the scene at step {O.iter} holds no saved water of WaterEngine {key} ({where}): {remedy}")
    try:
        ck = decode(where, O.tags[TAG + key])
    except checkpoint.CheckpointError as e:
        raise RestoreError(f"{e}: {remedy}") from None
    if ck.step != O.iter or ck.yade != {"iter": O.iter}:
        raise RestoreError(f"{where} holds the water of step {ck.step}, the scene is at step {O.iter} (the scene went "
                           f"back or forward without O.load): {remedy}")
    water = ENGINES.get(key)
    if water is None:
        water = WaterEngine(**arguments(ck.recipe))
    values = dict(ck.state)
    try:
        named_state.restore(water, values)
    except named_state.StateError as e:
        raise RestoreError(f"{where}: {e}: {remedy}") from None
    if values:
        raise RestoreError(f"{where}: unknown field(s) {sorted(values)[:5]}: {remedy}")
    if water.model.F is not None:
        water.write_forces()
    ENGINES[key] = water
    _STALE.discard(key)
    return water


# -- YADE's save and load, wrapped ------------------------------------------------------------------
def install():
    """Wrap Omega.save, saveTmp (the tags written first) and load, loadTmp (the engines' water
    restored from the loaded tags at their next call); once per process."""
    from yade.wrapper import Omega
    if getattr(Omega.save, "_pore_water", False):
        return

    def before(method):
        def wrapped(self, *args, **kwargs):
            save_tags()
            return method(self, *args, **kwargs)
        wrapped._pore_water = True
        return wrapped

    def after(method):
        def wrapped(self, *args, **kwargs):
            out = method(self, *args, **kwargs)
            _STALE.update(ENGINES)
            return out
        wrapped._pore_water = True
        return wrapped

    Omega.save, Omega.saveTmp = before(Omega.save), before(Omega.saveTmp)
    Omega.load, Omega.loadTmp = after(Omega.load), after(Omega.loadTmp)
