"""One sweep runner for the studies: command-line jobs, each in its own directory, run on the
local cores or on a Dask distributed cluster, resumable.

    from engines.run.sweep import Job, run_sweep
    jobs = [Job("phi10-seed1", ["yade", "-n", "-x", "yade_scripts/biaxial.py", "--phi-e", "10",
                                "--out", "{out}"])]
    records = run_sweep(jobs, "out/study", workers=2, scheduler=None, resume=True)

A job is a name and a command line; ``{out}`` in an argument becomes the job's directory
``ROOT/NAME`` (also given to the job as the environment variable SWEEP_JOB_DIR, where a scene
script run from a table writes). A job runs in the directory the sweep was started from,
wherever it runs, so relative paths in its command line mean the same on every worker. Each job
writes there ``stdout.log``, ``stderr.log`` (without the lines of YADE's banner that give its
listeners' ports and its console's cookie, BANNER) and ``job.json``: status ("running", then "ok",
"failed" or "interrupted"), return code, wall and CPU seconds, command, working directory, host, and the tail of
stderr. ``run_sweep`` returns the records of all jobs in the order given, prints one line per
finished job and a summary, and writes ``ROOT/sweep.json``. With ``resume`` (the default) a job
whose job.json says "ok" for the same command is not run again; failed, interrupted or changed
jobs are.

Each job runs in its own process group and dies with its runner (Linux's PR_SET_PDEATHSIG: a
killed runner or Dask worker takes its jobs with it). SIGINT or SIGTERM to the runner is passed to
its running jobs' process groups (a scene script then stops after its step with a checkpoint); the
runner waits for them (up to STOP_SECONDS, then kills them), records them "interrupted", and exits
with 128 + the signal's number and one line. A job whose folder another live run holds (its
lock, engines.run.guard) is not started: its record says "locked" and by whom.

Local: ``workers`` processes at a time (default 2, the machine's cores). Cluster: ``scheduler``
is a Dask scheduler address ("tcp://host:8786") or a ``distributed.Client``, or
``scheduler_file`` the file a scheduler started with ``--scheduler-file`` wrote; the same jobs run
on its workers, which need ROOT and the sweep's directory on a shared file system, not this
project on their path (the runner is sent to them by value). YADE's own parameter tables
(yade-batch's format) become jobs with ``jobs_from_table``: one job per table line, run as
yade-batch runs it (YADE_BATCH=table:line, from which the script reads its line). Tables are
read as data (engines.run.table: literal values only). The module imports nothing of YADE: the
sweep runs under a plain ``python3``.

The command line is yade_scripts/sweep.py.
"""
import ctypes
import ctypes.util
import fcntl
import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field

from engines import ROOT
from engines.files.inputs import check_name
from engines.run.table import BATCH, DESCRIPTION, read_table
from engines.run.talk import results_table

STDERR_TAIL = 2000  # characters of stderr kept in job.json
TABLE_LIMIT = 10 << 20  # the largest table or jobs file read [bytes]
NAME = re.compile(r"^[A-Za-z0-9._=,+-]+$")
JOB_DIR = "SWEEP_JOB_DIR"  # the environment variable holding a job's directory
# the project's own yade launches: YADE's console and XML-RPC server never started (the launcher
# imports engines/yade/no_servers.py first, found through yade_environment()'s PYTHONPATH)
YADE = ("yade", "-n", "-L", "engines.yade.no_servers")


def yade_environment():
    """The environment a job running YADE as YADE (above) needs: the project's folder first on
    PYTHONPATH (this process's PYTHONPATH after it)."""
    rest = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p and p != ROOT]
    return {"PYTHONPATH": os.pathsep.join([ROOT, *rest])}


LOCK_FILE = ".lock"  # a run's lock in its folder (engines.run.guard.LOCK)
STOP_SECONDS = 20  # after a signal: how long the runner waits for its jobs to stop before killing them


@dataclass(frozen=True)
class Job:
    """One run: ``name`` (its directory under the root; letters, digits and ._=,+-, no leading dot
    and no ``..``: engines.files.inputs.check_name), ``argv``
    (the command line, "{out}" replaced by the directory), ``env`` (extra environment) and
    ``timeout`` (seconds, None = none)."""

    name: str
    argv: tuple
    env: dict = field(default_factory=dict)
    timeout: float = None

    def __post_init__(self):
        if not NAME.match(self.name or ""):
            raise ValueError(f"job name {self.name!r}: use letters, digits and . _ = , + - only")
        check_name(self.name, "job name")
        object.__setattr__(self, "argv", tuple(str(a) for a in self.argv))
        if not self.argv:
            raise ValueError(f"job {self.name}: empty command")

    def command(self, out_dir):
        return [a.replace("{out}", out_dir) for a in self.argv]


def _write_json(path, data):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1)
    os.replace(tmp, path)


def read_record(root, name):
    """The job.json of a job, or None."""
    try:
        with open(os.path.join(root, name, "job.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def lock_holder(folder):
    """'' if no live process holds ``folder``'s lock (LOCK_FILE), else its "HOST PID" (or "a process").
    Here, not in engines.run.guard (which uses it): the sweep's workers get this module by value and
    import nothing of the project. Never ask about a folder this process holds: closing the probe's
    descriptor would release this process's own POSIX lock."""
    try:
        fd = os.open(os.path.join(folder, LOCK_FILE), os.O_RDWR)
    except OSError:
        return ""
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        who = os.pread(fd, 200, 0).decode(errors="replace").strip()
        return who or "a process"
    finally:
        os.close(fd)
    return ""


_running = {}  # process group id -> job name, of the jobs this runner started and waits for
_stopping = []  # not empty after a signal: no job starts any more (a list: the workers get this module by value)
_PR_SET_PDEATHSIG = 1


def _libc():
    return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)


def _die_with(parent, prctl):
    """preexec_fn of a job: SIGTERM when the thread that started it ends (its runner or Dask worker
    died), and an end at once if that happened before this line."""
    def preexec():
        prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
        if os.getppid() != parent:
            os._exit(1)
    return preexec


def _run_timed(cmd, stdout, stderr, env, timeout, cwd):
    """Run ``cmd`` in ``cwd`` to its end, in its own process group and session, dying with this
    process: (return code, CPU seconds it used (user + system, with the children it waited for),
    whether it was killed at ``timeout`` seconds)."""
    proc = subprocess.Popen(cmd, stdout=stdout, stderr=stderr, env=env, cwd=cwd, start_new_session=True,
                            preexec_fn=_die_with(os.getpid(), _libc().prctl))
    _running[proc.pid] = cmd
    killed = threading.Event()

    def kill():
        killed.set()
        _signal_group(proc.pid, signal.SIGKILL)

    timer = threading.Timer(timeout, kill) if timeout else None
    if timer:
        timer.start()
    try:
        _, status, usage = os.wait4(proc.pid, 0)
    finally:
        if timer:
            timer.cancel()
        _running.pop(proc.pid, None)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return proc.returncode, usage.ru_utime + usage.ru_stime, killed.is_set()


def _signal_group(pgid, sig):
    try:
        os.killpg(pgid, sig)
    except (ProcessLookupError, PermissionError):
        pass


# set by a Dask nanny for its worker: glibc then hands freed memory back at once, and a job's
# numba and NumPy temporaries pay for it (a seismic start: 15 % more CPU on a worker than locally)
DASK_WORKER_ENVIRON = ("MALLOC_TRIM_THRESHOLD_",)


def _environment(extra):
    """This process's environment with ``extra``; with HOME, which YADE needs (its config folder)
    and a clean environment (env -i) or a service's worker lacks; on a Dask worker without the
    nanny's DASK_WORKER_ENVIRON, so that a job runs there as on the local pool."""
    env = {"HOME": os.path.expanduser("~"), **os.environ}
    if "distributed" in sys.modules and _on_dask_worker():
        for name in DASK_WORKER_ENVIRON:
            env.pop(name, None)
    return {**env, **extra}


def _on_dask_worker():
    from distributed import get_worker
    try:
        get_worker()
        return True
    except ValueError:
        return False


# the lines of YADE's banner that give its console's and XML-RPC server's ports and the console's
# cookie (yade.remote: "TCP python prompt on localhost:9000, auth cookie `...'" on stderr,
# "XMLRPC info provider on http://localhost:21000" on stdout): never written to a job's logs
BANNER = re.compile(rb"(TCP python prompt on |XMLRPC info provider on )[^\n]*\n?")


class _Log:
    """A job's log file, written from a pipe (its ``fileno()``, given to the job as its stdout or
    stderr) by a thread that leaves out YADE's BANNER lines; closed and complete on exit."""

    def __init__(self, path):
        self.path = path

    def __enter__(self):
        read, self.write = os.pipe()
        self.copier = threading.Thread(target=self._copy, args=(read,), daemon=True)
        self.copier.start()
        return self

    def fileno(self):
        return self.write

    def _copy(self, read):
        with open(read, "rb") as src, open(self.path, "wb") as dst:
            for line in src:
                if not BANNER.fullmatch(line):
                    dst.write(line)
                    dst.flush()

    def __exit__(self, *exc):
        os.close(self.write)
        self.copier.join(timeout=5)  # what the job wrote is copied by then; a process it left behind may hold the pipe


def run_job(job, root, cwd=None):
    """Run one job (blocking) in the directory ``cwd`` (None: this process's), its outputs in its
    own directory under ``root``; write and return its record. Runs wherever it is called: in a
    local thread or on a Dask worker."""
    out = os.path.abspath(os.path.join(root, job.name))
    os.makedirs(out, exist_ok=True)
    cmd = job.command(out)
    rec = {"name": job.name, "status": "running", "command": cmd, "env": dict(job.env), "cwd": cwd,
           "host": socket.gethostname(), "started": time.time()}
    held = lock_holder(out)
    if held or _stopping:  # its folder is another live run's, or the runner is stopping: not started
        why = f"not started: {out} is in use by another run ({held})" if held else "not started: the sweep was stopped"
        return {**rec, "status": "locked" if held else "interrupted", "returncode": None, "wall_s": 0.0, "cpu_s": 0.0,
                "started": None, "stderr_tail": why}
    _write_json(os.path.join(out, "job.json"), rec)
    env = _environment({**job.env, JOB_DIR: out})
    t0 = time.time()
    err_path = os.path.join(out, "stderr.log")
    cpu_s, note = 0.0, ""
    try:
        with _Log(os.path.join(out, "stdout.log")) as so, _Log(err_path) as se:
            rc, cpu_s, timed_out = _run_timed(cmd, so, se, env, job.timeout, cwd)
        if timed_out:
            rc, note = -9, f"timeout after {job.timeout} s"
    except OSError as e:
        rc, note = 127, f"could not start: {e}"
    with open(err_path, errors="replace") as f:
        tail = f.read()[-STDERR_TAIL:]
    stopped = bool(_stopping) and rc in (-signal.SIGINT, -signal.SIGTERM, -signal.SIGKILL,
                                            128 + signal.SIGINT, 128 + signal.SIGTERM)
    rec.update(status="ok" if rc == 0 else "interrupted" if stopped else "failed", returncode=rc,
               wall_s=time.time() - t0, cpu_s=cpu_s,
               finished=time.time(), stderr_tail=(note + "\n" + tail).strip())
    _write_json(os.path.join(out, "job.json"), rec)
    return rec


def _fields(job):
    """A job as built-in types, which a worker unpickles without this module."""
    return {"name": job.name, "argv": job.argv, "env": dict(job.env), "timeout": job.timeout}


def _run_fields(fields, root, cwd):
    """run_job of the job ``_fields`` gave (on a Dask worker)."""
    return run_job(Job(**fields), root, cwd)


def is_done(job, root):
    rec = read_record(root, job.name)
    out = os.path.abspath(os.path.join(root, job.name))
    return rec is not None and rec.get("status") == "ok" and rec.get("command") == job.command(out) \
        and rec.get("env", {}) == dict(job.env)


SCHEDULER_TIMEOUT = 5.0  # seconds to wait for a Dask scheduler's port to answer


def check_scheduler(address, arg="--scheduler"):
    """Raise ValueError (one line naming ``arg``) unless a TCP connection to the Dask scheduler
    ``address`` (tcp://HOST:PORT, tls://HOST:PORT or HOST:PORT) opens within SCHEDULER_TIMEOUT s."""
    from urllib.parse import urlsplit
    parts = urlsplit(address if "://" in address else "tcp://" + address)
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or not port or parts.scheme not in ("tcp", "tls"):
        raise ValueError(f"{arg} {address}: expected tcp://HOST:PORT (the Dask scheduler's address)")
    try:
        socket.create_connection((host, port), timeout=SCHEDULER_TIMEOUT).close()
    except OSError as e:
        raise ValueError(f"{arg} {address}: no Dask scheduler answers there ({e.strerror or e}); start one "
                         f"(docs/SWEEPS.md) or run on this machine without {arg}") from None


def run_sweep(jobs, root, workers=2, scheduler=None, resume=True, log=print, scheduler_file=None):
    """Run ``jobs`` (a list of Job) under ``root``; returns their records in the given order.

    workers: local processes at a time (ignored with a scheduler). scheduler: None (local), a
    Dask scheduler address or a distributed.Client; or scheduler_file: the JSON file a Dask
    scheduler started with ``--scheduler-file`` wrote. resume: skip jobs already "ok" with the
    same command. ``log``: a print-like function for progress (None = quiet).
    """
    _check_jobs(jobs, workers)
    os.makedirs(root, exist_ok=True)
    root, cwd = os.path.abspath(root), os.getcwd()
    log = log or (lambda *a: None)
    t0 = time.time()
    kept = {j.name: read_record(root, j.name) for j in jobs if resume and is_done(j, root)}
    todo = [j for j in jobs if j.name not in kept]
    cluster = scheduler if scheduler_file is None else f"scheduler file {scheduler_file}"
    log(f"sweep {root}: {len(jobs)} jobs, {len(kept)} already ok, {len(todo)} to run "
        f"({'Dask ' + str(cluster) if cluster is not None else f'{workers} local workers'})")
    done = {}
    finished = _recorder(root, len(todo), done, log)
    stopped_by, running_on_cluster = None, []
    if cluster is None:
        stopped_by = _run_local(todo, root, cwd, workers, finished, done)
    elif todo:
        stopped_by, running_on_cluster = _run_on_cluster(todo, root, cwd, scheduler, scheduler_file, finished, done)
    records = _records(jobs, kept, done)
    failed = [r["name"] for r in records if r["status"] != "ok"]
    summary = {"root": root, "n_jobs": len(jobs), "n_ok": len(jobs) - len(failed), "failed": failed,
               "wall_s": time.time() - t0, "jobs": records}
    _write_json(os.path.join(root, "sweep.json"), summary)
    log(format_summary(records, root))
    if stopped_by is not None:
        on_cluster = (f" (not finished: {', '.join(running_on_cluster)}; those already running on the cluster's "
                      "workers go on to their end: stop the workers to end them)") if running_on_cluster else ""
        print(f"sweep {root} stopped by {signal.Signals(stopped_by).name}: its running jobs were stopped and recorded "
              f"\"interrupted\"; run it again to continue them{on_cluster}", file=sys.stderr, flush=True)
        raise SystemExit(128 + stopped_by)
    return records


def _check_jobs(jobs, workers):
    """Refuse (ValueError) jobs of the same name, or a count of workers that is not an integer >= 1."""
    names = [j.name for j in jobs]
    if len(set(names)) != len(names):
        raise ValueError("job names must be unique: " + ", ".join(sorted({n for n in names if names.count(n) > 1})))
    if not (isinstance(workers, int) and workers >= 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")


def _recorder(root, n_todo, done, log):
    """finished(job, future): records a job's end in ``done`` {name: record} and logs it; a runner
    that failed itself (a lost Dask worker, a full disk) gives a "failed" record."""
    def finished(job, fut):
        try:
            rec = fut.result()
        except Exception as e:  # the runner itself failed (a lost Dask worker, a full disk): keep the job
            rec = {"name": job.name, "status": "failed", "returncode": None, "wall_s": 0.0,
                   "command": job.command(os.path.abspath(os.path.join(root, job.name))), "env": dict(job.env),
                   "stderr_tail": f"runner error: {type(e).__name__}: {e}"}
        done[job.name] = rec
        log(f"[{len(done)}/{n_todo}] {job.name}: {rec['status']} (rc {rec['returncode']}, {rec['wall_s']:.1f} s)")
    return finished


def _run_local(todo, root, cwd, workers, finished, done):
    """Run ``todo`` in ``workers`` local processes at a time; returns the signal that stopped the
    sweep (its running jobs stopped and recorded), or None."""
    _stopping.clear()
    with ThreadPoolExecutor(max_workers=workers) as pool, _Signals() as signals:
        futures = {pool.submit(run_job, j, root, cwd): j for j in todo}
        try:
            for fut in as_completed(futures):
                finished(futures[fut], fut)
        except _Stop as stop:
            _stop_jobs(stop.signum, futures, signals)
            for fut in futures:
                if futures[fut].name not in done and fut.done() and not fut.cancelled():
                    finished(futures[fut], fut)
            return stop.signum
    return None


def _run_on_cluster(todo, root, cwd, scheduler, scheduler_file, finished, done):
    """Run ``todo`` on a Dask cluster (``scheduler``: an address or a Client; or ``scheduler_file``);
    returns (the signal that stopped the sweep or None, the jobs left running on its workers)."""
    import cloudpickle
    from distributed import Client
    from distributed import as_completed as dask_completed

    # the workers get this module's functions by value: they need not import the project
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    client = scheduler if isinstance(scheduler, Client) else \
        Client(scheduler_file=scheduler_file) if scheduler_file is not None else Client(scheduler)
    try:
        with _Signals():
            futures = {client.submit(_run_fields, _fields(j), root, cwd, key=f"sweep-{j.name}-{time.time_ns()}",
                                     pure=False): j for j in todo}
            try:
                for fut in dask_completed(list(futures)):
                    finished(futures[fut], fut)
            except _Stop as stop:  # the jobs not started are cancelled; a task running on a worker cannot be
                client.cancel(list(futures))
                return stop.signum, [futures[f].name for f in futures if futures[f].name not in done]
    finally:
        if client is not scheduler:
            client.close()
    return None, []


def _records(jobs, kept, done):
    """The records of ``jobs`` in their order: kept (already ok), done, or else "interrupted"."""
    records = []
    for j in jobs:
        rec = dict(kept[j.name], kept=True) if j.name in kept else done.get(j.name) or \
            {"name": j.name, "status": "interrupted", "returncode": None, "wall_s": 0.0,
             "stderr_tail": "not finished: the sweep was stopped"}
        records.append(rec)
    return records


class _Stop(BaseException):
    def __init__(self, signum):
        super().__init__(signum)
        self.signum = signum


class _Signals:
    """While active, in the main thread: the first SIGINT or SIGTERM raises _Stop there; a second
    one kills the jobs' process groups and ends the runner at once (one line, 128 + its number)."""

    def __enter__(self):
        self.received, self._previous = [], {}
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                self._previous[s] = signal.signal(s, self._handle)
        return self

    def _handle(self, signum, frame):  # noqa: ARG002
        self.received.append(signum)
        if len(self.received) == 1:
            raise _Stop(signum)
        for pgid in list(_running):
            _signal_group(pgid, signal.SIGKILL)
        print(f"sweep stopped at once by a second {signal.Signals(signum).name}: its running jobs were killed",
              file=sys.stderr, flush=True)
        os._exit(128 + signum)

    def __exit__(self, *exc):
        for s, handler in self._previous.items():
            signal.signal(s, handler)


def _stop_jobs(signum, futures, signals):
    """Pass ``signum`` to the running jobs' process groups, let no other job start, wait up to
    STOP_SECONDS for them, then kill what is left."""
    from concurrent.futures import wait
    _stopping.append(signum)
    for fut in futures:
        fut.cancel()  # those not started
    for pgid in list(_running):
        _signal_group(pgid, signum)
    wait(futures, timeout=STOP_SECONDS)
    for pgid in list(_running):
        _signal_group(pgid, signal.SIGKILL)
    wait(futures, timeout=STOP_SECONDS)


def format_summary(records, root=None):
    """A table of the jobs: name, status, return code, wall seconds; then, of the jobs under
    ``root`` that wrote a summary.json (a scene script's run), their headline results
    (engines.run.talk.results_table)."""
    width = max([len(r["name"]) for r in records] + [4])
    lines = [f"{'job':<{width}}  status  rc    wall_s"]
    for r in records:
        status = "ok*" if r.get("kept") else r["status"]
        lines.append(f"{r['name']:<{width}}  {status:<6}  {str(r.get('returncode', '')):<4}  {r.get('wall_s', 0):8.1f}")
    failed = [r for r in records if r["status"] != "ok"]
    lines.append(f"{len(records) - len(failed)} ok ({sum(1 for r in records if r.get('kept'))} kept from before, *), "
                 f"{len(failed)} failed" + ("".join(f"\n  {r['name']}: {r.get('stderr_tail', '').splitlines()[-1:]}"
                                                    for r in failed)))
    runs = []
    for r in records if root is not None else ():
        try:
            with open(os.path.join(root, r["name"], "summary.json")) as f:
                runs.append((r["name"], json.load(f)["results"]))
        except (OSError, ValueError, KeyError, TypeError):
            continue  # no run's summary there (a job of another kind, or one that failed before writing it)
    if runs:
        lines += ["the results of the jobs that wrote a summary.json:", results_table(runs)]
    return "\n".join(lines)


def jobs_from_table(table, script, yade=YADE):
    """Jobs from a yade-batch parameter table (read as data by engines.run.table, without YADE):
    one per line, named by its description, run as ``yade -x script`` (without YADE's servers,
    YADE) with YADE_BATCH=table:line, from which the script reads its line
    (engines.run.command_line)."""
    table = os.path.abspath(table)
    jobs = []
    for line, params in sorted(read_table(table).items()):
        name = re.sub(r"[^A-Za-z0-9._=,+-]", "_", params[DESCRIPTION])
        try:
            jobs.append(Job(name, (*yade, "-x", os.path.abspath(script)), {BATCH: f"{table}:{line}", **yade_environment()}))
        except ValueError as e:
            raise ValueError(f"{table}, line {line}: {e}; change the line's description (it names the job's folder)") from None
    return jobs
