"""The liquefaction resistance curve (issue 42 item 3; beyond the paper: a shaking-box analogue of
the laboratory's cyclic tests, not an element test). No YADE.

The saturated undrained seismic box (seismic case 1's scene, yade_scripts/scenes/) is shaken at the
base by cosines of case 1's frequency at AMPLITUDES, each an ensemble of perturbed starts run for
CYCLES cycles, on two packings (PACKINGS: the preset's deposit, loose; one deposited with mu = 0,
dense). Per run (``run_reading``), from its history.csv (the bands' r_u, sigma'_v, sigma'_xz of
engines.model.effective_stress) and summary.json:

* N_L: the cycles (f t) to the first row where a band's r_u, averaged over the cycle before it
  (a trailing one-period mean: the shaking's dynamic pressure swings within a cycle), reaches
  RU_LIQUEFIED (so N_L >= 1); that band is the run's band (the one that gets there first; a tie:
  the lowest). Only the bands whose top lies SURFACE_DIAMETERS mean diameters or more below the
  bed's top at the start count: near the surface sigma'_v0 tends to 0 and r_u to noise. A run where
  no band gets there within its CYCLES is censored (N_L > CYCLES); its band is then the counted
  one of the largest mean r_u.
* CSR = the amplitude of the band's sigma'_xz over its sigma'_v0 (the first row's sigma'_v): the
  amplitude of a least-squares sinusoid at the input's frequency (with a constant and a linear
  drift) over the first CSR_CYCLES cycles, or up to N_L when the band liquefies sooner (at least
  one cycle): the shear stress the band carried while its pore pressure rose.
* the simplified CSR beside it (Seed & Idriss): 0.65 a_max/g sigma_v/sigma'_v0 at the band's
  middle, sigma'_v0 the buoyant overburden of the discs above (summary's band_overburden_Pa),
  sigma_v = sigma'_v0 + rho_w g d, d the depth of the band's middle below the bed's top.

Per amplitude and packing (``group_reading``): N_L as the median of the starts with censored runs
counted as longer than every liquefied one (with all runs censored at the same CYCLES this is the
Kaplan–Meier median), with its distribution-free interval between order statistics (the binomial
coverage stated, >= 95 % where the starts allow it; a bound on a censored run reads "> CYCLES");
the fraction liquefied with its Wilson 95 % interval; CSR and the simplified CSR as means over the
starts with Student's 95 % intervals (engines.studies.ensemble.statistics).
"""
import math

import numpy as np
from scipy import stats

from engines.model.effective_stress import SURFACE_DIAMETERS, counted_bands  # noqa: F401  (the study's rule)
from engines.studies.ensemble import CONFIDENCE, statistics

CYCLES = 30           # a run's length [cycles]; longer is censored
RU_LIQUEFIED = 0.9    # r_u at which a band has liquefied
CSR_CYCLES = 3        # cycles over which sigma'_xz's amplitude is fitted
BASE_AMPLITUDE = 15.0  # m/s^2: case 1's 1500 gal
FREQUENCY = 50.0      # Hz: case 1's
# amplitudes: case 1's times sqrt(2)^k, k = -2..2 (7.5 to 30 m/s^2): above 30 m/s^2 every start
# stopped on a pore's water area falling through zero within a step, even at 2.5e-7 s (42.4 and
# 60 m/s^2, 6 starts each, 2026-12-05), so the curve is read where the model runs
AMPLITUDES = tuple(round(BASE_AMPLITUDE * math.sqrt(2.0) ** k, 3) for k in range(-2, 3))
BASE_DT = 1e-6        # s: case 1's step, kept up to its amplitude


def time_step(amplitude):
    """The step [s] at ``amplitude`` [m/s^2]: case 1's, times BASE_AMPLITUDE / amplitude above it
    (the grains' speeds grow with the input: at 3000 gal and 1e-6 s a pore's water area fell
    through zero within a step, DarcyStabilityError, 2026-12-05)."""
    return BASE_DT * min(1.0, BASE_AMPLITUDE / amplitude)
STARTS = 8
SCENE = "liquefaction_case1"
PACKINGS = {"loose": {}, "dense": {"mu": 0.0}}  # the deposit's [contact] changes (none: the preset's file)


def cycle_mean(t, y, frequency):
    """The trailing one-period mean of y (T, ...) at each time of t (T,) [s]: the mean of the
    finite rows in (t - 1/f, t]; nan before a whole period has passed or without a finite row."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    ok = np.isfinite(y)
    zero = np.zeros((1,) + y.shape[1:])
    total = np.concatenate([zero, np.cumsum(np.where(ok, y, 0.0), axis=0)])
    count = np.concatenate([zero, np.cumsum(ok, axis=0)])
    k0 = np.searchsorted(t, t - 1.0 / frequency * (1 - 1e-9), side="right")
    k1 = np.arange(1, len(t) + 1)
    n = count[k1] - count[k0]
    out = np.divide(total[k1] - total[k0], n, out=np.full(n.shape, np.nan), where=n > 0)
    out[t < t[0] + (1 - 1e-9) / frequency] = np.nan
    return out


def liquefaction_cycle(t, ru, frequency, threshold=RU_LIQUEFIED):
    """(N_L [cycles], band index) of the first time in t (T,) [s] where a band's cycle-mean r_u
    (``cycle_mean`` of ru (T, B)) reaches ``threshold`` (the lowest band on a tie); (None, None)
    when none does."""
    hit = cycle_mean(t, ru, frequency) >= threshold  # nan (a band without pores, the first cycle) is not a hit
    rows = np.flatnonzero(hit.any(axis=1))
    if len(rows) == 0:
        return None, None
    k = rows[0]
    return float(frequency * t[k]), int(np.flatnonzero(hit[k])[0])


def sinusoid_amplitude(t, y, frequency):
    """The amplitude of the least-squares fit a cos(2 pi f t) + b sin(2 pi f t) + c + d t to y(t)
    (same unit as y): sqrt(a^2 + b^2)."""
    w = 2 * np.pi * frequency * np.asarray(t, float)
    A = np.column_stack([np.cos(w), np.sin(w), np.ones_like(w), w])
    (a, b, _, _), *_ = np.linalg.lstsq(A, np.asarray(y, float), rcond=None)
    return float(np.hypot(a, b))


def simplified_csr(a_max, g, overburden, depth, rho_w):
    """0.65 a_max/g sigma_v/sigma'_v0 with sigma'_v0 = ``overburden`` [Pa] (buoyant) and sigma_v =
    overburden + rho_w g depth [Pa]; a_max, g [m/s^2], depth [m], rho_w [kg/m^3]."""
    return 0.65 * a_max / g * (overburden + rho_w * g * depth) / overburden


def run_reading(history, summary, frequency, amplitude, cycles=CYCLES):
    """{"n_l" (None: censored), "censored", "band" (1-based), "csr", "csr_simplified", "sigma_v0_Pa",
    "tau_amplitude_Pa", "cycles_run", "ru_cycle_mean_max" (the largest cycle-mean r_u of the counted
    bands; None before a cycle)} of one run (csr nan where the band's sigma'_v0 is not > 0): ``history`` {column: array} (history.csv),
    ``summary`` (its summary.json), the input's frequency [Hz] and amplitude [m/s^2]. A run shorter
    than ``cycles`` that did not liquefy raises ValueError (it was stopped, not censored)."""
    t = np.asarray(history["t"], float)
    bed_top = float(history["bed_top"][0])
    counted = counted_bands(summary["band_bounds_m"], bed_top, summary["parameters"]["packing"]["mean_diameter"])
    if not counted:
        raise ValueError(f"no band lies {SURFACE_DIAMETERS:g} mean diameters below the bed's top: no r_u to read")
    ru = np.column_stack([history[f"ru_band{k + 1}"] for k in counted])
    n_l, band = liquefaction_cycle(t, ru, frequency)
    if n_l is not None and n_l > cycles:
        n_l, band = None, None
    ran = float(frequency * t[-1])
    if n_l is None and ran < cycles * (1 - 1e-9):
        raise ValueError(f"a run of {ran:.3g} cycles did not liquefy: it stopped before the {cycles} cycles that censor it")
    peak = np.nan_to_num(cycle_mean(t, ru, frequency), nan=-np.inf).max(axis=0)
    if band is None:
        band = int(np.argmax(peak))  # the first counted band when no cycle has passed
    ru_peak = float(peak.max()) if np.isfinite(peak.max()) else None
    band = counted[band]
    sv0 = float(history[f"sv_band{band + 1}"][0])
    t1 = max(1.0, min(n_l if n_l is not None else np.inf, CSR_CYCLES)) / frequency
    win = t <= t1 * (1 + 1e-9)
    tau = sinusoid_amplitude(t[win], np.asarray(history[f"sxz_band{band + 1}"], float)[win], frequency)
    z0, z1 = summary["band_bounds_m"][band]
    mat = summary["parameters"]["material"]
    depth = bed_top - 0.5 * (z0 + z1)
    simple = simplified_csr(amplitude, mat["g"], summary["band_overburden_Pa"][band], depth, mat["rho_w"])
    return {"n_l": n_l, "censored": n_l is None, "band": band + 1, "csr": tau / sv0 if sv0 > 0 else np.nan, "csr_simplified": simple,
            "sigma_v0_Pa": sv0, "tau_amplitude_Pa": tau, "cycles_run": ran, "ru_cycle_mean_max": ru_peak}


def median_interval(n_l, cycles=CYCLES, confidence=CONFIDENCE):
    """{"median", "low", "high", "coverage"} of the cycles to liquefaction n_l (None: censored at
    ``cycles``) of n starts: the median (the ceil(n/2)-th smallest, a censored run counted above
    every liquefied one: the Kaplan–Meier median when all are censored at the same time) and the
    interval [x_(j), x_(n+1-j)] of order statistics with the largest j whose binomial coverage
    1 - 2 P(B <= j - 1), B ~ Bin(n, 1/2), is at least ``confidence`` (j = 1, the range, when none
    is: its coverage is then below it). A value on a censored run is None ("> cycles")."""
    x = sorted(np.inf if v is None else float(v) for v in n_l)
    n = len(x)
    if n == 0:
        raise ValueError("median_interval: no runs")
    j = 1
    while j + 1 <= n + 1 - (j + 1) and 1 - 2 * stats.binom.cdf(j, n, 0.5) >= confidence:
        j += 1
    coverage = float(1 - 2 * stats.binom.cdf(j - 1, n, 0.5))

    def value(v):
        return None if math.isinf(v) else v

    return {"median": value(x[math.ceil(n / 2) - 1]), "low": value(x[j - 1]), "high": value(x[n - j]),
            "coverage": coverage}


def wilson(k, n, confidence=CONFIDENCE):
    """(low, high) of the Wilson score interval of a fraction k/n."""
    z = stats.norm.ppf(0.5 + confidence / 2)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, centre - half), min(1.0, centre + half)


def group_reading(readings, cycles=CYCLES):
    """The entry of one amplitude and packing from its runs' ``run_reading``s: n_starts, N_L's
    median and interval (``median_interval``), the fraction liquefied with its Wilson interval,
    each run's band and largest cycle-mean r_u (and as "ru_peak" their mean, interval and largest), and
    CSR and the simplified CSR as {"mean", "ci95_low", "ci95_high", "values"} over the starts."""
    n_l = [r["n_l"] for r in readings]
    k = sum(v is not None for v in n_l)
    out = {"n_starts": len(readings), "n_l": {**median_interval(n_l, cycles), "values": n_l},
           "liquefied": {"fraction": k / len(readings), **dict(zip(("low", "high"), wilson(k, len(readings))))},
           "bands": [r["band"] for r in readings], "ru_cycle_mean_max": [r["ru_cycle_mean_max"] for r in readings]}
    for key in ("csr", "csr_simplified"):
        out[key] = _mean_interval([r[key] for r in readings])
    peaks = out["ru_cycle_mean_max"]
    out["ru_peak"] = {**_mean_interval(peaks), "max": max((v for v in peaks if v is not None), default=None)}  # None: < 1 cycle
    return out


def _mean_interval(values):
    """{"mean", "ci95_low", "ci95_high", "values"} of ``values`` over the starts (None left out)."""
    s = statistics(np.array(values, float))
    return {"mean": float(s["mean"]), "ci95_low": float(s["ci95_low"]), "ci95_high": float(s["ci95_high"]),
            "values": values}


def void_ratio(porosity):
    """e = n / (1 - n) of a porosity n."""
    return porosity / (1.0 - porosity)


def _bounds(n_l):
    """(low, high) of an N_L interval as numbers (a bound on a censored run: inf)."""
    return tuple(np.inf if v is None else v for v in (n_l["low"], n_l["high"]))


def read_rows(packing):
    """The rows of a packing with a reading (not those whose every start failed)."""
    return [r for r in packing["rows"] if "n_l" in r]


def statements(packings):
    """What the intervals decide ({"csr_falls_with_n_l": {packing: text}, "loose_below_dense": {amplitude: text}}):
    CSR falls with N_L in a packing when two of its rows separate in both (one's CSR interval wholly
    above the other's and its N_L interval wholly below), rises when a pair separates the other way;
    at an amplitude, loose lies below dense when loose's N_L interval lies wholly below dense's at a
    CSR interval not above dense's (and the reverse); else undecided with these intervals."""
    falls = {}
    for name, p in packings.items():
        ways, rows = set(), read_rows(p)
        for a in rows:
            for b in rows:
                if a["csr"]["ci95_low"] > b["csr"]["ci95_high"]:
                    (a_lo, a_hi), (b_lo, b_hi) = _bounds(a["n_l"]), _bounds(b["n_l"])
                    ways |= {"falls"} if a_hi < b_lo else {"rises"} if a_lo > b_hi else set()
        falls[name] = ("CSR falls with N_L (a pair of rows separates in both)" if ways == {"falls"} else
                       "CSR rises with N_L (a pair of rows separates in both)" if ways == {"rises"} else
                       "contradictory pairs" if ways else "undecided with these intervals (no pair separates in both)")
    below = {}
    if {"loose", "dense"} <= set(packings):
        dense = {r["amplitude_m_s2"]: r for r in read_rows(packings["dense"])}
        for r in read_rows(packings["loose"]):
            d = dense.get(r["amplitude_m_s2"])
            if d is None:
                continue
            (l_lo, l_hi), (d_lo, d_hi) = _bounds(r["n_l"]), _bounds(d["n_l"])
            key = f"{r['amplitude_m_s2']:g} m/s^2"
            if l_hi < d_lo and r["csr"]["ci95_low"] <= d["csr"]["ci95_high"]:
                below[key] = "loose liquefies in fewer cycles at a CSR not above dense's: loose lies below"
            elif d_hi < l_lo and d["csr"]["ci95_low"] <= r["csr"]["ci95_high"]:
                below[key] = "dense liquefies in fewer cycles at a CSR not above loose's: dense lies below"
            else:
                below[key] = "undecided with these intervals"
    return {"csr_falls_with_n_l": falls, "loose_below_dense": below}
