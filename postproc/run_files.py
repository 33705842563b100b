"""Readers of what a run writes (engines/run/runner.py): history.csv, snapshot_*.npz, summary.json."""
import csv
import glob
import json
import os
import re

import numpy as np


def run_dir(path):
    """argparse type of a run folder argument: ``path`` if it holds a run's history.csv, else one line
    saying what it is and what to give instead."""
    import argparse
    if not os.path.isdir(path):
        raise argparse.ArgumentTypeError(f"{path}: no such folder (give the --out folder of a run)")
    if not os.path.isfile(os.path.join(path, "history.csv")):
        raise argparse.ArgumentTypeError(f"{path}: not a run folder (no history.csv; give the --out folder of a run)")
    return path


def read_history(path):
    """history.csv as {column: array}."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else {}


def snapshot_files(run_dir):
    """The run's snapshot_*.npz files in time order."""
    files = glob.glob(os.path.join(run_dir, "snapshot_*.npz"))
    return sorted(files, key=lambda f: float(re.search(r"snapshot_([0-9.]+)ms", f).group(1)))


def read_snapshot(path):
    """One snapshot as a dict of arrays (t, xz, r, group, density_factor, vel, pairs, f_n, f_s
    and, with water, tri, tri_pore, U, W, A, rule, with flat walls vertices, and the network under
    OpenPNM's names, read_network; engines.run.runner.snapshot_data)."""
    with np.load(path, allow_pickle=False) as z:
        return dict(z)


def run_folders(path):
    """The run folders under ``path``: each start's (start_<k>) of an ensemble (ensemble.json there,
    engines.run.ensemble), else ``path`` itself."""
    plan = os.path.join(path, "ensemble.json")
    if not os.path.exists(plan):
        return [path]
    with open(plan) as f:
        return [os.path.join(path, f"start_{k}") for k in json.load(f)["seeds"]]


def ensemble_history(path):
    """(history of the means over the starts {column: array}, {column: (95 % low, high)}) of the
    ensemble in ``path`` (its ensemble.json's history statistics), or (None, None) before they exist."""
    with open(os.path.join(path, "ensemble.json")) as f:
        doc = json.load(f)
    if "history" not in doc:
        return None, None
    cols = doc["history"]["columns"]
    f = lambda v: np.array([np.nan if x is None else x for x in v], float)  # noqa: E731
    mean = {"t": np.array(doc["history"]["t"], float), **{c: f(st["mean"]) for c, st in cols.items()}}
    return mean, {c: (f(st["ci95_low"]), f(st["ci95_high"])) for c, st in cols.items()}


def read_summary(run_dir):
    """summary.json of a run as a dict ({} when missing)."""
    path = os.path.join(run_dir, "summary.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)


def headline_results(history, heave_rise):
    """The headline numbers of a run from its history ({column: array}) for summary.json:
    per pressure block the peak of its mean excess pore pressure U [N/m] and when; the heave time:
    the first row whose bed top (highest particle top) lies ``heave_rise`` [m] or more above that
    of the first row (None if it never does); the porosity of the last row and its change from the
    first (a seismic run's compaction < 0, a heave's dilation > 0); the bands' effective stress and
    r_u (``band_results``). {} without rows."""
    t = history.get("t", np.zeros(0))
    if not len(t):
        return {}
    peaks = {}
    for name in sorted(c for c in history if c.startswith("U_block")):
        u = history[name]
        ok = np.flatnonzero(np.isfinite(u))
        k = ok[np.argmax(u[ok])] if len(ok) else None
        peaks[name] = None if k is None else {"U_max_N_per_m": float(u[k]), "t_s": float(t[k])}
    bed = history["bed_top"]
    risen = np.flatnonzero(bed - bed[0] >= heave_rise)
    bands = band_results(history, risen[0] if len(risen) else None)
    return {"peak_block_pressures": peaks, **({"bands": bands} if bands else {}),
            "heave_rise_m": heave_rise, "bed_top_initial_m": float(bed[0]), "bed_top_max_m": float(bed.max()),
            "heave_time_s": float(t[risen[0]]) if len(risen) else None,
            "porosity_last_row": float(history["porosity"][-1]), "t_last_row_s": float(t[-1]),
            "porosity_change": float(history["porosity"][-1] - history["porosity"][0])}


RU_LIQUEFIED = 0.9  # r_u at which a band counts as liquefied (the first time it is reached)
QUICK = 0.1  # a band's contacts let go when its sigma'_v falls below this fraction of its first row's


def band_results(history, heave_row=None):
    """Per band of the bed (history.csv's sv_band*, p_band*, ru_band* columns; engines.model.effective_stress)
    {band<k>: results}: the least p'/p'_0 over the run (p'_0 the first row's; None where p'_0 <= 0);
    the first time its contacts let go, sigma'_v < QUICK sigma'_v0 (``t_quick_s``, None if never: the
    bottom band's is the quick sand's heave onset, the base lifted by its water); with water, the
    largest r_u, the first time r_u >= RU_LIQUEFIED (None if never), r_u where the contacts let go
    and at the heave's row ``heave_row`` (the quick sand's surface risen); {} without the columns."""
    t = history["t"]
    out = {}
    for k in range(1, 1 + sum(c.startswith("p_band") for c in history)):
        p, sv = history[f"p_band{k}"], history[f"sv_band{k}"]
        quick = np.flatnonzero(sv < QUICK * sv[0]) if sv[0] > 0 else []
        q = quick[0] if len(quick) else None
        res = {"p_ratio_min": float(np.nanmin(p / p[0])) if p[0] > 0 and np.isfinite(p).any() else None,
               "t_quick_s": None if q is None else float(t[q])}
        ru = history.get(f"ru_band{k}")
        if ru is not None:
            ok = np.isfinite(ru)
            hit = np.flatnonzero(ok & (ru >= RU_LIQUEFIED))
            at = lambda row: float(ru[row]) if row is not None and ok[row] else None  # noqa: E731
            res.update(ru_max=float(np.max(ru[ok])) if ok.any() else None,
                       t_ru_0p9_s=float(t[hit[0]]) if len(hit) else None, ru_at_quick=at(q))
            if heave_row is not None:
                res["ru_at_heave"] = at(heave_row)
        out[f"band{k}"] = res
    return out


NETWORK_PREFIXES = ("pore.", "throat.", "polygon.", "balance.")  # engines.model.network_view's keys


def read_network(path):
    """The pore network of a snapshot file (engines.model.network_view: its pore.*, throat.*,
    polygon.* and balance.* arrays), {} for a dry one or a snapshot written before them."""
    return {k: v for k, v in read_snapshot(path).items() if k.startswith(NETWORK_PREFIXES)}
