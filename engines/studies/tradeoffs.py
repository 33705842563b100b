"""Error metrics of the speed/accuracy study, on statistics of runs, not on positions.

DEM runs are chaotic: two time steps, or a 1e-9 m nudge of the start, give trajectories that part
after a few milliseconds. A setting is therefore run from ``n`` perturbed starts
(engines.studies.ensemble.perturbed) and compared with the reference run from the same starts
through ensemble means. The nudge must be large enough that the starts have parted before the
window's events: a cloud of starts that is still one trajectory has a small spread (so a small
floor) and a mean that any change of the step moves; check that the means do not depend on the
size (the knob "perturbation" of CASES; docs/TRADEOFFS.md: 1e-9 m was too small for the seismic
box, 1e-7 m is not).

* ``pressure_rms``: RMS over time and blocks of (<U>_run - <U>_ref) over the RMS of <U>_ref,
  <.> the mean over starts of the block-mean pore pressure histories (N/m, per block and time);
* ``pressure_rms_below_surface``: the same without the last (surface) block, a diagnostic: the
  surface block's pressure swings most between starts and carries most of the error;
* ``change_error``: |<x>_run - <x>_ref| / |<x>_ref| for a scalar change x per start: the
  porosity change over the window, the settlement (drop of the particles' mean height);
* the chaos floor of each metric (``pressure_floor``, ``change_floor``): the value the metric
  takes between two independent ensembles of n starts at the reference settings, estimated from
  the spread between the reference's own starts (a difference of two means of n has standard
  deviation sqrt(2/n) times that of one start). An error at the floor is chaos, not error.
* the noise-corrected (systematic) error of a run (``systematic``): a measured metric m of two
  ensembles of na and nb starts has E[m^2] = bias^2 + floor^2, floor^2 = (sa^2/na + sb^2/nb) / ref^2
  (sa, sb the spreads of one start of run and reference, per sample for the pressures); the
  estimate of the bias is sqrt(max(0, m^2 - floor^2)), its uncertainty the standard deviation of
  the same estimate over bootstrap resamples of both sets of starts.

``pareto_front`` marks the settings that no other setting beats on both cost and error.

The study's points: CASES (per case its window, base dt and the values of each knob), ``points``
in the order they run, their starts and perturbation sizes, their job names; engines.run.tradeoffs
gives each point its scene settings and runs it, postproc.tradeoffs draws the tables and figures.
Plain NumPy; no YADE.
"""
import numpy as np

from engines.model.settings import DT_AUTO_FACTOR
from engines.studies.ensemble import QUICKSAND_PERTURBATION, SEISMIC_PERTURBATION


def _on_grid(t, values, t_ref):
    """values (starts, times, ...) sampled at t, linearly interpolated onto t_ref."""
    values = np.asarray(values, float)
    if len(t) == len(t_ref) and np.allclose(t, t_ref, rtol=0, atol=1e-12):
        return values
    flat = values.reshape(values.shape[0], values.shape[1], -1)
    out = np.empty((flat.shape[0], len(t_ref), flat.shape[2]))
    for s in range(flat.shape[0]):
        for b in range(flat.shape[2]):
            out[s, :, b] = np.interp(t_ref, t, flat[s, :, b], left=np.nan, right=np.nan)
    return out.reshape((flat.shape[0], len(t_ref)) + values.shape[2:])


def _rms(x):
    x = np.asarray(x, float)
    return float(np.sqrt(np.nanmean(x * x)))


def _pressure_error(A, R):
    """RMS(<A> - <R>) / RMS(<R>) of block pressure histories A, R (starts, times, blocks) on the same
    times (nan samples, blocks without pores, are left out)."""
    mean_ref = np.nanmean(R, axis=0)
    return _rms(np.nanmean(A, axis=0) - mean_ref) / _rms(mean_ref)


def pressure_floor(U_ref):
    """Chaos floor of ``pressure_rms``: sqrt(2/n) RMS(std over the n starts) / RMS(<U_ref>)."""
    U_ref = np.asarray(U_ref, float)
    n = U_ref.shape[0]
    spread = np.nanstd(U_ref, axis=0, ddof=1)
    return float(np.sqrt(2.0 / n) * _rms(spread) / _rms(np.nanmean(U_ref, axis=0)))


def _pressure_noise(A, R):
    """Floor of ``_pressure_error`` between these two ensembles: sqrt(mean over samples of
    (var_A/n_A + var_R/n_R)) / RMS(<R>), the variances over starts (ddof 1)."""
    var = np.nanvar(A, axis=0, ddof=1) / np.sum(np.isfinite(A), axis=0) + \
        np.nanvar(R, axis=0, ddof=1) / np.sum(np.isfinite(R), axis=0)
    return float(np.sqrt(np.nanmean(var)) / _rms(np.nanmean(R, axis=0)))


def change_noise(x, x_ref, scale=None):
    """floor of ``change_error`` between these two ensembles: sqrt(var/n + var_ref/n_ref) / scale
    (default |<x_ref>|)."""
    x, x_ref = np.asarray(x, float), np.asarray(x_ref, float)
    scale = abs(np.mean(x_ref)) if scale is None else scale
    return float(np.sqrt(np.var(x, ddof=1) / len(x) + np.var(x_ref, ddof=1) / len(x_ref)) / scale)


def change_error(x, x_ref, scale=None):
    """|<x> - <x_ref>| / scale (default |<x_ref>|) of a scalar per start (x: (starts,))."""
    scale = abs(np.mean(x_ref)) if scale is None else scale
    return float(abs(np.mean(x) - np.mean(x_ref)) / scale)


def change_floor(x_ref):
    """Chaos floor of ``change_error``: sqrt(2/n) std(x_ref) / |<x_ref>|."""
    x_ref = np.asarray(x_ref, float)
    return float(np.sqrt(2.0 / len(x_ref)) * np.std(x_ref, ddof=1) / abs(np.mean(x_ref)))


def is_wet(run):
    """Whether the run has block pressures (a dry scene records none: all NaN)."""
    return bool(np.any(np.isfinite(np.asarray(run["U"], float))))


def floors(ref):
    """{metric: chaos floor} of the reference (see ``_metric_pairs``; no pressure metrics when dry)."""
    U = np.asarray(ref["U"], float)
    out = {"porosity_change": change_floor(porosity_change(ref)), "settlement": change_floor(settlement(ref))}
    if is_wet(ref):
        out.update(pressure_rms=pressure_floor(U), pressure_rms_below_surface=pressure_floor(U[:, :, :-1]))
    return out


def block_mean_pressures(U):
    """The time-mean pressure of each block per start [N/m] of histories U (starts, times, blocks),
    over the samples where the block has pores (NaN for a block that never has one)."""
    U = np.asarray(U, float)
    n = np.sum(np.isfinite(U), axis=1)
    return np.divide(np.nansum(U, axis=1), n, out=np.full(n.shape, np.nan), where=n > 0)


def corrected(measured, floor):
    """The systematic part of a measured metric: sqrt(max(0, measured^2 - floor^2))."""
    return float(np.sqrt(max(0.0, measured * measured - floor * floor)))


def _metric_pairs(run, ref, blocks=False):
    """{metric: (measured, floor)} of a run's histories against the reference's (dicts as written by
    yade_scripts/tradeoffs.py: t (times,), U (starts, times, blocks), porosity (starts, times),
    height (starts, times) the particles' mean centre height [m]; the run's U is interpolated onto
    the reference's times). No pressure metrics when the reference is dry. With ``blocks``, also
    ``block_mean_<b>`` for each block b (1 at the bottom) with pores: the change error of its
    time-mean pressure per start (``block_mean_pressures``) over RMS(<U_ref>), the scale of
    ``pressure_rms``, so that a block whose mean pressure is near 0 is judged on the scene's pressures."""
    A, R = _on_grid(run["t"], run["U"], ref["t"]), np.asarray(ref["U"], float)
    out = {}
    if is_wet(ref):
        for key, a, r in (("pressure_rms", A, R), ("pressure_rms_below_surface", A[:, :, :-1], R[:, :, :-1])):
            out[key] = (_pressure_error(a, r), _pressure_noise(a, r))
    if blocks and is_wet(ref):
        scale = _rms(np.nanmean(R, axis=0))
        x, x_ref = block_mean_pressures(A), block_mean_pressures(R)
        for b in range(R.shape[2]):
            if np.all(np.isfinite(x_ref[:, b])) and np.all(np.isfinite(x[:, b])):
                out[f"block_mean_{b + 1}"] = (change_error(x[:, b], x_ref[:, b], scale),
                                              change_noise(x[:, b], x_ref[:, b], scale))
    for key, f in (("porosity_change", porosity_change), ("settlement", settlement)):
        x, x_ref = f(run), f(ref)
        out[key] = (change_error(x, x_ref), change_noise(x, x_ref))
    return out


def _subset(run, idx):
    return {"t": run["t"], **{k: np.asarray(run[k], float)[idx] for k in ("U", "porosity", "height")}}


def systematic(run, ref, n_boot=400, seed=0, blocks=False):
    """{metric: {"measured", "floor", "systematic", "sigma"}}: the metric, its floor between these
    two ensembles (``_pressure_noise``, ``change_noise``), the noise-corrected estimate
    ``corrected(measured, floor)`` and the standard deviation of that estimate over ``n_boot``
    bootstrap resamples of the starts of run and reference (module docstring); ``blocks``: with
    the blocks' time-mean pressures (``_metric_pairs``)."""
    pairs = _metric_pairs(run, ref, blocks)
    out = {k: {"measured": m, "floor": f, "systematic": corrected(m, f)} for k, (m, f) in pairs.items()}
    rng = np.random.default_rng(seed)
    na, nb = len(run["U"]), len(ref["U"])
    boot = {k: [] for k in out}
    for _ in range(n_boot):
        pairs = _metric_pairs(_subset(run, rng.integers(0, na, na)), _subset(ref, rng.integers(0, nb, nb)), blocks)
        for k in out:
            boot[k].append(corrected(*pairs[k]) if k in pairs else np.nan)
    for k in out:
        out[k]["sigma"] = float(np.nanstd(boot[k], ddof=1))
    return out


def porosity_change(run):
    """Porosity at the end minus at the start, per start."""
    p = np.asarray(run["porosity"], float)
    return p[:, -1] - p[:, 0]


def settlement(run):
    """Drop of the particles' mean centre height over the window [m] per start (> 0: settled)."""
    h = np.asarray(run["height"], float)
    return h[:, 0] - h[:, -1]


def pareto_front(cost, error):
    """Indices of the points no other point beats on both (cost, error): each has the lowest
    error among the points at its cost or below. Sorted by cost."""
    cost, error = np.asarray(cost, float), np.asarray(error, float)
    order = np.lexsort((error, cost))
    front, best = [], np.inf
    for i in order:
        if np.isfinite(error[i]) and error[i] < best:
            front.append(int(i))
            best = error[i]
    return front


# -- the study's points ----------------------------------------------------------------------------
RECORD = 5e-4      # s between samples of the histories (a multiple of every dt below)
REBUILD_PERIOD = 1e-3  # s between pore rebuilds in the dt sweep: the paper's 1000 steps of 1e-6 s
STARTS = 5         # perturbed starts per setting, unless the case's "starts" says more for a knob
REFERENCE_DT = 5e-7
PERTURBATION = 1e-9  # m: the size of the perturbation of the starts (engines.studies.ensemble.perturbed)
PAPER_DT = 1e-6

# The named settings chosen from the study: the fast one (dt = "auto" at the schema's dt_auto_factor) and
# the paper's numerics
FAST = {"name": "fast", "numerics.dt": "auto", "numerics.rebuild_interval": 50, "numerics.water_interval": 1}
ACCURATE = {"name": "accurate", "numerics.dt": PAPER_DT, "numerics.rebuild_interval": 1000, "numerics.water_interval": 1}

# Per case: the window [s], the base dt the other knobs are swept around (rebuilds every 1 ms) and
# the values of each knob; "preset" (default: the key) and "reference_dt" (default REFERENCE_DT)
# where they differ; "starts": {knob: starts} where a knob needs more than STARTS (the chaos floor
# falls as 1/sqrt(starts)); "perturbation_size": the size of the perturbation of the starts [m] (default
# PERTURBATION), large enough that the ensemble means no longer depend on it (the knob
# "perturbation" checks that; docs/TRADEOFFS.md). "defaults" are the named settings chosen from the study.
CASES = {
    "liquefaction_case1": {"window": 0.04, "fast_dt": 2e-5, "perturbation_size": SEISMIC_PERTURBATION,
                           "starts": {"reference": 20, "dt": 20, "defaults": 20, "candidate": 20, "perturbation": 20},
                           "dt": [1e-6, 5e-6, 1e-5, 2e-5, 5e-5, 1e-4],
                           # the ensemble's convergence in the size of the perturbation (at fast_dt)
                           "perturbation": [1e-9, 1e-8, 3e-7],
                           "water_interval": [2, 5, 10], "rebuild_period": [2e-4, 5e-4, 2e-3, 5e-3],
                           "smoothing": [True], "transfer": ["conserving"], "E_w_scale": [0.1, 10.0, 100.0],
                           "precision": ["longdouble"],
                           "defaults": [FAST, ACCURATE],
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
    "liquefaction_case4": {"window": 0.02, "fast_dt": 2e-5, "dt": [1e-6, 2e-5], "law": ["yade"]},
}

# The validation of the fast setting where it is offered: on every preset scene, over the scene's whole
# duration ("window": None), from VALIDATION_STARTS starts at the scene's perturbation, against the
# paper's numerics (dt = 1e-6 s, rebuilds every 1000 steps, water every step: dt_settings(PAPER_DT)) as
# the reference. Case "<scene>_full"; not part of the trade study's default points (``points``).
VALIDATION = {"liquefaction_case1": SEISMIC_PERTURBATION, "quicksand_case1": QUICKSAND_PERTURBATION,
              "quicksand_case2": QUICKSAND_PERTURBATION,
              **{f"liquefaction_case{n}": SEISMIC_PERTURBATION for n in range(2, 8)}}
VALIDATION_STARTS = 20
# tried on the seismic box where the fast setting is not validated: half its dt (dt_auto_factor 0.18, 2.0e-5 s,
# within the chaos on every metric over 0.04 s) with the pores rebuilt every 1 ms
VALIDATION_CANDIDATE = {"name": "f0.18_rb50", "numerics.dt": "auto", "numerics.dt_auto_factor": 0.18,
                        "numerics.rebuild_interval": 50, "numerics.water_interval": 1}
for _scene, _size in VALIDATION.items():
    CASES[f"{_scene}_full"] = {"preset": _scene, "window": None, "reference_dt": PAPER_DT, "perturbation_size": _size,
                               "starts": {"reference": VALIDATION_STARTS, "defaults": VALIDATION_STARTS,
                                          "candidate": VALIDATION_STARTS},
                               "defaults": [FAST], "validation": True,
                               "candidate": [VALIDATION_CANDIDATE] if _size == SEISMIC_PERTURBATION else []}
VALIDATION_CASES = tuple(f"{scene}_full" for scene in VALIDATION)

# The default [numerics] dt_auto_factor, and per factor tried the preset scenes on which dt = "auto" at that
# factor, with the pores rebuilt every 50 steps and the water every step, is within 5 % of the paper's numerics
# (dt = 1e-6 s, rebuilds every 1000 steps) on every judged statistic over the whole run (docs/TRADEOFFS.md,
# "Validation"; tests/studies/test_tradeoffs.py ties them to docs/tradeoffs/validation.json).
VALIDATED_FACTOR = DT_AUTO_FACTOR  # the default of [numerics] dt_auto_factor
VALIDATED_ON = {0.36: ("quicksand_case2", "liquefaction_case2", "liquefaction_case3", "liquefaction_case7"),
                0.18: ("liquefaction_case1", "liquefaction_case2", "liquefaction_case3", "liquefaction_case5",
                       "liquefaction_case7")}
SHORT_WINDOW_EVIDENCE = {0.36: "within 5 % over the first 0.04 s of liquefaction_case1 only (the trade study)"}


def validation_note(factor):
    """Where the automatic time step's dt_auto_factor ``factor`` was validated (VALIDATED_ON)."""
    if factor not in VALIDATED_ON:
        return f"dt_auto_factor {factor:g} is not validated (docs/TRADEOFFS.md, Validation)"
    where = ", ".join(VALIDATED_ON[factor]) or "no preset scene"
    extra = f"; {SHORT_WINDOW_EVIDENCE[factor]}" if factor in SHORT_WINDOW_EVIDENCE else ""
    return (f"dt_auto_factor {factor:g} with rebuild_interval 50 and water_interval 1 against the paper's numerics: "
            f"validated over the whole run on {where} (other scenes: not validated){extra} (docs/TRADEOFFS.md, Validation)")


def dt_settings(dt):
    """dt [s] with the pores rebuilt every REBUILD_PERIOD (so that the dt sweep does not also
    change the rebuild period), water every step."""
    return {"numerics.dt": dt, "numerics.rebuild_interval": max(1, int(round(REBUILD_PERIOD / dt))),
            "numerics.water_interval": 1}


PRIORITY = (("reference", "dt", "defaults", "perturbation", "candidate", "water_interval", "rebuild_period"),
            ("smoothing", "transfer", "E_w_scale", "precision", "law"))
LAST = ("liquefaction_case4",)  # run after every knob of the other cases


def points(cases=None):
    """[(case, knob, value)] of the study (of ``cases`` only, when given; by default every case
    but the validation's) in the order it runs: the references, dt (with the paper's settings),
    water_interval and rebuild_period of every case, then the other knobs, case by case in the
    order of CASES (liquefaction case 4 last), so that a stopped study has the first knobs."""
    chosen = [c for c in CASES if (c in cases if cases else not CASES[c].get("validation"))]
    out = []
    order = [(knobs, [c for c in chosen if c not in LAST]) for knobs in PRIORITY]
    order.append((sum(PRIORITY, ()), [c for c in chosen if c in LAST]))
    for knobs, names in order:
        for case in names:
            spec = CASES[case]
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


def more_starts_name(name, first, count):
    """The job that runs starts first .. first + count - 1 of the job ``name``'s setting (a
    validation row given more starts, engines.run.tradeoffs.run_study)."""
    return f"{name}.starts{first}-{first + count - 1}"


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
