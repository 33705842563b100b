"""The resistance-curve study run (make resistance; yade_scripts/resistance.py; the analysis:
engines.studies.resistance): the dense packing's deposit (seismic case 1's deposition with
[contact] mu = 0), then per packing and amplitude an ensemble of perturbed starts of case 1 under
its cosine at that amplitude for CYCLES cycles (yade_scripts/liquefaction.py --starts), through the
sweep runner (local or Dask; resumable: a re-run skips the finished jobs and continues an ensemble
from its finished starts), then OUT/resistance.json and OUT/resistance.png.

    OUT/runs/dense_packing/packing.csv               the dense deposit
    OUT/runs/<packing>_<gal>gal/ensemble/            an ensemble: start_<k>/, ensemble.json

``ground``: the folder of one run of the 10,000-disc ground (make resistance-ground: case 1's cosine
for CYCLES cycles), read the same way and kept beside the curve as an illustration (one run, not
an ensemble: no statement uses it).

SHORT (``short=True``): a few milliseconds of two amplitudes, two starts, a dense deposit settled
for milliseconds: the pipeline end to end (its runs are all censored at their 0.1 cycle).
"""
import json
import os
from dataclasses import dataclass

import numpy as np

from engines import ROOT, files
from engines.run.provenance import git_state
from engines.studies import resistance as rs
from postproc.run_files import read_history, read_summary

SCRIPTS = os.path.join(ROOT, "yade_scripts")
ENSEMBLE = "ensemble"
SHORT_DURATION = 0.002  # s: SHORT's runs
SHORT_DEPOSIT = {"settle_time": 0.003, "settle_loaded": 0.002}  # s: SHORT's dense deposit


@dataclass(frozen=True)
class Plan:
    """What the study runs: amplitudes [m/s^2], starts per ensemble, the runs' duration [s], the
    deposit's extra [packing] fields, and whether its JSON is a pilot."""

    amplitudes: tuple = rs.AMPLITUDES
    starts: int = rs.STARTS
    duration: float = rs.CYCLES / rs.FREQUENCY
    deposit: tuple = ()
    pilot: bool = False

    @property
    def cycles(self):
        return self.duration * rs.FREQUENCY


def short_plan():
    return Plan(amplitudes=(rs.AMPLITUDES[0], rs.AMPLITUDES[-1]), starts=2, duration=SHORT_DURATION,
                deposit=tuple(SHORT_DEPOSIT.items()))


def job_name(packing, amplitude):
    """The job of ``packing`` at ``amplitude`` [m/s^2], named by the amplitude in gal."""
    return f"{packing}_{amplitude * 100:.0f}gal"


def packing_path(root):
    return os.path.join(root, "dense_packing", "packing.csv")


def ensemble_path(root, packing, amplitude):
    return os.path.join(root, job_name(packing, amplitude), ENSEMBLE)


def _sets(table, fields):
    return [w for f, v in fields for w in ("--set", f"{table}.{f}={json.dumps(v)}")]


def _ensemble_done(ensemble):
    """None before the ensemble began; True when it has ended with each start completed or failed
    (a failed start, e.g. a water step the shaking outran, is recorded and not run again); False
    when it was stopped during its starts."""
    try:
        with open(os.path.join(ensemble, "ensemble.json")) as f:
            doc = json.load(f)
    except FileNotFoundError:
        return None
    return doc.get("status") == "completed" or (doc.get("status") == "incomplete" and all(
        v == "completed" or v.startswith("failed") for v in doc.get("start_status", {}).values()))


def study_jobs(root, plan, yade=("yade", "-n")):
    """(deposit jobs, ensemble jobs) for engines.run.sweep; ``root``: the sweep's folder (OUT/runs).
    A completed ensemble has no job; one stopped during its starts resumes them."""
    from engines.run.sweep import Job
    env = {"PYTHONPATH": ROOT}
    deposits = [Job("dense_packing", [*yade, "-x", os.path.join(SCRIPTS, "deposit.py"), "--scene", rs.SCENE,
                                      *_sets("contact", rs.PACKINGS["dense"].items()), *_sets("packing", plan.deposit),
                                      "--out", "{out}/packing.csv"], env)]
    runs = []
    for packing, change in rs.PACKINGS.items():
        for a in plan.amplitudes:
            script = [*yade, "-x", os.path.join(SCRIPTS, "liquefaction.py")]
            done = _ensemble_done(ensemble_path(root, packing, a))
            if done:
                continue
            if done is not None:  # stopped during its starts: continue it
                argv = [*script, "--resume", ensemble_path(root, packing, a), "--jobs", "1"]
            else:
                pk = _sets("packing", [("source", "file"), ("file", packing_path(root))]) if change else []
                argv = [*script, "--case", "1", *pk, *_sets("loading", [("amplitude", a), ("frequency", rs.FREQUENCY)]),
                        "--duration", repr(plan.duration), "--dt", repr(rs.time_step(a)), "--starts", str(plan.starts), "--jobs", "1",
                        "--quiet", "--out", f"{{out}}/{ENSEMBLE}"]
            runs.append(Job(job_name(packing, a), argv, env))
    return deposits, runs


def _starts(ensemble):
    """(the folders of its completed starts, {start: the first line of its failure}) of an ensemble."""
    done, failed = [], {}
    names = [n for n in os.listdir(ensemble) if n.startswith("start_")] if os.path.isdir(ensemble) else []
    for name in sorted(names, key=lambda n: int(n.split("_")[-1])):
        d = os.path.join(ensemble, name)
        status = read_summary(d).get("status") or "not started"
        if status == "completed":
            done.append(d)
        else:
            failed[name] = status.splitlines()[0][:200]
    return done, failed


def analyse(root, plan):
    """The study's document from the ensembles in ``root``: per packing its void ratio and per
    amplitude the group reading (engines.studies.resistance.group_reading), the trend statements."""
    doc = {"pilot": plan.pilot, "scene": rs.SCENE, "frequency_Hz": rs.FREQUENCY, "cycles": plan.cycles,
           "ru_liquefied": rs.RU_LIQUEFIED, "csr_cycles": rs.CSR_CYCLES, "surface_diameters": rs.SURFACE_DIAMETERS,
           "amplitudes_m_s2": list(plan.amplitudes), "starts_planned": plan.starts, "commit": git_state(ROOT)[0],
           "method": rs.__doc__.split("\n\n", 1)[1].strip(), "packings": {}}
    cpu = []
    for packing, change in rs.PACKINGS.items():
        rows, porosity = [], []
        for a in plan.amplitudes:
            starts, failed = _starts(ensemble_path(root, packing, a))
            if not starts:
                if failed:
                    rows.append({"amplitude_m_s2": a, "n_starts": 0, "not_completed": failed})
                continue
            readings = []
            for d in starts:
                h, s = read_history(os.path.join(d, "history.csv")), read_summary(d)
                readings.append(rs.run_reading(h, s, rs.FREQUENCY, a, plan.cycles))
                porosity.append(float(h["porosity"][0]))
                cpu.append(s["cpu_seconds"])
            g = s["parameters"]["material"]["g"]
            rows.append({"amplitude_m_s2": a, "a_max_g": a / g, "dt_s": rs.time_step(a),
                         **rs.group_reading(readings, plan.cycles), "not_completed": failed})
        if porosity:
            n = float(np.mean(porosity))
            doc["packings"][packing] = {"deposit": change or "the preset's (liquefaction_packing.csv)",
                                        "porosity": n, "void_ratio": rs.void_ratio(n), "rows": rows}
    doc["cpu_seconds_per_run"] = float(np.mean(cpu)) if cpu else None
    doc["statements"] = rs.statements(doc["packings"])
    return doc


def ground_reading(run, cycles):
    """The reading (engines.studies.resistance.run_reading) of one completed run in the folder
    ``run`` at its own cosine's amplitude, with its discs, porosity and void ratio; ValueError (one
    line: the status and the command that finishes it) for a run not completed."""
    s = read_summary(run)
    if s.get("status") != "completed":
        raise ValueError(f"{run}: the ground run is {str(s.get('status') or 'not started').splitlines()[0]!r}, not "
                         "completed: make resistance-ground runs or resumes it")
    h = read_history(os.path.join(run, "history.csv"))
    load = s["parameters"]["loading"]
    if load["type"] != "cosine":
        raise ValueError(f"{run}: [loading] type = {load['type']!r}; the resistance curve reads cosine inputs only")
    a = float(load["amplitude"]) * float(load["amplitude_scale"])
    n = float(h["porosity"][0])
    return {"run": os.path.basename(os.path.normpath(run)), "scene": s["scene"], "n_particles": s["n_particles"],
            "amplitude_m_s2": a, "a_max_g": a / s["parameters"]["material"]["g"], "porosity": n,
            "void_ratio": rs.void_ratio(n), "cpu_seconds": s["cpu_seconds"],
            "note": "one run: an illustration beside the curve, not an ensemble", **rs.run_reading(h, s, float(load["frequency"]), a, cycles)}


def run_study(out, plan, workers=1, scheduler=None, analyse_only=False, docs=None, ground=None):
    """The deposit, then the ensembles, through the sweep runner (none with ``analyse_only``),
    then OUT/resistance.json and OUT/resistance.png (copied to ``docs``, a folder, if given), with
    the reading of the run in the folder ``ground`` (``ground_reading``) if given; returns the
    document."""
    reading = ground_reading(ground, plan.cycles) if ground else None  # refused before any run
    root = os.path.join(out, "runs")
    if not analyse_only:
        from engines.run.sweep import run_sweep
        for jobs in study_jobs(root, plan):
            if jobs:
                records = run_sweep(jobs, root, workers=workers, scheduler=scheduler)
                bad = [r["name"] for r in records if r.get("status") != "ok"]
                if bad:  # an ensemble with a failed start exits non-zero: its failures go in the JSON
                    print(f"note: {', '.join(bad)} ended with failed starts (logs: {root}/<job>/...); "
                          "resistance.json lists them under each row's \"failed\"")
    from postproc.resistance import resistance_figure
    doc = analyse(root, plan)
    if reading:
        doc["ground"] = reading
    for folder in [out] + ([docs] if docs else []):
        os.makedirs(folder, exist_ok=True)
        files.write_json(os.path.join(folder, "resistance.json"), doc)
        resistance_figure(doc, os.path.join(folder, "resistance.png"))
    return doc
