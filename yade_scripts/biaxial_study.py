"""`make biaxial`: seed 003's study (Murakami et al. §3) through the sweep runner.

    /usr/bin/python3 yade_scripts/biaxial_study.py --out out/biaxial [--workers 2] [--scheduler ADDR]
                     [--parts main,calibration,stiffness,discs,rate,dt,stability] [--seeds 1,2,3]
                     [--estimate] [--analyse-only] [--quick]

Runs yade_scripts/biaxial.py jobs (one directory each under OUT/runs/, resumable) with Table 2's
constants (kn = 1e8 Pa/m, ks/kn = 0.25, ρ = 2500, Δt = 0.5e-4 s, 100 %/min), every point on 3
packings (seeds), in this order (the judged comparisons first):
    main        φe = 5, 10, 15° × σ3 = 100, 200, 300, 400 Pa to 5 % strain on the paper's
                1000-disc specimen (Table 1) (Fig. 9–12, 15, 19–21)
    calibration target φ*, E50 → φe, kn (eq 5–6) → the biaxial test again (yade_scripts/calibrate.py)
    stiffness   kn ×0.5, ×2 and ks/kn ×0.5, ×2 (Fig. 13–14, 17)     } φe = 10°, σ3 = 200 Pa, to 4 %,
    dt          Δt = 0.25e-4, 1e-4 s in the test (packed at 0.5e-4) } on SMALL_DISCS = 500 discs
                (Fig. 6)                                            } (the budget: docs/BIAXIAL.md)
    discs       125, 250, 500, 1000 discs (Fig. 7–8)                } φe = 10°, σ3 = 200 Pa, to 4 %
    rate        axial strain rate 25, 50, 100 %/min (the paper's three) on 1000 discs (Fig. 5)
    stability   time steps and contact widths at which a packed specimen stays at rest
                (yade_scripts/biaxial_stability.py on the 1000-disc reference packing of the first seed)
    sideload    (not in the default) φe = 15° with σ3 on every side disc's diameter (the paper's words
                read literally), 1000 discs
then writes into OUT: study.json (every number, the CPU cost), fit.json (the eq 2/4 curves calibrate.py
reads), table.md (side by side with the paper, and the time steps) and the figures
fig05_strain_rate.png, fig06_dt.png, fig08_discs.png, fig09_11_curves.png, fig12_phi_star.png,
fig13_kn.png, fig14_ks.png, fig15_e50_sigma3.png, fig18_sigma3_over_kn.png, fig19_eq4.png,
fig20_21_A_m.png. ``--estimate`` prints the predicted CPU cost of the jobs still to run, and stops.
"""
import argparse
import json
import math
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from engines import ROOT
from engines.run.sweep import Job, read_record, run_sweep
from engines.seeds.biaxial.calibration import Calibration, eq4_e50, fit_eq4
from engines.seeds.biaxial.specimen import Curve, mohr_coulomb_fit

BIAXIAL = os.path.join(ROOT, "yade_scripts", "biaxial.py")
STABILITY = os.path.join(ROOT, "yade_scripts", "biaxial_stability.py")
PARTS = ("main", "calibration", "stiffness", "dt", "discs", "rate", "stability", "sideload")
DEFAULT_PARTS = PARTS[:-1]
PHI_E = (5.0, 10.0, 15.0)
SIGMA3 = (100.0, 200.0, 300.0, 400.0)
KN = 1e8
KS = 0.25
SENS_PHI, SENS_SIGMA3, SENS_STRAIN = 10.0, 200.0, 4.0  # the paper's sensitivity runs (§3(1)–(2), Fig. 13–14)
RATES = (25.0, 50.0)                                     # %/min, besides the reference 100 (the paper's)
DTS = (2.5e-5, 1e-4)                                     # s, besides the reference 0.5e-4
DISCS = (125, 250, 500)                                  # besides the reference 1000
KNS = (0.5e8, 2e8)
KSS = (0.125, 0.5)
KS_DT = {0.5: 3.5e-5}  # s: at stable_dt (4.08e-5 s) the 500-disc specimen did not come to rest (docs/BIAXIAL.md)
SMALL_DISCS = 500  # the specimen of the stiffness and dt sensitivities (docs/BIAXIAL.md: the budget)
MS_PER_STEP_1000 = 1.1  # CPU ms per step of a 1000-disc test, measured alone (docs/BIAXIAL.md): --estimate
PAPER = {"phi_star_deg": {15.0: 27.4}, "c_star_pa": {15.0: 0.4}, "peak_deviator_200_pa": {5.0: 140.0, 10.0: 240.0, 15.0: 330.0}}
CALIBRATION_TARGET_SIGMA3 = 250.0  # Pa: between the study's σ3, so the round trip interpolates in σ3 too


QUICK = {"n_discs": 150, "max_strain": 1.5, "strain_rate": 400.0}  # --quick: a pipeline check, not a result


def biaxial_job(name, yade=("yade", "-n"), quick=False, **options):
    """A biaxial.py job; options by their long names (phi_e=10 → --phi-e 10). ``quick`` puts
    QUICK's small specimen, short test and fast rate in place of the paper's where the job
    does not study that knob."""
    if quick:
        options = {**options, **{k: v for k, v in QUICK.items() if k not in options or k == "max_strain"}}
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


def sensitivity_name(seed, **changes):
    label = "_".join(f"{k}{v:g}" if isinstance(v, float) else f"{k}{v}" for k, v in changes.items()) or "reference"
    return f"sens_{label}_seed{seed}"


def main_jobs(seeds, quick=False):
    """The main grid: φe × the four σ3 on one packing seed per job, to 5 % strain; φe = 15° (the
    paper's φ*, c*) first."""
    return [biaxial_job(f"main_phi{p:g}_seed{s}", quick=quick, phi_e=p, sigma3=SIGMA3, max_strain=5.0, seed=s)
            for p in sorted(PHI_E, reverse=True) for s in seeds]


def ks_dt(ks_ratio):
    """The time step option of a ks/kn sensitivity run: KS_DT's, else none (stable_dt)."""
    return {"dt": KS_DT[ks_ratio]} if ks_ratio in KS_DT else {}


def sensitivity_jobs(parts, seeds, quick=False):
    """The sensitivity runs of ``parts``, the judged ones (kn, ks/kn) first."""
    jobs = []
    sens = lambda s, **c: sensitivity(s, quick=quick, **c)  # noqa: E731
    small = {"n_discs": SMALL_DISCS}
    if parts & {"stiffness", "dt", "discs"}:
        jobs += [sens(s, **small) for s in seeds]
    if "stiffness" in parts:
        jobs += [sens(s, kn=k, **small) for k in KNS for s in seeds]
        jobs += [sens(s, ks_ratio=k, **ks_dt(k), **small) for k in KSS for s in seeds]
    if parts & {"discs", "rate", "stability"}:
        jobs += [sens(s) for s in seeds]
    if "discs" in parts:
        jobs += [sens(s, n_discs=n) for n in DISCS if n != SMALL_DISCS for s in seeds]
    if "rate" in parts:
        jobs += [sens(s, strain_rate=r) for r in RATES for s in seeds]
    if "dt" in parts:
        jobs += [sens(s, dt=dt, packing_dt=5e-5, **small) for dt in sorted(DTS, reverse=True) for s in seeds]
    if "sideload" in parts:
        jobs += [biaxial_job(f"sideload_diameter_seed{s}", quick=quick, phi_e=15.0, sigma3=(100.0, 400.0),
                             max_strain=5.0, side_load="diameter", seed=s) for s in seeds]
    return jobs


def stability_job(runs, seed):
    """biaxial_stability.py on the reference packing of ``seed`` (it must have run)."""
    block = os.path.join(os.path.abspath(runs), sensitivity_name(seed), f"packing_sigma3_{SENS_SIGMA3:g}")
    return Job("stability", ("yade", "-n", "-x", STABILITY, "--block", block, "--out", "{out}"))


# ---- the cost -------------------------------------------------------------------------------

PACK_STEPS = (10000, 1500)  # packing steps at Δt = 0.5e-4 s: to the first σ3, then to each further one
EQUILIBRIUM_STEPS = 4500    # preliminary equilibrium per σ3 at Δt = 0.5e-4 s (3000–5500 measured)


def predicted_cpu_s(job):
    """Predicted CPU seconds of a biaxial.py or biaxial_stability.py job: its steps × MS_PER_STEP_1000
    × discs / 1000. Steps: PACK_STEPS and EQUILIBRIUM_STEPS (scaled to the job's Δt), and the
    compression's max_strain / rate / Δt plus the ramp, per σ3."""
    from engines.seeds.biaxial.cem_contact import CemContact, stable_dt
    from engines.seeds.biaxial.periodic import table1_radii
    from engines.seeds.biaxial.specimen import BiaxialSettings
    from yade_scripts.biaxial import parser
    from yade_scripts.biaxial_stability import CASES, REST_TIME

    script = job.argv[job.argv.index("-x") + 1]
    if script == STABILITY:
        return sum(REST_TIME / dt for *_, dt in CASES) * MS_PER_STEP_1000 / 1000
    a = parser().parse_args([x.replace("{out}", ".") for x in job.argv[job.argv.index("-x") + 2:]])
    dt = a.dt or stable_dt(table1_radii(a.n_discs), CemContact(kn=a.kn, ks_ratio=a.ks_ratio, phi_e_deg=a.phi_e))
    scale = 5e-5 / (a.packing_dt or dt), 5e-5 / dt
    steps = (PACK_STEPS[0] + PACK_STEPS[1] * (len(a.sigma3) - 1)) * scale[0]
    steps += len(a.sigma3) * (EQUILIBRIUM_STEPS * scale[1] + (a.max_strain / 100) / (a.strain_rate / 6000) / dt
                              + BiaxialSettings.ramp_time / dt)
    return steps * MS_PER_STEP_1000 / 1000 * a.n_discs / 1000


def estimate(jobs, runs, log=print):
    """Print (``log``; None = quiet) the predicted CPU minutes of the jobs not yet done; returns
    their sum [s]."""
    from engines.run.sweep import is_done

    log = log or (lambda *a: None)
    todo = [j for j in jobs if not is_done(j, runs)]
    cost = {j.name: predicted_cpu_s(j) for j in todo}
    for name, c in cost.items():
        log(f"  {name:<48} {c / 60:6.1f} core-min")
    log(f"{len(todo)} of {len(jobs)} jobs to run: {sum(cost.values()) / 60:.1f} core-min predicted "
        f"({MS_PER_STEP_1000} ms per 1000-disc step)")
    return sum(cost.values())


# ---- reading the runs ------------------------------------------------------------------------

def read_run(runs, name):
    """(summary, {σ3: Curve}) of a finished run, or (None, {}) if it failed without results."""
    path = os.path.join(runs, name)
    try:
        with open(os.path.join(path, "summary.json")) as f:
            summary = json.load(f)
    except OSError:
        return None, {}
    d = np.loadtxt(os.path.join(path, "curves.csv"), delimiter=",", skiprows=1, ndmin=2)
    curves = {}
    for s3 in np.unique(d[:, 0]):
        m = d[:, 0] == s3
        curves[float(s3)] = Curve(float(s3), d[m, 1], d[m, 3], d[m, 4], d[m, 5], d[m, 6] - d[m, 1])
    return summary, curves


def job_status(runs, name):
    try:
        with open(os.path.join(runs, name, "job.json")) as f:
            rec = json.load(f)
    except OSError:
        return {"status": "missing"}
    return {k: rec.get(k) for k in ("status", "wall_s", "stderr_tail")}


def _mean_sd(values):
    v = np.asarray([x for x in values if x is not None and np.isfinite(x)], float)
    if len(v) == 0:
        return {"mean": None, "sd": None, "n": 0, "values": []}
    return {"mean": float(v.mean()), "sd": float(v.std(ddof=1)) if len(v) > 1 else 0.0, "n": int(len(v)),
            "values": v.tolist()}


def analyse_main(runs, seeds):
    """φ*, c*, peaks and E50 per φe and seed; the eq 4 fits."""
    out = {"per_phi_e": {}, "points": [], "fits": {}, "rows": []}
    for p in PHI_E:
        per = {"phi_star_deg": [], "c_star_pa": [], "peak": {s3: [] for s3 in SIGMA3}, "e50": {s3: [] for s3 in SIGMA3},
               "peak_strain": {s3: [] for s3 in SIGMA3}, "peak_at_end": 0, "curves": {}}
        for s in seeds:
            summary, curves = read_run(runs, f"main_phi{p:g}_seed{s}")
            if summary is None or "error" in summary:
                continue
            s3s = sorted(curves)
            phi, c_star = mohr_coulomb_fit(s3s, [s3 + curves[s3].peak()[1] for s3 in s3s])
            per["phi_star_deg"].append(phi)
            per["c_star_pa"].append(c_star)
            out["rows"].append({"phi_e_deg": p, "seed": s, "phi_star_deg": phi, "c_star_pa": c_star})
            per["curves"][s] = curves
            for s3, c in sorted(curves.items()):  # peak and E50 from the records (engines.seeds.biaxial.specimen)
                eps_f, q_f = c.peak()
                per["peak"][s3].append(q_f)
                per["e50"][s3].append(c.e50())
                per["peak_strain"][s3].append(eps_f)
                per["peak_at_end"] += int(eps_f >= c.strain[-1] - 0.001)
                out["points"].append({"phi_e_deg": p, "seed": s, "sigma3_pa": s3, "kn": KN, "e50_pa": c.e50(),
                                      "peak_deviator_pa": q_f})
        pts = [x for x in out["points"] if x["phi_e_deg"] == p]
        if len(pts) >= 2:
            out["fits"][p] = fit_eq4([x["sigma3_pa"] for x in pts], [x["kn"] for x in pts], [x["e50_pa"] for x in pts])
        out["per_phi_e"][p] = per
    return out


def phi_one_circle(q_f, sigma3):
    """φ [deg] of the line through the origin tangent to one Mohr circle (c* = 0)."""
    return math.degrees(math.asin(q_f / (q_f + 2 * sigma3)))


def analyse_sensitivity(runs, seeds):
    """Peak, E50 and φ (line through the origin, c* = 0) at σ3 = 200 Pa for each knob's value
    (the reference value's runs are those of the knob's specimen: 1000 or SMALL_DISCS discs)."""
    small = {"n_discs": SMALL_DISCS}
    groups = {"strain_rate_pct_min": ("strain_rate", RATES, 100.0, lambda v: {}, {}),
              "dt_s": ("dt", DTS, 5e-5, lambda v: {"packing_dt": 5e-5}, small),
              "n_discs": ("n_discs", DISCS, 1000, lambda v: {}, {}),
              "kn_pa_per_m": ("kn", KNS, KN, lambda v: {}, small), "ks_ratio": ("ks_ratio", KSS, KS, ks_dt, small)}
    out = {}
    for label, (opt, values, ref, extra, base) in groups.items():
        res = {}
        for v in sorted((*values, ref)):
            cells = {"peak_deviator_pa": [], "e50_pa": [], "phi0_deg": [], "failed": [], "curves": [], "wall_s": []}
            for s in seeds:
                changes = base if v == ref else {opt: v, **extra(v), **base}
                name = sensitivity_name(s, **changes)
                summary, curves = read_run(runs, name)
                st = job_status(runs, name)
                if st["status"] != "ok" or summary is None or "error" in summary:
                    cells["failed"].append({"seed": s, "status": st["status"],
                                            "reason": (st.get("stderr_tail") or "").strip().splitlines()[-1:]})
                    continue
                c = curves[SENS_SIGMA3]
                q_f = c.peak()[1]
                cells["peak_deviator_pa"].append(q_f)
                cells["e50_pa"].append(c.e50())
                cells["phi0_deg"].append(phi_one_circle(q_f, SENS_SIGMA3))
                cells["curves"].append(c)
                cells["wall_s"].append(summary["wall_s"])
            res[v] = cells
        out[label] = res
    return out


# ---- the study -------------------------------------------------------------------------------

def calibration_from(main):
    """fit.json: φ*(φe) means and A(φe), m(φe) (eq 2, 4) from the main grid."""
    pe = [p for p in PHI_E if p in main["fits"] and main["per_phi_e"][p]["phi_star_deg"]]
    return Calibration(pe, [float(np.mean(main["per_phi_e"][p]["phi_star_deg"])) for p in pe],
                       [main["fits"][p][0] for p in pe], [main["fits"][p][1] for p in pe], KN, KS)


def calibration_target(cal):
    """A target inside the studied range and off its grid: φ* halfway between the φe = 10° and
    15° grounds, and the E50 at σ3 = 250 Pa that eq 4 gives there for kn = 1.5e8 Pa/m."""
    phi_star = 0.5 * (cal.phi_star[-2] + cal.phi_star[-1])
    A, m = cal.eq4_at(cal.phi_e_for(phi_star))
    return phi_star, float(eq4_e50(CALIBRATION_TARGET_SIGMA3, 1.5e8, A, m)), CALIBRATION_TARGET_SIGMA3


def _num(x, fmt="{:.1f}"):
    return "–" if x is None else fmt.format(x)


def _ms(stat, fmt="{:.1f}", unit=""):
    """'mean ± s.d. (n)' of a _mean_sd record, '–' when nothing finished."""
    if not stat or stat["mean"] is None:
        return "–"
    return f"{fmt.format(stat['mean'])} ± {fmt.format(stat['sd'])}{unit} (n = {stat['n']})"


SENS_ROWS = (("strain_rate_pct_min", "strain rate [%/min] (Fig. 5)", "1000"),
             ("dt_s", "Δt [s] (Fig. 6)", f"{SMALL_DISCS}"), ("n_discs", "discs (Fig. 8)", "—"),
             ("kn_pa_per_m", "kn [Pa/m] (Fig. 13)", f"{SMALL_DISCS}"), ("ks_ratio", "ks/kn (Fig. 14)", f"{SMALL_DISCS}"))


def write_table(study, path):
    """The side-by-side tables with the paper (markdown): main grid, sensitivities, calibration,
    time steps, cost."""
    m, sens, cal = study["main"], study["sensitivity"], study.get("calibration")
    paper_q = PAPER["peak_deviator_200_pa"]
    lines = ["Main grid (1000 discs, 100 %/min, 5 % strain; mean ± s.d. over packings):", "",
             "| φe | φ* paper | φ* model | c* paper | c* model [Pa] | peak q at σ3 = 200 Pa, paper | model [Pa] |"
             " φ at σ3 = 200 Pa, c* = 0 | eq 4: A | m |", "|---|---|---|---|---|---|---|---|---|---|"]
    for p in PHI_E:
        k = f"{p}"
        eq4 = m["eq4"].get(k)
        q200 = m["peak_deviator_pa"].get(k, {}).get("200.0")
        lines.append(f"| {p:g}° | {PAPER['phi_star_deg'].get(p, '–')} | {_ms(m['phi_star_deg'].get(k), unit='°')} | "
                     f"{PAPER['c_star_pa'].get(p, '–')} | {_ms(m['c_star_pa'].get(k))} | ≈ {paper_q[p]:g} | "
                     f"{_ms(q200, '{:.0f}')} | {_ms(q200 and _mean_sd([phi_one_circle(q, 200.0) for q in q200['values']]), unit='°')} | "
                     f"{_num(eq4 and eq4['A'], '{:.3g}')} | {_num(eq4 and eq4['m'], '{:.3f}')} |")
    ref = sens.get("n_discs", {}).get("1000")
    if ref and ref["peak_deviator_pa"]["n"]:
        lines += ["", f"φe = {SENS_PHI:g}° at σ3 = {SENS_SIGMA3:g} Pa from the sensitivity reference runs (1000 discs packed "
                  f"straight to {SENS_SIGMA3:g} Pa, {SENS_STRAIN:g} % strain): peak q = "
                  f"{_ms(ref['peak_deviator_pa'], '{:.0f}')} Pa (paper ≈ {paper_q[SENS_PHI]:g}), φ (c* = 0) = "
                  f"{_ms(ref['phi0'], unit='°')}, E50 = {_ms(ref['e50_pa'], '{:.3g}')} Pa."]
    lines += ["", "Peak deviator and E50 against σ3 (Fig. 9–11, 15):", "",
              "| φe | σ3 [Pa] | peak q [Pa] | strain at peak [%] | E50 [Pa] |", "|---|---|---|---|---|"]
    for p in PHI_E:
        for s3 in SIGMA3:
            k, j = f"{p}", f"{s3}"
            eps = m["peak_strain"].get(k, {}).get(j)
            eps = eps and {**eps, **{x: eps[x] and 100 * eps[x] for x in ("mean", "sd")}}
            lines.append(f"| {p:g}° | {s3:g} | {_ms(m['peak_deviator_pa'].get(k, {}).get(j), '{:.0f}')} | "
                         f"{_ms(eps, '{:.2f}')} | {_ms(m['e50_pa'].get(k, {}).get(j), '{:.3g}')} |")
    lines += ["", f"Sensitivities (φe = {SENS_PHI:g}°, σ3 = {SENS_SIGMA3:g} Pa, {SENS_STRAIN:g} % strain; "
              "φ from the one circle with c* = 0):", "",
              "| knob | discs | value | peak q [Pa] | E50 [Pa] | φ (c* = 0) | failed |", "|---|---|---|---|---|---|---|"]
    for key, label, discs in SENS_ROWS:
        for v, c in sens.get(key, {}).items():
            lines.append(f"| {label} | {v if key == 'n_discs' else discs} | {v} | {_ms(c['peak_deviator_pa'], '{:.0f}')} | "
                         f"{_ms(c['e50_pa'], '{:.3g}')} | {_ms(c['phi0'], unit='°')} | {len(c['failed']) or ''} |")
    if cal and cal.get("verified"):
        v, t = cal["verified"], cal["target"]
        lines += ["", "Calibration round trip (eq 5–6, then the biaxial test again, 1000 discs):", "",
                  "| | target | inverted | verified (mean of packings) | error |", "|---|---|---|---|---|",
                  f"| φ* | {t['phi_star_deg']:.2f}° | φe = {cal['inverted']['phi_e_deg']:.2f}° | "
                  f"{v['phi_star_deg']['mean']:.2f}° ({', '.join(f'{x:.2f}' for x in v['phi_star_deg']['values'])}) | "
                  f"{100 * v['phi_star_error']:+.1f} % |",
                  f"| E50 at σ3 = {t['sigma3_pa']:g} Pa | {t['e50_pa']:.4g} Pa | kn = {cal['inverted']['kn_pa_per_m']:.4g} Pa/m | "
                  f"{v['e50_pa']['mean']:.4g} Pa ({', '.join(f'{x:.4g}' for x in v['e50_pa']['values'])}) | "
                  f"{100 * v['e50_error']:+.1f} % |"]
    elif cal:
        why = cal.get("error") or "no result from " + ", ".join(f["job"] for f in cal.get("failed", []))
        inv = cal.get("inverted")
        lines += ["", "Calibration round trip: not verified: " + why + (
            f" (eq 5–6 gave φe = {inv['phi_e_deg']:.2f}°, kn = {inv['kn_pa_per_m']:.4g} Pa/m for φ* = "
            f"{cal['target']['phi_star_deg']:.2f}°, E50 = {cal['target']['e50_pa']:.4g} Pa at σ3 = "
            f"{cal['target']['sigma3_pa']:g} Pa)" if inv else "")]
    if study.get("stability"):
        st = study["stability"]
        lines += ["", f"Time steps ({st['n_discs']} discs packed at 0.5e-4 s, left at rest {st['rest_time_s']:g} s):", "",
                  "| contact width / harmonic-mean radius | kn [Pa/m] | ks/kn | Δt [s] | unbalanced force ratio | "
                  "σ change over the last half | outcome |", "|---|---|---|---|---|---|---|"]
        lines += [f"| {c['width_factor']:g} | {c['kn_pa_per_m']:.0e} | {c['ks_ratio']:g} | {c['dt_s']:.2e} | "
                  f"{c['unbalanced']:.1e} | {100 * c['stress_change']:.2f} % | {c['outcome']} |" for c in st["cases"]]
    t = study.get("timing")
    if t:
        lines += ["", f"Cost: {t['jobs']} jobs, {t['cpu_min']:.1f} CPU minutes recorded ({t['jobs_with_cpu']} jobs), "
                  f"{t['wall_min']:.1f} wall minutes; {_ms(t['ms_cpu_per_step_1000_discs'], '{:.2f}')} CPU ms per "
                  "1000-disc step."]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return "\n".join(lines)


def figures(out, main, sens):
    from postproc.biaxial_plots import (
        plot_A_m,
        plot_e50_sigma3,
        plot_eq4,
        plot_phi_star,
        plot_sensitivity,
        plot_sigma3_kn_collapse,
        plot_study_curves,
    )

    if main["rows"]:
        plot_phi_star(main["rows"], {15.0: 27.4}, os.path.join(out, "fig12_phi_star.png"))
        plot_e50_sigma3(main["points"], os.path.join(out, "fig15_e50_sigma3.png"))
        plot_study_curves(main["per_phi_e"], os.path.join(out, "fig09_11_curves.png"))
    if main["fits"]:
        kn_points = [{"phi_e_deg": SENS_PHI, "sigma3_pa": SENS_SIGMA3, "kn": float(k), "e50_pa": e}
                     for k, c in sens["kn_pa_per_m"].items() for e in c["e50_pa"] if float(k) != KN]
        plot_eq4(main["points"], main["fits"], os.path.join(out, "fig19_eq4.png"), extra=kn_points)
        plot_A_m(main["fits"], os.path.join(out, "fig20_21_A_m.png"))
    pairs = {}  # Fig. 18: the kn runs at σ3 = 200 Pa against the main grid's φe = 10° at the same σ3/kn
    for kn, s3 in ((2e8, 100.0), (0.5e8, 400.0)):
        main_curves = [c[s3] for c in main["per_phi_e"].get(SENS_PHI, {}).get("curves", {}).values() if s3 in c]
        kn_curves = sens["kn_pa_per_m"].get(kn, {}).get("curves", [])
        if main_curves and kn_curves:
            pairs[s3 / KN] = {f"kn = {KN:.0e}, σ3 = {s3:g} Pa, 1000 discs": main_curves,
                              f"kn = {kn:.0e}, σ3 = {SENS_SIGMA3:g} Pa, {SMALL_DISCS} discs": kn_curves}
    if pairs:
        plot_sigma3_kn_collapse(pairs, os.path.join(out, "fig18_sigma3_over_kn.png"))
    for key, fname, title, label in [
            ("strain_rate_pct_min", "fig05_strain_rate.png", "axial strain rate, 1000 discs (Fig. 5)", "strain rate [%/min]"),
            ("dt_s", "fig06_dt.png", f"time step, {SMALL_DISCS} discs (Fig. 6)", "Δt [s]"),
            ("n_discs", "fig08_discs.png", "number of discs (Fig. 8)", "discs"),
            ("kn_pa_per_m", "fig13_kn.png", f"kn, {SMALL_DISCS} discs (Fig. 13)", "kn [Pa/m]"),
            ("ks_ratio", "fig14_ks.png", f"ks/kn, {SMALL_DISCS} discs (Fig. 14)", "ks/kn")]:
        groups = {float(v): c["curves"] for v, c in sens[key].items() if c["curves"]}
        failed = {float(v): len(c["failed"]) for v, c in sens[key].items() if c["failed"]}
        if groups:
            plot_sensitivity(groups, os.path.join(out, fname),
                             f"φe = {SENS_PHI:g}°, σ3 = {SENS_SIGMA3:g} Pa: {title}", label, failed)


def summarise(main, sens, seeds):
    """study.json's numbers (curves left out)."""
    m = {"phi_star_deg": {}, "c_star_pa": {}, "peak_deviator_pa": {}, "e50_pa": {}, "peak_strain": {}, "eq4": {},
         "peaks_at_end_of_test": {}}
    for p, per in main["per_phi_e"].items():
        m["phi_star_deg"][f"{p}"] = _mean_sd(per["phi_star_deg"])
        m["c_star_pa"][f"{p}"] = _mean_sd(per["c_star_pa"])
        m["peak_deviator_pa"][f"{p}"] = {f"{s3}": _mean_sd(v) for s3, v in per["peak"].items()}
        m["e50_pa"][f"{p}"] = {f"{s3}": _mean_sd(v) for s3, v in per["e50"].items()}
        m["peak_strain"][f"{p}"] = {f"{s3}": _mean_sd(v) for s3, v in per["peak_strain"].items()}
        m["peaks_at_end_of_test"][f"{p}"] = per["peak_at_end"]
        if p in main["fits"]:
            m["eq4"][f"{p}"] = {"A": main["fits"][p][0], "m": main["fits"][p][1]}
    s = {}
    for key, res in sens.items():
        s[key] = {f"{v:g}": {"peak_deviator_pa": _mean_sd(c["peak_deviator_pa"]), "e50_pa": _mean_sd(c["e50_pa"]),
                             "phi0": _mean_sd(c["phi0_deg"]), "wall_s": _mean_sd(c["wall_s"]), "failed": c["failed"]}
                  for v, c in res.items()}
    return {"seeds": list(seeds), "main": m, "sensitivity": s}


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
            "ms_cpu_per_step_1000_discs": _mean_sd(per_step), "per_job": jobs}


def calibration_jobs(cal, seeds, quick=False):
    """The verification runs of calibration_target (``cal`` None: a stand-in φe = 12.5°,
    kn = 1.5e8 Pa/m, for --estimate before the main grid has run); (target, (φe, kn), jobs)."""
    from yade_scripts.calibrate import verification_jobs

    target = calibration_target(cal) if cal else (None, None, CALIBRATION_TARGET_SIGMA3)
    phi_e, kn = cal.invert(*target) if cal else (12.5, 1.5e8)
    return target, (phi_e, kn), verification_jobs(phi_e, kn, target[2], seeds, prefix="calibration", quick=quick)


def calibration_round_trip(runs, cal, seeds, run, quick=False):
    """eq 5–6 for calibration_target, the verification runs (``run(jobs)``), and the record
    comparing what they give with the target."""
    from yade_scripts.calibrate import verify

    target, (phi_e, kn), jobs = calibration_jobs(cal, seeds, quick)
    run(jobs)
    rec = verify(runs, jobs, target)
    rec.update(target={"phi_star_deg": target[0], "e50_pa": target[1], "sigma3_pa": target[2]},
               inverted={"phi_e_deg": phi_e, "kn_pa_per_m": kn})
    return rec


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/biaxial", help="output directory (runs in OUT/runs)")
    ap.add_argument("--workers", type=int, default=2, help="local processes (default 2)")
    ap.add_argument("--scheduler", help="Dask scheduler address: run the jobs on that cluster")
    ap.add_argument("--parts", default=",".join(DEFAULT_PARTS),
                    help=f"comma-separated parts of the study, of {', '.join(PARTS)} (default: all but sideload)")
    ap.add_argument("--seeds", default="1,2,3", help="packings per point (placement seeds)")
    ap.add_argument("--estimate", action="store_true", help="print the predicted CPU cost of what is to run, and stop")
    ap.add_argument("--analyse-only", action="store_true", help="do not run anything, analyse what is there")
    ap.add_argument("--quick", action="store_true",
                    help="150 discs, 1.5 %% strain, 400 %%/min: checks the pipeline in minutes (numbers meaningless)")
    a = ap.parse_args(argv)
    parts = set(a.parts.split(","))
    unknown = parts - set(PARTS)
    if unknown:
        ap.error(f"--parts: unknown {', '.join(sorted(unknown))}")
    seeds = [int(s) for s in a.seeds.split(",")]
    runs = os.path.join(a.out, "runs")

    def run(jobs):
        if jobs and not a.analyse_only:
            run_sweep(jobs, runs, workers=a.workers, scheduler=a.scheduler)

    main_res = analyse_main(runs, seeds)
    cal = calibration_from(main_res) if len(main_res["fits"]) >= 2 else None
    if a.estimate:
        jobs = (main_jobs(seeds, a.quick) if "main" in parts else []) + sensitivity_jobs(parts, seeds, a.quick)
        jobs += calibration_jobs(cal, seeds, a.quick)[2] if "calibration" in parts else []
        estimate(jobs + ([stability_job(runs, seeds[0])] if "stability" in parts else []), runs)
        return
    if "main" in parts:
        run(main_jobs(seeds, a.quick))
        main_res = analyse_main(runs, seeds)
        cal = calibration_from(main_res) if len(main_res["fits"]) >= 2 else None
    study = {}
    if cal:
        cal.save(os.path.join(a.out, "fit.json"))
        if "calibration" in parts:
            try:
                study["calibration"] = calibration_round_trip(runs, cal, seeds, run, quick=a.quick)
            except ValueError as e:
                study["calibration"] = {"error": str(e)}
    run(sensitivity_jobs(parts, seeds, a.quick))
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
    figures(a.out, main_res, sens)
    with open(os.path.join(a.out, "study.json"), "w") as f:
        json.dump(study, f, indent=1)
    print(write_table(study, os.path.join(a.out, "table.md")))


if __name__ == "__main__":
    main()
