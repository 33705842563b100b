"""The battery of real signals and processes (``make check``): a signal before the run starts (a
fresh run, a resume) ends the script in one line with nothing changed; a second signal gives one
line and the first one's status; SIGKILL then --resume keeps every segment and the first command
line; a second run on a folder is refused naming the first's host and pid; the sweep runner stops
its jobs' process groups and its jobs die with it; a real full disk (tmpfs, as root) ends a run in
one line with no empty file left."""
import glob
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

import pytest

from engines import ROOT

pytestmark = pytest.mark.check

ENV = dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg", OMP_NUM_THREADS="1")
SCRIPT = "yade_scripts/quicksand.py"
SHORT = ["--case", "1", "--duration", "0.002", "--set", "output.history_interval=100"]
LONG = ["--case", "1", "--duration", "1", "--set", "output.history_interval=100"]


def start(args, **kw):
    return subprocess.Popen(["yade", "-n", "-x", SCRIPT, *args], cwd=ROOT, env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kw)


def wait_for(condition, proc, seconds=300):
    deadline = time.time() + seconds
    while not condition():
        assert proc.poll() is None, proc.communicate()
        assert time.time() < deadline, "timed out"
        time.sleep(0.01)


def past_first_line(proc):
    """The script is importing or compiling (numba's LLVM is loaded: after its first line)."""
    def loaded():
        with open(f"/proc/{proc.pid}/maps") as f:
            return "llvmlite" in f.read()
    return loaded


def rows(path):
    return open(path).read().count("\n") - 1 if os.path.exists(path) else 0


def folder_bytes(folder):
    return {os.path.relpath(p, folder): open(p, "rb").read()
            for p in glob.glob(os.path.join(folder, "**"), recursive=True) if os.path.isfile(p)}


def error_lines(stderr):
    """The script's lines of ``stderr`` (after YADE's banner, which ends "Running script ...")."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    starts = [k for k, line in enumerate(lines) if line.startswith("Running script ")]
    return lines[starts[0] + 1:] if starts else lines


@pytest.fixture(scope="module")
def stopped(tmp_path_factory):
    """A quick-sand run stopped by SIGINT part way (its folder)."""
    out = str(tmp_path_factory.mktemp("stopped") / "run")
    proc = start(["--out", out] + LONG)
    wait_for(lambda: rows(os.path.join(out, "history.csv")) >= 3, proc)
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=60) == 130
    return out


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_before_the_run_ends_a_fresh_run_in_one_line_with_nothing_written(tmp_path, sig):
    out = str(tmp_path / "run")
    proc = start(["--out", out] + SHORT)
    wait_for(past_first_line(proc), proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig
    assert error_lines(err) == [f"interrupted before the run started ({sig.name})"], err
    assert not os.path.exists(out)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_the_resumes_start_changes_nothing(stopped, tmp_path, sig):
    out = str(tmp_path / "run")
    subprocess.run(["cp", "-a", stopped, out], check=True)
    before = folder_bytes(out)
    proc = start(["--resume", out])
    wait_for(past_first_line(proc), proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig
    assert error_lines(err) == [f"interrupted before the run started ({sig.name})"], err
    assert folder_bytes(out) == before


def test_a_second_signal_gives_one_line_and_the_first_ones_status(stopped, tmp_path):
    # before the run
    proc = start(["--out", str(tmp_path / "early")] + SHORT)
    wait_for(past_first_line(proc), proc)
    os.kill(proc.pid, signal.SIGINT)
    os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and error_lines(err) == ["interrupted before the run started (SIGINT)"], err
    # during the run: stopped at once, resumable from its last checkpoint
    out = str(tmp_path / "run")
    proc = start(["--out", out] + LONG)
    wait_for(lambda: rows(os.path.join(out, "history.csv")) >= 3, proc)
    os.kill(proc.pid, signal.SIGINT)
    os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    lines = error_lines(err)
    assert proc.returncode == 130 and len(lines) == 1 and lines[0].startswith("stopped at once by a second SIGTERM"), err
    assert not os.path.exists(os.path.join(out, ".lock"))
    resumed = subprocess.run(["yade", "-n", "-x", SCRIPT, "--resume", out, "--duration", "0.003"], cwd=ROOT, env=ENV,
                             capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    summary = json.load(open(os.path.join(out, "summary.json")))
    assert [s["status"] for s in summary["segments"]] == ["killed", "completed"]


def test_sigkill_then_resume_keeps_every_segment_and_the_first_command_line(tmp_path):
    out = str(tmp_path / "run")
    proc = start(["--out", out, "--case", "1", "--duration", "0.004", "--set", "output.history_interval=100",
                  "--set", "output.checkpoint_seconds=0.05"])
    wait_for(lambda: rows(os.path.join(out, "history.csv")) >= 8, proc)
    proc.kill()
    proc.wait()
    killed_at = json.load(open(os.path.join(out, "summary.json")))["segments"][0]["to_step"]
    resumed = subprocess.run(["yade", "-n", "-x", SCRIPT, "--resume", out], cwd=ROOT, env=ENV, capture_output=True,
                             text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    summary = json.load(open(os.path.join(out, "summary.json")))
    first = summary["segments"][0]
    assert [s["status"] for s in summary["segments"]] == ["killed", "completed"]
    assert first["to_step"] >= killed_at > 0 and summary["segments"][1]["from_step"] <= first["to_step"]
    assert summary["provenance"] == first["provenance"] and "--out" in first["provenance"]["command_line"]
    assert "--resume" in summary["segments"][1]["provenance"]["command_line"]
    t = [line.split(",")[0] for line in open(os.path.join(out, "history.csv")).read().splitlines()[1:]]
    assert len(t) == len(set(t)) == 41  # rows every 100 steps from 0 to the end at 4000, none twice
    assert [n for n in os.listdir(out) if n.startswith(".")] == []


def test_a_second_run_on_a_folder_is_refused_naming_the_first(tmp_path):
    out = str(tmp_path / "run")
    first = start(["--out", out] + LONG)
    wait_for(lambda: rows(os.path.join(out, "history.csv")) >= 2, first)
    try:
        for args in (["--out", out, "--overwrite"] + SHORT, ["--resume", out]):
            second = subprocess.run(["yade", "-n", "-x", SCRIPT, *args], cwd=ROOT, env=ENV, capture_output=True,
                                    text=True, timeout=300)
            assert second.returncode == 1 and "Traceback" not in second.stderr, second.stderr
            assert error_lines(second.stderr)[-1].startswith(
                f"error: {out} is in use by another run (host {socket.gethostname()}, pid {first.pid}"), second.stderr
    finally:
        first.send_signal(signal.SIGINT)
        assert first.wait(timeout=60) == 130
    assert json.load(open(os.path.join(out, "summary.json")))["status"] == "interrupted"


RUNNER = """
import sys
from engines.run.sweep import Job, run_sweep
job = ["sh", "-c", "echo $$ > {out}/pid; sleep 300 & echo $! > {out}/grandchild; wait"]
run_sweep([Job("a", job), Job("b", job)], sys.argv[1], workers=1, log=None)
"""


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:
        return f.read().split(")")[-1].split()[0] != "Z"


def read_pid(path, proc):
    wait_for(lambda: os.path.exists(path) and open(path).read().strip(), proc, 60)
    return int(open(path).read())


def test_the_sweep_runner_stops_its_jobs_process_groups_at_a_signal(tmp_path):
    root = str(tmp_path / "sweep")
    runner = subprocess.Popen([sys.executable, "-c", RUNNER, root], cwd=ROOT, env=ENV, stderr=subprocess.PIPE, text=True)
    pids = [read_pid(os.path.join(root, "a", name), runner) for name in ("pid", "grandchild")]
    t0 = time.time()
    runner.send_signal(signal.SIGTERM)
    _, err = runner.communicate(timeout=60)
    assert runner.returncode == 143 and time.time() - t0 < 10
    assert len(error_lines(err)) == 1 and "stopped by SIGTERM" in err, err
    time.sleep(0.2)
    assert not any(alive(p) for p in pids)
    sweep = json.load(open(os.path.join(root, "sweep.json")))
    assert [j["status"] for j in sweep["jobs"]] == ["interrupted", "interrupted"]
    assert json.load(open(os.path.join(root, "a", "job.json")))["status"] == "interrupted"
    assert not os.path.exists(os.path.join(root, "b", "pid"))  # never started


def test_a_job_dies_with_its_killed_runner(tmp_path):
    root = str(tmp_path / "sweep")
    runner = subprocess.Popen([sys.executable, "-c", RUNNER, root], cwd=ROOT, env=ENV)
    job = read_pid(os.path.join(root, "a", "pid"), runner)
    runner.kill()
    runner.wait()
    deadline = time.time() + 10
    while alive(job):
        assert time.time() < deadline, "the job outlived its runner"
        time.sleep(0.05)


@pytest.fixture
def full_disk():
    """A 64 KiB tmpfs (root only; skipped elsewhere)."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    where = tempfile.mkdtemp()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", where], capture_output=True).returncode:
        os.rmdir(where)
        pytest.skip("tmpfs could not be mounted")
    yield where
    subprocess.run(["umount", where], check=True)
    os.rmdir(where)


def test_a_full_disk_ends_the_run_in_one_line_with_no_empty_file(full_disk):
    out = os.path.join(full_disk, "run")
    run = subprocess.run(["yade", "-n", "-x", SCRIPT, "--out", out] + SHORT, cwd=ROOT, env=ENV, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 1 and "Traceback" not in run.stderr and "Exception ignored" not in run.stderr, run.stderr
    last = error_lines(run.stderr)[-1]
    assert last.startswith(f"error: cannot write {out}/") and last.endswith(": no space left on the device"), last
    names = os.listdir(out)
    assert all(os.path.getsize(os.path.join(out, n)) > 0 for n in names) and not any(n.startswith(".") for n in names)
    summary = json.load(open(os.path.join(out, "summary.json")))
    assert summary["status"] == "failed: " + last.removeprefix("error: ")
