"""Parallel efficiency of an ensemble (a scene script's --starts) on J local processes and on a
Dask cluster of J single-threaded workers.

    /usr/bin/python3 benchmarks/ensemble.py --json out/bench-ensemble.json [--script yade_scripts/liquefaction.py]
        [--case 1] [--duration 0.01] [--starts 4] [--jobs 2] [--no-dask]

Runs the same ensemble (into fresh folders under the JSON file's folder) with --jobs 1, with
--jobs J and, unless --no-dask, with --scheduler on a distributed.LocalCluster of J worker
processes; the efficiency of each is the --jobs 1 wall time over (J x its wall time): 1 when J
processes finish the starts J times faster. The wall time is the whole command's (YADE's start,
the checks, the starts and their figures, the statistics); the checks, the statistics and the
ensemble figures run once, in the parent, and count against the efficiency. Beside it, the
starts' CPU over wall seconds (their job.json): near 1 when each start had a core to itself, lower
when other work shared the cores. Not a test: it takes minutes at the defaults, and the machine
must be otherwise idle for the efficiency to mean much.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

from benchmarks import write_json
from engines import ROOT


def timed(argv, out):
    """(wall seconds of ``yade -n -x ARGV --out OUT`` (OUT replaced), the starts' CPU / wall
    seconds); exits on a failure."""
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    run = subprocess.run(["yade", "-n", "-x", *argv, "--out", out], capture_output=True, text=True,
                         env=dict(os.environ, MPLBACKEND="Agg"))
    wall = time.perf_counter() - t0
    if run.returncode != 0:
        sys.exit(f"{' '.join(argv)}: exit {run.returncode}: {run.stdout[-500:]} {run.stderr[-500:]}")
    with open(os.path.join(out, "sweep.json")) as f:
        jobs = json.load(f)["jobs"]
    return wall, sum(j["cpu_s"] for j in jobs) / sum(j["wall_s"] for j in jobs)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--script", default=os.path.join(ROOT, "yade_scripts", "liquefaction.py"))
    ap.add_argument("--case", default="1")
    ap.add_argument("--duration", type=float, default=0.01)
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--no-dask", action="store_true")
    a = ap.parse_args(argv)
    root = os.path.join(os.path.dirname(os.path.abspath(a.json)), "bench-ensemble")
    base = [a.script, "--case", a.case, "--duration", repr(a.duration), "--starts", str(a.starts)]
    walls = {"jobs=1": timed(base + ["--jobs", "1"], os.path.join(root, "jobs1"))}
    walls[f"jobs={a.jobs}"] = timed(base + ["--jobs", str(a.jobs)], os.path.join(root, f"jobs{a.jobs}"))
    if not a.no_dask:
        from distributed import LocalCluster
        with LocalCluster(n_workers=a.jobs, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=None) as cluster:
            walls[f"dask={a.jobs}"] = timed(base + ["--scheduler", cluster.scheduler_address], os.path.join(root, "dask"))
    efficiency = {k: walls["jobs=1"][0] / (a.jobs * w) for k, (w, _) in walls.items() if k != "jobs=1"}
    for k, (w, busy) in walls.items():
        print(f"{k:>8}: {w:7.1f} s, the starts' CPU / wall {busy:.2f}" +
              (f", parallel efficiency {efficiency[k]:.2f}" if k in efficiency else ""))
    write_json(a.json, {"script": a.script, "case": a.case, "duration_s": a.duration, "starts": a.starts, "jobs": a.jobs,
                        "wall_s": {k: w for k, (w, _) in walls.items()},
                        "starts_cpu_over_wall": {k: b for k, (_, b) in walls.items()}, "parallel_efficiency": efficiency})


if __name__ == "__main__":
    main(sys.argv[1:])
