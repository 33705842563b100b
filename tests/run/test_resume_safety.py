"""Nothing lost on resume (in-process): history.csv is checked against its checkpoint (row count,
last t, SHA-256) and refused in one line when it differs; it is never rewritten in place; the
summary keeps every segment, a killed one included, and the first segment's provenance; a full
disk ends the run in one line naming the path, with no empty file left looking valid."""
import errno
import json
import os
import re
import subprocess
import sys

import pytest
from yade import O

from engines import ROOT, files
from engines.run import history, runner
from engines.run import scene as scenes
from engines.run.runner import resume_run, run_scene
from engines.yade import checkpoint
from engines.yade.deposition import scene_packing

STEPS = 600
BASE = {"numerics": {"rebuild_interval": 200, "duration": STEPS * 1e-6},
        "output": {"snapshot_times": [3e-4], "history_interval": 100}}
ENV = dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg")


@pytest.fixture(scope="module")
def packing():
    return scene_packing(scenes.preset("quicksand_case1"))


def scene(**over):
    return scenes.preset("quicksand_case1", {**BASE, **over})


def stopped_run(out, packing, k=300, **over):
    """A run of ``scene(**over)`` stopped as by a signal once step k is done; its summary."""
    requested = runner.Interrupts.requested
    runner.Interrupts.requested = lambda self: bool(self.received) or O.iter >= k
    try:
        summary = run_scene(scene(**over), packing, str(out), figures=False)
    finally:
        runner.Interrupts.requested = requested
    assert summary["status"] == "interrupted"
    return summary


def info_of(out):
    return checkpoint.read_info(os.path.join(out, checkpoint.NAME))


def refused_by_script(out):
    """The one line with which quicksand.py --resume OUT is refused (before YADE starts)."""
    run = subprocess.run([sys.executable, "yade_scripts/quicksand.py", "--resume", str(out)], cwd=ROOT, env=ENV,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 1 and "Traceback" not in run.stderr and len(run.stderr.strip().splitlines()) == 1, \
        run.stderr
    return run.stderr.strip()


def test_the_checkpoint_records_the_run_and_its_history(tmp_path, packing):
    summary = stopped_run(tmp_path, packing)
    info = info_of(tmp_path)
    data = open(tmp_path / history.NAME, "rb").read()
    assert info["run_id"] == summary["run_id"] and len(info["run_id"]) == 32
    assert info["history_rows"] == data.count(b"\n") - 1 == 4  # rows at steps 0, 100, 200, 300
    assert info["history_last_t"] == pytest.approx(3e-4, rel=1e-9)
    size, whole, sha = history.kept(str(tmp_path), info)
    assert (size, whole, sha.hexdigest()) == (len(data), True, info["history_sha256"])


@pytest.mark.parametrize("damage, match", [
    ("missing", r"history.csv is missing; the checkpoint at step 300 recorded 4 rows"),
    ("empty", r"history.csv is empty"),
    ("short", r"history.csv has 3 rows, the checkpoint at step 300 recorded 4: rows were lost"),
    ("edited", r"its header and first 4 rows are not those the checkpoint at step 300 recorded \(SHA-256"),
    ("other run", r"row 4 has t = 0.0004 s, the checkpoint at step 300 recorded t = 0.0003 s"),
])
def test_a_history_that_is_not_the_checkpoints_is_refused_in_one_line(tmp_path, packing, damage, match):
    stopped_run(tmp_path, packing)
    path = tmp_path / history.NAME
    lines = open(path).read().splitlines(keepends=True)
    if damage == "missing":
        os.remove(path)
    elif damage == "empty":
        open(path, "w").close()
    elif damage == "short":
        open(path, "w").writelines(lines[:-1])
    elif damage == "edited":
        lines[2] = lines[2][:-1] + "1\n"  # one more digit in its last column
        open(path, "w").writelines(lines)
    else:  # another run's rows, one interval further on
        other = tmp_path / "other"
        stopped_run(other, packing, k=400)
        open(path, "w").writelines(open(other / history.NAME).read().splitlines(keepends=True)[:1] + lines[2:] +
                                   open(other / history.NAME).read().splitlines(keepends=True)[-1:])
    before = open(path, "rb").read() if os.path.exists(path) else None
    assert re.search(match, refused_by_script(tmp_path))
    O.reset()
    with pytest.raises(history.HistoryMismatch, match=match):
        resume_run(str(tmp_path), figures=False)
    assert (open(path, "rb").read() if os.path.exists(path) else None) == before
    assert not os.path.exists(tmp_path / ".lock")


def test_the_resume_appends_or_rebuilds_and_is_never_caught_half_way(tmp_path, packing, monkeypatch):
    """Rows written after the checkpoint (and a half row) are dropped by rebuilding the kept rows in
    a temporary file renamed over history.csv: stopped at the rename, the file is as it was; a
    history that holds exactly the checkpoint's rows is appended to, not rewritten."""
    stopped_run(tmp_path, packing)
    path = tmp_path / history.NAME
    exact = open(path, "rb").read()
    with open(path, "ab") as f:
        f.write(b"0.0004,1,2,3\n0.0005,1,")
    grown = open(path, "rb").read()

    class Killed(BaseException):
        pass

    def killed(*a):
        raise Killed

    monkeypatch.setattr(files.os, "replace", killed)
    O.reset()
    with pytest.raises(Killed):
        resume_run(str(tmp_path), figures=False)
    assert open(path, "rb").read() == grown
    assert [n for n in os.listdir(tmp_path) if ".tmp-" in n] == []
    monkeypatch.undo()

    # exactly the checkpoint's rows: appended to (a rewrite would fail here)
    open(path, "wb").write(exact)
    saved = files.saved
    monkeypatch.setattr(files, "saved", lambda path, *a: killed() if path.endswith(history.NAME) else saved(path, *a))
    O.reset()
    summary = resume_run(str(tmp_path), figures=False)
    assert summary["status"] == "completed" and summary["steps"] == STEPS
    assert open(path, "rb").read().startswith(exact) and open(path, "rb").read().count(b"\n") == 2 + STEPS // 100  # header, rows 0 ... STEPS


def test_a_killed_segment_stays_in_the_summary_with_the_first_command_line(tmp_path, packing, monkeypatch):
    """A segment killed after a checkpoint (as SIGKILL leaves it: checkpoint and summary saying
    "running", nothing written at the end) is listed "killed" with its last known step after the
    resume; the summary's provenance stays the first segment's."""
    class Killed(BaseException):
        pass

    dead = []

    def hook(cp):
        if cp.step_index >= 450:
            dead.append(True)
            raise Killed

    for name in ("save_checkpoint", "write_summary"):  # a dead process writes nothing more
        original = getattr(runner.Run, name)
        monkeypatch.setattr(runner.Run, name, lambda self, *a, _f=original: None if dead else _f(self, *a))
    monkeypatch.setattr(runner, "write_failure_state", lambda *a: None)
    monkeypatch.setattr(runner.Recorder, "__call__", lambda self, cp, _f=runner.Recorder.__call__: (hook(cp), _f(self, cp)))
    sc = scene(output={**BASE["output"], "checkpoint_seconds": 1e-9})
    with pytest.raises(Killed):
        run_scene(sc, packing, str(tmp_path), figures=False)
    before = json.load(open(tmp_path / "summary.json"))
    assert before["status"] == "running" and before["segments"][0]["to_step"] == 400
    monkeypatch.undo()
    O.reset()
    after = resume_run(str(tmp_path), figures=False)
    assert [s["status"] for s in after["segments"]] == ["killed", "completed"]
    assert [(s["from_step"], s["to_step"]) for s in after["segments"]] == [(0, 400), (400, STEPS)]
    assert after["provenance"] == before["provenance"] == before["segments"][0]["provenance"]
    assert after["provenance"]["overrides"] == json.loads(json.dumps(sc.overrides))
    assert after["run_id"] == before["run_id"]
    assert json.load(open(tmp_path / "summary.json"))["segments"] == json.loads(json.dumps(after["segments"]))


def test_stale_temporaries_are_removed_at_the_next_start(tmp_path, packing):
    stopped_run(tmp_path, packing)
    stale = [".checkpoint-abc", ".checkpoint-def.yade.gz", ".summary.json.tmp-xyz"]
    for name in stale:
        open(tmp_path / name, "w").close()
    O.reset()
    assert resume_run(str(tmp_path), figures=False)["status"] == "completed"
    assert not any(os.path.exists(tmp_path / name) for name in stale)


class FullFile:
    """A file on a full disk: every write fails as write(2) does."""

    def __init__(self, f):
        self.f = f

    def write(self, text):  # noqa: ARG002
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def __getattr__(self, name):
        return getattr(self.f, name)


@pytest.mark.parametrize("full", ["history.csv", "snapshot_", "checkpoint.npz", "summary.json", "failure"])
def test_a_full_disk_ends_the_run_in_one_line_naming_the_path(tmp_path, packing, monkeypatch, full):
    """ENOSPC on one kind of write after the run started: the run raises WriteError naming that
    file and the cause; summary.json (when it can be written) says "failed: ..."; no empty or
    half file is left (no temporaries, no zero-byte failure_state.npz)."""
    fsync = files.os.fsync
    prefix = {"snapshot_": ".snapshot_", "checkpoint.npz": ".checkpoint.npz.tmp-", "summary.json": ".summary.json.tmp-",
              "failure": ".failure_state.npz.tmp-"}.get(full)
    first_failing = 2 if full in ("checkpoint.npz", "summary.json") else 1  # the start's checkpoint and summary pass
    seen = []

    def full_fsync(fd):
        if prefix and os.path.basename(os.readlink(f"/proc/self/fd/{fd}")).startswith(prefix):
            seen.append(fd)
            if len(seen) >= first_failing:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return fsync(fd)

    monkeypatch.setattr(files.os, "fsync", full_fsync)
    if full == "history.csv":  # its third row meets a full disk
        monkeypatch.setattr(runner.Recorder, "row", lambda self, cp, xz, k, _f=runner.Recorder.row: (
            setattr(self, "file", FullFile(self.file)) if self.rows == 2 else None, _f(self, cp, xz, k)))
    if full == "failure":  # an error in the run, then a full disk for its post-mortem
        monkeypatch.setattr(runner.Recorder, "row", lambda *a: (_ for _ in ()).throw(FloatingPointError("boom")))
    with pytest.raises(files.WriteError if full != "failure" else FloatingPointError) as e:
        run_scene(scene(), packing, str(tmp_path), figures=False)
    message = str(e.value)
    names = os.listdir(tmp_path)
    assert [n for n in names if ".tmp-" in n or n.startswith(".checkpoint-")] == []
    assert all(os.path.getsize(tmp_path / n) > 0 for n in names if n != ".lock"), names
    assert ".lock" not in names
    if full == "failure":
        assert "failure_state.npz" not in names and message == "boom"
    else:
        assert "\n" not in message and message.startswith(f"cannot write {tmp_path}/") and \
            message.endswith(": no space left on the device")
        assert os.path.basename(message.split()[2].rstrip(":")).startswith(full)
    if full != "summary.json":
        summary = json.load(open(tmp_path / "summary.json"))
        assert summary["status"] == f"failed: {message}" if full != "failure" else "failed: FloatingPointError: boom"
        assert summary["segments"][-1]["status"] == summary["status"]


def test_a_full_disk_is_one_line_from_the_script(tmp_path, monkeypatch, capsys):
    from yade_scripts import quicksand

    def full(fd):  # noqa: ARG001
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(files.os, "fsync", full)
    out = tmp_path / "run"
    O.reset()
    with pytest.raises(SystemExit) as e:
        quicksand.main(["--case", "1", "--out", str(out), "--duration", "2e-4"])
    assert e.value.code == f"error: cannot write {out}/manifest.json: no space left on the device"  # its first file
    assert not os.path.exists(out / ".lock")


@pytest.mark.parametrize("chunk", [1, 7, 1 << 20])
@pytest.mark.parametrize("after", [b"", b"0.001,10\n", b"0.001,"])
def test_the_history_is_checked_in_chunks_to_the_checkpoints_last_row(tmp_path, monkeypatch, chunk, after):
    """What history.kept keeps and whether it is the whole file, whatever the chunks' edges."""
    import hashlib
    body = b"t,a\n" + b"".join(b"%.9g,%d\n" % (k * 1e-4, k) for k in range(10))
    (tmp_path / history.NAME).write_bytes(body + after)
    info = {"step": 900, **history.info(10, 9e-4, hashlib.sha256(body).hexdigest())}
    monkeypatch.setattr(history, "CHUNK", chunk)
    size, whole, sha = history.kept(str(tmp_path), info)
    assert (size, whole, sha.hexdigest()) == (len(body), not after, info["history_sha256"])
    with pytest.raises(history.HistoryMismatch, match="row 10 has t = 0.0009 s, the checkpoint at step 900 recorded "
                                                      "t = 0.001 s"):
        history.kept(str(tmp_path), {**info, "history_last_t": 1e-3})
