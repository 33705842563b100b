"""Checks made before a run writes anything, and the scripts' argument parsing.

``preflight(scene, packing, out_dir)`` checks what can be known before the first step: the time
step against eq 52, against the side-wall ties (Fig. 27) and against the explicit Darcy limit of
the pores of the packing at the start, the duration, the loading record and the output directory.
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


def output_dir(path):
    """argparse type of an output directory: refused unless it can be written."""
    problem = output_problem(path)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return path


# -- the scene against its packing ----------------------------------------------------------------
def check_time_step(scene, packing):
    """dt <= dt_safety x 2 sqrt(m_min / kn) over the mobile discs (eq 52)."""
    from engines.model.contact import critical_time_step
    from engines.model.pore_dem import disc_masses

    num = scene.numerics
    mass, _ = disc_masses(scene, packing)
    mobile = mass[packing.mobile]
    if not len(mobile):
        return
    limit = num.dt_safety * critical_time_step(mobile, scene.contact.kn)
    if num.dt > limit:
        raise InputError(f"[numerics] dt = {num.dt:.3g} s exceeds the stability limit {limit:.3g} s of eq 52 "
                         f"(dt_safety {num.dt_safety:g} x 2 sqrt(m_min / kn), m_min = {mobile.min():.3g} kg/m, "
                         f"kn = {scene.contact.kn:.3g} N/m)")


def check_tie_time_step(scene, packing):
    """dt <= sqrt(m_min / k'_s) of the side-wall ties ([loading] side_walls = "springs")."""
    from engines.model import pore_dem

    try:
        pore_dem.check_tie_time_step(scene, pore_dem.side_wall_ties(scene, packing), pore_dem.disc_masses(scene, packing)[0])
    except ValueError as e:
        raise InputError(str(e)) from None


def start_darcy_limit(scene, packing):
    """The explicit Darcy limit [s] of the water at the start: the pores of the packing built
    as the engine builds them, W = A (U = 0). None for a dry scene."""
    if not scene.water.enabled:
        return None
    from engines.model.time_step import start_pores
    _, m, water = start_pores(scene, packing)
    return water.darcy_limit(m.void_area, m.link_contact)


def check_darcy(scene, packing):
    """The water step water_interval x dt against the explicit Darcy limit at the start: above it,
    refused without [water] substep (the engine would refuse it at step 0), and with it refused when
    it needs more than [water] max_substeps sub-steps."""
    if not scene.water.enabled:
        return
    num, w = scene.numerics, scene.water
    h = num.water_interval * num.dt
    limit = start_darcy_limit(scene, packing)
    where = f"the explicit Darcy limit {limit:.3g} s at the start (k1 = {w.k1:g}, k2 = {w.k2:g} 1/s, E_w = {w.E_w:g} N/m)"
    if not w.substep and h > limit:
        raise InputError(f"[numerics] dt = {num.dt:.3g} s: the water step water_interval x dt = {h:.3g} s exceeds "
                         f"{where}; reduce dt or the permeabilities, or set [water] substep = true")
    n_sub = math.ceil(h / limit * (1 - 1e-12))
    if w.substep and n_sub > w.max_substeps:
        raise InputError(f"[numerics] dt = {num.dt:.3g} s: the water step water_interval x dt = {h:.3g} s needs "
                         f"{n_sub} sub-steps at {where}, more than [water] max_substeps = {w.max_substeps}; "
                         f"reduce dt or the permeabilities, or raise max_substeps")


def check_water_stiffness(scene, packing):
    """dt <= 2 sqrt(m / k_w) of the stiffness the water adds to the particles at the start
    (engines.model.time_step: k_w = E_w sum_p (2 r)^2 / A_p over the pores a disc bounds)."""
    if not scene.water.enabled:
        return
    from engines.model import time_step
    from engines.model.pore_dem import disc_masses

    net, m, _ = time_step.start_pores(scene, packing)
    limit = time_step.water_stiffness_limit(net, m.void_area, packing.r, scene.water.E_w,
                                            disc_masses(scene, packing)[0], packing.mobile)
    dt = scene.numerics.dt
    if dt > limit:
        raise InputError(f"[numerics] dt = {dt:.3g} s exceeds the water-stiffness limit {limit:.3g} s at the start "
                         f"(2 sqrt(m / k_w), k_w = E_w sum (2 r)^2 / A over the pores a disc bounds, [water] E_w = "
                         f"{scene.water.E_w:g} N/m); reduce dt or E_w, or set dt = \"auto\"")


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
    check_time_step(scene, packing)
    check_tie_time_step(scene, packing)
    check_water_stiffness(scene, packing)
    check_darcy(scene, packing)
    late = [t for t in scene.output.snapshot_times if t > scene.numerics.duration]
    if late:
        return [f"note: [output] snapshot_times {', '.join(f'{t:g}' for t in late)} s lie after the end "
                f"({scene.numerics.duration:g} s) and are skipped"]
    return []
