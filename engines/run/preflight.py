"""Checks made before a run writes anything, and the scripts' argument parsing.

``preflight(scene, packing, out_dir, prepared)`` checks what can be known before the first step: the
time step against the stability limits at the start (engines.model.start: eq 52, the side-wall ties,
the water stiffness, the Darcy limit and the sub-step count; ``prepared``, the run's Start, is the one
the engines then run on, so the limits checked are those of the network that runs), the duration, the
loading record, the packing against the walls' box and the contact law (``check_packing``) and the
output directory. ``check_fresh_output`` refuses an output directory holding another run's outputs
or files the project did not write (engines.run.manifest); ``check_resume`` refuses a resume that
cannot go on; ``announce_output`` prints the folder a script writes into, ``announce_dt`` the
choice of dt = "auto".
Each refusal raises InputError with one line naming the field or argument and the limit; the
scripts print it and exit non-zero before the output directory exists. The engines keep their own
checks at construction.

``ArgumentParser``, ``number`` and ``output_dir`` give the scripts one-line argument errors (exit
status 2).
"""
import argparse
import functools
import math
import os
import tempfile

from engines.files.inputs import ArgumentParser  # noqa: F401  (the scripts import it from here)
from engines.run import guard, history, manifest
from engines.run.talk import say
from engines.run.manifest import ENSEMBLE  # noqa: F401  (an ensemble's statistics, engines.run.ensemble; the scripts import it from here)


class InputError(ValueError):
    """Bad input found before a run: the message (one line) names the field and the limit."""


# -- arguments ------------------------------------------------------------------------------------
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
    """Raise InputError (naming ``arg``) if ``path`` holds another run's outputs or anything this
    project did not write (engines.run.manifest.check_fresh): a run writes into a new or empty
    folder, or replaces with --overwrite only what the project wrote."""
    try:
        manifest.check_fresh(path, arg, resumable)
    except ValueError as e:
        raise InputError(str(e)) from None


def check_resume(run_dir, duration):
    """A resume that can go on: writable, not held by another run, not complete unless a later
    --duration is given, its history.csv holding the rows its checkpoint recorded (engines.run.history)."""
    from engines.yade.checkpoint import NAME, read_info, resume_end
    check_output_dir(run_dir, "--resume")
    guard.check_free(run_dir)
    info = read_info(os.path.join(run_dir, NAME))
    try:
        resume_end(info["step"], info["n_steps"], info["dt"], duration)
    except ValueError as e:
        raise InputError(f"--resume {run_dir}: {e}") from None
    history.kept(run_dir, info)


def announce_output(path):
    """Print the folder a script writes into, before it writes: ``output: /absolute/path``."""
    say(f"output: {os.path.abspath(path)}")


def output_dir(path):
    """argparse type of an output directory: refused unless it can be written."""
    problem = output_problem(path)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return path


# -- the scene against its packing ----------------------------------------------------------------
def check_limits(prepared):
    """The dt of the Start ``prepared`` against every stability limit at the start (Start.check)."""
    try:
        prepared.check()
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
        remedy = ("raise [contact] f_max (the force cap cannot hold the packing where it rests) or redeposit the packing "
                  "with these constants" if "overlaps" in str(e) else "move the particle inside or the walls out")
        raise InputError(f"{e}; {remedy}") from None


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
        input_acceleration(scene.settings)
    except ValueError as e:
        raise InputError(str(e)) from None


# -- a sense of scale ------------------------------------------------------------------------------
COST_BENCHMARK = os.path.join("docs", "performance", "608e748", "bench-coupling.json")  # the newest measurement
CPU_LIMIT = 24 * 3600.0     # the estimated CPU [s] above which a run needs --force
OUTPUT_LIMIT = 10 * (1 << 30)  # the estimated output size [bytes] above which a run needs --force
VALUE_BYTES = 16            # a history value as written ("%.9g" and its comma)
SNAPSHOT_BYTES = 150        # a snapshot per body (positions, velocities, contacts, pores; compressed)
VTK_BYTES = 600             # a VTK frame per body (discs, forces, pores; ASCII XML)
CHECKPOINT_BYTES = 1500     # the checkpoint per body (YADE's scene and the run's state)


@functools.lru_cache(maxsize=None)
def cost_per_step(law):
    """(µs per body and step of the contact law alone, µs per body and water step) of ``law``
    ('paper' or 'yade'): the medians over the sizes of COST_BENCHMARK (its CPU µs per step, dry,
    and wet minus dry with a water step every step, divided by the bodies)."""
    import json
    import statistics

    from engines import ROOT
    with open(os.path.join(ROOT, COST_BENCHMARK)) as f:
        results = json.load(f)["results"]
    dry = [r["cpu_us"][f"{law}_law_dry_us"] / r["n_bodies"] for r in results]
    water = [(r["cpu_us"][f"{law}_law_wet_us"] - r["cpu_us"][f"{law}_law_dry_us"]) / r["n_bodies"] for r in results]
    return statistics.median(dry), statistics.median(water)


def estimate(scene, packing):
    """The run's estimated CPU [s] and output size [bytes], with the model's terms, as a dict.

    The cost model: CPU = steps x bodies x (c_law + c_water / water_interval) with c_law, c_water
    the µs per body and step of ``cost_per_step`` (water only for a wet scene), bodies = the
    packing's discs (walls included); outputs = history rows (steps / history_interval + 1, and the end's) x
    columns (t, the blocks, 13 measures, 6 wall loads) x VALUE_BYTES + snapshots x bodies x
    SNAPSHOT_BYTES (the scene's snapshots and the end's) + VTK frames x bodies x VTK_BYTES + bodies x CHECKPOINT_BYTES. The per-body sizes
    are those of the quick-sand and seismic runs, rounded up. A dt = "auto" is estimated as chosen."""
    if scene.numerics.dt == "auto":
        from engines.model.start import Start
        scene = timed(scene, Start(scene.settings, packing))
    num, out = scene.numerics, scene.output
    steps = int(round(num.duration / num.dt))
    bodies = len(packing.r)
    c_law, c_water = cost_per_step(scene.contact.law)
    wet = scene.water.enabled
    cpu = steps * bodies * (c_law + (c_water / num.water_interval if wet else 0.0)) * 1e-6
    rows = steps // out.history_interval + 1 + (steps % out.history_interval > 0)  # the end's row too
    columns = 1 + len(out.block_z) + 13 + 6
    snapshots = len({round(t / num.dt) for t in out.snapshot_times if t <= num.duration} | {steps})  # the end's too
    frames = (steps // out.vtk_interval + 1 if out.vtk_interval else snapshots) if out.vtk else 0
    size = (rows * columns * VALUE_BYTES + snapshots * bodies * SNAPSHOT_BYTES + frames * bodies * VTK_BYTES
            + bodies * CHECKPOINT_BYTES)
    return {"cpu_s": cpu, "bytes": size, "steps": steps, "bodies": bodies, "c_law": c_law,
            "c_water": c_water if wet else 0.0, "rows": rows, "columns": columns, "snapshots": snapshots, "frames": frames}


def _duration_text(seconds):
    return (f"{seconds:.3g} s" if seconds < 120 else f"{seconds / 60:.3g} min" if seconds < 7200 else
            f"{seconds / 3600:.3g} h")


def check_scale(scene, packing, force=False, starts=1):
    """The line that states the estimate of ``starts`` runs (``estimate``); raises InputError if
    it is above CPU_LIMIT or OUTPUT_LIMIT unless ``force``."""
    from engines.files.inputs import size_text
    e = estimate(scene, packing)
    cpu, size = starts * e["cpu_s"], starts * e["bytes"]
    runs = f"{starts} starts x " if starts > 1 else ""
    per = f"{e['c_law']:.3g} us, law {scene.contact.law}"
    if e["c_water"]:
        per = f"({per}, + {e['c_water']:.3g} us / water_interval {scene.numerics.water_interval})"
    line = (f"estimate: {_duration_text(cpu)} of CPU ({runs}{e['steps']} steps x {e['bodies']} bodies x {per}; "
            f"{COST_BENCHMARK}), outputs {size_text(size)} "
            f"({runs}{e['rows']} history rows x {e['columns']} columns, {e['snapshots']} snapshots, {e['frames']} VTK frames)")
    over = [f"{_duration_text(cpu)} of CPU is above {_duration_text(CPU_LIMIT)}" if cpu > CPU_LIMIT else "",
            f"{size_text(size)} of outputs is above {size_text(OUTPUT_LIMIT)}" if size > OUTPUT_LIMIT else ""]
    over = [o for o in over if o]
    if over and not force:
        raise InputError(f"{' and '.join(over)} (the estimate: {line.removeprefix('estimate: ')}): shorten "
                         f"[numerics] duration, raise [output] history_interval, or give --force to run it anyway")
    return line


def preflight(scene, packing, out_dir, prepared=None, force=False, scale=True):
    """Every check of a run that can be made before its first step; raises InputError.

    Returns notes (one line each) for the script to print: the estimate of its CPU time and
    outputs (``check_scale``; refused above the limits unless ``force``; ``scale`` False: not
    made, an ensemble makes it once for all its starts) and what the run will silently skip.
    ``prepared``: the run's Start of scene on packing (engines.model.start; made here if None);
    a dt = "auto" is checked as it will be chosen."""
    if prepared is None:
        from engines.model.start import Start
        prepared = Start(scene.settings, packing)
    scene = timed(scene, prepared)
    check_output_dir(out_dir)
    check_duration(scene)
    check_record(scene)
    check_packing(scene, packing)
    check_limits(prepared)
    notes = [check_scale(scene, packing, force)] if scale else []
    late = [t for t in scene.output.snapshot_times if t > scene.numerics.duration]
    if late:
        notes.append(f"note: [output] snapshot_times {', '.join(f'{t:g}' for t in late)} s lie after the end "
                     f"({scene.numerics.duration:g} s) and are skipped")
    return notes


# -- dt = "auto" ----------------------------------------------------------------------------------
def describe_auto_dt(dt, lims, name, n_sub, factor):
    """The lines a run prints about its automatic time step dt [s], chosen from the limits ``lims``
    {name: limit [s]} at the start, bound by ``name``, with n_sub water sub-steps at the start."""
    from engines.model import limits as lim
    from engines.studies.tradeoffs import validation_note
    shown = ", ".join(f"{k} {v:.3g} s" for k, v in lims.items())
    text = (f"dt = auto: {dt:.3g} s, bound by the {name} limit"
            + ("" if name == "darcy_check" else f" x dt_auto_factor {factor:g}") + f" (limits at the start: {shown})")
    text += "\n" + validation_note(factor)
    if n_sub > 1:
        text += (f"\nwater: {n_sub} sub-steps per water step at the start (substep = true, Gershgorin Darcy limit "
                 f"{lims['darcy_check']:.3g} s per DEM step); each costs about {lim.SUBSTEP_COST:.0%} of a water step, "
                 f"so the water costs about {lim.substep_cost(n_sub):.2g}x a water step without sub-steps")
    return text


def timed(scene, prepared):
    """``scene`` with the time step of its Start ``prepared``: itself for a numeric dt, for dt =
    "auto" a copy with the chosen dt ("auto" stays the recorded choice in ``overrides``)."""
    if prepared.auto is None:
        return scene
    out = scene.with_overrides({"numerics": {"dt": prepared.auto[0]}})
    out.overrides = scene.overrides
    return out


def announce_dt(prepared, log=print):
    """Print through ``log`` how the Start ``prepared`` chose dt = "auto" (nothing for a numeric dt)."""
    if prepared.auto is not None:
        dt, name, n_sub = prepared.auto
        log(describe_auto_dt(dt, prepared.limits, name, n_sub, prepared.given.numerics.dt_auto_factor))
