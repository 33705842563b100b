"""Scenes for the tests of the model step and the reference (no YADE)."""
from engines.run import scene as sc


def make_scene(**tables):
    """A validated scene: dry, no gravity, no separation adjustment, dt = 1e-7 s unless
    overridden; ``tables``: {table: {field: value}} merged over that."""
    raw = {"scene": {"name": "test"}, "material": {"g": 0.0}, "water": {"enabled": False, "transfer": "paper"},
           "contact": {"separation_adjustment": False}, "numerics": {"dt": 1e-7}}
    for table, fields in tables.items():
        raw.setdefault(table, {}).update(fields)
    return sc.validate(raw)
