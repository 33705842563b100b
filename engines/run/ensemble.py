"""A scene script's ensemble: ``--starts N`` runs the scene from N perturbed starts through the
sweep runner (engines.run.sweep: local processes or a Dask cluster) and states every result
and history column across them (engines.studies.ensemble: mean, standard error, 95 % interval).

    yade -n -x yade_scripts/liquefaction.py --case 1 --starts 8 --out DIR [--perturbation M]
                                            [--jobs J | --scheduler tcp://HOST:PORT | --scheduler-file PATH]
    yade -n -x yade_scripts/liquefaction.py --resume DIR [--duration S]

Start k is the script's own command line with ``--start k --perturbation M --out DIR/start_k``
(without the ensemble's options): a complete run in DIR/start_<k>/ (history, summary, checkpoint,
figures; the sweep runner's job.json and logs beside them), its packing ``perturbed`` with seed k
(start 0 is the scene's packing). Before anything is written every start is checked as a run is
(preflight of its perturbed packing; one line names the start; beyond 64 starts a seeded sample of
64, and the output says so) and the estimate of all of them is stated (refused above 24 h of CPU
or 10 GB without --force). DIR/ensemble.json is written at
the start (the plan: seeds, perturbation, the starts' command line; "status": "running") and
when the starts have ended: "completed" with the statistics and the figures
(postproc.ensemble), or "incomplete" with each start's status. ``--resume DIR`` continues the
starts that did not complete from their checkpoints (with ``--duration`` every start, to a later
end) and starts those that never began, then writes the statistics again. What runs is never
taken from ensemble.json: the starts run the script the resume was started with (refused unless
it has the name of the one that made the ensemble), the plan is refused unless it is one this
project writes (integer seeds, start folders start_<seed> inside DIR, start_argv made of the
script's own options without --out, --resume or the ensemble's).
"""
import json
import os
import re
import time

from engines.run import manifest
from engines.run.preflight import ENSEMBLE, InputError, check_resume, check_scale, number, preflight
from engines.run.sweep import YADE, Job, run_sweep, yade_environment
from engines.run.talk import interval_lines, say
from engines.studies.ensemble import CONFIDENCE, ensemble_statistics, perturbed

OWN_OPTIONS = ("--starts", "--perturbation", "--jobs", "--scheduler", "--scheduler-file", "--out", "--overwrite")  # not passed to a start
PLAN = ("scene", "script", "n_starts", "seeds", "perturbation_m", "perturbation", "start_argv", "starts")  # ensemble.json's plan
PERTURBATION_TEXT = ("start k moves every particle (not the walls) by perturbation_m x N(0, 1) in x and z, "
                     "numpy Generator(k); start 0 is the scene's packing")
INTERVAL_TEXT = (f"{100 * CONFIDENCE:g} % interval: mean -+ t({0.5 + CONFIDENCE / 2:g}, n - 1) standard_error, "
                 "standard_error = std (ddof 1) / sqrt(n), over the n starts with a value (NaN and null left out)")


def add_arguments(ap, perturbation):
    """The ensemble's options (module docstring); ``perturbation`` [m]: the scene's default size."""
    g = ap.add_argument_group("ensembles (docs/SWEEPS.md)")
    g.add_argument("--starts", type=number(int, lo=2), metavar="N",
                   help="run the scene from N perturbed starts, each in OUT/start_<k>/, and write OUT/ensemble.json")
    g.add_argument("--perturbation", type=number(lo=0, lo_open=True, unit="m"), metavar="SIZE",
                   help=f"size of the starts' perturbation [m] (default {perturbation:g}: this scene's)")
    where = g.add_mutually_exclusive_group()
    where.add_argument("--jobs", type=number(int, lo=1), metavar="J", help="starts run at a time on this machine (default 2)")
    where.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="run the starts on this Dask cluster's workers")
    where.add_argument("--scheduler-file", metavar="PATH",
                       help="run the starts on the workers of the Dask scheduler that wrote PATH (docs/SWEEPS.md)")
    g.add_argument("--start", type=number(int, lo=0), metavar="K",
                   help="run start K of an ensemble alone (what --starts runs in OUT/start_K)")
    ap.set_defaults(scene_perturbation=perturbation)


def is_ensemble(path):
    return os.path.exists(os.path.join(path, ENSEMBLE))


def size_of(args):
    """The perturbation [m] the options give."""
    return args.scene_perturbation if args.perturbation is None else args.perturbation


def check_options(ap, args):
    """Refuse (one line) ensemble options that do not go together."""
    ensemble_resume = bool(args.resume) and is_ensemble(args.resume)
    if args.starts is not None and args.start is not None:
        ap.error("--start K runs one start of an ensemble: it cannot be given with --starts")
    if args.perturbation is not None and args.starts is None and args.start is None:
        ap.error("--perturbation needs --starts N (or --start K)")
    where = [o for o, v in (("--jobs", args.jobs), ("--scheduler", args.scheduler), ("--scheduler-file", args.scheduler_file))
             if v is not None]
    if where and args.starts is None and not ensemble_resume:
        ap.error(f"{where[0]} needs --starts N (or --resume of an ensemble)")


def start_dir(out, k):
    """The folder of start ``k`` (an integer >= 0: a crafted ensemble.json cannot name another)."""
    if isinstance(k, bool) or not isinstance(k, int) or k < 0:
        raise InputError(f"{os.path.join(out, ENSEMBLE)}: start {k!r} is not a start number (an integer >= 0)")
    return os.path.join(out, f"start_{k}")


def start_argv(ap, argv):
    """``argv`` without the ensemble's own options (OWN_OPTIONS, abbreviated or --opt=value too)."""
    actions = ap._option_string_actions
    own = {actions[o] for o in OWN_OPTIONS if o in actions}
    out, i = [], 0
    while i < len(argv):
        word = str(argv[i])
        name = word.split("=", 1)[0]
        matches = [a for o, a in actions.items() if o == name] or \
                  [a for o, a in actions.items() if name.startswith("--") and o.startswith(name)]
        action = matches[0] if len(set(matches)) == 1 else None
        takes = 0 if action is None or action.nargs == 0 or "=" in word else 1
        if action not in own:
            out += argv[i:i + 1 + takes]
        i += 1 + takes
    return [str(a) for a in out]


CHECKED_STARTS = 64  # starts checked before an ensemble runs; beyond, a seeded sample of this many


def checked_seeds(seeds):
    """The starts ``check_starts`` checks: all of ``seeds`` up to CHECKED_STARTS, else a sample of
    that many drawn by numpy Generator(0), start 0 always among them (sorted)."""
    seeds = list(seeds)
    if len(seeds) <= CHECKED_STARTS:
        return seeds
    import numpy as np
    rest = np.random.default_rng(0).choice(len(seeds) - 1, CHECKED_STARTS - 1, replace=False) + 1
    return [seeds[0]] + [seeds[i] for i in sorted(rest)]


def check_starts(scene, packing, out, seeds, size, force=False):
    """Preflight of the starts' perturbed packings (``checked_seeds``; one line names a refused
    start), the estimate of all of them once (preflight.check_scale), the notes once."""
    seeds = list(seeds)
    notes = [check_scale(scene, packing, force, starts=len(seeds))]
    checked = checked_seeds(seeds)
    if len(checked) < len(seeds):
        notes.append(f"note: checked {len(checked)} of the {len(seeds)} starts before the run (a sample drawn by numpy "
                     f"Generator(0), start 0 among them); each start is checked again as it begins")
    for k in checked:
        try:
            notes += [n for n in preflight(scene, perturbed(packing, k, size), start_dir(out, k), scale=False)
                      if n not in notes]
        except InputError as e:
            raise InputError(f"start {k} (perturbed by {size:g} m): {e}") from None
    return notes


def _yade(script, argv):
    return [*YADE, "-x", script, *argv]


def _job(k, argv):
    # YADE_BATCH emptied: a start does not read the table line of an ensemble run by yade-batch again
    return Job(f"start_{k}", argv, {"YADE_BATCH": "", **yade_environment()})


def _start_job(plan, k):
    """The job of start k from its beginning."""
    return _job(k, _yade(plan["script"], plan["start_argv"] + ["--start", str(k), "--perturbation",
                                                                repr(plan["perturbation_m"]), "--out", "{out}"]))


def _write(out, doc):
    tmp = os.path.join(out, ENSEMBLE + ".tmp")
    with open(tmp, "w") as f:
        json.dump(_plain(doc), f, indent=1)
    os.replace(tmp, os.path.join(out, ENSEMBLE))


def _plain(x):
    """JSON without NaN: non-finite numbers as null."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, float) and not (x == x and abs(x) != float("inf")):
        return None
    return x


def read_plan(out):
    """The plan (PLAN) of the ensemble in ``out``, checked to be one this project wrote (its
    starts are start_<k> folders of ``out``); refuses (InputError, one line) anything else."""
    path = os.path.join(out, ENSEMBLE)
    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, ValueError, RecursionError) as e:
        raise InputError(f"{path}: cannot be read as JSON ({e})") from None
    problem = _plan_problem(doc)
    if problem:
        raise InputError(f"{path}: {problem}: not an ensemble plan this project wrote; start the ensemble again "
                         f"with --starts N --out NEW_DIR")
    return {k: doc[k] for k in PLAN}


def _plan_problem(doc):
    """What is wrong with an ensemble.json's plan, or None."""
    if not isinstance(doc, dict):
        return "not a JSON object"
    missing = [k for k in PLAN if k not in doc]
    if missing:
        return f"no {', '.join(missing)}"
    seeds = doc["seeds"]
    if not (isinstance(seeds, list) and seeds and all(type(k) is int and k >= 0 for k in seeds)
            and len(set(seeds)) == len(seeds)):
        return "seeds must be a list of distinct integers >= 0"
    if doc["n_starts"] != len(seeds) or doc["starts"] != [f"start_{k}" for k in seeds]:
        return "n_starts and starts do not match the seeds (starts are the folders start_<seed>)"
    size = doc["perturbation_m"]
    if not (type(size) in (int, float) and 0 < size < float("inf")):
        return "perturbation_m must be a number > 0 [m]"
    if not isinstance(doc["script"], str) or not isinstance(doc["start_argv"], list) \
            or not all(isinstance(a, str) for a in doc["start_argv"]):
        return "script must be a name and start_argv a list of strings"
    return None


def _argv_problem(ap, argv):
    """What in a plan's ``start_argv`` is not the script's own options, less the ensemble's and
    the run folder's (the starts get those from the ensemble), or None."""
    actions = ap._option_string_actions
    set_here = set(OWN_OPTIONS + ("--resume", "--start"))
    for word in argv:
        if not word.startswith("-") or re.fullmatch(r"-[0-9.][0-9.eE+-]*", word):
            continue
        name = word.split("=", 1)[0]
        found = {a for o, a in actions.items() if o == name} or \
                {a for o, a in actions.items() if name.startswith("--") and o.startswith(name)}
        if len(found) != 1:
            return f"start_argv holds {word!r}, which is not an option of this script"
        if set_here & set(found.pop().option_strings):
            return f"start_argv holds {word!r}, which the ensemble gives each start itself"
    return None


def start(ap, args, script, scene):
    """Write the plan and run the starts of a fresh ensemble (checked by the caller); returns the
    exit status."""
    out, size = args.out, size_of(args)
    seeds = list(range(args.starts))
    if args.overwrite:  # the earlier ensemble's files and the start folders its ensemble.json lists
        manifest.clear(out)
    os.makedirs(out, exist_ok=True)
    plan = {"scene": scene.scene.name, "script": script, "n_starts": len(seeds), "seeds": seeds, "perturbation_m": size,
            "perturbation": PERTURBATION_TEXT, "start_argv": start_argv(ap, args.argv), "starts": [f"start_{k}" for k in seeds]}
    _write(out, {**plan, "status": "running"})
    return run_starts([_start_job(plan, k) for k in seeds], out, plan, args)


def resume_jobs(ap, out, duration, script):
    """(the jobs that continue the ensemble in ``out``, its plan) (module docstring), to
    ``duration`` [s] if given (then also the plan's end); refuses (InputError) a start that
    cannot go on, before anything runs. The jobs run ``script``, the scene script this resume was
    started with (the plan's script is only compared with it by name, never run), with the
    plan's start_argv only when they are the options of ``ap``, the script's parser."""
    from engines.yade.checkpoint import NAME, OLD_NAME
    from postproc.run_files import read_summary
    plan = read_plan(out)
    made_by = os.path.basename(plan["script"])
    if made_by != os.path.basename(script):
        raise InputError(f"--resume {out}: this ensemble was run by {made_by!r} ({ENSEMBLE}); resume it with that "
                         f"script, not {os.path.basename(script)}")
    problem = _argv_problem(ap, plan["start_argv"])
    if problem:
        raise InputError(f"{os.path.join(out, ENSEMBLE)}: {problem}; start the ensemble again with --starts N "
                         f"--out NEW_DIR")
    plan = {**plan, "script": script}
    jobs = []
    for k in plan["seeds"]:
        d = start_dir(out, k)
        if any(os.path.exists(os.path.join(d, name)) for name in (NAME, OLD_NAME)):  # an older one: refused by name
            if read_summary(d).get("status") == "completed" and duration is None:
                continue
            check_resume(d, duration)
            extra = [] if duration is None else ["--duration", repr(duration)]
            jobs.append(_job(k, _yade(plan["script"], ["--resume", "{out}", *extra])))
        elif duration is not None:
            raise InputError(f"--resume {out} --duration: start {k} never began; resume without --duration first")
        else:
            jobs.append(_start_job(plan, k))
    if duration is not None:  # a start begun later runs to the new end (the last --duration counts)
        plan = {**plan, "start_argv": plan["start_argv"] + ["--duration", repr(duration)]}
    return jobs, plan


def run_starts(jobs, out, plan, args):
    """Run the starts' jobs, then write ensemble.json (and the figures) from the start folders."""
    from postproc import ensemble as figures
    from postproc.run_files import read_history, read_summary
    t0 = time.time()
    try:
        run_sweep(jobs, out, workers=args.jobs or 2, scheduler=args.scheduler, resume=False,
                  scheduler_file=args.scheduler_file, log=say)  # --quiet: the starts' lines left out
    except (OSError, TimeoutError) as e:
        if not (args.scheduler or args.scheduler_file):
            raise
        where = f"--scheduler {args.scheduler}" if args.scheduler else f"--scheduler-file {args.scheduler_file}"
        _write(out, {**plan, "status": "failed", "error": f"{where}: {type(e).__name__}: {e}"})
        print(f"error: {where}: the cluster could not be reached or was lost ({type(e).__name__}: "
              f"{e}); {os.path.join(out, ENSEMBLE)} says \"failed\"; continue with yade -n -x {plan['script']} "
              f"--resume {out}", flush=True)
        return 1
    summaries = {k: read_summary(start_dir(out, k)) for k in plan["seeds"]}
    status = {k: s.get("status", "not started") for k, s in summaries.items()}
    doc = {**plan, "status": "completed", "start_status": {f"start_{k}": v for k, v in status.items()},
           "wall_seconds_last_sweep": time.time() - t0}
    bad = [k for k, v in status.items() if v != "completed"]
    if bad:
        doc["status"] = "incomplete"
        _write(out, doc)
        print(f"error: {len(bad)} of {len(status)} starts did not complete (" +
              ", ".join(f"start_{k}: {status[k]}" for k in bad) + f"; logs in {out}/start_<k>/stderr.log); "
              f"continue with yade -n -x {plan['script']} --resume {out}", flush=True)
        return 1
    histories = [read_history(os.path.join(start_dir(out, k), "history.csv")) for k in plan["seeds"]]
    doc.update(interval=INTERVAL_TEXT, **ensemble_statistics(histories, [summaries[k]["results"] for k in plan["seeds"]]),
               cpu_seconds_per_start=[summaries[k]["cpu_seconds"] for k in plan["seeds"]])
    _write(out, doc)
    drawn = figures.figures(out)
    print("\n".join([f"done: {len(status)} starts perturbed by {plan['perturbation_m']:g} m, {len(doc['results'])} "
                     f"results and {len(doc['history']['columns'])} history columns across them in "
                     f"{os.path.join(out, ENSEMBLE)}; the means:"]
                    + ["  " + line for line in interval_lines(doc["results"])]
                    + [f"  figure {path}" for path in drawn]), flush=True)
    return 0
