"""The speed/accuracy study's judgement (engines.studies.tradeoffs gives its points and metrics;
engines.run.tradeoffs runs them; postproc.tradeoffs writes the tables and figures).

``assess(results, meta)``: each setting's errors against its case's reference (``systematic``:
ensemble means over the starts, chaos floors), its CPU speed-up over the case's run at the paper's
settings (dt = 1e-6 s, water every step, rebuilds every 1000 steps), and the judgement against the
5 % target (``judge``): on the noise-corrected estimate (``within_target``), the raw metric being
the estimate plus the chaos of finite ensembles; ``resolved`` when the estimate plus 2 sigma is
within 5 % too; ``within_target_raw`` for comparison. The defaults' row, and whether they meet the
target (5 % at a 10x speed-up), as ``defaults``.

``validation(results, meta)``: the validation's runs (the fast setting against the paper's numerics
on every preset over its whole duration, engines.studies.tradeoffs.VALIDATION): per scene every
metric of ``systematic`` with the blocks' time-mean pressures, and the ``verdict`` ("pass" when
every judged metric's estimate + 2 sigma is within 5 %) of the fast setting and of the candidate
settings tried.

``results``: {job name: ``load`` of its result.json}; ``meta``: job name -> (case, knob, value).
Plain NumPy; no YADE.
"""
import json

import numpy as np

from engines.studies import ensemble
from engines.studies import tradeoffs as tr

METRICS = ("pressure_rms", "porosity_change", "settlement")  # judged; pressure_rms_below_surface: a diagnostic
TARGET = 0.05          # every metric's systematic error (noise-corrected estimate) of the defaults
SPEEDUP_TARGET = 10.0  # the defaults' CPU speed-up over the paper's settings
NOTES = ("error: ensemble means over the starts against the reference's (engines.studies.tradeoffs), as fractions; "
         "floor: the same metric between two sets of starts at the reference settings (chaos); "
         "speedup: CPU seconds per start at the paper's settings of the case over the run's")


def load(path, *more):
    """A result.json as arrays over its ok starts: t, U (starts, times, blocks), porosity, height,
    kinetic_energy (starts, times); None when no start ran to the end. ``more``: the result.json of
    jobs that ran further starts of the same setting, their starts appended in order (cpu_s and
    wall_s the means per ok start over them all); None when one of them is missing."""
    parts = []
    for one in (path, *more):
        try:
            with open(one) as f:
                parts.append(json.load(f))
        except (OSError, ValueError):
            return None
    res = parts[0]
    if more:
        n_ok = [sum(s["status"] == "ok" for s in p["starts"]) for p in parts]
        for key in ("cpu_s", "wall_s"):
            res[key] = sum(p[key] * n for p, n in zip(parts, n_ok)) / max(sum(n_ok), 1)
        res["starts"] = [s for p in parts for s in p["starts"]]
    ok = [s for s in res["starts"] if s["status"] == "ok"]
    res["n_ok"] = len(ok)
    rec = [s["cpu_record_s"] for s in ok if "cpu_record_s" in s]
    res["cpu_record_s"] = float(np.mean(rec)) if rec and len(rec) == len(ok) else None
    res["messages"] = sorted({s.get("message", "") for s in res["starts"] if s["status"] != "ok"})
    if not ok or len({len(s["t"]) for s in ok}) != 1:
        res["data"] = None
        return res
    res["data"] = {"t": np.array(ok[0]["t"]), **{k: np.array([s[k] for s in ok], float)
                                                  for k in ("U", "porosity", "height", "kinetic_energy")}}
    return res


def record_cost(results, meta):
    """Runs written before the recording was timed on its own (no cpu_record_s) have it in their
    cpu_s: take out the median recording cost of the same case's other runs (the same window and
    samples), and mark them ("record_cost_estimated")."""
    for case in {c for c, _, _ in meta.values()}:
        named = [n for n, (c, _, _) in meta.items() if c == case and results.get(n)]
        known = [results[n]["cpu_record_s"] for n in named if results[n]["cpu_record_s"] is not None]
        if not known:
            continue
        for n in named:
            res = results[n]
            if res["cpu_record_s"] is None and res.get("data") is not None:
                res["cpu_s"] -= float(np.median(known))
                res["record_cost_estimated"] = True


def is_paper(knob, value):
    return knob == "dt" and value == tr.PAPER_DT


def judge(rows):
    """Mark each row: ``within_target`` (the noise-corrected estimate of every metric <= 5 %),
    ``resolved`` (also the estimate + 2 sigma <= 5 %), ``within_target_raw`` (every raw metric
    <= 5 %) and ``within_paper`` (every estimate <= max(5 %, the paper settings' estimate on it))."""
    paper = next((r for r in rows if is_paper(r["knob"], r["value"]) and r["error"]), None)
    for r in rows:
        err, sys_ = r["error"], r["systematic"]
        r["within_target_raw"] = bool(err) and all(err[m] <= TARGET for m in METRICS)
        r["within_target"] = bool(sys_) and all(sys_[m]["systematic"] <= TARGET for m in METRICS)
        r["resolved"] = bool(sys_) and all(sys_[m]["systematic"] + 2 * sys_[m]["sigma"] <= TARGET for m in METRICS)
        r["within_paper"] = bool(sys_) and paper is not None and \
            all(sys_[m]["systematic"] <= max(TARGET, paper["systematic"][m]["systematic"]) for m in METRICS)


def _reference(names, results, meta):
    """(the reference run of a case's jobs ``names``, the case's entry of ``reference``), or None
    when its reference has not run."""
    ref = next((results[n] for n in names if meta[n][1] == "reference"), None)
    paper = next((results[n] for n in names if is_paper(*meta[n][1:])), None)
    if ref is None or ref.get("data") is None:
        return None
    if paper is None and ref["dt"] == tr.PAPER_DT:  # a case whose reference is the paper's settings
        paper = ref
    paper_cpu = paper["cpu_s"] if paper and paper.get("data") is not None else None
    return ref, {"settings": ref["overrides"], "dt": ref["dt"], "window_s": ref["window"], "starts": ref["n_ok"],
                 "cpu_s": ref["cpu_s"], "wall_s": ref["wall_s"], "floor": tr.floors(ref["data"]),
                 "paper_cpu_s": paper_cpu}


def _row(case, knob, value, res, ref, paper_cpu):
    """One setting's row: its run ``res`` against the case's reference run ``ref``."""
    row = {"case": case, "knob": knob, "value": value, "settings": res["overrides"], "dt": res["dt"],
           "starts_ok": res["n_ok"], "starts": len(res["starts"]), "wall_s": res["wall_s"], "cpu_s": res["cpu_s"],
           "program": res.get("program", "yade"), "messages": res["messages"]}
    if res["data"] is None:
        return {**row, "speedup": None, "error": None, "systematic": None}
    row["speedup"] = paper_cpu / res["cpu_s"] if paper_cpu else None
    row["systematic"] = tr.systematic(res["data"], ref["data"])
    row["error"] = {m: v["measured"] for m, v in row["systematic"].items()}
    row["substeps_max"] = max(s.get("substeps_max", 0) for s in res["starts"])
    row["kinetic_energy_max"] = float(np.max(res["data"]["kinetic_energy"]))
    return row


def _defaults(doc):
    """The fast defaults' judgement on liquefaction_case1 (None when they have not run)."""
    fast = doc["alternatives"].get("liquefaction_case1:fast")
    if fast is None:
        return None
    return {"settings": fast["settings"], "speedup": fast["speedup"], "error": fast["error"],
            "systematic": fast["systematic"], "within_target": fast["within_target"],
            "resolved": fast["resolved"], "starts": fast["starts_ok"],
            "target": {"error": TARGET, "speedup": SPEEDUP_TARGET},
            "target_met": bool(fast["within_target"] and (fast["speedup"] or 0) >= SPEEDUP_TARGET),
            "floor": doc["reference"]["liquefaction_case1"]["floor"], "case": "liquefaction_case1",
            "window_s": doc["reference"]["liquefaction_case1"]["window_s"]}


def assess(results, meta, log=None):
    """The study's tradeoffs.json dict (module docstring); ``log`` names a case without a reference."""
    record_cost(results, meta)
    cases = sorted({c for c, _, _ in meta.values()}, key=[c for c, _, _ in meta.values()].index)
    doc = {"reference": {}, "runs": [], "defaults": None, "alternatives": {}, "notes": NOTES}
    for case in cases:
        names = [n for n, (c, _, _) in meta.items() if c == case]
        got = _reference(names, results, meta)
        if got is None:
            if log:
                log(f"{case}: no reference yet")
            continue
        ref, doc["reference"][case] = got
        for n in names:
            _, knob, value = meta[n]
            if knob == "reference" or results[n] is None:
                continue
            row = _row(case, knob, value, results[n], ref, doc["reference"][case]["paper_cpu_s"])
            if knob == "defaults":
                key = value.get("name", "defaults") if isinstance(value, dict) else "defaults"
                doc["alternatives"][f"{case}:{key}"] = row
            doc["runs"].append(row)
        judge([r for r in doc["runs"] if r["case"] == case])
    doc["defaults"] = _defaults(doc)
    return doc


def judged_metrics(systematic):
    """The metrics a validation judges, of those ``systematic`` gave: METRICS and the blocks' time means."""
    return [m for m in systematic if m in METRICS or m.startswith("block_mean_")]


def verdict(systematic):
    """"pass" when every judged metric's estimate + 2 sigma is within TARGET; "fail" when an estimate
    is above it; else "not resolved" (every estimate within, not every estimate + 2 sigma)."""
    judged = [systematic[m] for m in judged_metrics(systematic)]
    if all(m["systematic"] + 2 * m["sigma"] <= TARGET for m in judged):
        return "pass"
    return "fail" if any(m["systematic"] > TARGET for m in judged) else "not resolved"


def starts_needed(systematic, n):
    """The starts per setting that would decide a "not resolved" row of n starts: per judged metric
    whose estimate is below TARGET but not its estimate + 2 sigma, with sigma ~ 1/sqrt(starts)
    (engines.studies.ensemble.starts_needed, not capped), the largest; None for a decided row (and
    for one whose estimate is exactly TARGET: no number of starts decides it)."""
    need = [ensemble.starts_needed(n, 2 * m["sigma"], TARGET - m["systematic"], cap=np.inf)
            for m in (systematic[k] for k in judged_metrics(systematic))
            if m["systematic"] < TARGET < m["systematic"] + 2 * m["sigma"]]
    return max(need) if need and verdict(systematic) == "not resolved" else None


def validated(ref, run):
    """The validation of one setting's run against the paper's (results of ``load``): its cost,
    metrics (``systematic`` with the blocks) and verdict."""
    row = {"window_s": ref["window"], "dt_fast": run["dt"], "starts": {"paper": ref["n_ok"], "fast": run["n_ok"]},
           "cpu_s": {"paper": ref["cpu_s"], "fast": run["cpu_s"]}, "messages": ref["messages"] + run["messages"]}
    if ref["data"] is None or run["data"] is None:
        return {**row, "verdict": "failed"}
    sys_ = tr.systematic(run["data"], ref["data"], blocks=True)
    row = {**row, "speedup": ref["cpu_s"] / run["cpu_s"], "floor": tr.floors(ref["data"]), "metrics": sys_,
           "judged": judged_metrics(sys_), "verdict": verdict(sys_)}
    need = starts_needed(sys_, min(ref["n_ok"], run["n_ok"]))
    return {**row, "starts_needed": need} if need else row


def validation(results, meta, log=None):
    """The validation.json dict (module docstring); ``log`` gets one line per scene: its verdicts."""
    doc = {"target": TARGET, "criterion": "pass: every judged metric's noise-corrected estimate + 2 sigma <= target; "
                                          "fail: an estimate > target; not resolved: otherwise",
           "paper": {k: v for k, v in tr.ACCURATE.items() if k != "name"},
           "fast": {k: v for k, v in tr.FAST.items() if k != "name"}, "scenes": {},
           "notes": "systematic: the noise-corrected estimate of the metric (engines.studies.tradeoffs.systematic, as "
                    "fractions), sigma its bootstrap standard deviation; block_mean_<b>: the error of block b's "
                    "time-mean pressure over the RMS of the paper's ensemble-mean pressures; dry scenes have no "
                    "pressure metrics; cpu_s: CPU seconds per start"}
    for case in dict.fromkeys(c for c, _, _ in meta.values()):
        scene = tr.CASES[case].get("preset", case)
        ref = next((results[n] for n, (c, k, _) in meta.items() if c == case and k == "reference"), None)
        runs = {v["name"]: results[n] for n, (c, k, v) in meta.items() if c == case and k in ("defaults", "candidate")}
        entry = {"case": case, "perturbation_m": tr.CASES[case]["perturbation_size"], "verdict": "not run"}
        for name, run in runs.items():
            row = validated(ref, run) if ref is not None and run is not None else {"verdict": "not run"}
            if name == tr.FAST["name"]:
                entry.update(row)
            else:
                entry.setdefault("candidates", {})[name] = {
                    "settings": next(v for v in tr.CASES[case]["candidate"] if v["name"] == name), **row}
        doc["scenes"][scene] = entry
        if log:
            log(f"{scene}: {entry['verdict']}" + "".join(f"; {n}: {c['verdict']}"
                                                          for n, c in entry.get("candidates", {}).items()))
    return doc
