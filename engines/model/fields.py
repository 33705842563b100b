"""Settings declared once: each field's type, default, range or choices and meaning. No YADE.

The model's settings classes (ContactSettings, WaterSettings, and the tables of engines.model.settings)
are made from their FIELDS by ``settings_class``; the scene schema (engines.run.scene) takes the same
FIELDS as its tables, so a scene file and a Python script get the same defaults and the same checks
(``check``, run once, when a table is made), with errors that name the field as the scene file does
("[water] k1: ...").
"""
import copy
import dataclasses
import math
import numbers
from typing import NamedTuple

REQUIRED = object()                    # a default: the field must be given
POS = (0.0, math.inf)                  # a check: > 0
NONNEG = (0.0, math.inf)               # a check: >= 0 (equal to POS, told apart by identity)
POS_OR_AUTO = (0.0, math.inf, "auto")  # a check: > 0, or the string "auto"


class Field(NamedTuple):
    """type; default (or REQUIRED); check: None, (lo, hi) inclusive bounds (POS: > 0), a tuple of
    allowed strings, or POS_OR_AUTO; doc: unit and meaning."""

    type: type
    default: object
    check: object
    doc: str


def check(where, value, spec, error=ValueError):
    """``value`` converted to the field's type (any real number where a float is expected, any
    integer where an int is), or ``error`` naming ``where`` (e.g. "[water] k1") and the limit."""
    typ, _, bounds, _ = spec
    if bounds is POS_OR_AUTO:
        if value == "auto":
            return value
        if isinstance(value, str):
            raise error(f"{where}: expected a number > 0 or \"auto\", got {value!r}")
        bounds = POS
    number = not isinstance(value, bool) and isinstance(value, numbers.Real)
    if typ is float and number:
        value = float(value)
    elif typ is int and number and isinstance(value, numbers.Integral):
        value = int(value)
    if typ in (float, int) and not (number and isinstance(value, typ)) or typ in (str, bool, list) and not isinstance(value, typ):
        raise error(f"{where}: expected {typ.__name__}, got {value!r}")
    if typ is float and not math.isfinite(value):
        raise error(f"{where}: must be finite, got {value}")
    if isinstance(bounds, tuple) and bounds and isinstance(bounds[0], str):
        if value not in bounds:
            raise error(f"{where}: must be one of {', '.join(bounds)}, got {value!r}")
    elif bounds is not None:
        lo, hi = bounds
        if not lo <= value <= hi or (bounds is POS and value == 0):
            raise error(f"{where}: must be {'> 0' if bounds is POS else f'in [{lo}, {hi}]'}, got {value}")
    return value


def describe_check(bounds):
    """The range or choices of a check, as the schema table shows it."""
    if bounds is None:
        return ""
    if bounds is POS_OR_AUTO:
        return "> 0 or 'auto'"
    if isinstance(bounds[0], str):
        return ", ".join(bounds)
    return "> 0" if bounds is POS else f"[{bounds[0]}, {bounds[1]}]"


def settings_class(name, fields, table, module, doc):
    """A dataclass ``name`` with one attribute per field of ``fields`` (defaults from them) whose
    construction checks every value (``check``, errors naming "[table] field")."""

    def __post_init__(self):
        for key, spec in fields.items():
            setattr(self, key, check(f"[{table}] {key}", getattr(self, key), spec))

    def default(f):  # a list's default copied for each instance
        if isinstance(f.default, list):
            return dataclasses.field(default_factory=lambda: copy.deepcopy(f.default))
        return dataclasses.field(default=f.default)

    cls = dataclasses.make_dataclass(name, [(k, f.type, default(f)) for k, f in fields.items()],
                                     namespace={"__post_init__": __post_init__, "FIELDS": fields, "__doc__": doc})
    cls.__module__ = module  # the module that makes it, as for a class written there (pickle, reprs)
    return cls


def checked(cls, values):
    """An instance of the settings class ``cls`` (``settings_class``) from {field: value} already
    checked against the same fields (a table of validated settings): made without a second check."""
    obj = object.__new__(cls)
    obj.__dict__.update({k: values[k] for k in cls.FIELDS})
    return obj


POSITIVE = Field(float, REQUIRED, POS, "a number > 0")
COUNT = Field(int, REQUIRED, (1, math.inf), "an integer >= 1")


def check_each(obj, names, spec):
    """``check`` the attributes ``names`` of ``obj`` against one Field ``spec`` (errors name the attribute)."""
    for name in names:
        check(name, getattr(obj, name), spec)
