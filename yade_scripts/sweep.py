"""The sweep runner (engines.run.sweep) from the command line: jobs on the local cores or on a
Dask cluster, each in its own directory, resumable.

Command line (under /usr/bin/python3, or yade -n -x, alike):
    /usr/bin/python3 yade_scripts/sweep.py --out DIR --table T.table --script S.py [--workers N]
                                           [--scheduler ADDR | --scheduler-file PATH] [--no-resume]
    /usr/bin/python3 yade_scripts/sweep.py --out DIR --jobs jobs.json ...   # [{"name", "argv", "env", "timeout"}]

Each job runs in the directory the sweep was started from (relative paths in its command line
and --script resolve there) and writes into its own directory DIR/NAME.
"""
import json
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.preflight import ArgumentParser, number, output_dir
from engines.run.sweep import Job, jobs_from_table, run_sweep


def main(argv=None):
    ap = ArgumentParser(description=__doc__,
                        epilog="Writes DIR/NAME/{job.json,stdout.log,stderr.log} and DIR/sweep.json.")
    ap.add_argument("--out", type=output_dir, required=True, help="root directory of the sweep")
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--table", help="yade-batch parameter table (needs --script)")
    src.add_argument("--jobs", help='JSON list of {"name", "argv", "env"}')
    ap.add_argument("--script", help="the YADE script the table's lines run")
    ap.add_argument("--workers", type=number(int, 1), default=2, help="local processes at a time (default 2)")
    cluster = ap.add_mutually_exclusive_group()
    cluster.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://127.0.0.1:PORT")
    cluster.add_argument("--scheduler-file", metavar="PATH",
                         help="the file a Dask scheduler started with --scheduler-file wrote (docs/SWEEPS.md)")
    ap.add_argument("--no-resume", action="store_true", help="re-run jobs that are already ok")
    a = ap.parse_args(argv)
    if a.table:
        if not a.script:
            ap.error("--table needs --script")
        try:
            jobs = jobs_from_table(a.table, a.script)
        except ValueError as e:  # the table refused, in one line
            ap.error(str(e))
    else:
        with open(a.jobs) as f:
            jobs = [Job(d["name"], d["argv"], d.get("env", {}), d.get("timeout")) for d in json.load(f)]
    records = run_sweep(jobs, a.out, workers=a.workers, scheduler=a.scheduler, resume=not a.no_resume,
                        scheduler_file=a.scheduler_file)
    return 0 if all(r["status"] == "ok" for r in records) else 1


if __name__ == "__main__":
    sys.exit(main())
