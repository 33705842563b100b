"""Sweeps from any worker: a Dask scheduler and two workers started as their own processes on
127.0.0.1, in a working directory of their own and without the project on their path; the sweep
started under Debian's python3 with a clean environment; each scene script writes into its job's
directory, and relative paths resolve against the directory the sweep was started from."""
import json
import os
import shutil
import subprocess
import time

import pytest

from engines import ROOT
from engines.run.command_line import BATCH_OUT

pytestmark = pytest.mark.check  # Dask processes and scene scripts under YADE
distributed = pytest.importorskip("distributed")
DASK = shutil.which("dask")
CLEAN_ENV = {"PATH": "/usr/bin:/bin"}  # no PYTHONPATH, no HOME
SWEEP = os.path.join(ROOT, "yade_scripts", "sweep.py")


@pytest.fixture
def cluster(tmp_path):
    """(scheduler address, the workers' working directory, the scheduler file); every process
    stopped at the end. All on 127.0.0.1 without dashboards, the port chosen by the system and found
    by the workers in the scheduler file (docs/SWEEPS.md's recipe)."""
    if DASK is None:
        pytest.skip("no dask command")
    cwd = tmp_path / "workers"
    cwd.mkdir()
    info = tmp_path / "scheduler.json"
    procs = []

    def start(*args, log):
        with open(tmp_path / log, "w") as f:
            procs.append(subprocess.Popen([DASK, *args], cwd=cwd, env=CLEAN_ENV, stdout=f, stderr=subprocess.STDOUT))

    try:
        start("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(info),
              log="scheduler.log")
        for i in (1, 2):
            start("worker", "--scheduler-file", str(info), "--host", "127.0.0.1", "--nthreads", "1", "--no-nanny",
                  "--no-dashboard", "--local-directory", str(tmp_path / f"space{i}"), log=f"worker{i}.log")
        deadline = time.time() + 30
        while not info.exists() and time.time() < deadline:
            time.sleep(0.1)
        with distributed.Client(scheduler_file=str(info), timeout=30) as client:
            client.wait_for_workers(2, timeout=30)
            address = client.scheduler.address
        yield address, cwd, str(info)
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def sweep(*args):
    """yade_scripts/sweep.py under /usr/bin/python3 with a clean environment, started in ROOT."""
    run = subprocess.run(["/usr/bin/python3", SWEEP, *args], cwd=ROOT, env=CLEAN_ENV, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr


def test_scene_scripts_write_into_their_job_directories_on_dask_workers(cluster, tmp_path):
    address, workers_cwd, info = cluster
    # a yade-batch table (no out column) with a script path relative to ROOT
    table = tmp_path / "qs.table"
    table.write_text("duration water.q_w\n1e-5 2.5e-4\n1e-5 1e-3\n")
    sweep("--table", str(table), "--script", "yade_scripts/quicksand.py", "--out", str(tmp_path / "qs"),
          "--scheduler", address)
    for line, q_w in ((2, "2.5e-4"), (3, "1e-3")):
        name = f"duration=1e-5,water.q_w={q_w}"  # yade-batch's description of the line
        with open(tmp_path / "qs" / name / "summary.json") as f:
            summary = json.load(f)
        assert summary["status"] == "completed" and summary["steps"] == 10
        assert summary["provenance"]["yade_batch"] == f"{table}:{line}" and summary["parameters"]["water"]["q_w"] == float(q_w)
        assert (tmp_path / "qs" / name / "history.csv").exists()
        assert not os.path.exists(os.path.join(ROOT, BATCH_OUT, name))
    # a job list whose command names the script by a path relative to ROOT
    jobs = tmp_path / "jobs.json"
    jobs.write_text(json.dumps([{"name": "liq", "argv": ["yade", "-n", "-x", "yade_scripts/liquefaction.py", "--case",
                                                         "1", "--duration", "1e-5", "--out", "{out}"]}]))
    sweep("--jobs", str(jobs), "--out", str(tmp_path / "liq"), "--scheduler-file", info)
    with open(tmp_path / "liq" / "liq" / "summary.json") as f:
        assert json.load(f)["steps"] == 10
    assert os.listdir(workers_cwd) == []
