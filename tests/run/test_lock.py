"""One run per folder: engines.run.guard's lockf lock, refused in one line naming host and pid; the
sweep runner does not start a job whose folder another live run holds."""
import json
import os
import socket
import subprocess
import sys

import pytest

from engines import ROOT
from engines.run import guard, sweep

ENV = dict(os.environ, PYTHONPATH=ROOT)
# holds FOLDER's lock until its stdin closes; with "die", ends without releasing it (as a killed run)
HOLDER = """
import os, sys
from engines.run import guard
with guard.hold(sys.argv[1]):
    print("held", flush=True)
    sys.stdin.read()
    if sys.argv[2:] == ["die"]:
        os._exit(0)
"""


class Holder:
    """Another process holding ``folder``'s lock while the ``with`` lasts."""

    def __init__(self, folder, die=False):
        self.proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(folder)] + (["die"] if die else []), cwd=ROOT,
                                     env=ENV, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def __enter__(self):
        assert self.proc.stdout.readline() == "held\n"
        return self.proc

    def __exit__(self, *exc):
        self.proc.stdin.close()
        assert self.proc.wait(timeout=30) == 0


def test_a_folder_held_by_another_process_is_refused_naming_its_host_and_pid(tmp_path):
    with Holder(tmp_path) as other:
        expected = f"{tmp_path} is in use by another run (host {socket.gethostname()}, pid {other.pid}; its lock: "
        for attempt in (guard.check_free, lambda d: guard.hold(d).__enter__()):
            with pytest.raises(guard.FolderLocked) as e:
                attempt(str(tmp_path))
            assert str(e.value).startswith(expected) and "\n" not in str(e.value)
        assert sweep.lock_holder(str(tmp_path)) == f"{socket.gethostname()} {other.pid}"
    assert not os.path.exists(tmp_path / guard.LOCK)  # released and removed by its holder
    assert sweep.lock_holder(str(tmp_path)) == ""
    with guard.hold(str(tmp_path)):
        assert open(tmp_path / guard.LOCK).read() == f"{socket.gethostname()} {os.getpid()}\n"


def test_a_killed_holders_lock_is_taken_over(tmp_path):
    with Holder(tmp_path, die=True):
        pass
    assert os.path.exists(tmp_path / guard.LOCK) and sweep.lock_holder(str(tmp_path)) == ""
    guard.check_free(str(tmp_path))
    with guard.hold(str(tmp_path)):
        assert open(tmp_path / guard.LOCK).read().split() == [socket.gethostname(), str(os.getpid())]


def test_the_same_process_holds_a_folder_once_and_releases_it_at_the_outermost_end(tmp_path):
    out = tmp_path / "new"
    with guard.hold(str(out)):
        with guard.hold(str(out) + "/"):
            guard.check_free(str(out))  # its own lock is not another run's
        assert os.path.exists(out / guard.LOCK)
        # a probe of another process sees it held
        probe = subprocess.run([sys.executable, "-c", "import sys; from engines.run import sweep; "
                                "print(sweep.lock_holder(sys.argv[1]))", str(out)], env=ENV, cwd=ROOT,
                               capture_output=True, text=True)
        assert probe.stdout.split() == [socket.gethostname(), str(os.getpid())]
    assert os.listdir(out) == []
    with guard.hold(str(out)):
        guard.release_all(undo_made=True)
    assert os.path.isdir(out)  # not made by that hold
    with guard.hold(str(tmp_path / "made")):
        guard.release_all(undo_made=True)
    assert not os.path.exists(tmp_path / "made")


def test_a_scene_script_refuses_a_held_folder_in_one_line(tmp_path):
    from engines.run.preflight import check_resume
    from yade_scripts import quicksand
    out = tmp_path / "run"
    with Holder(out) as other:
        expected = f"{out} is in use by another run (host {socket.gethostname()}, pid {other.pid}"
        with pytest.raises(SystemExit) as e:
            quicksand.main(["--case", "1", "--out", str(out), "--overwrite"])
        assert str(e.value.code).startswith(f"error: {expected}")
        with pytest.raises(guard.FolderLocked, match=expected.replace("(", r"\(")):
            check_resume(str(out), None)  # before its checkpoint is read
        assert os.listdir(out) == [guard.LOCK]


def test_the_sweep_does_not_start_a_job_whose_folder_is_held(tmp_path):
    job = sweep.Job("a", (sys.executable, "-c", "open('ran', 'w').close()"))
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "job.json").write_text('{"status": "running", "theirs": true}')
    with Holder(tmp_path / "a") as other:
        rec, = sweep.run_sweep([job], str(tmp_path), log=None)
    assert rec["status"] == "locked" and f"{socket.gethostname()} {other.pid}" in rec["stderr_tail"]
    assert json.loads((tmp_path / "a" / "job.json").read_text()) == {"status": "running", "theirs": True}
    assert sorted(os.listdir(tmp_path / "a")) == ["job.json"]
    assert json.loads((tmp_path / "sweep.json").read_text())["failed"] == ["a"]
