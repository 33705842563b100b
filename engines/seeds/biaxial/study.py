"""Seed 003's study (Murakami et al. §3, docs/BIAXIAL.md): its parts and their settings, and its
numbers from the finished runs: φ*, c*, peaks and E50 of the main grid and the eq 4 fits
(analyse_main), the sensitivities (analyse_sensitivity), the curves calibrate.py inverts
(calibration_from), study.json (summarise) and the tables beside the paper's (write_table).
No YADE: engines.run.biaxial_study runs the jobs, postproc.biaxial_plots draws the figures.
"""
import json
import math
import os

import numpy as np

from engines import files
from engines.seeds.biaxial.calibration import Calibration, eq4_e50, fit_eq4
from engines.seeds.biaxial.cem_contact import TABLE2_DT
from engines.seeds.biaxial.specimen import Curve, mohr_coulomb_fit

PARTS = ("main", "calibration", "stiffness", "dt", "discs", "rate", "stability", "hypotheses", "judged")
DEFAULT_PARTS = PARTS[:-2]  # hypotheses and judged run on request
PHI_E = (5.0, 10.0, 15.0)
SIGMA3 = (100.0, 200.0, 300.0, 400.0)
KN = 1e8
KS = 0.25
SENS_PHI, SENS_SIGMA3, SENS_STRAIN = 10.0, 200.0, 4.0  # the paper's sensitivity runs (§3(1)–(2), Fig. 13–14)
RATES = (25.0, 50.0)                                     # %/min, besides the reference 100 (the paper's)
DTS = (2.5e-5, 5e-5, 1e-4)                               # s (the paper's three), besides the reference TABLE2_DT
DISCS = (125, 250, 500)                                  # besides the reference 1000
KNS = (0.5e8, 2e8)
KSS = (0.125, 0.5)
SMALL_DISCS = 500  # the specimen of the stiffness and dt sensitivities (docs/BIAXIAL.md: the budget)
PAPER = {"phi_star_deg": {15.0: 27.4}, "c_star_pa": {15.0: 0.4}, "peak_deviator_200_pa": {5.0: 140.0, 10.0: 240.0, 15.0: 330.0}}
CALIBRATION_TARGET_SIGMA3 = 250.0  # Pa: between the study's σ3, so the round trip interpolates in σ3 too


def sensitivity_name(seed, **changes):
    label = "_".join(f"{k}{v:g}" if isinstance(v, float) else f"{k}{v}" for k, v in changes.items()) or "reference"
    return f"sens_{label}_seed{seed}"


# The readings of the paper that may change strength, each an option of yade_scripts/biaxial.py
# against the reference (every option at its default): name -> (options, the φe it runs at)
HYPOTHESES = {
    "reference": ({}, (15.0, 5.0)),
    "rotation_locked": ({"rotation": "locked"}, (15.0, 5.0)),
    "side_load_diameter": ({"side_load": "diameter"}, (15.0,)),
    "periodic_cell": ({"specimen": "periodic"}, (15.0,)),
    "packing_at_test_phi": ({"packing_phi_e": "test"}, (15.0, 5.0)),
    "width_diameter": ({"width_factor": 2.0}, (15.0,)),
}
HYP_STRAIN = 5.0                              # % (the main grid's)
HYP_SMALL = 250                               # discs of the size-effect runs (against 1000), φe = 15°, σ3 = 200 Pa
HYP_SIZE_VARIANTS = ("reference", "periodic_cell")  # do the bands make the size effect?


def hypothesis_name(variant, phi_e, sigma3, seed, n_discs=1000):
    size = "" if n_discs == 1000 else f"_n{n_discs}"
    return f"hyp_{variant}_phi{phi_e:g}_s3{sigma3:g}{size}_seed{seed}"


def hypothesis_points(seeds):
    """(job name, biaxial.py options) of the hypotheses study, one per variant, φe, σ3, packing
    seed; seed by seed (every variant gets its first packing before any its second), then the
    size-effect runs."""
    out = []
    for s in seeds:
        for variant, (opts, phis) in HYPOTHESES.items():
            out += [(hypothesis_name(variant, p, s3, s), dict(phi_e=p, sigma3=s3, max_strain=HYP_STRAIN, seed=s, **opts))
                    for p in phis for s3 in SIGMA3]
    for s in seeds:
        for variant in HYP_SIZE_VARIANTS:
            out.append((hypothesis_name(variant, 15.0, 200.0, s, HYP_SMALL), dict(
                phi_e=15.0, sigma3=200.0, max_strain=HYP_STRAIN, seed=s, n_discs=HYP_SMALL, **HYPOTHESES[variant][0])))
    return out


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


def mean_sd(values):
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
              "dt_s": ("dt", DTS, TABLE2_DT, lambda v: {"packing_dt": TABLE2_DT}, small),
              "n_discs": ("n_discs", DISCS, 1000, lambda v: {}, {}),
              "kn_pa_per_m": ("kn", KNS, KN, lambda v: {}, small), "ks_ratio": ("ks_ratio", KSS, KS, lambda v: {}, small)}
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


def _difference(a, b):
    """(mean a − mean b, its 95 % half-width from the two standard errors (1.96 √(s_a²/n_a + s_b²/n_b)))
    of two mean_sd records, or None when either has fewer than two values."""
    if a["n"] < 2 or b["n"] < 2:
        return None
    return a["mean"] - b["mean"], 1.96 * math.sqrt(a["sd"] ** 2 / a["n"] + b["sd"] ** 2 / b["n"])


def verdict(row, ref, paper_phi, paper_q):
    """One line: what a variant does to φ* and to the peak at 200 Pa against the reference
    (a change counts when it exceeds its 95 % interval), and which share of the gap to the
    paper it closes."""
    parts = []
    for key, label, unit, paper in (("phi_star_deg", "φ*", "°", paper_phi), ("peak_200_pa", "q_f(200 Pa)", " Pa", paper_q)):
        d = _difference(row[key], ref[key])
        if d is None:
            parts.append(f"{label}: too few packings yet (n = {row[key]['n']}, reference {ref[key]['n']})")
            continue
        delta, half = d
        share = None if paper is None else delta / (paper - ref[key]["mean"])
        gap = "" if share is None else (f", {100 * share:.0f} % of the gap to the paper" if share >= 0
                                         else ", away from the paper")
        if abs(delta) > half:
            parts.append(f"{label} {delta:+.1f} ± {half:.1f}{unit}{gap}")
        else:
            parts.append(f"{label} unchanged within the scatter ({delta:+.1f} ± {half:.1f}{unit})")
    return "; ".join(parts)


def analyse_hypotheses(runs, seeds):
    """The hypotheses table's numbers: per variant and φe, over the packing seeds whose four σ3
    finished: φ*, c* (Mohr–Coulomb over the four circles), and over the finished σ3 = 200 Pa jobs:
    peak q, E50, the porosity after packing (1 − solid fraction), the confining stress applied
    during the test over the nominal σ3 (the side loads over the covered height, the cell's σx);
    the disc-count dependence
    q_f(200 Pa) at HYP_SMALL over that at 1000 discs (seed by seed); a verdict against the
    reference at the same φe; the jobs done and failed."""
    rows, done, failed = [], 0, []
    for variant, (opts, phis) in HYPOTHESES.items():
        for p in phis:
            phi, c_star, q200, e200, poro, side = [], [], [], [], [], []
            for s in seeds:
                peaks = {}
                for s3 in SIGMA3:
                    name = hypothesis_name(variant, p, s3, s)
                    summary, curves = read_run(runs, name)
                    if summary is None or "error" in summary:
                        if job_status(runs, name)["status"] == "failed":
                            failed.append(name)
                        continue
                    done += 1
                    c = curves[s3]
                    peaks[s3] = c.peak()[1]
                    if s3 == 200.0:
                        q200.append(peaks[s3])
                        e200.append(c.e50())
                        poro.append(1 - summary["packings"][0]["solid_fraction"])
                        side.append(float(np.mean(c.sigma3_applied)) / s3)
                if len(peaks) == len(SIGMA3):
                    f = mohr_coulomb_fit(list(peaks), [s3 + q for s3, q in peaks.items()])
                    phi.append(f[0])
                    c_star.append(f[1])
            rows.append({"variant": variant, "options": opts, "phi_e_deg": p, "phi_star_deg": mean_sd(phi),
                         "c_star_pa": mean_sd(c_star), "peak_200_pa": mean_sd(q200), "e50_200_pa": mean_sd(e200),
                         "porosity": mean_sd(poro), "sigma3_applied_ratio": mean_sd(side)})
    for row in rows:
        size = []
        if row["variant"] in HYP_SIZE_VARIANTS and row["phi_e_deg"] == 15.0:
            for s in seeds:
                small, _ = read_run(runs, hypothesis_name(row["variant"], 15.0, 200.0, s, HYP_SMALL))
                large, _ = read_run(runs, hypothesis_name(row["variant"], 15.0, 200.0, s))
                done += int(bool(small) and "error" not in small)
                if small and large and "error" not in small and "error" not in large:
                    size.append(small["per_sigma3"][0]["peak_deviator_pa"] / large["per_sigma3"][0]["peak_deviator_pa"])
        row["size_ratio"] = mean_sd(size)
        ref = next(r for r in rows if r["variant"] == "reference" and r["phi_e_deg"] == row["phi_e_deg"])
        row["verdict"] = "reference" if row is ref else verdict(
            row, ref, PAPER["phi_star_deg"].get(row["phi_e_deg"]), PAPER["peak_deviator_200_pa"].get(row["phi_e_deg"]))
    return {"seeds": list(seeds), "rows": rows, "jobs_done": done, "jobs_failed": sorted(failed),
            "jobs_total": len(hypothesis_points(seeds))}


def write_hypotheses(res, json_path, md_path):
    """hypotheses.json and the markdown table of analyse_hypotheses; returns the table."""
    files.write_json(json_path, res)
    lines = [f"Hypotheses (1000 discs, σ3 = {', '.join(f'{v:g}' for v in SIGMA3)} Pa, one packing per σ3 and seed, "
             f"{HYP_STRAIN:g} % strain; mean ± s.d. over packings; {res['jobs_done']} of {res['jobs_total']} jobs done"
             + (f", {len(res['jobs_failed'])} failed" if res["jobs_failed"] else "") + "):", "",
             "| variant | options | φe | φ* | c* [Pa] | peak q at 200 Pa | E50 at 200 Pa | porosity after packing | "
             f"σ3 applied / nominal | q_f({HYP_SMALL} discs) / q_f(1000) | verdict against the reference |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in res["rows"]:
        opts = ", ".join(f"{k} = {v}" for k, v in r["options"].items()) or "defaults"
        lines.append(f"| {r['variant']} | {opts} | {r['phi_e_deg']:g}° | {_ms(r['phi_star_deg'], unit='°')} | "
                     f"{_ms(r['c_star_pa'])} | {_ms(r['peak_200_pa'], '{:.0f}')} | {_ms(r['e50_200_pa'], '{:.3g}')} | "
                     f"{_ms(r['porosity'], '{:.4f}')} | {_ms(r['sigma3_applied_ratio'], '{:.3f}')} | "
                     f"{_ms(r['size_ratio'], '{:.2f}')} | {r['verdict']} |")
    lines += ["", f"Paper: φ* = {PAPER['phi_star_deg'][15.0]}° at φe = 15°; peak q at 200 Pa ≈ "
              + ", ".join(f"{v:g} Pa (φe = {k:g}°)" for k, v in PAPER["peak_deviator_200_pa"].items()) + "."]
    files.write_text(md_path, "\n".join(lines) + "\n")
    return "\n".join(lines)


def summarise(main, sens, seeds):
    """study.json's numbers (curves left out)."""
    m = {"phi_star_deg": {}, "c_star_pa": {}, "peak_deviator_pa": {}, "e50_pa": {}, "peak_strain": {}, "eq4": {},
         "peaks_at_end_of_test": {}}
    for p, per in main["per_phi_e"].items():
        m["phi_star_deg"][f"{p}"] = mean_sd(per["phi_star_deg"])
        m["c_star_pa"][f"{p}"] = mean_sd(per["c_star_pa"])
        m["peak_deviator_pa"][f"{p}"] = {f"{s3}": mean_sd(v) for s3, v in per["peak"].items()}
        m["e50_pa"][f"{p}"] = {f"{s3}": mean_sd(v) for s3, v in per["e50"].items()}
        m["peak_strain"][f"{p}"] = {f"{s3}": mean_sd(v) for s3, v in per["peak_strain"].items()}
        m["peaks_at_end_of_test"][f"{p}"] = per["peak_at_end"]
        if p in main["fits"]:
            m["eq4"][f"{p}"] = {"A": main["fits"][p][0], "m": main["fits"][p][1]}
    s = {}
    for key, res in sens.items():
        s[key] = {f"{v:g}": {"peak_deviator_pa": mean_sd(c["peak_deviator_pa"]), "e50_pa": mean_sd(c["e50_pa"]),
                             "phi0": mean_sd(c["phi0_deg"]), "wall_s": mean_sd(c["wall_s"]), "failed": c["failed"]}
                  for v, c in res.items()}
    return {"seeds": list(seeds), "main": m, "sensitivity": s}


def _num(x, fmt="{:.1f}"):
    return "–" if x is None else fmt.format(x)


def _ms(stat, fmt="{:.1f}", unit=""):
    """'mean ± s.d. (n)' of a mean_sd record, '–' when nothing finished."""
    if not stat or stat["mean"] is None:
        return "–"
    return f"{fmt.format(stat['mean'])} ± {fmt.format(stat['sd'])}{unit} (n = {stat['n']})"


SENS_ROWS = (("strain_rate_pct_min", "strain rate [%/min] (Fig. 5)", "1000"),
             ("dt_s", "Δt [s] (Fig. 6)", f"{SMALL_DISCS}"), ("n_discs", "discs (Fig. 8)", "—"),
             ("kn_pa_per_m", "kn [Pa/m] (Fig. 13)", f"{SMALL_DISCS}"), ("ks_ratio", "ks/kn (Fig. 14)", f"{SMALL_DISCS}"))


def calibration_lines(cal):
    """The calibration round trip's table (markdown lines) of calibration_round_trip's record,
    or the reason it was not verified; [] for None."""
    if cal and cal.get("verified"):
        v, t = cal["verified"], cal["target"]
        return ["", "Calibration round trip (eq 5–6, then the biaxial test again, 1000 discs):", "",
                "| | target | inverted | verified (mean of packings) | error |", "|---|---|---|---|---|",
                f"| φ* | {t['phi_star_deg']:.2f}° | φe = {cal['inverted']['phi_e_deg']:.2f}° | "
                f"{v['phi_star_deg']['mean']:.2f}° ({', '.join(f'{x:.2f}' for x in v['phi_star_deg']['values'])}) | "
                f"{100 * v['phi_star_error']:+.1f} % |",
                f"| E50 at σ3 = {t['sigma3_pa']:g} Pa | {t['e50_pa']:.4g} Pa | kn = {cal['inverted']['kn_pa_per_m']:.4g} Pa/m | "
                f"{v['e50_pa']['mean']:.4g} Pa ({', '.join(f'{x:.4g}' for x in v['e50_pa']['values'])}) | "
                f"{100 * v['e50_error']:+.1f} % |"]
    if cal:
        why = cal.get("error") or "no result from " + ", ".join(f["job"] for f in cal.get("failed", []))
        inv = cal.get("inverted")
        return ["", "Calibration round trip: not verified: " + why + (
            f" (eq 5–6 gave φe = {inv['phi_e_deg']:.2f}°, kn = {inv['kn_pa_per_m']:.4g} Pa/m for φ* = "
            f"{cal['target']['phi_star_deg']:.2f}°, E50 = {cal['target']['e50_pa']:.4g} Pa at σ3 = "
            f"{cal['target']['sigma3_pa']:g} Pa)" if inv else "")]
    return []


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
                     f"{_ms(q200, '{:.0f}')} | {_ms(q200 and mean_sd([phi_one_circle(q, 200.0) for q in q200['values']]), unit='°')} | "
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
    lines += calibration_lines(cal)
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
    files.write_text(path, "\n".join(lines) + "\n")
    return "\n".join(lines)
