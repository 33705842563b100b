"""Compile the numba kernels once, before a first run (``make warmup``, the end of ``make deps``).

    /usr/bin/python3 yade_scripts/warmup.py [--again]

Runs a few short scenes and the examples' WaterEngine (engines/run/warmup.py lists them), each in
its own YADE process, so that every kernel lands in numba's cache folder for this version of the
code (engines/compiled/cache.py); a later ``make demo`` loads them instead of compiling (about a
minute on 2 quiet cores, a few on a loaded machine). Once done, it is skipped for the same code
(--again runs it anyway). Exits 1 if one of the runs fails, with its last lines.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))
import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.warmup import warm  # noqa: E402

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--again", action="store_true", help="run the warm-up although it was done for this code")
    sys.exit(warm(say=lambda line: print(line, flush=True), again=ap.parse_args().again))
