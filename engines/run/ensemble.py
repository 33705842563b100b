"""A scene script's ensemble: ``--starts N`` runs the scene from N perturbed starts through the
sweep runner (engines.run.sweep: local processes or a Dask cluster) and states every result
and history column across them (engines.studies.ensemble: mean, standard error, 95 % interval).

    yade -n -x yade_scripts/liquefaction.py --case 1 --starts 8 --out DIR [--perturbation M]
                                            [--jobs J | --scheduler tcp://HOST:PORT]
    yade -n -x yade_scripts/liquefaction.py --resume DIR [--duration S]

Start k is the script's own command line with ``--start k --perturbation M --out DIR/start_k``
(without the ensemble's options): a complete run in DIR/start_<k>/ (history, summary, checkpoint,
figures; the sweep runner's job.json and logs beside them), its packing ``perturbed`` with seed k
(start 0 is the scene's packing). Before anything is written every start is checked as a run is
(preflight of its perturbed packing; one line names the start). DIR/ensemble.json is written at
the start (the plan: seeds, perturbation, the starts' command line; "status": "running") and
when the starts have ended: "completed" with the statistics and the figures
(postproc.ensemble), or "incomplete" with each start's status. ``--resume DIR`` continues the
starts that did not complete from their checkpoints (with ``--duration`` every start, to a later
end) and starts those that never began, then writes the statistics again.
"""
import json
import os
import shutil
import time

from engines.run.preflight import ENSEMBLE, InputError, number, preflight
from engines.run.sweep import Job, run_sweep
from engines.studies.ensemble import CONFIDENCE, ensemble_statistics, perturbed

OWN_OPTIONS = ("--starts", "--perturbation", "--jobs", "--scheduler", "--out", "--overwrite")  # not passed to a start
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
    if (args.jobs is not None or args.scheduler) and args.starts is None and not ensemble_resume:
        ap.error(f"{'--jobs' if args.jobs is not None else '--scheduler'} needs --starts N (or --resume of an ensemble)")


def start_dir(out, k):
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


def check_starts(scene, packing, out, seeds, size):
    """Preflight of every start's perturbed packing (one line naming the start); the notes once."""
    notes = []
    for k in seeds:
        try:
            notes += [n for n in preflight(scene, perturbed(packing, k, size), start_dir(out, k)) if n not in notes]
        except InputError as e:
            raise InputError(f"start {k} (perturbed by {size:g} m): {e}") from None
    return notes


def _yade(script, argv):
    return ["yade", "-n", "-x", script, *argv]


def _job(k, argv):
    # YADE_BATCH emptied: a start does not read the table line of an ensemble run by yade-batch again
    return Job(f"start_{k}", argv, {"YADE_BATCH": ""})


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
    """The plan (PLAN) of the ensemble in ``out``."""
    with open(os.path.join(out, ENSEMBLE)) as f:
        doc = json.load(f)
    return {k: doc[k] for k in PLAN}


def start(ap, args, script, scene):
    """Write the plan and run the starts of a fresh ensemble (checked by the caller); returns the
    exit status."""
    out, size = args.out, size_of(args)
    seeds = list(range(args.starts))
    if args.overwrite:
        for name in os.listdir(out) if os.path.isdir(out) else []:
            if name.startswith("start_") and os.path.isdir(os.path.join(out, name)):
                shutil.rmtree(os.path.join(out, name))
    os.makedirs(out, exist_ok=True)
    plan = {"scene": scene.scene.name, "script": script, "n_starts": len(seeds), "seeds": seeds, "perturbation_m": size,
            "perturbation": PERTURBATION_TEXT, "start_argv": start_argv(ap, args.argv), "starts": [f"start_{k}" for k in seeds]}
    _write(out, {**plan, "status": "running"})
    return run_starts([_start_job(plan, k) for k in seeds], out, plan, args)


def resume_jobs(out, duration):
    """(the jobs that continue the ensemble in ``out``, its plan) (module docstring), to
    ``duration`` [s] if given (then also the plan's end); refuses (InputError) a start that
    cannot go on, before anything runs."""
    from engines.run.command_line import check_resume
    from engines.yade.checkpoint import NAME, OLD_NAME
    from postproc.run_files import read_summary
    plan = read_plan(out)
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
    run_sweep(jobs, out, workers=args.jobs or 2, scheduler=args.scheduler, resume=False)
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
    for path in figures.figures(out):
        print("figure:", path)
    print(f"done: {len(status)} starts perturbed by {plan['perturbation_m']:g} m, {len(doc['results'])} results and "
          f"{len(doc['history']['columns'])} history columns across them in {os.path.join(out, ENSEMBLE)}", flush=True)
    return 0
