"""Readers of what a run writes (engines/yade_run.py): history.csv, snapshot_*.npz, summary.json."""
import csv
import glob
import json
import os
import re

import numpy as np


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
    """One snapshot as a dict of arrays (t, xz, r, group, density_factor, vel, pairs, f_n and,
    with water, tri, tri_pore, U)."""
    with np.load(path, allow_pickle=False) as z:
        return dict(z)


def read_summary(run_dir):
    """summary.json of a run as a dict ({} when missing)."""
    path = os.path.join(run_dir, "summary.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)
