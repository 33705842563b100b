"""Seed 003's judged points on the default reading (docs/BIAXIAL.md, "The judged points"): the
command `yade -n -x yade_scripts/biaxial.py --phi-e P --sigma3 100,200,300 --out DIR` at φe = 15°
and 5° (and 10°, so that the eq 2 curve f1 has its middle) on JUDGED_SEEDS packings; φ*, c* (Mohr–Coulomb over the three circles of a packing), peak
q, E50 and the porosity after packing, as means with 95 % intervals over the packings (Student's
t, engines.studies.ensemble.statistics) beside the paper and the judged tolerances; the eq 2/4
curves they give (Calibration, with the packing-to-packing scatter of E50 and φ*).
No YADE: engines.run.biaxial_study runs the jobs, postproc.biaxial_plots.plot_judged draws the figure.
"""
import math

import numpy as np

from engines import files
from engines.seeds.biaxial.calibration import Calibration, fit_eq4
from engines.seeds.biaxial.specimen import mohr_coulomb_fit
from engines.seeds.biaxial.study import KN, KS, PAPER, calibration_lines, job_status, read_run
from engines.studies.ensemble import CONFIDENCE, statistics, t_half_width

JUDGED_PHI = (15.0, 5.0, 10.0)         # deg, in the order they run: the judged two, then the middle of f1 (eq 2)
JUDGED_SIGMA3 = (100.0, 200.0, 300.0)  # Pa, the judged command's
JUDGED_SEEDS = (1, 2, 3, 4, 5)         # packings (placement seeds) per φe
PHI_TOLERANCE = 3.0                    # deg: φ* within 3° of the paper's at φe = 15°
PEAK_TOLERANCE = 0.25                  # peak q at 200 Pa within 25 % of the paper's


def judged_name(phi_e, seed):
    return f"judged_phi{phi_e:g}_seed{seed}"


def interval(values):
    """{"n", "mean", "low", "high", "values"} of the finite ``values``: mean and its 95 % interval
    (statistics: mean ∓ t(0.975, n − 1) s/√n); None for what n does not allow (mean: n = 0,
    interval: n < 2)."""
    v = [float(x) for x in values if x is not None and math.isfinite(x)]
    st = statistics(np.asarray(v, float)) if v else None
    val = lambda k: None if st is None or not np.isfinite(st[k]) else float(st[k])  # noqa: E731
    return {"n": len(v), "mean": val("mean"), "low": val("ci95_low"), "high": val("ci95_high"), "values": v}


def read_judged(runs, phi_e, seeds):
    """Per packing seed whose run finished: φ* [deg], c* [Pa], {σ3: (peak q [Pa], E50 [Pa],
    strain at the peak [-])}, porosity after packing (mean over its σ3); and the failed jobs."""
    out, failed = [], []
    for s in seeds:
        name = judged_name(phi_e, s)
        summary, curves = read_run(runs, name)
        if summary is None or "error" in summary or sorted(curves) != list(JUDGED_SIGMA3):
            if job_status(runs, name)["status"] == "failed":
                failed.append(name)
            continue
        per = {s3: (c.peak()[1], c.e50(), c.peak()[0]) for s3, c in curves.items()}
        phi, c_star = mohr_coulomb_fit(list(per), [s3 + p[0] for s3, p in per.items()])
        out.append({"seed": s, "phi_star_deg": phi, "c_star_pa": c_star, "per_sigma3": per,
                    "porosity": float(np.mean([1 - p["solid_fraction"] for p in summary["packings"]]))})
    return out, failed


def log_sd(values_by_group):
    """Pooled standard deviation of ln(value) within groups (e.g. E50 of the packings at each σ3):
    the packing-to-packing scatter as a factor exp(s); None with no group of two."""
    dev, dof = 0.0, 0
    for v in values_by_group:
        x = np.log([a for a in v if a and math.isfinite(a) and a > 0])
        if len(x) >= 2:
            dev += float(np.sum((x - x.mean()) ** 2))
            dof += len(x) - 1
    return math.sqrt(dev / dof) if dof else None


def analyse_judged(runs, seeds=JUDGED_SEEDS):
    """The judged table's numbers per φe (intervals over the finished packings), the judged
    criteria, and the Calibration of the eq 2/4 curves (None with fewer than two φe fitted)."""
    rows, failed, fits = [], [], {}
    for p in JUDGED_PHI:
        packs, bad = read_judged(runs, p, seeds)
        failed += bad
        row = {"phi_e_deg": p, "seeds": [x["seed"] for x in packs],
               "phi_star_deg": interval([x["phi_star_deg"] for x in packs]),
               "c_star_pa": interval([x["c_star_pa"] for x in packs]),
               "porosity": interval([x["porosity"] for x in packs]), "per_sigma3": {}}
        for s3 in JUDGED_SIGMA3:
            row["per_sigma3"][f"{s3:g}"] = {key: interval([x["per_sigma3"][s3][k] for x in packs])
                                            for k, key in enumerate(("peak_pa", "e50_pa", "peak_strain"))}
        row["e50_log_sd"] = log_sd([[x["per_sigma3"][s3][1] for x in packs] for s3 in JUDGED_SIGMA3])
        if len(packs) >= 2:
            pts = [(s3, x["per_sigma3"][s3][1]) for x in packs for s3 in JUDGED_SIGMA3]
            fits[p] = fit_eq4([a for a, _ in pts], [KN] * len(pts), [b for _, b in pts])
            row["eq4"] = {"A": fits[p][0], "m": fits[p][1]}
        rows.append(row)
    res = {"seeds": list(seeds), "sigma3_pa": list(JUDGED_SIGMA3), "confidence": CONFIDENCE, "rows": rows,
           "jobs_failed": sorted(failed), "criteria": criteria(rows)}
    cal = calibration(rows, fits)
    return res, cal


def calibration(rows, fits):
    """Calibration (eq 2, 4) of the rows with an eq 4 fit, φe increasing, with the scatter."""
    rows = sorted((r for r in rows if r["phi_e_deg"] in fits), key=lambda r: r["phi_e_deg"])
    if len(rows) < 2:
        return None
    return Calibration([r["phi_e_deg"] for r in rows], [r["phi_star_deg"]["mean"] for r in rows],
                       [fits[r["phi_e_deg"]][0] for r in rows], [fits[r["phi_e_deg"]][1] for r in rows], KN, KS,
                       e50_log_sd=[r["e50_log_sd"] for r in rows],
                       phi_star_sd=[float(np.std(r["phi_star_deg"]["values"], ddof=1)) for r in rows],
                       packings=[r["phi_star_deg"]["n"] for r in rows])


def criteria(rows):
    """The issue's judged criteria, each {"what", "paper", "model" (interval), "met" (by the mean),
    "paper_inside" (the paper's value within the model's interval; None without one)}: φ* within
    PHI_TOLERANCE of 27.4° at φe = 15°; peak q at 200 Pa within PEAK_TOLERANCE of the paper's at
    15° and 5°; φ* rising with φe (the difference of the means and its interval from the two
    packings' sets, Welch's t at CONFIDENCE)."""
    by = {r["phi_e_deg"]: r for r in rows}
    out = []
    if 15.0 in by:
        m = by[15.0]["phi_star_deg"]
        paper = PAPER["phi_star_deg"][15.0]
        out.append({"what": f"φ* at φe = 15° within {PHI_TOLERANCE:g}° of {paper}°", "paper": paper, "model": m,
                    "met": m["mean"] is not None and abs(m["mean"] - paper) <= PHI_TOLERANCE,
                    "paper_inside": inside(paper, m)})
    for p in (15.0, 5.0):
        if p in by:
            m = by[p]["per_sigma3"]["200"]["peak_pa"]
            paper = PAPER["peak_deviator_200_pa"][p]
            out.append({"what": f"peak q at σ3 = 200 Pa, φe = {p:g}°, within {100 * PEAK_TOLERANCE:g} % of {paper:g} Pa",
                        "paper": paper, "model": m,
                        "met": m["mean"] is not None and abs(m["mean"] / paper - 1) <= PEAK_TOLERANCE,
                        "paper_inside": inside(paper, m)})
    if 15.0 in by and 5.0 in by:
        d = difference(by[15.0]["phi_star_deg"]["values"], by[5.0]["phi_star_deg"]["values"])
        out.append({"what": "φ* rising with φe: φ*(15°) − φ*(5°) > 0 beyond its interval", "paper": None,
                    "model": d, "met": d["low"] is not None and d["low"] > 0, "paper_inside": None})
    return out


def inside(value, st):
    """Is ``value`` within the interval record ``st``? None when it has no interval."""
    return None if st["low"] is None else bool(st["low"] <= value <= st["high"])


def difference(a, b):
    """Mean of a − mean of b with its interval at CONFIDENCE (Welch: Student's t with the
    Welch–Satterthwaite degrees of freedom): {"mean", "low", "high"}; None bounds below 2 values each."""
    from scipy import stats

    a, b = np.asarray(a, float), np.asarray(b, float)
    d = {"mean": float(a.mean() - b.mean()) if len(a) and len(b) else None, "low": None, "high": None}
    if len(a) >= 2 and len(b) >= 2:
        va, vb = a.var(ddof=1) / len(a), b.var(ddof=1) / len(b)
        dof = (va + vb) ** 2 / (va ** 2 / (len(a) - 1) + vb ** 2 / (len(b) - 1))
        half = float(stats.t.ppf(0.5 + CONFIDENCE / 2, dof) * math.sqrt(va + vb))
        d.update(low=d["mean"] - half, high=d["mean"] + half)
    return d


def _ci(st, fmt="{:.1f}", unit=""):
    """'mean [low, high] (n = N)' of an interval record, '–' when nothing finished."""
    if not st or st["mean"] is None:
        return "–"
    if st.get("low") is None:
        return f"{fmt.format(st['mean'])}{unit} (n = {st.get('n', 1)})"
    n = f" (n = {st['n']})" if "n" in st else ""
    return f"{fmt.format(st['mean'])}{unit} [{fmt.format(st['low'])}, {fmt.format(st['high'])}]{n}"


def write_judged(res, json_path, md_path):
    """judged.json and the markdown tables of analyse_judged's record; returns the markdown."""
    files.write_json(json_path, res)
    paper_q = PAPER["peak_deviator_200_pa"]
    lines = [f"Judged points (1000 discs, σ3 = {', '.join(f'{v:g}' for v in JUDGED_SIGMA3)} Pa from one placement per "
             f"packing, 6 % strain; mean [{100 * res['confidence']:g} % interval, Student's t] over packings"
             + (f"; failed: {', '.join(res['jobs_failed'])}" if res["jobs_failed"] else "") + "):", "",
             "| φe | φ* paper | φ* model | c* paper | c* model [Pa] | porosity after packing | eq 4: A | m |",
             "|---|---|---|---|---|---|---|---|"]
    rows = sorted(res["rows"], key=lambda r: r["phi_e_deg"])
    for r in rows:
        p = r["phi_e_deg"]
        eq4 = r.get("eq4")
        lines.append(f"| {p:g}° | {PAPER['phi_star_deg'].get(p, '–')} | {_ci(r['phi_star_deg'], unit='°')} | "
                     f"{PAPER['c_star_pa'].get(p, '–')} | {_ci(r['c_star_pa'])} | {_ci(r['porosity'], '{:.4f}')} | "
                     f"{'–' if not eq4 else format(eq4['A'], '.3g')} | {'–' if not eq4 else format(eq4['m'], '.3f')} |")
    lines += ["", "| φe | σ3 [Pa] | peak q paper [Pa] | peak q model [Pa] | strain at peak [%] | E50 model [Pa] |",
              "|---|---|---|---|---|---|"]
    for r in rows:
        for s3, c in r["per_sigma3"].items():
            eps = {k: (v if k in ("n", "values") or v is None else 100 * v) for k, v in c["peak_strain"].items()}
            paper = f"≈ {paper_q[r['phi_e_deg']]:g}" if s3 == "200" else "–"
            lines.append(f"| {r['phi_e_deg']:g}° | {s3} | {paper} | {_ci(c['peak_pa'], '{:.0f}')} | "
                         f"{_ci(eps, '{:.2f}')} | {_ci(c['e50_pa'], '{:.3g}')} |")
    yes_no = {True: "yes", False: "no", None: "–"}
    lines += ["", "| judged criterion | paper | model | met (by the mean) | paper inside the model's interval |",
              "|---|---|---|---|---|"]
    for c in res["criteria"]:
        lines.append(f"| {c['what']} | {'–' if c['paper'] is None else c['paper']} | {_ci(c['model'])} | "
                     f"{yes_no[c['met']]} | {yes_no[c['paper_inside']]} |")
    lines += ["", "The paper gives E50 in figures only (Fig. 15–16), no number in the text; its φ* at φe = 5° "
              "and 10° only in Fig. 12."]
    cal = res.get("calibration")
    lines += calibration_lines(cal)
    if cal and cal.get("conditioning"):
        lines += ["", conditioning_text(cal["conditioning"]).replace("\n", "; ") + "."]
    t = res.get("timing")
    if t:
        lines += ["", f"Cost: {t['jobs']} jobs, {t['cpu_min']:.1f} CPU minutes recorded ({t['jobs_with_cpu']} jobs), "
                  f"{t['wall_min']:.1f} wall minutes."]
    files.write_text(md_path, "\n".join(lines) + "\n")
    return "\n".join(lines)


def conditioning(cal, phi_e=None, packings=None, tolerance=0.25):
    """How well E50 fixes kn through eq 6 at φe [deg] (default: the middle of ``cal``'s range),
    given the packing-to-packing scatter in ``cal`` (Calibration with e50_log_sd, phi_star_sd)
    and ``packings`` (default: cal's at that φe) verification packings:
        dlnE50_dlnkn       −m (eq 4 at fixed σ3 and φe);
        e50_log_sd         s, the s.d. of ln E50 of one packing;
        e50_half_width     the 95 % half-width of the mean of n packings' E50, relative:
                           exp(t s/√n) − 1 (t_half_width);
        kn_factor          the factor within which that mean fixes kn: exp(t s/√n / |m|) (eq 6);
        packings_for_e50   the fewest packings whose mean E50 is known within ``tolerance``;
        phi_star_half_width  t s_φ/√n [deg].
    None when ``cal`` has no scatter."""
    if not cal.e50_log_sd or any(v is None for v in cal.e50_log_sd):
        return None
    p = float(np.mean([cal.phi_e[0], cal.phi_e[-1]])) if phi_e is None else float(phi_e)
    n = int(round(np.interp(p, cal.phi_e, cal.packings))) if packings is None else int(packings)
    s = float(np.interp(p, cal.phi_e, cal.e50_log_sd))
    m = cal.eq4_at(p)[1]
    half = float(t_half_width(s / math.sqrt(n), n))
    kn_log = half / abs(m) if m else math.inf  # eq 6: δ ln kn = δ ln E50 / |m|
    need = next((k for k in range(2, 10000) if t_half_width(s / math.sqrt(k), k) <= math.log(1 + tolerance)), None)
    return {"phi_e_deg": p, "m": m, "dlnE50_dlnkn": -m, "e50_log_sd": s, "packings": n,
            "e50_half_width": math.exp(half) - 1, "kn_factor": math.exp(kn_log) if kn_log < 700 else math.inf,
            "packings_for_e50": need, "tolerance": tolerance,
            "phi_star_half_width": float(t_half_width(float(np.interp(p, cal.phi_e, cal.phi_star_sd)) / math.sqrt(n), n))}


def conditioning_text(c):
    """conditioning's record in two lines (calibrate.py prints them)."""
    return (f"E50 scatter between packings: s.d. of ln E50 = {c['e50_log_sd']:.3f} (x{math.exp(c['e50_log_sd']):.2f} "
            f"for one packing); the mean of {c['packings']} packings is known within +-{100 * c['e50_half_width']:.0f} % "
            f"(95 %), phi* within +-{c['phi_star_half_width']:.2f} deg\n"
            f"eq 4: dlnE50/dlnkn = -m = {c['dlnE50_dlnkn']:.3f} at phi_e = {c['phi_e_deg']:.2f} deg, so that E50 fixes kn "
            f"only within a factor {c['kn_factor']:.3g}; E50 within {100 * c['tolerance']:g} % needs "
            f"{c['packings_for_e50']} packings")
