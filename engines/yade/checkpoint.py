"""Checkpoints from which a run continues exactly (engines.run.runner: interrupt, crash, resume).

One file, written atomically (a temporary file renamed over the old one), holding

* YADE's own ``O.save`` of the scene, as bytes: the bodies with their positions, velocities, spins,
  masses and blocked DOFs, the engines (a wall's TranslationEngine velocity), the interactions and
  collider of law = 'yade', O.iter, O.time, O.dt, O.tags;
* the Python side of the run, pickled whole: for engines.run.runner the ``Run`` with its coupling,
  the paper's law (contact springs, pair list, separation state, spin, previous positions), the
  pores and water (W, smoothing memory, balance, rules), the input motion, the recorder (rows
  written, snapshot and VTK schedule).

Pickling the objects rather than listing their fields keeps whatever state an engine gains later
in the checkpoint without extra work; completeness is tested by continuing a run and comparing it
with one that was not stopped (tests/yade/test_checkpoint.py). A closure in that state cannot be pickled
(make it a small class, as engines.model.ground_motion.Cosine): a run says so at its first checkpoint, at
step 0, rather than when it is interrupted. YADE objects that the
Python state refers to (a wall's engine) must be in O.engines: they are stored as their place
there and bound to the loaded scene's engines on load. O.save does not keep YADE's permanent
forces: whoever holds them sets them again after ``load`` (YadeCoupling.restore_forces).
"""
import io
import os
import pickle
import tempfile

FORMAT = 4  # raised when the pickled classes change (moved, split, fields): a checkpoint of another format is refused
NAME = "checkpoint.pkl"  # a run's checkpoint in its output directory (engines.run.runner)


class CheckpointError(ValueError):
    """A checkpoint that cannot be read or does not belong here; the message says why."""


class _Pickler(pickle.Pickler):
    def __init__(self, f):
        from yade import O
        super().__init__(f, protocol=pickle.HIGHEST_PROTOCOL)
        self._engines = list(O.engines)  # held, so that the ids below stay valid while pickling
        self._place = {id(e): k for k, e in enumerate(self._engines)}

    def persistent_id(self, obj):
        from yade.wrapper import Serializable
        if not isinstance(obj, Serializable):
            return None
        k = self._place.get(id(obj))
        if k is None:
            raise pickle.PicklingError(f"checkpoint: the run's state refers to a YADE {type(obj).__name__} that is not "
                                       "in O.engines (only O.engines are bound again on load)")
        return ("engine", k)


class _Unpickler(pickle.Unpickler):
    def __init__(self, f):
        from yade import O
        super().__init__(f)
        # engines made by O.load get a new Python wrapper at each access; given back to YADE
        # from Python, they keep these wrappers, so that the next save finds them in O.engines
        self._engines = list(O.engines)
        O.engines = self._engines

    def persistent_load(self, pid):
        kind, k = pid
        if kind != "engine" or k >= len(self._engines):
            raise CheckpointError(f"checkpoint: no YADE engine {pid} in the saved scene")
        return self._engines[k]


def save(path, state, info=None):
    """Write YADE's scene and the picklable ``state`` to ``path`` (replacing it atomically);
    ``info``: a small dict of plain values readable without YADE (``read_info``)."""
    from yade import O
    folder = os.path.dirname(os.path.abspath(path))
    buf = io.BytesIO()
    try:
        _Pickler(buf).dump(state)
    except (pickle.PicklingError, TypeError, AttributeError) as e:
        if str(e).startswith("checkpoint:"):
            raise
        raise pickle.PicklingError(f"checkpoint: the run's state holds an object that does not pickle ({e}); "
                                   "a lambda or closure? make it a small class (as engines.model.ground_motion.Cosine)") from e
    fd, scene_file = tempfile.mkstemp(prefix=".checkpoint-", suffix=".yade.gz", dir=folder)
    os.close(fd)
    try:
        O.save(scene_file)  # binary, gzip'd: doubles exactly
        with open(scene_file, "rb") as f:
            scene = f.read()
    finally:
        os.remove(scene_file)
    payload = {"format": FORMAT, "step": O.iter, "info": info or {}, "yade_scene": scene, "state": buf.getvalue()}
    fd, tmp = tempfile.mkstemp(prefix=".checkpoint-", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            pickle.dump(payload, f, protocol=pickle.HIGHEST_PROTOCOL)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # as an ordinary file, not mkstemp's 0600
        os.replace(tmp, path)
    except BaseException:
        os.remove(tmp)
        raise


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


def read_info(path):
    """The step and ``info`` of a checkpoint, without YADE: {"step": k, **info}. Raises
    CheckpointError for a missing or unreadable file."""
    payload = _payload(path)
    return {"step": payload["step"]} | payload["info"]


def _payload(path):
    try:
        with open(path, "rb") as f:
            payload = pickle.load(f)
    except FileNotFoundError:
        raise CheckpointError(f"no checkpoint: {path} does not exist") from None
    except (pickle.UnpicklingError, EOFError, AttributeError, ImportError) as e:
        raise CheckpointError(f"{path}: not a readable checkpoint ({type(e).__name__}: {e})") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"{path}: not a checkpoint of format {FORMAT}")
    return payload


def load(path):
    """Load a checkpoint: YADE's scene becomes the current one (O.load), then the Python state is
    unpickled against it and returned."""
    from yade import O
    payload = _payload(path)
    fd, scene_file = tempfile.mkstemp(suffix=".yade.gz")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(payload["yade_scene"])
        O.load(scene_file)
    finally:
        os.remove(scene_file)
    if O.iter != payload["step"]:
        raise CheckpointError(f"{path}: YADE's scene is at step {O.iter}, the run's state at {payload['step']}")
    return _Unpickler(io.BytesIO(payload["state"])).load()
