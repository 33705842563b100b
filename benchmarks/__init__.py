"""Benchmarks: each script prints its ratios and writes JSON (``write_json``)."""
import os

from engines import files


def write_json(path, obj):
    """obj as indented JSON at path, its folder made."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    files.write_json(path, obj)
