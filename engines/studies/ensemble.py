"""Ensembles of runs: the perturbed starts and their statistics across starts.

DEM runs are chaotic: starts a little apart follow trajectories that part after some
milliseconds, so one run is one sample. An ensemble runs a scene from ``n`` starts, start k the
scene's packing with every particle (not the walls) moved by ``size`` x N(0, 1) in x and z
(``perturbed``, numpy Generator(k); start 0 is the packing itself), and states each quantity as
its mean over the starts, the standard error of that mean and a 95 % interval (Student's t with
n - 1 degrees of freedom: mean +- t(0.975, n - 1) standard error; ``statistics``).

The size must part the starts before the events the scene is about, yet stay far below a disc
(docs/SWEEPS.md, "Ensembles"): SEISMIC_PERTURBATION for the seismic box (docs/TRADEOFFS.md: 1e-9 m
starts follow one trajectory through the pressure build-up, from 1e-7 m the ensemble means no
longer depend on the size), QUICKSAND_PERTURBATION for the quick sand (measured before its heave).

Used by the scene scripts' ``--starts`` (engines.run.ensemble) and by the speed/accuracy study
(engines.studies.tradeoffs). Plain NumPy and SciPy; no YADE.
"""
import dataclasses

import numpy as np
from scipy import stats

SEISMIC_PERTURBATION = 1e-7     # m: the seismic box (yade_scripts/liquefaction.py)
QUICKSAND_PERTURBATION = 1e-8   # m: the quick sand (yade_scripts/quicksand.py)
CONFIDENCE = 0.95


def perturbed(packing, seed, size):
    """A copy of ``packing`` whose particles (not the walls) are moved by ``size`` [m] times a
    standard normal in x and z, drawn from numpy's Generator(seed); seed 0 is the packing itself."""
    if seed == 0:
        return packing
    rng = np.random.default_rng(seed)
    xz = packing.xz.copy()
    mob = packing.mobile
    xz[mob] += size * rng.standard_normal((int(mob.sum()), 2))
    return dataclasses.replace(packing, xz=xz)


def statistics(values):
    """Statistics over axis 0 (the starts) of ``values`` (starts, ...), each entry over the starts
    where it is finite (n of them): {"n", "mean", "standard_error" (std with ddof 1 / sqrt(n)),
    "ci95_low", "ci95_high" (mean -+ t(0.975, n - 1) standard error)}, arrays of the shape of one
    start; NaN where n = 0 (mean) or n < 2 (the others)."""
    v = np.asarray(values, float)
    ok = np.isfinite(v)
    n = ok.sum(axis=0)
    x = np.where(ok, v, 0.0)
    mean = np.divide(x.sum(axis=0), n, out=np.full(n.shape, np.nan), where=n > 0)
    dev = np.where(ok, v - mean, 0.0)
    var = np.divide((dev * dev).sum(axis=0), n - 1, out=np.full(n.shape, np.nan), where=n > 1)
    se = np.sqrt(var / np.maximum(n, 1))
    half = t_half_width(se, n)
    return {"n": n, "mean": mean, "standard_error": se, "ci95_low": mean - half, "ci95_high": mean + half}


def t_half_width(standard_error, n):
    """Half-width of the CONFIDENCE interval of a mean of n values with this standard error
    (s.d. / √n): t((1 + CONFIDENCE)/2, n − 1) standard_error (n < 2: t at one degree of freedom)."""
    return stats.t.ppf(0.5 + CONFIDENCE / 2, np.maximum(np.asarray(n) - 1, 1)) * standard_error


MAX_STARTS = 80  # the most starts a study's row is given (issue 42: starts chosen from sigma ~ 1/sqrt(n))


def starts_needed(n, half_width, distance, cap=MAX_STARTS):
    """The starts that would shrink an interval's half-width (n starts) below ``distance`` (the
    estimate's distance to the criterion's threshold, same units), with the interval narrowing as
    1/sqrt(starts): ceil(n (half_width / distance)^2), at least n + 1; None where it exceeds
    ``cap`` (or the distance is 0)."""
    if distance <= 0:
        return None
    need = max(int(np.ceil(n * (half_width / distance) ** 2)), n + 1)
    return need if need <= cap else None


def flat_results(results, prefix=""):
    """The numbers of a run's ``results`` (summary.json, nested dicts) as {"a.b.c": value}; a
    None (e.g. a heave that did not happen) as NaN."""
    out = {}
    for key, value in results.items():
        name = prefix + key
        if isinstance(value, dict):
            out.update(flat_results(value, name + "."))
        elif value is None or (isinstance(value, (int, float)) and not isinstance(value, bool)):
            out[name] = np.nan if value is None else float(value)
    return out


def on_common_grid(histories):
    """(t, {column: (starts, times) array}) of histories ({column: array}, with "t"): the times
    of the first start within the span every start covers; a start sampled at other times (dt =
    "auto" chooses dt from each start's packing) is interpolated linearly onto them."""
    t0 = np.asarray(histories[0]["t"], float)
    lo, hi = max(h["t"][0] for h in histories), min(h["t"][-1] for h in histories)
    t = t0[(t0 >= lo) & (t0 <= hi)]
    columns = {}
    for col in (c for c in histories[0] if c != "t" and all(c in h for h in histories)):  # the columns all have
        rows = []
        for h in histories:
            tk, y = np.asarray(h["t"], float), np.asarray(h[col], float)
            k0 = int(np.searchsorted(tk, t[0]))
            same = len(tk) >= k0 + len(t) and np.array_equal(tk[k0:k0 + len(t)], t)
            rows.append(y[k0:k0 + len(t)] if same else np.interp(t, tk, y))
        columns[col] = np.array(rows)
    return t, columns


def ensemble_statistics(histories, results):
    """{"results": {entry: statistics and per-start values}, "history": {"t", "columns": {column:
    statistics}}} of the starts' histories and ``results`` dicts (in the order of the starts)."""
    flat = [flat_results(r) for r in results]
    names = set().union(*flat)
    # a None in one start where another has numbers below it: no value for those numbers
    keys = sorted(k for k in names if not any(m.startswith(k + ".") for m in names))
    out_results = {}
    for key in keys:
        values = np.array([f.get(key, np.nan) for f in flat])
        out_results[key] = {**{k: v.item() for k, v in statistics(values).items()}, "values": values.tolist()}
    t, columns = on_common_grid(histories)
    out_history = {"t": t.tolist(),
                   "columns": {c: {k: v.tolist() for k, v in statistics(y).items()} for c, y in columns.items()}}
    return {"results": out_results, "history": out_history}
