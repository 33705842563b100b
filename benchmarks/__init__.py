"""Benchmarks: each script prints its ratios and writes JSON (``write_json``)."""
import json
import os


def write_json(path, obj):
    """obj as indented JSON at path, its folder made."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        json.dump(obj, f, indent=1)
