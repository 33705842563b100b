"""Make the project importable and YADE's Python package findable under Debian's python3."""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
YADE_PY = "/usr/lib/x86_64-linux-gnu/yade-double/py"
if os.path.isdir(YADE_PY) and YADE_PY not in sys.path:
    sys.path.append(YADE_PY)
os.environ.setdefault("MPLBACKEND", "Agg")
