"""The demo's numbers quoted in README.md and docs/OUTPUTS.md, from one file (``make demo-numbers``).

``measure`` runs the demo as ``make demo`` does (quick sand, case 1, timed as a whole command) and an
ensemble of STARTS perturbed starts of it, and returns the record written to docs/demo/demo.json:
the date, commit and version, the machine (cores, load average before and after), the demo's
headline results and cost, and the ensemble's means with their 95 % intervals. ``text`` renders the
paragraph the documents quote between MARKS; ``update`` writes it there, ``quoted`` reads it back
(tests/run/test_demo_numbers.py compares them without running anything).
"""
import json
import os
import subprocess
import textwrap
import time

from engines import ROOT, __version__, files
from engines.run.talk import headline

JSON = os.path.join(ROOT, "docs", "demo", "demo.json")
DOCS = (os.path.join(ROOT, "README.md"), os.path.join(ROOT, "docs", "OUTPUTS.md"))
MARKS = ("<!-- demo-numbers: written by make demo-numbers from docs/demo/demo.json -->", "<!-- /demo-numbers -->")
STARTS = 8
SCRIPT = os.path.join(ROOT, "yade_scripts", "quicksand.py")


def _run(argv):
    """Run ``argv`` (a scene script's command) quietly; its wall time [s]; RuntimeError with its
    last lines when it fails."""
    t0 = time.time()
    done = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed ({done.returncode}): {done.stderr.strip()[-500:]}")
    return time.time() - t0


def _commit():
    """The commit of the tree (with "-dirty" when it has uncommitted changes), or None outside git."""
    try:
        head = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return head + ("-dirty" if dirty else "")


def measure(out):
    """Run the demo (OUT/demo) and its ensemble (OUT/ensemble, STARTS starts, 2 at a time); the record."""
    load_before = os.getloadavg()
    demo, ensemble = os.path.join(out, "demo"), os.path.join(out, "ensemble")
    wall = _run(["yade", "-n", "-x", SCRIPT, "--case", "1", "--overwrite", "--quiet", "--out", demo])
    load_after = os.getloadavg()
    _run(["yade", "-n", "-x", SCRIPT, "--case", "1", "--starts", str(STARTS), "--jobs", "2", "--overwrite", "--quiet",
          "--out", ensemble])
    with open(os.path.join(demo, "summary.json")) as f:
        summary = json.load(f)
    with open(os.path.join(ensemble, "ensemble.json")) as f:
        stats = json.load(f)
    return {"date": time.strftime("%Y-%m-%d"), "commit": _commit(), "version": __version__,
            "machine": {"cores": os.cpu_count(), "load_1min_before": round(load_before[0], 1),
                        "load_1min_after": round(load_after[0], 1)},
            "demo": {"command": "make demo", "command_seconds": round(wall, 1), "steps": summary["steps"],
                     "run_seconds": round(summary["wall_seconds"], 2), "us_per_step": round(summary["us_per_step"], 1),
                     "results": {k: (None if v != v else v) for k, v in headline(summary["results"]).items()}},
            "ensemble": {"starts": STARTS, "perturbation_m": stats["perturbation_m"],
                         "results": {k: {s: v[s] for s in ("mean", "ci95_low", "ci95_high")}
                                     for k, v in stats["results"].items() if k in headline(summary["results"])}}}


def text(doc):
    """The paragraph the documents quote (Markdown, wrapped at 100 characters)."""
    return textwrap.fill(_sentences(doc).replace("\n", " "), 100, break_on_hyphens=False, break_long_words=False)


def _sentences(doc):
    """The paragraph's sentences, unwrapped."""
    r, e, n = doc["demo"]["results"], doc["ensemble"]["results"], doc["ensemble"]["starts"]
    U = "peak_block_pressures.U_block{}.{}"

    def ci(key, f=1.0, fmt=".1f"):
        return f"{e[key]['ci95_low'] * f:{fmt}}–{e[key]['ci95_high'] * f:{fmt}}"

    def peak(b):
        return (f"{r[U.format(b, 'U_max_N_per_m')]:.1f} N/m at {r[U.format(b, 't_s')] * 1e3:.1f} ms "
                f"({n} starts: {ci(U.format(b, 'U_max_N_per_m'))} N/m at {ci(U.format(b, 't_s'), 1e3)} ms)")
    heave = r.get("heave_time_s")
    m = doc["machine"]
    return (f"Quick-sand case 1 (`make demo`; `make demo-numbers` on {doc['date']}, commit {doc['commit']}, "
            f"version {doc['version']}): peak block pressures {peak(1)} in the bottom block and {peak(2)} in the "
            f"surface block;\n"
            + (f"heave at {heave * 1e3:.1f} ms ({n} starts: {ci('heave_time_s', 1e3)} ms)" if heave is not None
               else "no heave") +
            f" and window porosity {r['porosity_end']:.3f} at the end ({n} starts: {ci('porosity_end', 1.0, '.3f')}); "
            f"the ranges are the 95 % intervals of the mean of {n} starts perturbed by "
            f"{doc['ensemble']['perturbation_m']:g} m (the run is chaotic: the demo is one sample, which may lie "
            f"outside them).\n"
            f"The demo's {doc['demo']['steps']:,} steps took {doc['demo']['run_seconds']:.1f} s "
            f"({doc['demo']['us_per_step']:.0f} µs a step) and its whole `yade -n -x` command {doc['demo']['command_seconds']:.0f} s "
            f"with the kernels compiled, on {m['cores']} shared cores at a load of {m['load_1min_before']:g}.")


def quoted(path):
    """The text between the MARKS of the document ``path`` (None without them)."""
    with open(path, encoding="utf-8") as f:
        doc = f.read()
    if MARKS[0] not in doc or MARKS[1] not in doc:
        return None
    return doc.split(MARKS[0], 1)[1].split(MARKS[1], 1)[0].strip("\n")


def update(path, doc):
    """Write ``text(doc)`` between the MARKS of ``path`` (ValueError when it has none)."""
    with open(path, encoding="utf-8") as f:
        old = f.read()
    if quoted(path) is None:
        raise ValueError(f"{path} has no {MARKS[0]} ... {MARKS[1]} block")
    head, rest = old.split(MARKS[0], 1)
    files.write_text(path, head + MARKS[0] + "\n" + text(doc) + "\n" + MARKS[1] + rest.split(MARKS[1], 1)[1])
