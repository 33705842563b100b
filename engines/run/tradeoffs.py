"""The speed/accuracy study run (yade_scripts/tradeoffs.py; docs/TRADEOFFS.md): the scene
settings of each point of the study (settings_of; the points: engines.studies.tradeoffs), one
setting from perturbed starts inside YADE (run_setting, run_point), the speed-ups measured in one
process (measure_speed), and the study's jobs through the sweep runner with their analysis
(study_jobs, run_study; the tables and figures: postproc.tradeoffs); with ``validation`` the
study's validation of the fast setting on every preset (engines.studies.tradeoffs.VALIDATION).
"""
import json
import os
import sys
import time

import numpy as np

from engines import files
from engines import ROOT
from engines.studies.ensemble import MAX_STARTS, perturbed
from engines.studies.tradeoffs import (
    CASES,
    PERTURBATION,
    RECORD,
    REFERENCE_DT,
    VALIDATION_CASES,
    dt_settings,
    job_name,
    more_starts_name,
    named_value,
    nested,
    perturbation_of,
    points,
    starts_of,
)


def settings_of(case, knob, value):
    """(overrides, yade program) of one point of the study."""
    spec = CASES[case]
    base = dt_settings(spec["fast_dt"]) if "fast_dt" in spec else None  # the knobs' base settings
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


def window_of(case):
    """The window [s] of a case of the study: its own, or (None) the preset scene's duration."""
    spec = CASES[case]
    if spec["window"] is not None:
        return spec["window"]
    from engines.run import scene as scenes
    return scenes.preset(spec.get("preset", case)).numerics.duration


def run_setting(case, overrides, window, record, n_starts, out_dir, perturbation=None, first=0):
    """Run one setting from n_starts starts (seeds first, first + 1, ...) perturbed by
    ``perturbation`` [m] (default PERTURBATION); returns the result dict (yade_scripts/tradeoffs.py,
    ``run``, lists its fields)."""
    from engines.model.start import Start
    from engines.run import scene as scenes
    from engines.run.preflight import announce_dt, timed
    from engines.yade.coupling import YadeCoupling
    from engines.yade.deposition import scene_packing

    sc = scenes.preset(case, overrides)
    packing = scene_packing(sc)
    prepared = Start(sc.settings, packing)
    announce_dt(prepared)
    sc = timed(sc, prepared)
    dt = sc.numerics.dt
    every = max(1, int(round(record / dt)))
    n_steps = int(round(window / dt))
    YadeCoupling(sc, packing).run(10)  # loads the compiled kernels (numba's cache) outside the timing
    starts, cpu, wall = [], 0.0, 0.0
    for s in range(first, first + n_starts):
        rec = _run_start(sc, perturbed(packing, s, PERTURBATION if perturbation is None else perturbation), s,
                         out_dir, every, n_steps)
        if "cpu_s" in rec:  # it ran (ok, or nan)
            cpu += rec["cpu_s"]
            wall += rec["wall_s"]
        starts.append(rec)
    ok = [r for r in starts if r["status"] == "ok"]
    return {"case": case, "overrides": overrides, "dt": dt, "window": window, "record": record,
            "perturbation": PERTURBATION if perturbation is None else perturbation,
            "n_steps": n_steps, "cpu_s": cpu / max(len(ok), 1), "wall_s": wall / max(len(ok), 1),
            "starts": starts, "program": os.path.basename(sys.argv[0]) if sys.argv else "yade"}


def _run_start(sc, pk, seed, out_dir, every, n_steps):
    """One start of run_setting: the scene ``sc`` from the packing ``pk`` for ``n_steps`` steps,
    recorded every ``every`` steps; its record {seed, t, U, porosity, height, kinetic_energy,
    status, ...}: "ok", "nan", "refused" (preflight) or "failed" (stopped by an engine)."""
    from yade import O

    from engines.model.start import Start
    from engines.run.preflight import InputError, preflight
    from engines.yade.coupling import YadeCoupling

    rec = {"seed": seed, "t": [], "U": [], "porosity": [], "height": [], "kinetic_energy": []}
    try:
        prepared = Start(sc.settings, pk)
        preflight(sc, pk, out_dir, prepared)
        c0, w0 = time.process_time(), time.time()
        cp = YadeCoupling(sc, pk, prepared=prepared)
        xz, c_rec, w_rec = _recorded(cp, rec, pk.mobile, sc.numerics.dt, every, n_steps)
        cpu_s, wall_s = time.process_time() - c0 - c_rec, time.time() - w0 - w_rec
        w, wm = cp.water, cp.water_model
        rec.update(status="ok" if np.all(np.isfinite(xz)) else "nan", cpu_s=cpu_s, wall_s=wall_s, steps=int(O.iter),
                   cpu_record_s=c_rec,
                   water_balance_error=w.balance_error() if w else 0.0,
                   substeps_max=wm.substeps_max if wm else 0, substeps_total=wm.substeps_total if wm else 0,
                   n_rebuilds=wm.n_rebuilds if wm else 0,
                   contact_list_builds=cp.core.contact.list_builds if cp.core is not None else None)
    except InputError as e:  # refused up front
        rec.update(status="refused", message=str(e), steps=0)
    except ValueError as e:  # stopped by an engine (DarcyStabilityError ...)
        rec.update(status="failed", message=str(e), steps=int(O.iter))
    return rec


def _recorded(cp, rec, mob, dt, every, n_steps):
    """Run the coupling ``cp`` for ``n_steps`` steps (or to the first non-finite position), appending
    to ``rec`` every ``every`` steps; returns (the last positions, the recording's own CPU and wall
    seconds, left out of the cost)."""
    from yade import O

    k, c_rec, w_rec = 0, 0.0, 0.0
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
            return xz, c_rec, w_rec
        cp.run(min(every, n_steps - k))
        k += min(every, n_steps - k)


def run_point(case, sets, window, record, n_starts, out_dir, perturbation, first=0):
    """``tradeoffs.py run``: run_setting of the preset ``case`` with the scene settings ``sets``
    [(table, field, value)] for ``window`` seconds from starts first .. first + n_starts - 1;
    writes OUT/result.json; returns (the overrides, the result)."""
    over = {}
    for table, field, value in sets:
        over.setdefault(table, {})[field] = value
    over.setdefault("numerics", {})["duration"] = window
    result = run_setting(case, over, window, record, n_starts, out_dir, perturbation, first)
    os.makedirs(out_dir, exist_ok=True)
    files.write_json(os.path.join(out_dir, "result.json"), result, indent=None)
    return over, result


def measure_speed(case, settings, repeats, out):
    """Speed-ups measured in one YADE process: each of ``settings`` (texts KNOB=VALUE of the study,
    the first the base) run from one start per repeat, the settings interleaved (their order
    rotated every repeat), CPU seconds as in ``run_setting``; the median over the repeats of each
    over the first setting's (the paper's) -> OUT/speed.json, which it returns."""
    spec = CASES[case]
    pairs = [p.split("=", 1) for p in settings]
    cpu = {p: [] for p in settings}
    for rep in range(repeats):
        for k in range(len(pairs)):
            knob, text = pairs[(k + rep) % len(pairs)]
            over = nested(settings_of(case, knob, named_value(case, knob, text))[0])
            over.setdefault("numerics", {})["duration"] = window_of(case)
            res = run_setting(spec.get("preset", case), over, window_of(case), RECORD, 1, out,
                              perturbation_of(case, knob, named_value(case, knob, text)))
            cpu[f"{knob}={text}"].append(res["cpu_s"])
            print(f"repeat {rep}: {knob}={text}: {res['cpu_s']:.2f} CPU s", flush=True)
    med = {p: float(np.median(c)) for p, c in cpu.items()}
    doc = {"case": case, "window_s": window_of(case), "repeats": repeats, "cpu_s": cpu, "median_cpu_s": med,
           "speedup": {p: med[settings[0]] / m for p, m in med.items()}}
    os.makedirs(out, exist_ok=True)
    files.write_json(os.path.join(out, "speed.json"), doc)
    return doc


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
                "--case", CASES[case].get("preset", case), "--window", repr(window_of(case)),
                "--starts", str(starts_of(case, knob)), "--perturbation", repr(perturbation_of(case, knob, value)),
                "--out", "{out}"]
        for k, v in over.items():
            argv += ["--set", f"{k}={json.dumps(v)}"]
        jobs.append(Job(name, argv, {"PYTHONPATH": ROOT}))
        meta[name] = (case, knob, value)
    return jobs, meta


def more_starts_jobs(doc, jobs, meta):
    """The jobs that give each scene of the validation ``doc`` whose row (the fast setting's or a
    candidate's) is not resolved the starts its ``starts_needed`` asks, capped at MAX_STARTS, for
    every setting of the scene (the paper's too): one job per setting from the starts it has (the
    ``--starts`` of its jobs) on, named by ``more_starts_name`` (added to ``meta``). None left: []."""
    from engines.run.sweep import Job
    have = {}
    for job in jobs:
        base = job_name(*meta[job.name])
        have[base] = have.get(base, 0) + int(job.argv[job.argv.index("--starts") + 1])
    out = []
    for entry in doc["scenes"].values():
        rows = [entry, *entry.get("candidates", {}).values()]
        need = min(max([r.get("starts_needed") or 0 for r in rows]), MAX_STARTS)
        for job in jobs:
            case, knob, value = meta[job.name]
            base = job_name(case, knob, value)
            if case != entry["case"] or job.name != base or have[base] >= need:
                continue
            argv = list(job.argv)
            argv[argv.index("--starts") + 1] = str(need - have[base])
            argv[argv.index("--out"):argv.index("--out")] = ["--first-start", str(have[base])]
            out.append(Job(more_starts_name(base, have[base], need - have[base]), tuple(argv), job.env))
            meta[out[-1].name] = meta[job.name]
    return out


def run_study(out, workers=1, scheduler=None, cases=None, knobs=None, analyse_only=False, validation=False):
    """``tradeoffs.py study``: the study's jobs (of ``cases`` and ``knobs`` only, when given) through
    the sweep runner (none with ``analyse_only``), then postproc.tradeoffs.analyse: OUT/tradeoffs.json,
    table.md and the figures; returns the tradeoffs.json dict. With ``validation``: the validation's
    cases (of ``cases`` only, when given), then postproc.tradeoffs.validate: OUT/validation.json and
    validation.md, and again with the starts that rows not resolved ask (``more_starts_jobs``;
    with ``analyse_only``, those that ran); returns the validation.json dict."""
    from engines.run.sweep import run_sweep
    from postproc.tradeoffs import analyse, validate
    if validation:
        cases = [c for c in VALIDATION_CASES if not cases or c in cases]
    jobs, meta = study_jobs(cases, knobs=knobs)
    runs = os.path.join(out, "runs")
    if not analyse_only:
        run_sweep(jobs, runs, workers=workers, scheduler=scheduler)
    if not validation:
        return analyse(out, jobs, meta)
    while True:
        doc = validate(out, jobs, meta)
        more = more_starts_jobs(doc, jobs, meta)
        if analyse_only:
            more = [j for j in more if os.path.exists(os.path.join(runs, j.name, "result.json"))]
        if not more:
            return doc
        jobs += more
        if not analyse_only:
            run_sweep(more, runs, workers=workers, scheduler=scheduler)
