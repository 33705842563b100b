"""The seismic study's verdicts (seed 000 §6): the paper's trends (SPEC §2.5) judged on our
cases' starts (``trends``), each quantity with its 95 % interval over the starts and a verdict
holds / fails / undecided. postproc.liquefaction measures the runs (``case_summary``) and writes
the study's tables and figures; the reconstruction judges its variants with the same trends
(engines.studies.reconstruction.judged). No YADE.
"""
import numpy as np
from scipy import stats

from engines.studies.ensemble import CONFIDENCE, t_half_width

PERIOD = 0.02  # the cosine's period [s] (50 Hz): the averaging window of the end values


def holds_if(low, high):
    """The criterion (low, high) as text: "> low", "< high" or "in (low, high)"."""
    return f"> {low:g}" if high == np.inf else f"< {high:g}" if low == -np.inf else f"in ({low:g}, {high:g})"


# The paper's trends (SPEC §2.5) with the study's criteria, fixed before the runs: per trend its
# cases and its conditions (name, a quantity of the cases' means over their starts {case: {key:
# mean}}, low, high); the trend holds where every quantity lies in (low, high).
TRENDS = tuple(
    [(f"dry settles more than saturated-undrained ({label}: case {dry} vs {wet})",
      "undrained ≈ constant volume; dry porosity falls with time (Fig. 40/46)", (wet, dry),
      [(f"-Δn(case {dry}) / |Δn(case {wet})|",
        lambda m, w=wet, d=dry: -m[d]["porosity_change"] / abs(m[w]["porosity_change"]), 2.0, np.inf)])
     for wet, dry, label in ((1, 2, "cosine"), (6, 7, "El Centro"))]
    + [("drained sides with high k keep |U| small (case 3 vs 1)", "U hardly rises in any block, stays near 0 (Fig. 39)",
        (1, 3), [("time-mean |U| of blocks 1-4, case 3 / case 1",
                  lambda m: m[3]["U_low_abs_mean"] / m[1]["U_low_abs_mean"], -np.inf, 0.5)]),
       ("drained case lies between undrained and dry in porosity (case 3)", "intermediate (Fig. 40)", (1, 2, 3),
        [("(Δn3 - Δn1) / (Δn2 - Δn1)", lambda m: (m[3]["porosity_change"] - m[1]["porosity_change"])
          / (m[2]["porosity_change"] - m[1]["porosity_change"]), 0.0, 1.0)]),
       ("elastic springs keep porosity nearly constant (cases 4, 5 vs 2)",
        "porosity hardly changes, saturated or dry (Fig. 41)", (2, 4, 5),
        [("max(|Δn4|, |Δn5|) / |Δn2|", lambda m: max(abs(m[4]["porosity_change"]), abs(m[5]["porosity_change"]))
          / abs(m[2]["porosity_change"]), -np.inf, 0.5)]),
       ("elastic springs: U oscillates about 0 (case 4)",
        "U oscillates near 0 in every block, with suction; no build-up (Fig. 42)", (1, 4),
        [("|mean U| / std U of blocks 1-4, case 4", lambda m: abs(m[4]["U_low_mean"]) / m[4]["U_low_std"], -np.inf, 1.0),
         ("|mean U| of blocks 1-4, case 4 / case 1", lambda m: abs(m[4]["U_low_mean"]) / abs(m[1]["U_low_mean"]),
          -np.inf, 0.5)]),
       ("hysteretic springs: U builds up with the input period (case 1)",
        "U rises through the first cycle (0.02 s), then oscillates at the input period about a plateau (Fig. 37)", (1,),
        [("rise of U (blocks 1-4) in the first 20 ms / std U",
          lambda m: m[1]["U_low_rise_first_period"] / m[1]["U_low_std"], 0.0, np.inf),
         ("U over the last 20 ms / std U", lambda m: m[1]["U_low_end"] / m[1]["U_low_std"], 0.5, np.inf),
         ("dominant period of U / 20 ms", lambda m: m[1]["U_low_dominant_period"] / PERIOD, 0.75, 1.25)])])
N_BOOT = 2000  # bootstrap resamples of the starts of each case for a quantity's interval


def small_sample_factor(n):
    """The factor that widens a percentile bootstrap interval of means of n starts about its
    estimate to a Student-t one: t(q, n - 1) / z(q) x sqrt(n / (n - 1)), q = (1 + CONFIDENCE) / 2 (the
    bootstrap's spread of a mean is sqrt((n - 1) / n) of its standard error; 1.29 at n = 8)."""
    q = 0.5 + CONFIDENCE / 2
    return float(t_half_width(1.0, n) / stats.norm.ppf(q) * np.sqrt(n / (n - 1))) if n > 1 else np.nan


def _means(cases, keys, pick=None):
    """{case: {key: mean over the starts (those of ``pick`` {case: indices}, default all)}}."""
    return {k: {key: float(np.mean([runs[i][key] for i in (pick[k] if pick else range(len(runs)))]))
                for key in keys} for k, runs in cases.items()}


def _verdict(lo, hi, low, high):
    """holds: the interval (lo, hi) inside (low, high); fails: outside; undecided: it straddles a
    threshold (or is unknown)."""
    if np.isnan(lo) or np.isnan(hi):
        return "undecided"
    if low < lo and hi < high:
        return "holds"
    if hi <= low or lo >= high:
        return "fails"
    return "undecided"


def trends(cases, drainage=None, seed=0):
    """The paper's trends (TRENDS) on our runs: a list of rows {trend, paper, cases, starts,
    conditions: [{quantity, estimate, ci95, holds_if, verdict}], verdict}; rows whose cases are
    missing are left out. ``cases``: {case: [summary of each start (``case_summary``)]} (a dict for
    one run). Each quantity: its value on the means over the starts, its 95 % interval the
    percentile interval over N_BOOT bootstrap resamples of each case's starts (numpy Generator(seed))
    widened by ``small_sample_factor`` of the fewest starts,
    its verdict holds (the interval inside the criterion's range), fails (outside) or undecided
    (straddling a threshold, or a case with one start); the trend fails where a condition fails,
    holds where all hold. ``drainage``: drainage.json (yade_scripts/liquefaction_drainage.py), quoted
    in the drained row."""
    cases = {k: v if isinstance(v, list) else [v] for k, v in cases.items()}
    keys = ("porosity_change", "U_low_abs_mean", "U_low_mean", "U_low_std", "U_low_rise_first_period", "U_low_end",
            "U_low_dominant_period")
    rng = np.random.default_rng(seed)
    rows = []
    for trend, paper, need, conditions in TRENDS:
        if not all(k in cases for k in need):
            continue
        sub = {k: cases[k] for k in need}
        have = [key for key in keys if all(key in r for runs in sub.values() for r in runs)]
        mean = _means(sub, have)
        boot = [_means(sub, have, {k: rng.integers(0, len(runs), len(runs)) for k, runs in sub.items()})
                for _ in range(N_BOOT)]
        one = min(len(runs) for runs in sub.values()) < 2
        out = []
        with np.errstate(divide="ignore", invalid="ignore"):
            for name, f, low, high in conditions:
                est = float(f(mean))
                values = np.array([f(b) for b in boot], float)
                tails = [50 * (1 - CONFIDENCE), 50 * (1 + CONFIDENCE)]  # percent
                lo, hi = (np.nanpercentile(values, tails) if not one and np.isfinite(values).any()
                          else (np.nan, np.nan))
                widen = small_sample_factor(min(len(runs) for runs in sub.values()))
                lo, hi = est - widen * (est - lo), est + widen * (hi - est)
                out.append({"quantity": name, "estimate": est, "ci95": [float(lo), float(hi)],
                            "holds_if": holds_if(low, high),
                            "verdict": "undecided" if one else _verdict(lo, hi, low, high)})
        verdicts = {c["verdict"] for c in out}
        row = {"trend": trend, "paper": paper, "cases": list(need), "starts": {k: len(sub[k]) for k in need},
               "conditions": out,
               "verdict": "fails" if "fails" in verdicts else "holds" if verdicts == {"holds"} else "undecided"}
        tau = (drainage or {}).get("case3", {}).get("1", {}).get("tau")
        if 3 in need and "U_low_abs_mean" in have and tau:
            row["note"] = f"slowest drainage time constant of case 3 {1e3 * tau[0]:.0f} ms vs the 20-ms input period"
        rows.append(row)
    return rows
