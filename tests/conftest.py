"""Make the project importable and YADE's Python package findable under Debian's python3."""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
YADE_PY = "/usr/lib/x86_64-linux-gnu/yade-double/py"
if os.path.isdir(YADE_PY) and YADE_PY not in sys.path:
    sys.path.append(YADE_PY)
os.environ.setdefault("MPLBACKEND", "Agg")
# YADE imported into Python runs OpenMP on every core (the yade launcher starts with one thread):
# on a shared 2-core machine its threads' spin-waits made each step of these small scenes ~15x
# slower (measured: 1,500 quick-sand steps 27 s -> 1.5 s). Must be set before libyade is loaded.
os.environ.setdefault("OMP_NUM_THREADS", "1")
