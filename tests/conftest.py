"""YADE's Python package findable under Debian's python3, and a marker per layer of the tree.

tests/ mirrors engines/ (model/, compiled/, reference/, yade/, run/, studies/, seeds/) plus
packing/ and postproc/; each test is marked with its folder's name, so that
``pytest -m "model or reference"`` runs the NumPy core alone (``make test-fast``).
"""
import os
import sys

import pytest

YADE_PY = "/usr/lib/x86_64-linux-gnu/yade-double/py"
if os.path.isdir(YADE_PY) and YADE_PY not in sys.path:
    sys.path.append(YADE_PY)
os.environ.setdefault("MPLBACKEND", "Agg")
# YADE imported into Python runs OpenMP on every core (the yade launcher starts with one thread):
# on a shared 2-core machine its threads' spin-waits made each step of these small scenes ~15x
# slower (measured: 1,500 quick-sand steps 27 s -> 1.5 s). Must be set before libyade is loaded.
os.environ.setdefault("OMP_NUM_THREADS", "1")

TESTS = os.path.dirname(os.path.abspath(__file__))
LAYERS = ("files", "model", "compiled", "reference", "yade", "run", "studies", "seeds", "packing", "postproc")


def pytest_collection_modifyitems(items):
    for item in items:
        layer = os.path.relpath(str(item.path), TESTS).split(os.sep)[0]
        if layer in LAYERS:
            item.add_marker(getattr(pytest.mark, layer))
