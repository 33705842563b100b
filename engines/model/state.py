"""The named state of a run's objects, as data: what a checkpoint (engines.yade.checkpoint) stores.

A class whose instances carry state from step to step says which of its attributes do, next to it:

* ``CHECKPOINT_FIELDS``: the attributes a checkpoint stores. Each is a number, a string, None, a
  list or dict of those (JSON), a NumPy array of numbers, a dataclass of numbers (stored as a dict
  of its fields), a dict of arrays, or an object whose class lists its own CHECKPOINT_FIELDS (a
  part, stored field by field under its name);
* ``CHECKPOINT_DERIVED``: {attribute: why it is not stored}: made again, the same, when the run is
  built from its scene and packing (constants, the YADE bodies it talks to), scratch buffers that
  each step overwrites before reading, or state stored under another owner;
* ``CHECKPOINT_RESIZED`` (optional): the stored arrays whose shape may differ from that of the
  freshly built object (pair lists, pores; the same number of dimensions); the others keep their
  shape;
* ``checkpoint_restored()`` (optional): called after its fields were set: it checks what the
  lists cannot (the shapes of resized arrays, and of those the fresh object holds as None, the
  ranges of indices; a ValueError there is refused as a StateError) and builds buffers again.

``state_of(obj)`` gives {dotted name: value}; ``restore(obj, values)`` sets them on an object
built afresh, checking each against the attribute it replaces (type, dtype, dimensions) and
refusing a missing one; it removes what it took from ``values``, so the caller can refuse the
rest. tests/yade/test_checkpoint_format.py fails when an object of a run gains an attribute that neither
list names. Nothing is executed and no object is made from the data: only numbers, strings and
arrays of numbers are set on objects the code built.
"""
import dataclasses

import numpy as np


class StateError(ValueError):
    """Stored state that does not fit the object it is set on; the message names the field."""


def is_part(value):
    """Is ``value`` an object whose class lists its checkpoint fields?"""
    return hasattr(type(value), "CHECKPOINT_FIELDS")


def _plain(value, name):
    """``value`` as JSON-plain Python (NumPy scalars converted); refuses anything else."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, (list, tuple)):
        return [_plain(v, name) for v in value]
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            raise TypeError(f"checkpoint field {name}: dict keys must be strings")
        return {k: _plain(v, name) for k, v in value.items()}
    raise TypeError(f"checkpoint field {name}: a {type(value).__name__} is not data (list it as a part or derived)")


def state_of(obj, prefix=""):
    """{dotted name: value} of the checkpoint fields of ``obj`` and its parts (module docstring); a
    field the object does not have (an attribute of some scenes only) is left out."""
    out = {}
    for field in type(obj).CHECKPOINT_FIELDS:
        if not hasattr(obj, field):  # an attribute of some scenes only (flat walls, a law's engine)
            continue
        name, value = prefix + field, getattr(obj, field)
        if is_part(value):
            out.update(state_of(value, name + "."))
        elif isinstance(value, np.ndarray):
            if value.dtype.kind not in "biuf":
                raise TypeError(f"checkpoint field {name}: an array of {value.dtype} is not numbers")
            out[name] = value
        elif dataclasses.is_dataclass(value):
            out[name] = _plain(dataclasses.asdict(value), name)
        elif isinstance(value, dict) and value and all(isinstance(v, np.ndarray) for v in value.values()):
            out[name + "{}"] = sorted(value)  # the keys; the arrays under name{key}
            out.update({f"{name}{{{k}}}": v for k, v in value.items()})
        else:
            out[name] = _plain(value, name)
    return out


def _take(values, name):
    if name not in values:
        raise StateError(f"field {name} is missing")
    return values.pop(name)


def _same_kind(name, stored, current):
    """Refuse a stored plain value of another type than the attribute it replaces."""
    if stored is None:
        raise StateError(f"field {name}: expected a {type(current).__name__}, got null")
    if isinstance(current, bool) or isinstance(stored, bool):
        ok = isinstance(current, bool) and isinstance(stored, bool)
    elif isinstance(current, (int, np.integer)):
        ok = isinstance(stored, int)
    elif isinstance(current, (float, np.floating)):
        ok = isinstance(stored, (int, float))
    elif isinstance(current, (list, tuple)):
        ok = isinstance(stored, list)
    else:
        ok = isinstance(stored, type(current))
    if not ok:
        raise StateError(f"field {name}: expected a {type(current).__name__}, got a {type(stored).__name__}")


def _array(name, stored, current, resized):
    """The stored array for an attribute whose fresh value is ``current`` (an array, or None for
    one that is made during the run: then a float array or None)."""
    if stored is None and current is None:
        return None
    if not isinstance(stored, np.ndarray):
        raise StateError(f"field {name}: expected an array, got a {type(stored).__name__}")
    dtype, shape = (np.dtype(float), None) if current is None else (current.dtype, current.shape)
    if stored.dtype != dtype:
        raise StateError(f"field {name}: expected an array of {dtype}, got {stored.dtype}")
    if shape is not None and (stored.ndim != len(shape) or (not resized and stored.shape != shape)):
        any_lengths = " (any lengths)" if resized else ""
        raise StateError(f"field {name}: expected shape {shape}{any_lengths}, got {stored.shape}")
    return stored


def restore_all(obj, values):
    """``restore`` of every value of ``values`` {dotted name: value} (left as given) on ``obj``;
    StateError also for a value that no field of ``obj`` takes."""
    left = dict(values)
    restore(obj, left)
    if left:
        raise StateError(f"unknown field(s) {sorted(left)[:5]} (the state of other code?)")


def restore(obj, values, prefix=""):
    """Set the checkpoint fields of ``obj`` (built afresh) and its parts from ``values`` {dotted
    name: value}, removing those it takes. Arrays of a fixed shape are copied into the object's
    own (views and shared buffers stay valid), those of CHECKPOINT_RESIZED replace them. Raises
    StateError naming the field."""
    cls = type(obj)
    resized = getattr(cls, "CHECKPOINT_RESIZED", ())
    for field in cls.CHECKPOINT_FIELDS:
        if not hasattr(obj, field):  # as state_of: a stored value of it is left over, and refused
            continue
        name, current = prefix + field, getattr(obj, field)
        if is_part(current):
            restore(current, values, name + ".")
            continue
        if current is None:  # set during the run (a first step's positions, eq 46 flows, a step index):
            # None, a number or an array of floats
            stored = _take(values, name)
            if not (stored is None or type(stored) in (int, float)):
                stored = np.array(_array(name, stored, None, True))
            setattr(obj, field, stored)
        elif isinstance(current, np.ndarray):
            stored = _array(name, _take(values, name), current, field in resized)
            if field not in resized and current.flags.writeable:  # in place: views of it stay valid
                current[...] = stored
            else:
                setattr(obj, field, np.array(stored))
        elif dataclasses.is_dataclass(current):
            stored = _take(values, name)
            keys = [f.name for f in dataclasses.fields(current)]
            if not isinstance(stored, dict) or sorted(stored) != sorted(keys):
                raise StateError(f"field {name}: expected the fields {keys}")
            for k in keys:
                _same_kind(f"{name}.{k}", stored[k], getattr(current, k))
                setattr(current, k, stored[k])
        elif isinstance(current, dict) and current and all(isinstance(v, np.ndarray) for v in current.values()):
            keys = _take(values, name + "{}")
            if keys != sorted(current):
                raise StateError(f"field {name}: expected the keys {sorted(current)}, got {keys!r}")
            setattr(obj, field, {k: _array(f"{name}{{{k}}}", _take(values, f"{name}{{{k}}}"), current[k],
                                           field in resized) for k in keys})
        else:
            stored = _take(values, name)
            _same_kind(name, stored, current)
            setattr(obj, field, stored)
    hook = getattr(obj, "checkpoint_restored", None)
    if hook is not None:
        try:
            hook()
        except ValueError as e:  # the object's own check of what was set
            raise StateError(f"{prefix or type(obj).__name__ + ' '}{e}") from None
