"""Mutation testing of the core modules with mutmut (``make mutants``; not part of ``make test``).

    out/venv-mutants/bin/python tests/mutants.py [--out out/mutants] [--max-children 2] [--again]

Copies the project into OUT/work, configures mutmut (setup.cfg) to mutate MODULES (the core
modules, judged, and EXTRA, reported) and to run the tests of TESTS (those without YADE: mutmut
collects which tests reach each function and runs, per mutant, only those, fastest first
(tests/mutation_order.py), stopping at the first failure), runs it niced, and writes OUT/summary.json:

    {"modules": {path: {"total": n, "killed": k, "survived": s, "equivalent": e, "score": ...,
                        "not_checked": u}},
     "per_module": [{"name": dotted module name, "judged": bool, the same counts}, ...],
     "score": killed / (total - equivalent) over the judged MODULES, "seconds": ...,
     "stale_equivalent": [...], "date": ..., "commit": ...}

and OUT/survivors.txt (each surviving mutant's diff, for review). A timed-out or crashed mutant
counts as killed; a mutant no test reaches counts as survived; mutants an interrupted run did not
reach are left out of the totals (``not_checked``). ``--again`` keeps OUT/work and its results,
copies the current sources and tests in, and runs only what needs it: mutants of changed functions,
unchecked ones and the survivors (with the new tests); ``--again --only MODULE...`` tests just the
unchecked and surviving mutants of those files (a long run, module by module). Mutants judged equivalent (they
cannot change any result) are listed in tests/equivalent_mutants.txt, one per line as
``mutant-name  reason``; a listed mutant that was killed is reported as stale.
mutmut must run from a virtual environment over Debian's Python with --system-site-packages, so
that YADE's NumPy and SciPy are the ones the tests use (see the Makefile's mutants target).
"""
import argparse
import datetime
import os
import re
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

from engines import files  # noqa: E402
PORES = [f"engines/model/pores/{m}.py" for m in ("build", "checks", "faces", "links", "measure", "network", "overlaps", "triangulation")]
MODULES = ["engines/model/pore_water.py", *PORES, "engines/model/contact.py", "engines/model/pore_dem.py"]
EXTRA = ["engines/model/water_model.py", "engines/model/paper_law.py", "engines/model/flat_walls.py",
         "engines/model/limits.py", "engines/model/fields.py", "engines/compiled/contact.py",
         "engines/compiled/paper_law.py", "engines/compiled/water_model.py", "engines/compiled/pore_dem.py"]
# the tests without YADE, except those that run a copy of the project in another process (mutmut's
# trampolines do not work there)
TESTS = ["tests/model", "tests/compiled", "tests/reference", "tests/run/test_scene.py",
         "--ignore=tests/compiled/test_boundary_kinds.py", "--ignore=tests/compiled/test_cache.py"]
COPY = ["engines", "packing", "yade_scripts", "tests"]
EQUIVALENT = os.path.join(ROOT, "tests", "equivalent_mutants.txt")
KILLED = {"killed", "timeout", "segfault"}


def read_equivalent(path=EQUIVALENT):
    """{mutant name: reason} from the equivalent-mutant list (blank lines and # comments skipped)."""
    out = {}
    if os.path.exists(path):
        for line in open(path, encoding="utf-8"):
            line = line.strip()
            if line and not line.startswith("#"):
                name, _, reason = line.partition(" ")
                if not reason.strip():
                    raise ValueError(f"{path}: no reason given for {name}")
                out[name] = reason.strip()
    return out


def prepare(work, modules, tests, again=False):
    """A copy of the project in ``work`` with the mutmut configuration (fresh, or with ``again``
    over the previous copy, keeping mutmut's results in work/mutants)."""
    if os.path.exists(work) and not again:
        shutil.rmtree(work)
    os.makedirs(work, exist_ok=True)
    for d in COPY:
        shutil.copytree(os.path.join(ROOT, d), os.path.join(work, d), dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    lines = ["[mutmut]", "source_paths=", *(f"    {m}" for m in modules), "also_copy=",
             *(f"    {d}" for d in COPY if d != "tests"), "pytest_add_cli_args_test_selection=",
             *(f"    {t}" for t in tests), "pytest_add_cli_args=", "    -q", "    -p", "    no:cacheprovider",
             "    -p", "    no:warnings", "    -p", "    tests.mutation_order", "    -m", "    not check",
             "timeout_multiplier=3"]   # a mutant over 6x the CPU time of its tests hangs (mutmut's default: 30x)
    with open(os.path.join(work, "setup.cfg"), "w") as f:
        f.write("\n".join(lines) + "\n")


PROGRESS = re.compile(r"[\u2800-\u28ff] \d+/\d+ [^\u2800-\u28ff\n]*")


def run_mutmut(work, mutmut, max_children, names, log):
    """``mutmut run`` niced (on ``names`` only, if given), its progress spinner cut to the last frame."""
    run = subprocess.run(["nice", "-n", "10", mutmut, "run", "--max-children", str(max_children), *names],
                         cwd=work, capture_output=True, text=True)
    text = run.stdout + run.stderr
    frames = PROGRESS.findall(text)
    log.write(PROGRESS.sub("", text) + (f"\nlast progress: {frames[-1]}\n" if frames else ""))
    if run.returncode not in (0, 1):
        sys.exit(f"mutmut run failed ({run.returncode}); see {log.name}")


def results(work, mutmut):
    """{mutant name: status} from ``mutmut results --all true``."""
    out = subprocess.run([mutmut, "results", "--all", "true"], cwd=work, capture_output=True, text=True, check=True)
    status = {}
    for line in out.stdout.splitlines():
        name, sep, state = line.strip().rpartition(": ")
        if sep and "__mutmut_" in name:
            status[name] = state.strip()
    return status


def commit():
    """The project's commit (with "+dirty" when its tracked files differ from it)."""
    head = subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True).stdout.strip()
    return (head or "unknown") + ("+dirty" if dirty else "")


def module_of(name, modules):
    """The source path a mutant name (engines.model.pore_water.x...__mutmut_3) belongs to."""
    for m in modules:
        if name.startswith(m[:-3].replace("/", ".") + "."):
            return m
    raise ValueError(f"mutant {name} is in none of {modules}")


def summarise(status, modules, equivalent, judged=MODULES):
    """Counts and score per module; the overall score over the ``judged`` modules."""
    per = {m: {"total": 0, "killed": 0, "survived": 0, "equivalent": 0, "not_checked": 0} for m in modules}
    stale = []
    for name, state in status.items():
        row = per[module_of(name, modules)]
        if state == "not checked":      # an interrupted run: left out of the score, counted apart
            row["not_checked"] += 1
            continue
        row["total"] += 1
        if state in KILLED:
            row["killed"] += 1
            if name in equivalent:
                stale.append(name)
        elif name in equivalent:
            row["equivalent"] += 1
        else:
            row["survived"] += 1
    for row in per.values():
        n = row["total"] - row["equivalent"]
        row["score"] = row["killed"] / n if n else None
    rows = [r for m, r in per.items() if m in judged]
    total = sum(r["total"] for r in rows)
    killed = sum(r["killed"] for r in rows)
    equiv = sum(r["equivalent"] for r in rows)
    return {"modules": per, "score": killed / (total - equiv) if total > equiv else None,
            "stale_equivalent": sorted(stale)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "mutants"))
    ap.add_argument("--max-children", type=int, default=2, help="parallel mutant runs (the machine has 2 cores)")
    ap.add_argument("--modules", nargs="+", default=MODULES + EXTRA, help="source files to mutate")
    ap.add_argument("--report-only", action="store_true", help="summarise the last run in OUT/work again")
    ap.add_argument("--again", action="store_true",
                    help="keep the last run's results: re-test changed, unchecked and surviving mutants")
    ap.add_argument("--only", nargs="+", metavar="MODULE",
                    help="with --again: test only the unchecked and surviving mutants of these source files "
                         "(a run too long for one sitting, module by module)")
    ap.add_argument("--survivors-only", action="store_true",
                    help="with --again --only: re-test the surviving mutants only, not the unchecked ones")
    args = ap.parse_args(argv)
    if args.only and not ((args.again or args.report_only) and set(args.only) <= set(args.modules)):
        ap.error(f"--only needs --again (or --report-only: diffs of those files only) and modules among "
                 f"{args.modules}, got {args.only}")
    if args.max_children < 1:
        ap.error(f"--max-children must be >= 1, got {args.max_children}")
    mutmut = os.path.join(os.path.dirname(sys.executable), "mutmut")
    if not os.path.exists(mutmut):
        sys.exit(f"mutmut not found beside {sys.executable}: run `make mutants` (it makes the venv)")
    work = os.path.join(args.out, "work")
    t0 = time.time()
    if not args.report_only:
        again = args.again and os.path.exists(os.path.join(work, "mutants"))
        prepare(work, args.modules, TESTS, again)
        with open(os.path.join(args.out, "run.log"), "a" if again else "w") as log:
            if not (again and args.only):
                run_mutmut(work, mutmut, args.max_children, [], log)   # new, changed and unchecked mutants
            if again:
                equivalent = read_equivalent()
                redo = KILLED if args.only and not args.survivors_only else KILLED | {"not checked"}
                left = sorted(n for n, st in results(work, mutmut).items() if st not in redo and n not in equivalent
                              and (not args.only or module_of(n, args.modules) in args.only))
                for k in range(0, len(left), 400):
                    run_mutmut(work, mutmut, args.max_children, left[k:k + 400], log)
    status = results(work, mutmut)
    summary = summarise(status, args.modules, read_equivalent())
    summary["per_module"] = [{"name": m[:-3].replace("/", "."), "judged": m in MODULES, **row}   # for the docs' markers
                             for m, row in summary["modules"].items()]
    summary.update(seconds=time.time() - t0, max_children=args.max_children, tests=TESTS,
                   judged=MODULES, date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                   commit=commit())
    files.write_json(os.path.join(args.out, "summary.json"), summary)
    survivors = sorted(n for n, s in status.items() if s not in KILLED | {"not checked"} and n not in read_equivalent())
    parts = []
    for name in survivors:
        if args.only and module_of(name, args.modules) not in args.only:
            parts.append(f"## {name}: {status[name]}\n")    # (a diff costs a mutmut call: only for --only)
            continue
        diff = subprocess.run([mutmut, "show", name], cwd=work, capture_output=True, text=True).stdout
        parts.append(f"## {name}: {status[name]}\n{diff}\n")
    files.write_text(os.path.join(args.out, "survivors.txt"), "".join(parts))
    for m, row in summary["modules"].items():
        print(f"{m}: {row['killed']}/{row['total'] - row['equivalent']} killed ({row['equivalent']} equivalent), "
              f"score {row['score']:.3f}" if row["score"] is not None else f"{m}: no mutants")
    print(f"score {summary['score']}; {len(survivors)} survivors in {args.out}/survivors.txt; "
          f"{summary['seconds']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
