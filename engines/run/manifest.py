"""What in a run folder this project wrote: ``OUT/manifest.json``, and the one place that removes it.

A run records each name it writes (a file, or the folder ``vtk``) in the manifest before it first
writes it (``claim``), so that a kill between the two leaves no file of the run unlisted; a name
may be listed and never written (the failure state of a run that did not fail). The manifest is
written whole or not at all (engines.files.write_json).

``project_names(folder)`` splits a folder's entries into the project's and the others: the
manifest's names (without a manifest, a folder of an older run: the names a run, an ensemble or a
sweep job writes, RUN_FILES, ENSEMBLE_FILES, JOB_FILES and the snapshot pattern), the start
folders its ensemble.json lists, and the temporaries a killed writer leaves. ``clear(folder)``
(``--overwrite``, a sweep's re-run job) removes the project's names only, keeps everything else
and prints one line naming what it kept; inside ``vtk/`` it removes the VTK files a run writes and
the folder only if nothing else is left in it. ``check_fresh`` refuses a folder holding another
run's outputs, or anything this project did not write, without ``--overwrite``.
"""
import contextlib
import fnmatch
import json
import os
import re
import shutil

from engines.files import TEMP_MARK, TEMP_PREFIX, write_json
from engines.files.inputs import check_name
from engines.run.sweep import LOCK_FILE
from engines.yade.checkpoint import NAME as CHECKPOINT
from engines.yade.checkpoint import OLD_NAME as OLD_CHECKPOINT

NAME = "manifest.json"
VTK = "vtk"
# a run's files (engines.run.runner; figures: postproc.plots.figures_of_run, a script's own, e.g.
# postproc.liquefaction.run_figures, are claimed when drawn)
RUN_FILES = ("history.csv", "summary.json", CHECKPOINT, OLD_CHECKPOINT, "failure_state.npz", "pressure_blocks.png",
             "history_panels.png", "snapshots.png", "blocks.png", "depth.png", "stress_paths.png", NAME)
RUN_PATTERNS = ("snapshot_*ms.npz",)
VTK_PATTERNS = ("discs_*.vtp", "forces_*.vtp", "pores_*.vtp", "throats_*.vtp", "discs.pvd", "forces.pvd", "pores.pvd",
                "throats.pvd")  # postproc.vtk
# an ensemble's folder (engines.run.ensemble, postproc.ensemble) and a sweep's (engines.run.sweep)
ENSEMBLE = "ensemble.json"
ENSEMBLE_FILES = (ENSEMBLE, "sweep.json", "ensemble_pressure_blocks.png", "ensemble_history.png")
JOB_FILES = ("job.json", "stdout.log", "stderr.log")  # the sweep runner's, in each job's folder
TEMPORARIES = (f"{TEMP_PREFIX}*{TEMP_MARK}*", ".checkpoint-*", "*.json.tmp")  # left by a killed writer
START = re.compile(r"^start_\d+$")


def read(folder):
    """The names the manifest of ``folder`` lists, or None (no manifest, or not one we can read)."""
    try:
        with open(os.path.join(folder, NAME)) as f:
            names = json.load(f)["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return [n for n in names if isinstance(n, str) and _plain(n)] if isinstance(names, list) else None


def _plain(name):
    try:
        check_name(name, "manifest entry")
    except ValueError:
        return False
    return True


def claim(folder, names):
    """Add ``names`` (plain names inside ``folder``) to its manifest before they are first written."""
    listed = read(folder) or []
    new = [check_name(n, f"{folder}/{NAME}: entry") for n in names if n not in listed]
    if new or not os.path.exists(os.path.join(folder, NAME)):
        write_json(os.path.join(folder, NAME), {"files": listed + new + ([NAME] if NAME not in listed + new else []),
                                                "about": "the files this project wrote here (engines.run.manifest)"})


def ensemble_starts(folder):
    """The start folders the ensemble.json of ``folder`` lists (names start_<k> only)."""
    try:
        with open(os.path.join(folder, ENSEMBLE)) as f:
            starts = json.load(f).get("starts", [])
    except (OSError, ValueError, AttributeError):
        return []
    return [s for s in starts if isinstance(s, str) and START.match(s)] if isinstance(starts, list) else []


def _matches(name, patterns):
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)


def project_names(folder):
    """(the names in ``folder`` this project wrote, the others), each sorted; JOB_FILES, the sweep
    runner's, are in neither (they belong to the job, not to the run), nor is the folder's lock
    (LOCK_FILE: engines.run.guard takes it, removes it, and takes over one a killed run left)."""
    try:
        entries = os.listdir(folder)
    except FileNotFoundError:
        return [], []
    listed = read(folder)
    ours = set(listed) | {NAME} if listed is not None else set(RUN_FILES) | set(ENSEMBLE_FILES) | {VTK}
    ours |= set(ensemble_starts(folder))
    mine, others = [], []
    for name in entries:
        if name in JOB_FILES or name == LOCK_FILE:
            continue
        path = os.path.join(folder, name)
        is_ours = (name in ours or _matches(name, TEMPORARIES) or listed is None and _matches(name, RUN_PATTERNS))
        if name in ours and name != VTK and os.path.isdir(path) != bool(START.match(name)):
            is_ours = False  # a folder where we write a file, or the reverse: not ours
        (mine if is_ours else others).append(name)
    return sorted(mine), sorted(others)


def _remove(path):
    with contextlib.suppress(FileNotFoundError):
        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path)
        else:
            os.remove(path)


def clear(folder, log=print):
    """Remove what this project wrote in ``folder`` (``project_names``); keep the rest and name it
    in one line. Returns the kept names (inside vtk/ as vtk/NAME)."""
    mine, kept = project_names(folder)
    for name in mine:
        path = os.path.join(folder, name)
        if name == VTK and os.path.isdir(path) and not os.path.islink(path):
            others = [n for n in os.listdir(path) if not _matches(n, VTK_PATTERNS)]
            for n in os.listdir(path):
                if _matches(n, VTK_PATTERNS):
                    _remove(os.path.join(path, n))
            if others:
                kept += [f"{VTK}/{n}" for n in sorted(others)]
            else:
                os.rmdir(path)
        else:
            _remove(path)
    if kept and log:
        log(f"kept in {folder} (not written by this project): {', '.join(kept)}")
    return kept


def check_fresh(folder, arg="--out", resumable=False):
    """Raise ValueError (one line naming ``arg``) if ``folder`` holds another run's outputs or
    anything this project did not write; a new or empty folder (or a sweep job's, its JOB_FILES)
    passes."""
    mine, others = project_names(folder)
    if not (mine or others):
        return
    parts = []
    if mine:
        parts.append(f"another run's outputs ({', '.join(mine[:6])}{', ...' if len(mine) > 6 else ''})")
    if others:
        parts.append(f"files this project did not write ({', '.join(others[:6])}{', ...' if len(others) > 6 else ''})")
    resume = f", or --resume {folder} to continue that run" if resumable and mine else ""
    remedy = ("give --overwrite to replace them" if not others else
              "give --overwrite to write there anyway (they are kept), or name a new or empty folder" if not mine else
              "give --overwrite to replace the outputs (the other files are kept)")
    raise ValueError(f"{arg} {folder} holds {' and '.join(parts)}: {remedy}{resume}")
