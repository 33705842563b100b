"""Where a run came from, for summary.json: YADE version, the project's commit, the command line
and the overrides applied to the scene file."""
import os
import subprocess
import sys

from engines import ROOT, __version__


def yade_version():
    """The version of the YADE this process runs in (or would import), or None without YADE."""
    if "yade" in sys.modules:
        from yade import config
        return config.version
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "yade"], capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def git_state(root=ROOT):
    """(commit, dirty) of the project's checkout; (None, None) outside git. ``dirty``: tracked
    files differ from the commit."""
    def git(*args):
        return subprocess.run(["git", "-C", root, *args], capture_output=True, text=True, timeout=10)

    try:
        head = git("rev-parse", "HEAD")
        if head.returncode != 0:
            return None, None
        status = git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError):
        return None, None
    return head.stdout.strip(), bool(status.stdout.strip())


def provenance(argv=None, overrides=None):
    """JSON-ready dict: version (the project's, engines.__version__), yade_version, git_commit, git_dirty, python, command_line (the process's
    own argv, interpreter included: under ``yade -x`` the yade launcher and its options), cwd,
    overrides ({table: {field: value}} applied on top of the scene file, e.g. a --duration) and
    yade_batch (the job's table:line under yade-batch, else None)."""
    if argv is None:
        argv = getattr(sys, "orig_argv", sys.argv)
    commit, dirty = git_state()
    return {"version": __version__, "yade_version": yade_version(), "git_commit": commit, "git_dirty": dirty,
            "python": sys.version.split()[0], "command_line": list(argv), "cwd": os.getcwd(),
            "overrides": overrides or {}, "yade_batch": os.environ.get("YADE_BATCH") or None}
