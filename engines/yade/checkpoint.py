"""Checkpoints from which a run continues exactly (engines.run.runner: interrupt, crash, resume), as data.

One ``.npz`` file (NumPy's zip of arrays, read with ``allow_pickle=False``), written atomically
(engines.files.savez). Its member ``header`` is a uint8 array holding UTF-8 JSON:
{"format": FORMAT, "step": O.iter, "info": {...}, "recipe": {...}, "state": {...}, "yade": {...},
"arrays": [member names]}; every other member is an array of numbers named ``SECTION:NAME``:

* ``recipe``: what the reader needs to build the object again as a fresh run builds it (for a run:
  the scene's tables and the packing's arrays; engines.run.runner.Run.recipe);
* ``state``: the named state of that object and its parts (engines.model.state: each class lists
  the attributes it stores next to it, CHECKPOINT_FIELDS);
* ``yade``: O.iter, O.time, O.dt and the bodies' positions, velocities and spins (angular
  velocities); with YADE's own contact law (an InteractionLoop among O.engines: interactions with
  their history) YADE's own ``O.save`` of the scene instead of the bodies' arrays, as bytes.

Resuming (``load`` then ``restore``): the caller builds the object from the recipe (for a run:
the scene and packing, YADE's bodies and engines, the pores at the packing's positions), then
``restore`` sets YADE's bodies (or loads YADE's save and puts the freshly built engines back in
place of the loaded ones: the loaded engines never run, and engine types the scene does not
make, a PyRunner among them, are refused) and then every named field. Nothing in the file is
executed, no Python object is unpickled from it, O.tags are not read: a file that is anything else (a
pickle, another format, a truncated file, an array of another dtype or shape, a missing or
unknown field) is refused in one line naming it. YADE's own binary loader (O.load, law = 'yade'
only) is not hardened against crafted archives (docs/RELIABILITY.md).
"""
import io
import json
import os
import tempfile
import zipfile
from dataclasses import dataclass

import numpy as np

from engines import files
from engines.model import state as named_state

FORMAT = 4  # raised when the stored fields change: a checkpoint of another format is refused
NAME = "checkpoint.npz"  # a run's checkpoint in its output directory (engines.run.runner)
OLD_NAME = "checkpoint.pkl"  # the pickled checkpoints of formats 1-3: refused, never read
SECTIONS = ("recipe", "state", "yade")
PICKLE_MAGIC = b"\x80"  # the first byte of a pickle of protocol >= 2
ZIP_MAGIC = b"PK"
YADE_ENGINES = ("ForceResetter", "InsertionSortCollider", "InteractionLoop", "TranslationEngine", "NewtonIntegrator")


class CheckpointError(ValueError):
    """A checkpoint that cannot be read or does not belong here; the message says why, in one line."""


@dataclass
class Checkpoint:
    """What ``load`` read: the step, ``info``, and per section {name: plain value or array}."""

    path: str
    step: int
    info: dict
    recipe: dict
    state: dict
    yade: dict


def _yade_state(folder):
    """{name: value} of YADE's scene: see the module docstring."""
    from yade import O
    from yade.wrapper import InteractionLoop
    out = {"iter": int(O.iter), "time": float(O.time), "dt": float(O.dt)}
    if any(isinstance(e, InteractionLoop) for e in O.engines):
        fd, tmp = tempfile.mkstemp(prefix=f"{files.TEMP_PREFIX}{NAME}{files.TEMP_MARK}", suffix=".yade.gz", dir=folder)
        os.close(fd)
        try:
            O.save(tmp)  # binary, gzip'd: doubles exactly
            with open(tmp, "rb") as f:
                out["scene"] = np.frombuffer(f.read(), np.uint8)
        finally:
            os.remove(tmp)
        return out
    bodies = list(O.bodies)
    out["pos"] = np.array([tuple(b.state.pos) for b in bodies], float).reshape(-1, 3)
    out["vel"] = np.array([tuple(b.state.vel) for b in bodies], float).reshape(-1, 3)
    out["ang_vel"] = np.array([tuple(b.state.angVel) for b in bodies], float).reshape(-1, 3)
    return out


def save(path, state, info=None, recipe=None):
    """Write YADE's scene and the named state of ``state`` (an object whose class lists
    CHECKPOINT_FIELDS, engines.model.state) to ``path``, replacing it atomically; ``info``: a small
    dict of plain values readable without YADE (``read_info``); ``recipe``: {name: plain value or
    array} to build the object again (module docstring)."""
    from yade import O
    sections = {"recipe": recipe or {}, "state": named_state.state_of(state),
                "yade": _yade_state(os.path.dirname(os.path.abspath(path)))}
    files.savez(path, compressed=False, **pack(int(O.iter), info, sections))


def pack(step, info, sections):
    """{member: array} of the checkpoint format (module docstring) for ``sections`` {section:
    {name: plain value or array}}: the ``header`` member and one array member per array. The one
    encoding of a checkpoint file and of a WaterEngine's saved state in O.tags (engines.yade.scene_save)."""
    header = {"format": FORMAT, "step": int(step), "info": info or {}, "arrays": []}
    arrays = {}
    for section in SECTIONS:
        header[section] = {}
        for name, value in sections.get(section, {}).items():
            if isinstance(value, np.ndarray):
                arrays[f"{section}:{name}"] = value
            else:
                header[section][name] = value
    header["arrays"] = sorted(arrays)
    text = json.dumps(header, separators=(",", ":"))
    return {"header": np.frombuffer(text.encode("utf-8"), np.uint8), **arrays}


def resume_end(step, n_steps, dt, duration=None):
    """The last step of a run resumed at ``step`` that was to end at ``n_steps``: n_steps, or that
    of a later ``duration`` [s]. Raises ValueError (naming --duration or the complete run) when there
    is nothing left to run."""
    if duration is None:
        if step >= n_steps:
            raise ValueError(f"the run is complete (t = {step * dt:g} s); give a later --duration to continue it")
        return n_steps
    n = int(round(duration / dt))
    if n <= step:
        raise ValueError(f"--duration {duration:g} s: the run is already at t = {step * dt:g} s")
    return n


def _older(path):
    return CheckpointError(f"{path}: a checkpoint of an older format (a pickle), which is not read; run the scene "
                           "again (without --resume)")


def _read(path):
    """{member: array} of the checkpoint file ``path``, every member read (refusals: module docstring)."""
    if not os.path.exists(path):
        old = os.path.join(os.path.dirname(path), OLD_NAME)
        if os.path.basename(path) == NAME and os.path.exists(old):
            raise _older(old)
        raise CheckpointError(f"no checkpoint: {path} does not exist")
    if not os.path.isfile(path):
        raise CheckpointError(f"{path}: not a checkpoint (not a regular file)")
    with open(path, "rb") as f:
        head = f.read(2)
    if head[:1] == PICKLE_MAGIC:
        raise _older(path)
    return _members(path, path, head)


def _members(path, source, head):
    """{member: array} of the .npz ``source`` (a path or a binary file) whose first bytes are
    ``head``, read from ``path`` (named in the messages)."""
    if head != ZIP_MAGIC:
        raise CheckpointError(f"{path}: not a checkpoint (not a NumPy .npz file)")
    try:
        with np.load(source, allow_pickle=False) as z:
            members = {name: z[name] for name in z.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError, RuntimeError) as e:
        reason = "truncated or damaged" if isinstance(e, (zipfile.BadZipFile, EOFError)) else str(e).splitlines()[0]
        raise CheckpointError(f"{path}: not a readable checkpoint ({reason})") from None
    other = [name for name, a in members.items() if not isinstance(a, np.ndarray)]
    if other:
        raise CheckpointError(f"{path}: not a checkpoint (member {other[0]!r} is not a NumPy array)")
    return members


def load(path):
    """Read the checkpoint ``path`` without YADE: a Checkpoint, or CheckpointError in one line."""
    return unpack(path, _read(path))


def load_bytes(where, data):
    """The Checkpoint of the .npz bytes ``data`` (``pack``'s members, saved by np.savez), read from
    ``where`` (named in the messages); CheckpointError in one line."""
    return unpack(where, _members(where, io.BytesIO(data), data[:2]))


def unpack(path, members):
    """The Checkpoint of the members {name: array} read from ``path`` (a file, or where else they
    were read: named in the messages); CheckpointError in one line."""
    members = dict(members)
    raw = members.pop("header", None)
    if raw is None or raw.dtype != np.uint8 or raw.ndim != 1:
        raise CheckpointError(f"{path}: not a checkpoint (no header)")
    try:
        header = json.loads(raw.tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise CheckpointError(f"{path}: not a checkpoint (its header is not JSON: {e})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        found = header.get("format") if isinstance(header, dict) else None
        raise CheckpointError(f"{path}: not a checkpoint of format {FORMAT} (format {found!r}); run the scene again")
    expected = {"format", "step", "info", "arrays", *SECTIONS}
    if set(header) != expected:
        raise CheckpointError(f"{path}: the header's fields are {sorted(header)}, expected {sorted(expected)}")
    if not (type(header["step"]) is int and header["step"] >= 0 and isinstance(header["info"], dict)
            and all(isinstance(header[s], dict) for s in SECTIONS) and isinstance(header["arrays"], list)):
        raise CheckpointError(f"{path}: the header's step, info or sections are not of their types")
    if sorted(members) != sorted(header["arrays"]):
        unknown, missing = sorted(set(members) - set(header["arrays"])), sorted(set(header["arrays"]) - set(members))
        raise CheckpointError(f"{path}: arrays {unknown} not in the header, {missing} missing")
    sections = {s: dict(header[s]) for s in SECTIONS}
    for member, a in members.items():
        section, _, name = member.partition(":")
        if section not in sections or not name or name in sections[section]:
            raise CheckpointError(f"{path}: array {member!r} is not of a section ({', '.join(SECTIONS)})")
        if a.dtype.kind not in "biuf":
            raise CheckpointError(f"{path}: array {member!r} holds {a.dtype}, not numbers")
        sections[section][name] = a
    return Checkpoint(path, header["step"], header["info"], **sections)


def read_info(path):
    """The step and ``info`` of a checkpoint, without YADE: {"step": k, **info}. Raises
    CheckpointError for a missing or unreadable file."""
    ck = load(path)
    return {"step": ck.step} | ck.info


def restore(ck, state):
    """Make YADE's scene that of the checkpoint ``ck`` and set the named state of ``state`` (built
    afresh from ck.recipe, with its YADE scene; module docstring). CheckpointError in one line."""
    from yade import O
    y = dict(ck.yade)
    try:
        step, time_, dt = (y.pop(k) for k in ("iter", "time", "dt"))
    except KeyError as e:
        raise CheckpointError(f"{ck.path}: YADE's {e.args[0]} is missing") from None
    if not (type(step) is int and step == ck.step and type(time_) is float and type(dt) is float and dt > 0):
        raise CheckpointError(f"{ck.path}: YADE's iter, time and dt are not step {ck.step} and two numbers")
    if "scene" in y:  # O.load set iter, time and dt (setting them again by updateAttrs
        # changed how a loaded scene of law = 'yade' went on: measured)
        _load_yade_scene(ck.path, y.pop("scene"))
        if (O.iter, O.time, O.dt) != (step, time_, dt):
            raise CheckpointError(f"{ck.path}: YADE's scene is at step {O.iter}, the run's state at {step}")
    else:
        _set_bodies(ck.path, y)
        O._sceneObj.updateAttrs({"iter": step, "time": time_, "dt": dt})
    if y:
        raise CheckpointError(f"{ck.path}: unknown YADE field(s) {sorted(y)}")
    try:
        named_state.restore_all(state, ck.state)
    except named_state.StateError as e:
        raise CheckpointError(f"{ck.path}: {e}") from None


def _set_bodies(path, y):
    """Set the positions, velocities and spins of YADE's bodies (built afresh) from ``y``."""
    from yade import O
    from yade.minieigenHP import Vector3
    bodies = list(O.bodies)
    arrays = []
    for k in ("pos", "vel", "ang_vel"):
        a = y.pop(k, None)
        if not (isinstance(a, np.ndarray) and a.dtype == float and a.shape == (len(bodies), 3)
                and np.isfinite(a).all()):
            raise CheckpointError(f"{path}: YADE's {k} must be ({len(bodies)}, 3) finite floats, got "
                                  f"{getattr(a, 'shape', type(a).__name__)}")
        arrays.append(a.tolist())
    for b, p, v, w in zip(bodies, *arrays):
        b.state.pos, b.state.vel, b.state.angVel = Vector3(*p), Vector3(*v), Vector3(*w)


def _load_yade_scene(path, data):
    """O.load of YADE's own save (law = 'yade'), then the freshly built engines put back in place of
    the loaded ones, after checking that the loaded scene has the fresh one's bodies and only the
    engine types the scene makes."""
    from yade import O
    if not (isinstance(data, np.ndarray) and data.dtype == np.uint8 and data.ndim == 1):
        raise CheckpointError(f"{path}: YADE's scene must be bytes")
    fresh = list(O.engines)  # held: put back after the load
    shapes = [type(b.shape).__name__ for b in O.bodies]
    fd, tmp = tempfile.mkstemp(suffix=".yade.gz")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data.tobytes())
        O.load(tmp)
    except RuntimeError as e:  # YADE's loader: "input stream error", "gzip error: ..."
        reason = str(e).splitlines()[0] if str(e) else repr(e)
        raise CheckpointError(f"{path}: YADE's scene does not load ({reason})") from None
    finally:
        os.remove(tmp)
    loaded = [type(e).__name__ for e in O.engines]
    made = {type(e).__name__ for e in fresh}
    if not set(loaded) <= made & set(YADE_ENGINES):
        O.engines = []
        raise CheckpointError(f"{path}: YADE's scene holds engines {sorted(set(loaded) - made)} that the scene does "
                              "not make; refused")
    O.engines = fresh
    if [type(b.shape).__name__ for b in O.bodies] != shapes:
        raise CheckpointError(f"{path}: YADE's scene has other bodies than the run's scene builds")
