"""Checks made before a run writes anything, and the scripts' argument parsing.

``preflight(scene, packing, out_dir)`` checks what can be known before the first step: the time
step against the stability limits at the start (engines.model.time_step.check_start: eq 52, the
side-wall ties, the water stiffness, the Darcy limit and the sub-step count), the duration, the
loading record, the packing against the walls' box and the contact law (``check_packing``) and the
output directory. ``check_fresh_output`` refuses an output directory holding another run's outputs;
``announce_output`` prints the folder a script writes into.
Each refusal raises InputError with one line naming the field or argument and the limit; the
scripts print it and exit non-zero before the output directory exists. The engines keep their own
checks at construction.

``ArgumentParser``, ``number`` and ``output_dir`` give the scripts one-line argument errors (exit
status 2).
"""
import argparse
import math
import os
import tempfile

from engines.yade.checkpoint import NAME as CHECKPOINT
from engines.yade.checkpoint import OLD_NAME as OLD_CHECKPOINT

ENSEMBLE = "ensemble.json"  # an ensemble's statistics (engines.run.ensemble)
RUN_OUTPUTS = ("summary.json", "history.csv", CHECKPOINT, OLD_CHECKPOINT, ENSEMBLE)  # their presence marks a run's directory


class InputError(ValueError):
    """Bad input found before a run: the message (one line) names the field and the limit."""


# -- arguments ------------------------------------------------------------------------------------
class ArgumentParser(argparse.ArgumentParser):
    """argparse with a one-line error (``prog: error: ...``, no usage block), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message}\n")


def number(kind=float, lo=None, hi=None, lo_open=False, unit=""):
    """argparse type: a finite ``kind`` in [lo, hi] (lo excluded when ``lo_open``); the error
    names the limit, argparse adds the argument's name."""
    if lo is not None and hi is not None:
        bound = f"in {'(' if lo_open else '['}{lo:g}, {hi:g}]"
    elif lo is not None:
        bound = f"{'>' if lo_open else '>='} {lo:g}"
    else:
        bound = "finite" if hi is None else f"<= {hi:g}"
    unit = f" {unit}" if unit else ""

    def convert(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {'an integer' if kind is int else 'a number'}, "
                                             f"got {text!r}") from None
        if not math.isfinite(value) or (lo is not None and (value < lo or lo_open and value == lo)) \
                or (hi is not None and value > hi):
            raise argparse.ArgumentTypeError(f"must be {bound}{unit}, got {text}")
        return value

    return convert


# -- output ---------------------------------------------------------------------------------------
def output_problem(path):
    """Why ``path`` cannot be (made) a writable directory, or None. Creates nothing (a probe
    directory is made and removed in the nearest existing ancestor)."""
    if not path:
        return "empty path"
    probe = os.path.abspath(path)
    while not os.path.exists(probe):
        probe = os.path.dirname(probe)
    if not os.path.isdir(probe):
        return f"{probe} is not a directory, so {path} cannot be created"
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".write-probe-", dir=probe))
    except OSError as e:
        return f"cannot create {path}: {probe} is not writable ({e.strerror})"
    return None


def check_output_dir(path, arg="--out"):
    """Raise InputError (naming ``arg``) unless ``path`` is, or can be made, a writable directory."""
    problem = output_problem(path)
    if problem:
        raise InputError(f"{arg}: {problem}")


def check_fresh_output(path, arg="--out", resumable=False):
    """Raise InputError (naming ``arg``) if ``path`` holds another run's outputs: any of
    RUN_OUTPUTS (a run writes history.csv and its first checkpoint at its start)."""
    found = [name for name in RUN_OUTPUTS if os.path.exists(os.path.join(path, name))]
    if found:
        resume = f", or --resume {path} to continue that run" if resumable else ""
        raise InputError(f"{arg} {path} holds another run's outputs ({', '.join(found)}): give --overwrite to "
                         f"replace them{resume}")


def announce_output(path):
    """Print the folder a script writes into, before it writes: ``output: /absolute/path``."""
    print(f"output: {os.path.abspath(path)}", flush=True)


def output_dir(path):
    """argparse type of an output directory: refused unless it can be written."""
    problem = output_problem(path)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return path


# -- the scene against its packing ----------------------------------------------------------------
def check_limits(scene, packing):
    """The numeric dt against every stability limit at the start (engines.model.time_step.check_start)."""
    from engines.model.time_step import check_start
    try:
        check_start(scene, packing)
    except ValueError as e:
        raise InputError(str(e)) from None


def max_overlap(contact):
    """The deepest overlap a packing may start with [m]: f_max / kn, where the elastic force of
    springs c and d reaches its cap (eq 27) and stops growing, so that the law cannot push the discs
    apart any harder; springs a and b are held to the same force scale f_max."""
    return contact.f_max / contact.kn


def check_packing(scene, packing):
    """Particles inside the walls' box, no overlap deeper than ``max_overlap`` (Packing.check_fit);
    with [walls] kind = "flat" between particles only (the flat walls refuse a particle beyond a
    face when the pores are built)."""
    try:
        packing.check_fit(max_overlap(scene.contact), "[contact] f_max / kn", scene.walls.kind != "flat")
    except ValueError as e:
        raise InputError(str(e)) from None


def check_duration(scene):
    """At least one step."""
    num = scene.numerics
    if int(round(num.duration / num.dt)) < 1:
        raise InputError(f"[numerics] duration = {num.duration:.3g} s is shorter than one step (dt = {num.dt:.3g} s)")


def check_record(scene):
    """A loading record must be read by the engine's reader (engines.model.ground_motion.read_record:
    two numeric columns, increasing time; errors name the file and line)."""
    if scene.loading.type != "record":
        return
    from engines.model.ground_motion import input_acceleration
    try:
        input_acceleration(scene)
    except ValueError as e:
        raise InputError(str(e)) from None


def preflight(scene, packing, out_dir):
    """Every check of a run that can be made before its first step; raises InputError.

    Returns notes (one line each) on what the run will silently skip, for the script to print.
    A dt = "auto" is checked as it will be chosen (engines.model.time_step)."""
    from engines.model.time_step import resolve_dt
    scene = resolve_dt(scene, packing, log=None)
    check_output_dir(out_dir)
    check_duration(scene)
    check_record(scene)
    check_packing(scene, packing)
    check_limits(scene, packing)
    late = [t for t in scene.output.snapshot_times if t > scene.numerics.duration]
    if late:
        return [f"note: [output] snapshot_times {', '.join(f'{t:g}' for t in late)} s lie after the end "
                f"({scene.numerics.duration:g} s) and are skipped"]
    return []
