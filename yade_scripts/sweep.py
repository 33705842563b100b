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
from engines.files.inputs import check_input_file
from engines.run.preflight import ArgumentParser, number, output_dir
from engines.run.sweep import TABLE_LIMIT, Job, check_scheduler, jobs_from_table, run_sweep

MAX_WORKERS = 256


def read_jobs(path):
    """The jobs of a JSON file [{"name", "argv", "env", "timeout"}, ...]; ValueError naming the
    file and the job (or the line of a JSON error)."""
    check_input_file(path, "jobs file", TABLE_LIMIT)
    try:
        with open(path) as f:
            doc = json.load(f)
    except json.JSONDecodeError as e:
        raise ValueError(f"jobs file {path}, line {e.lineno}: not valid JSON: {e.msg}") from None
    except UnicodeDecodeError:
        raise ValueError(f"jobs file {path}: not a text file") from None
    if not isinstance(doc, list):
        raise ValueError(f"jobs file {path}: expected a JSON list of jobs, got {type(doc).__name__}")
    jobs = []
    for k, d in enumerate(doc, 1):
        try:
            if not isinstance(d, dict) or not {"name", "argv"} <= set(d) or set(d) - {"name", "argv", "env", "timeout"}:
                raise ValueError('expected {"name", "argv"[, "env", "timeout"]}')
            if not isinstance(d["argv"], list) or not isinstance(d.get("env", {}), dict):
                raise ValueError('"argv" must be a list and "env" an object')
            jobs.append(Job(d["name"], d["argv"], d.get("env", {}), d.get("timeout")))
        except ValueError as e:
            raise ValueError(f"jobs file {path}, job {k}: {e}") from None
    return jobs


def main(argv=None):
    ap = ArgumentParser(description=__doc__,
                        epilog="Writes DIR/NAME/{job.json,stdout.log,stderr.log} and DIR/sweep.json.")
    ap.add_argument("--out", type=output_dir, required=True, help="root directory of the sweep")
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--table", help="yade-batch parameter table (needs --script)")
    src.add_argument("--jobs", help='JSON list of {"name", "argv", "env"}')
    ap.add_argument("--script", help="the YADE script the table's lines run")
    ap.add_argument("--workers", type=number(int, 1, MAX_WORKERS), default=2, help="local processes at a time (default 2)")
    cluster = ap.add_mutually_exclusive_group()
    cluster.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://127.0.0.1:PORT")
    cluster.add_argument("--scheduler-file", metavar="PATH",
                         help="the file a Dask scheduler started with --scheduler-file wrote (docs/SWEEPS.md)")
    ap.add_argument("--no-resume", action="store_true", help="re-run jobs that are already ok")
    a = ap.parse_args(argv)
    if a.table and not a.script:
        ap.error("--table needs --script")
    if a.script and not a.table:
        ap.error("--script is the script of a --table's lines: give --table")
    try:  # every refusal in one line, before --out is made
        if a.table:
            check_input_file(a.table, "table", TABLE_LIMIT)
            check_input_file(a.script, "script", TABLE_LIMIT)
            jobs = jobs_from_table(a.table, a.script)
            source = f"table {a.table}"
        else:
            jobs = read_jobs(a.jobs)
            source = f"jobs file {a.jobs}"
        if not jobs:
            raise ValueError(f"{source} holds no jobs: nothing to run")
        if a.scheduler:
            check_scheduler(a.scheduler)
    except ValueError as e:
        sys.exit(f"error: {e}")
    try:
        records = run_sweep(jobs, a.out, workers=a.workers, scheduler=a.scheduler, resume=not a.no_resume,
                            scheduler_file=a.scheduler_file)
    except ValueError as e:  # refused before anything is written (job names not unique)
        sys.exit(f"error: {e}")
    except (OSError, TimeoutError) as e:
        if not (a.scheduler or a.scheduler_file):
            raise
        where = f"--scheduler {a.scheduler}" if a.scheduler else f"--scheduler-file {a.scheduler_file}"
        sys.exit(f"error: {where}: the cluster was lost ({type(e).__name__}: {e}); the jobs that ended "
                 f"are kept in {a.out}: the same command runs the others")
    return 0 if all(r["status"] == "ok" for r in records) else 1


if __name__ == "__main__":
    sys.exit(main())
