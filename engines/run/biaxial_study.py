"""Seed 003's study through the sweep runner (yade_scripts/biaxial_study.py lists its parts and
files): the jobs of each part (yade_scripts/biaxial.py runs, yade_scripts/biaxial_stability.py),
their predicted cost (--estimate), the calibration round trip, and ``run_study``, which runs what
is missing and writes study.json, fit.json, table.md and the figures; ``calibrate``
(yade_scripts/calibrate.py): eq 5–6 for a target, verified by the biaxial test.
"""
import json
import os

import numpy as np

from engines import files
from engines import ROOT
from engines.run.sweep import Job, is_done, read_record, run_sweep
from engines.seeds.biaxial.cem_contact import TABLE2_DT
from engines.seeds.biaxial.periodic import PACKING_PHI_E
from engines.seeds.biaxial.specimen import mohr_coulomb_fit
from engines.seeds.biaxial.study import (
    CALIBRATION_TARGET_SIGMA3,
    DISCS,
    DTS,
    KNS,
    KSS,
    PHI_E,
    RATES,
    SENS_PHI,
    SENS_SIGMA3,
    SENS_STRAIN,
    SIGMA3,
    SMALL_DISCS,
    analyse_hypotheses,
    analyse_main,
    analyse_sensitivity,
    calibration_from,
    calibration_target,
    hypothesis_points,
    mean_sd,
    read_run,
    sensitivity_name,
    summarise,
    write_hypotheses,
    write_table,
)
from engines.studies.biaxial_judged import (
    JUDGED_PHI,
    JUDGED_SEEDS,
    JUDGED_SIGMA3,
    analyse_judged,
    conditioning,
    conditioning_text,
    judged_name,
    write_judged,
)

BIAXIAL = os.path.join(ROOT, "yade_scripts", "biaxial.py")
STABILITY = os.path.join(ROOT, "yade_scripts", "biaxial_stability.py")
MS_PER_STEP_1000 = 1.1  # CPU ms per step of a 1000-disc test, measured alone (docs/BIAXIAL.md): --estimate
QUICK = {"n_discs": 150, "max_strain": 1.5, "strain_rate": 400.0}  # --quick: a pipeline check, not a result


def biaxial_job(name, yade=("yade", "-n"), quick=False, **options):
    """A biaxial.py job; options by their long names (phi_e=10 → --phi-e 10). ``quick`` puts
    QUICK's small specimen, short test and fast rate in place of the paper's where the job
    does not study that knob."""
    if quick:
        options = {**options, **{k: v for k, v in QUICK.items() if k not in options or k == "max_strain"}}
    # the packing protocol always on the command line: resume compares command lines, and one
    # without it does not say which protocol made the run
    options = {"packing_phi_e": PACKING_PHI_E, **options}
    argv = [*yade, "-x", BIAXIAL, "--out", "{out}"]
    for k, v in options.items():
        argv += ["--" + k.replace("_", "-"), ",".join(f"{x:g}" for x in v) if isinstance(v, (tuple, list)) else f"{v:g}"
                 if isinstance(v, float) else str(v)]
    return Job(name, argv)


def sensitivity(seed, quick=False, **changes):
    """A φe = 10°, σ3 = 200 Pa run to 4 % with one knob changed from the paper's values."""
    opts = dict(phi_e=SENS_PHI, sigma3=SENS_SIGMA3, max_strain=SENS_STRAIN, seed=seed)
    opts.update(changes)
    return biaxial_job(sensitivity_name(seed, **changes), quick=quick, **opts)


def main_jobs(seeds, quick=False):
    """The main grid: φe × the four σ3 on one packing seed per job, to 5 % strain; φe = 15° (the
    paper's φ*, c*) first."""
    return [biaxial_job(f"main_phi{p:g}_seed{s}", quick=quick, phi_e=p, sigma3=SIGMA3, max_strain=5.0, seed=s)
            for p in sorted(PHI_E, reverse=True) for s in seeds]


def sensitivity_jobs(parts, seeds, quick=False):
    """The sensitivity runs of ``parts``, the judged ones (kn, ks/kn) first."""
    jobs = []
    sens = lambda s, **c: sensitivity(s, quick=quick, **c)  # noqa: E731
    small = {"n_discs": SMALL_DISCS}
    if parts & {"stiffness", "dt", "discs"}:
        jobs += [sens(s, **small) for s in seeds]
    if "stiffness" in parts:
        jobs += [sens(s, kn=k, **small) for k in KNS for s in seeds]
        jobs += [sens(s, ks_ratio=k, **small) for k in KSS for s in seeds]
    if parts & {"discs", "rate", "stability"}:
        jobs += [sens(s) for s in seeds]
    if "discs" in parts:
        jobs += [sens(s, n_discs=n) for n in DISCS if n != SMALL_DISCS for s in seeds]
    if "rate" in parts:
        jobs += [sens(s, strain_rate=r) for r in RATES for s in seeds]
    if "dt" in parts:
        jobs += [sens(s, dt=dt, packing_dt=TABLE2_DT, **small) for dt in sorted(DTS, reverse=True) for s in seeds]
    return jobs


def hypothesis_jobs(seeds, quick=False):
    """The hypotheses study (engines.seeds.biaxial.study.HYPOTHESES): one biaxial.py job per
    variant, φe, σ3 and packing seed, and the size-effect runs."""
    return [biaxial_job(name, quick=quick, **opts) for name, opts in hypothesis_points(seeds)]


def judged_jobs(quick=False):
    """The judged command on each of JUDGED_SEEDS at each of JUDGED_PHI (in its order): every
    option at its default but the seed."""
    return [biaxial_job(judged_name(p, s), quick=quick, phi_e=p, sigma3=JUDGED_SIGMA3, seed=s)
            for p in JUDGED_PHI for s in JUDGED_SEEDS]


def stability_job(runs, seed):
    """biaxial_stability.py on the reference packing of ``seed`` (it must have run)."""
    block = os.path.join(os.path.abspath(runs), sensitivity_name(seed), f"packing_sigma3_{SENS_SIGMA3:g}")
    return Job("stability", ("yade", "-n", "-x", STABILITY, "--block", block, "--out", "{out}"))


# ---- the cost -------------------------------------------------------------------------------

PACK_STEPS = (20000, 3000)  # packing steps at Δt = 0.5e-4 s to the first σ3, then to each further one (the judged
                            # runs at 0.45e-4 s: 17 000–28 000, then 600–15 000)
EQUILIBRIUM_STEPS = 4500    # preliminary equilibrium per σ3 at Δt = 0.5e-4 s (3000–5500 measured)


def predicted_cpu_s(job):
    """Predicted CPU seconds of a biaxial.py or biaxial_stability.py job: its steps × MS_PER_STEP_1000
    × discs / 1000. Steps: PACK_STEPS and EQUILIBRIUM_STEPS (scaled to the job's Δt), and the
    compression's max_strain / rate / Δt plus the ramp, per σ3."""
    from engines.seeds.biaxial.cem_contact import CemContact, stable_dt
    from engines.seeds.biaxial.periodic import table1_radii
    from engines.seeds.biaxial.specimen import BiaxialSettings
    from engines.run.biaxial import parser
    from engines.seeds.biaxial.stability import REST_TIME, cases

    script = job.argv[job.argv.index("-x") + 1]
    if script == STABILITY:
        return sum(REST_TIME / dt for _, dt in cases(table1_radii(1000), SENS_PHI)) * MS_PER_STEP_1000 / 1000
    a = parser().parse_args([x.replace("{out}", ".") for x in job.argv[job.argv.index("-x") + 2:]])
    dt = a.dt or stable_dt(table1_radii(a.n_discs), CemContact(kn=a.kn, ks_ratio=a.ks_ratio, phi_e_deg=a.phi_e,
                                                               width_factor=a.width_factor, rotation=a.rotation))
    scale = 5e-5 / (a.packing_dt or dt), 5e-5 / dt
    steps = (PACK_STEPS[0] + PACK_STEPS[1] * (len(a.sigma3) - 1)) * scale[0]
    steps += len(a.sigma3) * (EQUILIBRIUM_STEPS * scale[1] + (a.max_strain / 100) / (a.strain_rate / 6000) / dt
                              + BiaxialSettings.ramp_time / dt)
    return steps * MS_PER_STEP_1000 / 1000 * a.n_discs / 1000


def estimate(jobs, runs, log=print):
    """Print (``log``; None = quiet) the predicted CPU minutes of the jobs not yet done; returns
    their sum [s]."""
    log = log or (lambda *a: None)
    todo = [j for j in jobs if not is_done(j, runs)]
    cost = {j.name: predicted_cpu_s(j) for j in todo}
    for name, c in cost.items():
        log(f"  {name:<48} {c / 60:6.1f} core-min")
    log(f"{len(todo)} of {len(jobs)} jobs to run: {sum(cost.values()) / 60:.1f} core-min predicted "
        f"({MS_PER_STEP_1000} ms per 1000-disc step)")
    return sum(cost.values())


def timing(runs):
    """Cost of the runs: wall and CPU seconds per job (CPU where the sweep runner recorded it), and
    the CPU milliseconds per step of the 1000-disc jobs (packing, equilibrium and test steps)."""
    jobs, per_step = {}, []
    for name in sorted(os.listdir(runs)) if os.path.isdir(runs) else []:
        rec = read_record(runs, name)
        if not rec or rec.get("status") not in ("ok", "failed"):
            continue
        jobs[name] = {"wall_s": rec.get("wall_s"), "cpu_s": rec.get("cpu_s")}
        summary, _ = read_run(runs, name)
        if summary and rec.get("cpu_s") and summary["parameters"]["n_discs"] == 1000:
            steps = sum(p["steps"] for p in summary["packings"]) + sum(q["steps"] for q in summary["per_sigma3"])
            per_step.append(1e3 * rec["cpu_s"] / steps)
    cpu = [j["cpu_s"] for j in jobs.values() if j["cpu_s"] is not None]
    return {"jobs": len(jobs), "jobs_with_cpu": len(cpu), "cpu_min": sum(cpu) / 60,
            "wall_min": sum(j["wall_s"] for j in jobs.values()) / 60,
            "ms_cpu_per_step_1000_discs": mean_sd(per_step), "per_job": jobs}


# ---- the calibration ------------------------------------------------------------------------

VERIFY_SIGMA3 = (100.0, 400.0)  # Pa, with the target's σ3: φ* over the study's range


def verification_jobs(phi_e, kn, sigma3, seeds, prefix="verify", quick=False):
    """The biaxial runs checking a calibration: one per packing seed."""
    s3 = tuple(sorted({*VERIFY_SIGMA3, float(sigma3)}))
    return [biaxial_job(f"{prefix}_phi{phi_e:.3f}_kn{kn:.4g}_seed{s}", quick=quick, phi_e=phi_e, kn=kn, sigma3=s3,
                        max_strain=5.0, seed=s) for s in seeds]


def verify(runs, jobs, target):
    """What the verification runs gave against the target (φ* [deg], E50 [Pa], σ3 [Pa])."""
    phi, e50, failed = [], [], []
    for j in jobs:
        summary, curves = read_run(runs, j.name)
        if summary is None or "error" in summary:
            rec = read_record(runs, j.name) or {}
            failed.append({"job": j.name, "reason": (rec.get("stderr_tail") or "no result").splitlines()[-1:]})
            continue
        s3 = sorted(curves)
        phi.append(mohr_coulomb_fit(s3, [s + curves[s].peak()[1] for s in s3])[0])
        e50.append(curves[float(target[2])].e50())
    rec = {"jobs": [j.name for j in jobs], "failed": failed}
    if phi:
        rec["verified"] = {"phi_star_deg": {"mean": float(np.mean(phi)), "values": phi},
                           "e50_pa": {"mean": float(np.mean(e50)), "values": e50},
                           "phi_star_error": float(np.mean(phi) / target[0] - 1),
                           "e50_error": float(np.mean(e50) / target[1] - 1)}
    return rec


def calibration_jobs(cal, seeds, quick=False):
    """The verification runs of calibration_target (``cal`` None: a stand-in φe = 12.5°,
    kn = 1.5e8 Pa/m, for --estimate before the main grid has run); (target, (φe, kn), jobs)."""
    target = calibration_target(cal) if cal else (None, None, CALIBRATION_TARGET_SIGMA3)
    phi_e, kn = cal.invert(*target) if cal else (12.5, 1.5e8)
    return target, (phi_e, kn), verification_jobs(phi_e, kn, target[2], seeds, prefix="calibration", quick=quick)


def calibration_round_trip(runs, cal, seeds, run, quick=False):
    """eq 5–6 for calibration_target, the verification runs (``run(jobs)``), and the record
    comparing what they give with the target."""
    target, (phi_e, kn), jobs = calibration_jobs(cal, seeds, quick)
    run(jobs)
    rec = verify(runs, jobs, target)
    rec.update(target={"phi_star_deg": target[0], "e50_pa": target[1], "sigma3_pa": target[2]},
               inverted={"phi_e_deg": phi_e, "kn_pa_per_m": kn})
    return rec


def run_judged(out, runs, run, quick=False):
    """The judged part: its jobs (``run(jobs)``), the calibration round trip on their curves (its
    jobs too), and OUT/judged.json (both, with the conditioning of E50 in kn), judged.md,
    judged_fit.json (the eq 2/4 curves with their scatter, for calibrate.py --fit) and
    fig_judged.png; returns the tables."""
    from postproc.biaxial_plots import plot_judged

    run(judged_jobs(quick))
    os.makedirs(out, exist_ok=True)
    res, cal = analyse_judged(runs)
    if cal:
        cal.save(os.path.join(out, "judged_fit.json"))
        try:
            res["calibration"] = calibration_round_trip(runs, cal, JUDGED_SEEDS, run, quick=quick)
        except ValueError as e:
            res["calibration"] = {"error": str(e)}
        res["calibration"]["conditioning"] = conditioning(cal, res["calibration"].get("inverted", {}).get("phi_e_deg"))
    res["timing"] = timing(runs)
    plot_judged(res, os.path.join(out, "fig_judged.png"))
    return write_judged(res, os.path.join(out, "judged.json"), os.path.join(out, "judged.md"))


def run_study(out, parts, seeds, workers=2, scheduler=None, estimate_only=False, analyse_only=False, quick=False):
    """The study's ``parts`` on the packings ``seeds`` (yade_scripts/biaxial_study.py): runs the jobs
    not yet done (none with ``analyse_only``; with ``estimate_only`` prints their predicted cost
    instead, and returns None), then writes OUT/study.json, fit.json, table.md and the figures;
    returns the table (markdown)."""
    from postproc.biaxial_plots import study_figures

    runs = os.path.join(out, "runs")

    def run(jobs):
        if jobs and not analyse_only:
            run_sweep(jobs, runs, workers=workers, scheduler=scheduler)

    main_res = analyse_main(runs, seeds)
    cal = calibration_from(main_res) if len(main_res["fits"]) >= 2 else None
    if estimate_only:
        jobs = (main_jobs(seeds, quick) if "main" in parts else []) + sensitivity_jobs(parts, seeds, quick)
        jobs += calibration_jobs(cal, seeds, quick)[2] if "calibration" in parts else []
        jobs += hypothesis_jobs(seeds, quick) if "hypotheses" in parts else []
        jobs += judged_jobs(quick) if "judged" in parts else []
        estimate(jobs + ([stability_job(runs, seeds[0])] if "stability" in parts else []), runs)
        return None
    if "judged" in parts:
        judged = run_judged(out, runs, run, quick)
        if parts == {"judged"}:
            return judged
    if "hypotheses" in parts:
        run(hypothesis_jobs(seeds, quick))
        hyp = write_hypotheses(analyse_hypotheses(runs, seeds), os.path.join(out, "hypotheses.json"),
                               os.path.join(out, "hypotheses.md"))
        if parts == {"hypotheses"}:
            return hyp
    if "main" in parts:
        run(main_jobs(seeds, quick))
        main_res = analyse_main(runs, seeds)
        cal = calibration_from(main_res) if len(main_res["fits"]) >= 2 else None
    study = {}
    if cal:
        cal.save(os.path.join(out, "fit.json"))
        if "calibration" in parts:
            try:
                study["calibration"] = calibration_round_trip(runs, cal, seeds, run, quick=quick)
            except ValueError as e:
                study["calibration"] = {"error": str(e)}
    run(sensitivity_jobs(parts, seeds, quick))
    if "stability" in parts:
        run([stability_job(runs, seeds[0])])
    sens = analyse_sensitivity(runs, seeds)
    study = {**summarise(main_res, sens, seeds), **study, "timing": timing(runs)}
    if cal:
        study["fit"] = {"phi_e": cal.phi_e, "phi_star": cal.phi_star, "A": cal.A, "m": cal.m, "kn": cal.kn}
    try:
        with open(os.path.join(runs, "stability", "stability.json")) as f:
            study["stability"] = json.load(f)
    except OSError:
        pass
    study_figures(out, main_res, sens)
    files.write_json(os.path.join(out, "study.json"), study)
    return write_table(study, os.path.join(out, "table.md"))


def calibrate(cal, inverted, target, fit, out, seeds, workers=2, scheduler=None, run_verification=True):
    """yade_scripts/calibrate.py: print eq 5's φe and eq 6's kn (``inverted``, from ``cal``, the
    curves in the file ``fit``) for ``target`` (φ* [deg], E50 [Pa], σ3 [Pa]); with
    ``run_verification`` run the biaxial test with them on the packings ``seeds`` (OUT/runs) and
    print what it gives. Writes OUT/calibration.json; returns its record."""
    phi_e, kn = inverted
    phi_star, e50, sigma3 = target
    A, m = cal.eq4_at(phi_e)
    print(f"eq 5: phi_e = {phi_e:.3f} deg (phi* = {phi_star} deg); eq 6: kn = {kn:.4g} Pa/m "
          f"(A = {A:.4g}, m = {m:.4f}; ks/kn = {cal.ks_ratio})", flush=True)
    record = {"target": {"phi_star_deg": phi_star, "e50_pa": e50, "sigma3_pa": sigma3},
              "inverted": {"phi_e_deg": phi_e, "kn_pa_per_m": kn, "A": A, "m": m}, "fit": fit,
              "conditioning": conditioning(cal, phi_e, len(seeds))}
    if record["conditioning"]:
        print(conditioning_text(record["conditioning"]), flush=True)
    else:
        print(f"note: {fit} has no packing-to-packing scatter: the uncertainty of E50 and kn is not known "
              "(biaxial_study.py --parts judged writes a fit with it)", flush=True)
    if kn / cal.kn > 2 or kn / cal.kn < 0.5:
        print(f"note: kn is {kn / cal.kn:.2g} x the kn of the fit ({cal.kn:g}): the paper checked f1 only for "
              "x0.5-2; refit at a kn near this one", flush=True)
    if run_verification:
        runs = os.path.join(out, "runs")
        jobs = verification_jobs(phi_e, kn, sigma3, seeds)
        run_sweep(jobs, runs, workers=workers, scheduler=scheduler)
        record.update(verify(runs, jobs, target))
        v = record.get("verified")
        if v:
            print(f"verified: phi* = {v['phi_star_deg']['mean']:.2f} deg ({100 * v['phi_star_error']:+.1f} %), "
                  f"E50 at {sigma3:g} Pa = {v['e50_pa']['mean']:.4g} Pa ({100 * v['e50_error']:+.1f} %)")
    os.makedirs(out, exist_ok=True)
    files.write_json(os.path.join(out, "calibration.json"), record)
    return record
