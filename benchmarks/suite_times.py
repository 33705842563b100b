"""How long the project's own commands take from a fresh clone: ``make deps`` (its warm-up compiles
every kernel for the new checkout), then ``make test``, RUNS times, each in a new clone of HEAD;
then ``make test-fast`` (warm) and, with --check, ``make check`` in the last clone.

    /usr/bin/python3 benchmarks/suite_times.py --json docs/performance/<commit>/tests.json [--runs 3] [--check]

Each command's wall seconds, CPU seconds (user + system of make and every process it waited for,
os.wait4) and the 1-minute load average before it; the medians over the runs; the tests pytest
counted. Run it on a quiet machine (load < 0.5) and say so. ``make deps`` installs the clone as the
editable project; the checkout this script lives in is installed again at the end.
"""
import argparse
import datetime
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

# the project's folder first: the script runs by its path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))
ROOT = sys.path[0]

from benchmarks import write_json  # noqa: E402

PASSED = re.compile(r"(\d+) passed.* in ([\d.]+)s")  # pytest's last line


def timed(args, cwd):
    """Run ``make ARGS`` in ``cwd``: {wall_s, cpu_s, load_average_1min, tests, pytest_wall_s}; exits on failure."""
    load = os.getloadavg()[0]
    t0 = time.time()
    p = subprocess.Popen(["make", "--no-print-directory", *args], cwd=cwd, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    text = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.time() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"make {' '.join(args)} failed in {cwd}:\n{text[-3000:]}")
    found = PASSED.findall(text)
    row = {"wall_s": round(wall, 2), "cpu_s": round(usage.ru_utime + usage.ru_stime, 2), "load_average_1min": load}
    if found:
        row.update(tests=int(found[-1][0]), pytest_wall_s=float(found[-1][1]))
    print(f"make {' '.join(args)}: {row}", flush=True)
    return row


def median_of(rows, key):
    return statistics.median(r[key] for r in rows)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", required=True, help="where to write the figures")
    ap.add_argument("--runs", type=int, default=3, help="fresh clones, each: make deps, make test")
    ap.add_argument("--check", action="store_true", help="also make check once, in the last clone")
    args = ap.parse_args(argv)
    if args.runs < 1:
        ap.error(f"--runs must be >= 1, got {args.runs}")
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    deps, tests, out = [], [], {}
    parent = tempfile.mkdtemp(prefix="pore-dem-suite-")
    try:
        for k in range(args.runs):
            clone = os.path.join(parent, f"clone{k}")
            subprocess.run(["git", "clone", "--quiet", ROOT, clone], check=True)
            deps.append(timed(["deps"], clone))
            tests.append(timed(["test"], clone))
        out["test_fast"] = {"command": "make test-fast", "warm": timed(["test-fast"], clone)}
        out["test_fast"]["tests"] = out["test_fast"]["warm"].pop("tests")
        if args.check:
            out["check"] = {"command": "make check", **timed(["check"], clone)}
    finally:
        shutil.rmtree(parent, ignore_errors=True)
        subprocess.run(["make", "--no-print-directory", "install"], cwd=ROOT, capture_output=True)
    doc = {"date": datetime.date.today().isoformat(), "commit": commit,
           "machine": "the project's 2-core virtual machine (load average before each command given)",
           "how": "benchmarks/suite_times.py: each run a fresh git clone of the commit, make deps (its warm-up "
                  "compiles the kernels for the new checkout), then make test; cpu_s is user + system of make and "
                  "every process it waited for; medians over the runs",
           "warmup": {"command": "make deps in a fresh clone (the warm-up: every kernel compiled)",
                      "wall_s": median_of(deps, "wall_s"), "cpu_s": median_of(deps, "cpu_s"), "runs": deps},
           "test": {"command": "make test in the fresh clone after make deps", "tests": tests[0].get("tests"),
                    "wall_s": median_of(tests, "wall_s"), "cpu_s": median_of(tests, "cpu_s"),
                    "pytest_wall_s": median_of(tests, "pytest_wall_s"), "runs": tests},
           **out}
    write_json(args.json, doc)
    print(f"make test: median {doc['test']['wall_s']} s wall, {doc['test']['cpu_s']} CPU s over {args.runs} fresh "
          f"clones; make deps {doc['warmup']['wall_s']} s; wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
