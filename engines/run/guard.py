"""One run per folder, and signals handled from a script's first line.

``catch_signals()``: the scene scripts call it right after putting the project on sys.path, before
their heavy imports (numba, YADE's glue). Until the run loop takes over (engines.run.runner's
``Interrupts``), SIGINT or SIGTERM ends the process at once with one line, ``interrupted before the
run started``, and exit status 128 + the signal's number (130, 143): the run's folder is as it was
(the lock this process took is removed with it). ``stage(text)`` changes what that line says after
the run (e.g. while the figures are drawn).

``hold(folder)``: a POSIX ``lockf`` lock on FOLDER/.lock (honoured on NFS), taken before a run writes
anything there and held while it runs; the file holds "HOST PID" of its holder. A second run on the
folder is refused in one line naming them (``FolderLocked``). Taken again by the same process, it
is the same lock (POSIX locks belong to the process: a second descriptor would release it when
closed). Released (and the file removed) when the outermost ``with`` ends; a killed process's
lock goes with it, and the stale file is taken over by the next run.
"""
import contextlib
import fcntl
import os
import signal
import socket
import sys

from engines.run.sweep import LOCK_FILE as LOCK  # in a run's folder
from engines.run.sweep import lock_holder

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class FolderLocked(ValueError):
    """Another live process holds the folder's lock; the message names its host and pid."""


_held = {}  # real path of a folder -> [descriptor, lock path, times taken, folder made by this process]
_when = ["before the run started"]
_exiting = []  # the signal that is ending the process


def _refusal(folder, who):
    who = who.split()
    named = f"host {who[0]}, pid {who[1]}" if len(who) == 2 else "another process"
    return FolderLocked(f"{folder} is in use by another run ({named}; its lock: {os.path.join(folder, LOCK)}): "
                        "wait until it ends, or give another --out")


def check_free(folder):
    """Raise FolderLocked if another live process holds ``folder``'s lock (a check before the
    preflight; ``hold`` takes the lock)."""
    if os.path.realpath(folder) not in _held:
        who = lock_holder(folder)
        if who:
            raise _refusal(folder, who)


def _take(folder):
    made = not os.path.isdir(folder)
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, LOCK)
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            who = os.pread(fd, 200, 0).decode(errors="replace").strip()
            os.close(fd)
            raise _refusal(folder, who) from None
        try:  # the file removed by its last holder after we opened it: lock the new one
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    # written in place, not by rename: the lock is on this file's inode
    os.ftruncate(fd, 0)
    os.write(fd, f"{socket.gethostname()} {os.getpid()}\n".encode())
    return [fd, path, 0, made]


@contextlib.contextmanager
def hold(folder):
    """``with hold(folder):`` this process's lock on ``folder`` (made if missing) for the block;
    raises FolderLocked when another process holds it."""
    key = os.path.realpath(folder)
    entry = _held.get(key)
    if entry is None:
        entry = _held[key] = _take(folder)
    entry[2] += 1
    try:
        yield
    finally:
        entry[2] -= 1
        if entry[2] == 0 and _held.get(key) is entry:  # (release_all may have released it)
            _release(key)


def _release(key):
    fd, path, _, _ = _held.pop(key)
    with contextlib.suppress(OSError):
        os.remove(path)  # before the unlock: a waiting run then locks a new file (the inode check in _take)
    os.close(fd)


def release_all(undo_made=False):
    """Release every lock this process holds (a process about to _exit); ``undo_made``: also remove
    the folders it made for them if they are empty again."""
    for key in list(_held):
        made = _held[key][3]
        _release(key)
        if undo_made and made:
            with contextlib.suppress(OSError):
                os.rmdir(key)


def stage(text):
    """What the line at a signal outside the run loop says happened: ``interrupted TEXT``."""
    _when[0] = text


def exit_now(signum, line):
    """Print ``line`` (one line, stderr), release the locks and end the process with 128 + signum,
    without the interpreter's and YADE's teardown. A signal arriving meanwhile ends it at once,
    with the same status and no second line."""
    if _exiting:
        os._exit(128 + _exiting[0])
    _exiting.append(signum)
    signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)  # no handler runs again in the middle of this one
    with contextlib.suppress(Exception):
        sys.stdout.flush()
        print(line, file=sys.stderr, flush=True)
    release_all(undo_made=_when[0] == "before the run started")
    os._exit(128 + signum)


def _early(signum, frame):  # noqa: ARG001
    exit_now(signum, f"interrupted {_when[0]} ({signal.Signals(signum).name})")


def catch_signals():
    """From here on, until a run loop sets its own handlers, SIGINT and SIGTERM end the process
    with one line and 128 + the signal's number (module docstring)."""
    for s in SIGNALS:
        signal.signal(s, _early)
