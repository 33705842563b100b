"""The command line shared by the scene scripts (yade_scripts/quicksand.py, liquefaction.py), and
its yade-batch form.

A script adds its own choice of scene (e.g. --case, --scene) and then::

    add_run_arguments(ap, perturbation)           # --out --overwrite --duration --dt --set --vtk --force --resume
                                                  # --quiet --verbose (engines.run.talk)
                                                  # and the ensemble's --starts --perturbation --jobs
                                                  # --scheduler --start (engines.run.ensemble)
    args = parse_run_arguments(ap, argv)          # argv, or the yade-batch job's table line
    run_script(ap, args, load_scene)              # preflight, run or resume, exit status

Under yade-batch (the YADE_BATCH variable names table:line) the job's line is read by
engines.run.table (as data: never through YADE's readParamsFromTable, which evaluates every
value); each column becomes arguments: a column named like an option (``duration``, ``dt``,
``case``, ``vtk``: True/False) gives that option, a column ``TABLE.FIELD`` (e.g. ``water.k1``)
gives ``--set TABLE.FIELD=VALUE``. Values are Python literals (quote strings: 'my.toml'); an
expression such as ``pi/4`` is refused in one line. Without an ``out`` column each job
writes to the sweep runner's job directory (engines.run.sweep; SWEEP_JOB_DIR), else to
out/batch/<the job's description>, the name yade-batch gives its log.
"""
import argparse
import os
import re
import sys
import tomllib

from engines.files.inputs import check_name
from engines.run import ensemble, guard, history, manifest, talk
from engines.run.preflight import ENSEMBLE, announce_output, check_fresh_output, check_resume, number, output_dir, preflight
from engines.run.sweep import JOB_DIR, check_scheduler
from engines.run.table import BATCH, DESCRIPTION, batch_line
from engines.run.talk import say
from engines.studies.ensemble import perturbed
from engines.yade.checkpoint import CheckpointError

BATCH_OUT = os.path.join("out", "batch")


# -- arguments ------------------------------------------------------------------------------------
def scene_setting(text):
    """argparse type of ``--set TABLE.FIELD=VALUE``: (table, field, value); VALUE is read as TOML
    (numbers, true/false, [lists], "strings") or else taken as a string."""
    from engines.run.scene import SCHEMA
    m = re.fullmatch(r"(\w+)\.(\w+)=(.*)", text.strip())
    if not m:
        raise argparse.ArgumentTypeError(f"expected TABLE.FIELD=VALUE, got {text!r}")
    table, field, value = m.groups()
    if field not in SCHEMA.get(table, {}):
        raise argparse.ArgumentTypeError(f"{table}.{field} is not a scene field (see yade_scripts/scenes/README.md)")
    try:
        value = tomllib.loads(f"v = {value}")["v"]
    except tomllib.TOMLDecodeError:
        pass  # a bare string
    return table, field, value


def resume_dir(path):
    """argparse type of --resume: a run directory holding a checkpoint, or an ensemble's."""
    from engines.yade.checkpoint import NAME, CheckpointError, read_info
    if os.path.exists(os.path.join(path, ENSEMBLE)):
        return path
    try:
        read_info(os.path.join(path, NAME))
    except CheckpointError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return path


def add_run_arguments(ap, perturbation):
    """The options every scene script has (see the module docstring); ``perturbation`` [m]: the
    scene's default size of an ensemble's perturbation (engines.studies.ensemble)."""
    ap.add_argument("--out", type=output_dir, help=f"output directory (required; a table's job's default: the "
                                                   f"sweep runner's job directory, or {BATCH_OUT}/<job description>)")
    ap.add_argument("--overwrite", action="store_true",
                    help="replace the outputs of another run in --out (refused without it)")
    ap.add_argument("--duration", type=number(lo=0, lo_open=True, unit="s"),
                    help="simulated time [s] (default: the scene's; with --resume: a later end)")
    ap.add_argument("--dt", type=number(lo=0, lo_open=True, unit="s"), help="time step [s] (default: the scene's)")
    ap.add_argument("--set", type=scene_setting, action="append", default=[], metavar="TABLE.FIELD=VALUE",
                    help="change a scene field, e.g. --set water.k1=20 (repeatable)")
    ap.add_argument("--vtk", action="store_true", help="write a ParaView series to OUT/vtk/ ([output] vtk = true)")
    ap.add_argument("--force", action="store_true",
                    help="run although the estimate is above 24 h of CPU or 10 GB of outputs (refused without it)")
    ap.add_argument("--resume", type=resume_dir, metavar="DIR",
                    help="continue the interrupted (or crashed) run in DIR from its checkpoint, in place "
                         "(an ensemble's DIR: its starts that did not complete)")
    loud = ap.add_mutually_exclusive_group()
    loud.add_argument("--quiet", action="store_true", help="print only errors and the end (results and figures)")
    loud.add_argument("--verbose", action="store_true",
                      help="print also where the compiled kernels are cached and the run's provenance")
    ensemble.add_arguments(ap, perturbation)


def parse_run_arguments(ap, argv):
    """The parsed arguments of ``job_argv(ap, argv)``; ``args.argv`` keeps them as given (an
    ensemble passes them on to its starts)."""
    argv = job_argv(ap, argv)
    args = ap.parse_args(argv)
    args.argv = list(argv)
    talk.set_level(args.quiet, args.verbose)
    return args


def overrides_of(args):
    """The command line's changes to the scene, {table: {field: value}} (recorded in summary.json)."""
    over = {}
    for table, field, value in args.set:
        over.setdefault(table, {})[field] = value
    for name in ("dt", "duration"):  # the run options, where the script has them
        if getattr(args, name, None) is not None:
            over.setdefault("numerics", {})[name] = getattr(args, name)
    if getattr(args, "vtk", False):
        over.setdefault("output", {})["vtk"] = True
    return over or None


# -- yade-batch -----------------------------------------------------------------------------------
def sweep_job_dir(path):
    """Is ``path`` the job directory the sweep runner gave this job? The runner re-runs only jobs
    that did not finish, so their outputs there are replaced without --overwrite."""
    job = os.environ.get(JOB_DIR)
    return bool(job) and os.path.abspath(job) == os.path.abspath(path)


def batch_out(root, description):
    """The output directory of a table's job without an ``out`` column: the sweep runner's job
    directory, or under yade-batch ROOT/DESCRIPTION (path separators made _; refused, ValueError,
    if it starts with a dot or holds "..": give the line a description column)."""
    if os.environ.get(JOB_DIR):
        return os.environ[JOB_DIR]
    name = description.replace(os.sep, "_").replace("\\", "_")
    check_name(name, f"yade-batch table {os.environ.get(BATCH, '')}: the job's description")
    return os.path.join(root, name)


def _as_argument(value):
    """A table value (a Python object) as the text the options read (TOML for --set)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(value)


def job_argv(ap, argv):
    """``argv``, or under yade-batch the job's table line as arguments (module docstring) before
    argv; a table that cannot be read, or a column that is no option, is refused in one line."""
    try:
        job = batch_line()
    except ValueError as e:
        ap.error(str(e))
    if job is None:
        return argv
    table, line, values = job
    options = ap._option_string_actions
    args = []
    for name, value in values.items():
        opt = "--" + name.replace("_", "-")
        if name == DESCRIPTION:
            continue
        if "." in name:
            args += ["--set", f"{name}={_as_argument(value)}"]
        elif opt in options and options[opt].nargs == 0:
            args += [opt] if value else []
        elif opt in options:
            args += [opt, value if isinstance(value, str) else _as_argument(value)]
        else:
            ap.error(f"yade-batch table {table}, line {line}: column {name!r} is neither an option of this script "
                     f"nor a scene field TABLE.FIELD")
    if "out" not in values and "resume" not in values:
        try:
            args += ["--out", batch_out(BATCH_OUT, values[DESCRIPTION])]
        except ValueError as e:
            ap.error(str(e))
    return args + list(argv)


# -- running --------------------------------------------------------------------------------------
def run_script(ap, args, load_scene, scene_given=False, check=None, figures=None):
    """Check, then run or resume, printing one line at the end; exits non-zero on refused input
    (one line, nothing written), on a folder another run holds (engines.run.guard: one line naming
    its host and pid) and on a failed write (one line naming the path), and with 128 + the
    signal's number after an interrupt. The folder's lock is held from the end of the checks to
    the end. With --starts, or --resume of an ensemble's folder, runs the ensemble
    (engines.run.ensemble), holding the ensemble's folder; each start holds its own.

    ``load_scene(overrides)`` -> Scene; ``scene_given``: the script's own scene options were used
    (they conflict with --resume); ``check(scene)``: the script's own refusals (raise ValueError);
    ``figures(out_dir)``: the script's own figures of a completed run (paths returned)."""
    ensemble.check_options(ap, args)
    _check_resume_options(ap, args, scene_given)
    many = args.starts is not None or bool(args.resume) and ensemble.is_ensemble(args.resume)
    out = args.resume or args.out
    try:  # bad scenes, packings, limits, a folder in use: one clear line, nothing written
        ready = _checked(ap, args, load_scene, check, many)
    except ValueError as e:
        sys.exit(f"error: {e}")
    try:
        with guard.hold(out):
            announce_output(out)
            summary = _run(ap, args, many, ready)
    except (OSError, guard.FolderLocked, history.HistoryMismatch, CheckpointError) as e:
        sys.exit(f"error: {e}")  # a full disk (WriteError), a folder taken meanwhile, a history not this run's
    if summary["status"] == "interrupted":
        _exit_interrupted(summary, out)
    from engines.run import runner
    drawn = list(summary.get("figures", []))
    if figures is not None:
        drawn += figures(out)
        manifest.claim(out, [os.path.basename(path) for path in drawn])
    print(runner.done_line(summary, drawn), flush=True)


def _check_resume_options(ap, args, scene_given):
    """--resume with an option that sets a run up (or the script's scene options), or neither
    --resume nor --out: the parser's one-line error."""
    if args.resume:
        setup = ("out", "overwrite", "dt", "set", "vtk", "force", "starts", "start", "perturbation")
        given = [f"--{k}" for k in setup if getattr(args, k) != ap.get_default(k)] + (["the scene"] if scene_given else [])
        if given:
            ap.error(f"--resume continues the run as it was set up: {', '.join(given)} cannot be given with it")
    elif not args.out:
        ap.error("--out is required (or --resume DIR)")


def _checked(ap, args, load_scene, check, many):
    """The checks before anything is written (run_script); raises ValueError (one line). Returns
    what the run goes on with: {jobs, plan} of an ensemble's resume, else {scene, packing, prepared}
    (the scene and packing only, for an ensemble's start)."""
    guard.check_free(args.resume or args.out)
    if args.resume and many:
        jobs, plan = ensemble.resume_jobs(ap, args.resume, args.duration, os.path.abspath(sys.argv[0]))
        if args.scheduler:
            check_scheduler(args.scheduler)
        return {"jobs": jobs, "plan": plan}
    if args.resume:
        check_resume(args.resume, args.duration)
        return {}
    if not (args.overwrite or sweep_job_dir(args.out)):
        check_fresh_output(args.out, resumable=True)
    sc = load_scene(overrides_of(args))
    if check is not None:
        check(sc)
    from engines.model.start import Start
    from engines.yade.deposition import scene_packing
    packing = scene_packing(sc)
    say_compile()  # the checks below build the pores: the first compiled kernels
    if many and args.scheduler:
        check_scheduler(args.scheduler)
    prepared = None
    if many:
        notes = ensemble.check_starts(sc, packing, args.out, range(args.starts), ensemble.size_of(args), args.force)
    else:
        if args.start is not None:
            packing = perturbed(packing, args.start, ensemble.size_of(args))
        prepared = Start(sc.settings, packing)  # the one start: preflight checks what the run runs on
        notes = preflight(sc, packing, args.out, prepared, args.force)
    for note in notes:
        say(note)
    return {"scene": sc, "packing": packing, "prepared": prepared}


def _run(ap, args, many, ready):
    """Run, resume or run the ensemble (``ready``: what ``_checked`` returned); returns the run's
    summary (an ensemble exits with its status)."""
    if many and args.resume:
        sys.exit(ensemble.run_starts(ready["jobs"], args.resume, ready["plan"], args))
    if many:
        sys.exit(ensemble.start(ap, args, os.path.abspath(sys.argv[0]), ready["scene"]))
    from engines.run import runner
    if args.resume:
        say_compile()
        return runner.resume_run(args.resume, args.duration)
    start = None if args.start is None else {"seed": args.start, "perturbation_m": ensemble.size_of(args)}
    return runner.run_scene(ready["scene"], ready["packing"], args.out, start=start, prepared=ready["prepared"])


def _exit_interrupted(summary, out):
    """Say where an interrupted run's files are and how to continue it, then end the process with
    128 + the signal's number."""
    import signal
    stop = summary.get("interrupt", {})
    print(f"interrupted{' by ' + stop['signal'] if stop else ''} at step {summary['steps']} "
          f"(t = {summary['t_end']:.6g} s): history, checkpoint and summary are in {out}; continue with\n"
          f"    yade -n -x {sys.argv[0]} --resume {out}", flush=True)
    sys.stdout.flush()
    sys.stderr.flush()
    # everything is written and closed: skip the interpreter's and YADE's teardown (about 1 s
    # on a busy 2-core machine), so that the process ends within a fraction of a second
    guard.release_all()
    os._exit(128 + (signal.Signals[stop["signal"]].value if stop else signal.SIGINT.value))


def say_compile():
    """Say (once per process) that the kernels are compiled now when numba's keyed cache folder
    held none (engines.compiled.cache.compile_note); with --verbose, the folder and the provenance."""
    from engines.compiled import cache
    from engines.run.provenance import provenance
    if not getattr(say_compile, "done", False):
        say_compile.done = True
        say(f"numba kernels: {os.environ.get('NUMBA_CACHE_DIR')}; provenance: {provenance()}", talk.VERBOSE)
        if cache.compile_note():
            say(cache.compile_note())
