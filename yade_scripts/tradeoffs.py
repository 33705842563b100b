"""Speed against accuracy: each numerical knob swept, error against a fine reference.

    make tradeoffs                                   # the study -> out/tradeoffs/ (resumable)
    /usr/bin/python3 yade_scripts/tradeoffs.py study --out out/tradeoffs [--workers 1] [--scheduler ADDR]
    /usr/bin/python3 yade_scripts/tradeoffs.py study --out out/tradeoffs --analyse-only
    /usr/bin/python3 yade_scripts/tradeoffs.py study --out out/tradeoffs --cases liquefaction_case1 \\
         --knobs reference dt defaults perturbation          # the judged rows only
    yade -n -j 1 -x yade_scripts/tradeoffs.py run --case liquefaction_case1 --window 0.04 \\
         --set numerics.dt=2e-5 --set numerics.rebuild_interval=50 --out out/one   # one setting
    yade -n -j 1 -x yade_scripts/tradeoffs.py speed --points dt=1e-06 defaults=fast --repeats 3 --out out/speed

``run`` (inside YADE) runs one setting of a preset from ``--starts`` perturbed starts
(engines.studies.tradeoffs.perturbed: start s moves the particles by ``--perturbation`` (default 1e-9 m;
the study gives the seismic case 1e-7 m, CASES) x N(0, 1), seed s; start 0 is the preset's packing)
for ``--window`` seconds and writes OUT/result.json: per start the block pressure, window porosity,
particles' mean height and kinetic energy every ``--record`` seconds, the CPU and wall seconds of
the run (after a warm-up that loads the compiled kernels), the water balance and sub-steps. The
cost leaves out the recording's own time (cpu_record_s). A start refused by preflight or by the
engines is recorded with its message.

``speed`` (inside YADE) measures speed-ups in one process: the settings interleaved, one start
each per repeat, the median CPU ratio to the first (the paper's settings).

``study`` builds the jobs of KNOBS (one per case, knob and value), runs them with the sweep runner
(yade_scripts/sweep.py: resumable, local processes or a Dask scheduler), then computes the
errors (engines.studies.tradeoffs) against each case's reference and writes out/tradeoffs/tradeoffs.json,
table.md and the error-against-cost figures (docs/TRADEOFFS.md explains them).
"""
import json
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from engines import ROOT

RECORD = 5e-4      # s between samples of the histories (a multiple of every dt below)
REBUILD_PERIOD = 1e-3  # s between pore rebuilds in the dt sweep: the paper's 1000 steps of 1e-6 s
STARTS = 5         # perturbed starts per setting, unless the case's "starts" says more for a knob
REFERENCE_DT = 5e-7
PERTURBATION = 1e-9  # m: the size of the perturbation of the starts (engines.studies.tradeoffs.perturbed)
PAPER_DT = 1e-6

# Per case: the window [s], the base dt the other knobs are swept around (rebuilds every 1 ms) and
# the values of each knob; "preset" (default: the key) and "reference_dt" (default REFERENCE_DT)
# where they differ; "starts": {knob: starts} where a knob needs more than STARTS (the chaos floor
# falls as 1/sqrt(starts)); "perturbation_size": the size of the perturbation of the starts [m] (default
# PERTURBATION), large enough that the ensemble means no longer depend on it (the knob
# "perturbation" checks that; docs/TRADEOFFS.md). "defaults" are the named settings chosen from the study.
CASES = {
    "liquefaction_case1": {"window": 0.04, "fast_dt": 2e-5, "perturbation_size": 1e-7,
                           "starts": {"reference": 20, "dt": 20, "defaults": 20, "candidate": 20, "perturbation": 20},
                           "dt": [1e-6, 5e-6, 1e-5, 2e-5, 5e-5, 1e-4],
                           # the ensemble's convergence in the size of the perturbation (at fast_dt)
                           "perturbation": [1e-9, 1e-8, 3e-7],
                           "water_interval": [2, 5, 10], "rebuild_period": [2e-4, 5e-4, 2e-3, 5e-3],
                           "smoothing": [True], "transfer": ["conserving"], "E_w_scale": [0.1, 10.0, 100.0],
                           "precision": ["longdouble"],
                           "defaults": [{"name": "fast", "numerics.dt": "auto",  # at the schema's dt_auto_factor
                                         "numerics.rebuild_interval": 50, "numerics.water_interval": 1},
                                        {"name": "accurate", "numerics.dt": 1e-6, "numerics.rebuild_interval": 1000,
                                         "numerics.water_interval": 1}],
                           # settings tried for the fast setting around the largest dt still within 5 % (2e-5 s at
                           # 1e-7 m starts; 5e-5 s is at 5 %): dt_auto_factor x eq 52 (1.108e-4 s), rebuilds every
                           # ~1 ms, the water every M steps; f0.45_M2_rb20 is the earlier fast setting
                           "candidate": [{"name": f"f{f:g}_M{m}_rb{rb}", "numerics.dt": "auto",
                                          "numerics.dt_auto_factor": f, "numerics.rebuild_interval": rb,
                                          "numerics.water_interval": m}
                                         for f, m, rb in ((0.27, 1, 33), (0.27, 2, 33), (0.36, 1, 25), (0.36, 2, 25),
                                                          (0.45, 1, 20), (0.45, 2, 20), (0.36, 1, 50))]},
    "quicksand_case1": {"window": 0.03, "fast_dt": 1e-5,
                        "dt": [1e-6, 5e-6, 1e-5, 2e-5, 2.5e-5],
                        "water_interval": [2, 5, 10, 20], "rebuild_period": [2.5e-4, 5e-4, 2e-3, 5e-3],
                        "smoothing": [True], "transfer": ["conserving"], "E_w_scale": [10.0, 100.0]},
    # the fast setting over the whole 0.18 s against the paper's settings as the reference
    "liquefaction_case1_full": {"preset": "liquefaction_case1", "window": 0.18, "reference_dt": PAPER_DT, "perturbation_size": 1e-7,
                                "fast_dt": 2e-5, "defaults": []},
    "liquefaction_case4": {"window": 0.02, "fast_dt": 2e-5, "dt": [1e-6, 2e-5], "law": ["yade"]},
}
CASES["liquefaction_case1_full"]["defaults"] = CASES["liquefaction_case1"]["defaults"][:1]


def dt_settings(dt):
    """dt [s] with the pores rebuilt every REBUILD_PERIOD (so that the dt sweep does not also
    change the rebuild period), water every step."""
    return {"numerics.dt": dt, "numerics.rebuild_interval": max(1, int(round(REBUILD_PERIOD / dt))),
            "numerics.water_interval": 1}


def settings_of(case, knob, value):
    """(overrides, yade program) of one point of the study."""
    spec = CASES[case]
    base = dt_settings(spec["fast_dt"])
    if knob == "reference":
        return dt_settings(spec.get("reference_dt", REFERENCE_DT)), "yade"
    if knob == "dt":
        return dt_settings(value), "yade"
    if knob == "perturbation":  # the base settings; the size goes to the job's --perturbation
        return base, "yade"
    if knob == "water_interval":
        return {**base, "numerics.water_interval": value}, "yade"
    if knob == "rebuild_period":
        return {**base, "numerics.rebuild_interval": int(round(value / spec["fast_dt"]))}, "yade"
    if knob in ("smoothing", "transfer"):
        return {**base, f"water.{knob}": value}, "yade"
    if knob == "E_w_scale":
        from engines.run import scene as scenes
        E_w = scenes.preset(case).water.E_w * value
        return {**base, "water.E_w": E_w, "water.substep": True}, "yade"
    if knob == "law":
        return {**base, "contact.law": value}, "yade"
    if knob == "precision":
        return base, f"yade-{value}"
    if knob in ("defaults", "candidate"):  # a named setting chosen from the study, or tried for it
        return {k: v for k, v in value.items() if k != "name"}, "yade"
    raise ValueError(f"unknown knob {knob!r}")


PRIORITY = (("reference", "dt", "defaults", "perturbation", "candidate", "water_interval", "rebuild_period"),
            ("smoothing", "transfer", "E_w_scale", "precision", "law"))
LAST = ("liquefaction_case1_full", "liquefaction_case4")  # run after every knob of the other cases


def points(cases=None):
    """[(case, knob, value)] of the study in the order it runs: the references, dt (with the paper's
    settings), water_interval and rebuild_period of every case, then the other knobs, case by case
    in the order of CASES (liquefaction case 4 last), so that a stopped study has the first knobs."""
    out = []
    order = [(knobs, [c for c in CASES if c not in LAST]) for knobs in PRIORITY]
    order.append((sum(PRIORITY, ()), list(LAST)))
    for knobs, names in order:
        for case in names:
            spec = CASES[case]
            if cases and case not in cases:
                continue
            for knob in knobs:
                if knob == "reference":
                    out.append((case, knob, spec.get("reference_dt", REFERENCE_DT)))
                else:
                    out += [(case, knob, v) for v in spec.get(knob, [])]
    return out


def starts_of(case, knob):
    """Perturbed starts of one point of the study."""
    return CASES[case].get("starts", {}).get(knob, STARTS)


def perturbation_of(case, knob, value):
    """The size [m] of the perturbation of the starts of one point of the study."""
    return value if knob == "perturbation" else CASES[case].get("perturbation_size", PERTURBATION)


def job_name(case, knob, value):
    text = value if isinstance(value, str) else value["name"] if isinstance(value, dict) else repr(value)
    safe = "".join(c if c.isalnum() or c in "._=,+-" else "_" for c in text)
    return f"{case}.{knob}={safe}"[:120]


# -- run (inside YADE) ----------------------------------------------------------------------------
def parse_set(text):
    from engines.run.command_line import scene_setting
    return scene_setting(text)


def run_main(argv):
    from engines.run.preflight import ArgumentParser, number, output_dir
    ap = ArgumentParser(prog="tradeoffs.py run")
    ap.add_argument("--case", required=True, help="a preset of yade_scripts/scenes (e.g. liquefaction_case1)")
    ap.add_argument("--set", type=parse_set, action="append", default=[], metavar="TABLE.FIELD=VALUE")
    ap.add_argument("--window", type=number(lo=0, lo_open=True, unit="s"), required=True)
    ap.add_argument("--record", type=number(lo=0, lo_open=True, unit="s"), default=RECORD)
    ap.add_argument("--starts", type=number(int, 1), default=STARTS)
    ap.add_argument("--perturbation", type=number(lo=0, unit="m"), default=PERTURBATION,
                    help="size of the perturbation of the starts [m] (engines.studies.tradeoffs.perturbed)")
    ap.add_argument("--out", type=output_dir, required=True)
    a = ap.parse_args(argv)
    over = {}
    for table, field, value in a.set:
        over.setdefault(table, {})[field] = value
    over.setdefault("numerics", {})["duration"] = a.window
    result = run_setting(a.case, over, a.window, a.record, a.starts, a.out, a.perturbation)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "result.json"), "w") as f:
        json.dump(result, f)
    print(f"{a.case} {over}: cpu {result['cpu_s']:.1f} s, wall {result['wall_s']:.1f} s, "
          f"{sum(1 for s in result['starts'] if s['status'] == 'ok')}/{a.starts} starts ok")


def nested(flat):
    """{"table.field": v} -> {table: {field: v}}."""
    out = {}
    for key, v in flat.items():
        table, field = key.split(".", 1)
        out.setdefault(table, {})[field] = v
    return out


def named_value(case, knob, text):
    """The value of a study point from its text in a job name: a number, or a named setting."""
    named = {v["name"]: v for v in CASES[case].get(knob, []) if isinstance(v, dict)}
    return named[text] if text in named else float(text)


def speed_main(argv):
    """Speed-ups measured in one YADE process: each setting run from one start per repeat, the
    settings interleaved (their order rotated every repeat), CPU seconds as in ``run``; the
    median over the repeats of each over the first setting's (the paper's) -> OUT/speed.json."""
    from engines.run.preflight import ArgumentParser, number, output_dir
    ap = ArgumentParser(prog="tradeoffs.py speed")
    ap.add_argument("--case", default="liquefaction_case1", choices=sorted(CASES))
    ap.add_argument("--points", nargs="+", default=["dt=1e-06", "defaults=fast"],
                    help="KNOB=VALUE of the study (VALUE a number or a setting's name); the first is the base")
    ap.add_argument("--repeats", type=number(int, 1), default=3)
    ap.add_argument("--out", type=output_dir, required=True)
    a = ap.parse_args(argv)
    spec = CASES[a.case]
    points = [p.split("=", 1) for p in a.points]
    cpu = {p: [] for p in a.points}
    for rep in range(a.repeats):
        for k in range(len(points)):
            knob, text = points[(k + rep) % len(points)]
            over = nested(settings_of(a.case, knob, named_value(a.case, knob, text))[0])
            over.setdefault("numerics", {})["duration"] = spec["window"]
            res = run_setting(spec.get("preset", a.case), over, spec["window"], RECORD, 1, a.out,
                              perturbation_of(a.case, knob, named_value(a.case, knob, text)))
            cpu[f"{knob}={text}"].append(res["cpu_s"])
            print(f"repeat {rep}: {knob}={text}: {res['cpu_s']:.2f} CPU s", flush=True)
    med = {p: float(np.median(c)) for p, c in cpu.items()}
    doc = {"case": a.case, "window_s": spec["window"], "repeats": a.repeats, "cpu_s": cpu, "median_cpu_s": med,
           "speedup": {p: med[a.points[0]] / m for p, m in med.items()}}
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "speed.json"), "w") as f:
        json.dump(doc, f, indent=1)
    for p in a.points:
        print(f"{p}: median {med[p]:.2f} CPU s, speed-up {doc['speedup'][p]:.1f}")


def run_setting(case, overrides, window, record, n_starts, out_dir, perturbation=None):
    """Run one setting from n_starts starts perturbed by ``perturbation`` [m] (default
    PERTURBATION); returns the result dict (module docstring)."""
    from yade import O

    from engines.model.time_step import resolve_dt
    from engines.run import scene as scenes
    from engines.run.preflight import InputError, preflight
    from engines.studies.tradeoffs import perturbed
    from engines.yade.coupling import YadeCoupling
    from engines.yade.deposition import scene_packing

    sc = scenes.preset(case, overrides)
    packing = scene_packing(sc)
    sc = resolve_dt(sc, packing)
    dt = sc.numerics.dt
    every = max(1, int(round(record / dt)))
    n_steps = int(round(window / dt))
    YadeCoupling(sc, packing).run(10)  # loads the compiled kernels (numba's cache) outside the timing
    starts, cpu, wall = [], 0.0, 0.0
    for s in range(n_starts):
        pk = perturbed(packing, s, PERTURBATION if perturbation is None else perturbation)
        rec = {"seed": s, "t": [], "U": [], "porosity": [], "height": [], "kinetic_energy": []}
        try:
            preflight(sc, pk, out_dir)
            c0, w0 = time.process_time(), time.time()
            cp = YadeCoupling(sc, pk)
            mob = pk.mobile
            k, c_rec, w_rec = 0, 0.0, 0.0  # the recording's own time, left out of the cost
            while True:
                r0, q0 = time.process_time(), time.time()
                xz = cp.positions()
                rec["t"].append(O.iter * dt)
                rec["U"].append([float(u) for u in cp.block_pressures(xz)])
                rec["porosity"].append(float(cp.porosity(xz)))
                rec["height"].append(float(np.mean(xz[mob, 1])))
                rec["kinetic_energy"].append(cp.kinetic_energy())
                c_rec, w_rec = c_rec + time.process_time() - r0, w_rec + time.time() - q0
                if k >= n_steps or not np.all(np.isfinite(xz)):
                    break
                cp.run(min(every, n_steps - k))
                k += min(every, n_steps - k)
            cpu_s, wall_s = time.process_time() - c0 - c_rec, time.time() - w0 - w_rec
            w, wm = cp.water, cp.water_model
            rec.update(status="ok" if np.all(np.isfinite(xz)) else "nan", cpu_s=cpu_s, wall_s=wall_s, steps=int(O.iter),
                       cpu_record_s=c_rec,
                       water_balance_error=w.balance_error() if w else 0.0,
                       substeps_max=wm.substeps_max if wm else 0, substeps_total=wm.substeps_total if wm else 0,
                       n_rebuilds=wm.n_rebuilds if wm else 0,
                       contact_list_builds=cp.core.contact.list_builds if cp.core is not None else None)
            cpu += cpu_s
            wall += wall_s
        except InputError as e:  # refused up front
            rec.update(status="refused", message=str(e), steps=0)
        except ValueError as e:  # stopped by an engine (DarcyStabilityError ...)
            rec.update(status="failed", message=str(e), steps=int(O.iter))
        starts.append(rec)
    ok = [r for r in starts if r["status"] == "ok"]
    return {"case": case, "overrides": overrides, "dt": dt, "window": window, "record": record,
            "perturbation": PERTURBATION if perturbation is None else perturbation,
            "n_steps": n_steps, "cpu_s": cpu / max(len(ok), 1), "wall_s": wall / max(len(ok), 1),
            "starts": starts, "program": os.path.basename(sys.argv[0]) if sys.argv else "yade"}


# -- study (Debian's Python) ----------------------------------------------------------------------
def study_jobs(cases=None, yade_args=("-n", "-j", "1"), knobs=None):
    """(jobs for engines.run.sweep, {job name: (case, knob, value)}) of the study's points (of the
    knobs ``knobs`` only, when given)."""
    from engines.run.sweep import Job
    jobs, meta = [], {}
    for case, knob, value in points(cases):
        if knobs and knob not in knobs:
            continue
        over, program = settings_of(case, knob, value)
        name = job_name(case, knob, value)
        argv = [program, *yade_args, "-x", os.path.join(ROOT, "yade_scripts", "tradeoffs.py"), "run",
                "--case", CASES[case].get("preset", case), "--window", repr(CASES[case]["window"]),
                "--starts", str(starts_of(case, knob)), "--perturbation", repr(perturbation_of(case, knob, value)),
                "--out", "{out}"]
        for k, v in over.items():
            argv += ["--set", f"{k}={json.dumps(v)}"]
        jobs.append(Job(name, argv, {"PYTHONPATH": ROOT}))
        meta[name] = (case, knob, value)
    return jobs, meta


def study_main(argv):
    from engines.run.preflight import ArgumentParser, number
    ap = ArgumentParser(prog="tradeoffs.py study")
    ap.add_argument("--out", default=os.path.join("out", "tradeoffs"))
    ap.add_argument("--workers", type=number(int, 1), default=int(os.environ.get("TRADE_JOBS", "1")),
                    help="local processes at a time (default 1: the study is timed)")
    ap.add_argument("--scheduler", help="Dask scheduler address (timings then come from the workers)")
    ap.add_argument("--cases", nargs="+", choices=sorted(CASES), help="a subset of the cases")
    ap.add_argument("--knobs", nargs="+", help="a subset of the knobs (e.g. reference dt defaults)")
    ap.add_argument("--analyse-only", action="store_true", help="skip the runs, analyse what is there")
    a = ap.parse_args(argv)
    jobs, meta = study_jobs(a.cases, knobs=a.knobs)
    if not a.analyse_only:
        from engines.run.sweep import run_sweep
        run_sweep(jobs, os.path.join(a.out, "runs"), workers=a.workers, scheduler=a.scheduler)
    from postproc.tradeoffs import analyse
    analyse(a.out, jobs, meta)


def main(argv):
    if argv and argv[0] == "run":
        return run_main(argv[1:])
    if argv and argv[0] == "study":
        return study_main(argv[1:])
    if argv and argv[0] == "speed":
        return speed_main(argv[1:])
    sys.exit("usage: tradeoffs.py run ... | study ... | speed ... (see the docstring)")


if __name__ == "__main__":
    main(sys.argv[1:])
