"""The effective-stress readings judged on a preset (SPEC §2.8; docs/READINGS.md, E1-E7), from an
ensemble's files: ``quicksand_ru(ENSEMBLE_DIR)`` the quick-sand bed's bottom band at the heave
(r_u with its 95 % interval over the starts, sigma'_v0 from the contacts and the buoyant overburden
beside it, and the check r_u in [0.8, 1.2]); the same band at its quick condition, the first output
row where its contacts carry less than QUICK of their start's σ'_v (``quick_condition``: the grains
carry nothing there, whatever holds the bed above); and how much of the bed's buoyant weight the walls
carry at t = 0 (``weight_carried``: 1 when the bed starts at rest). ``make readings`` runs the ensemble and writes
docs/readings/quicksand_ru.json, and again with every contact frictionless ([contact] mu = 0, the
scene's friction; the record's ``mu``) -> docs/readings/quicksand_ru_mu0.json:

    /usr/bin/python3 -m postproc.readings ENSEMBLE_DIR OUT.json
"""
import argparse
import json
import os
import time

import numpy as np

from engines import files
from engines.model.effective_stress import pair_contacts
from engines.studies.ensemble import statistics
from postproc.run_files import read_history, read_snapshot, read_summary, run_folders, snapshot_files

RU_HEAVE = (0.8, 1.2)  # the bottom band's r_u expected at the heave (issue 42)
QUICK = 0.1  # [-] the fraction of its start's sigma'_v below which a band's contacts count as carrying nothing


def quick_condition(history, band=1, fraction=QUICK):
    """(t [s], r_u) at the first row of ``history`` (read_history) where band ``band``'s sigma'_v
    falls below ``fraction`` of its first row's; (nan, nan) if it never does."""
    sv, ru = history[f"sv_band{band}"], history[f"ru_band{band}"]
    hit = np.flatnonzero(sv < fraction * sv[0])
    return (float(history["t"][hit[0]]), float(ru[hit[0]])) if len(hit) else (np.nan, np.nan)


def weight_carried(snap, rho, rho_w, g):
    """The walls' vertical push on the particles of snapshot ``snap`` (the sum of their contact
    forces: the particles' own pairs cancel) over the particles' buoyant weight [-]: 1 at rest."""
    m = snap["group"] == 0
    c = pair_contacts(snap["xz"], snap["r"], snap["pairs"], snap["f_n"], snap["f_s"], m)
    weight = float(np.sum((rho * snap["density_factor"][m] - rho_w) * g * np.pi * snap["r"][m] ** 2))
    return float(np.sum(c.force[:, 1])) / weight


def quicksand_ru(ensemble_dir):
    """The record of the quick-sand ensemble in ``ensemble_dir`` (engines.run.ensemble): see the module docstring."""
    with open(os.path.join(ensemble_dir, "ensemble.json")) as f:
        doc = json.load(f)
    res = doc["results"]
    first = read_summary(run_folders(ensemble_dir)[0])
    mat = first["parameters"]["material"]
    snap0 = read_snapshot(snapshot_files(run_folders(ensemble_dir)[0])[0])
    prov = first.get("provenance") or {}
    sv0, ob = first["band_sigma_v0_Pa"][0], first["band_overburden_Pa"][0]
    ru = res["bands.band1.ru_at_heave"]
    stats = lambda r: {k: r[k] for k in ("n", "mean", "ci95_low", "ci95_high")}  # noqa: E731
    quick = np.array([quick_condition(read_history(os.path.join(d, "history.csv"))) for d in run_folders(ensemble_dir)])
    quick_stats = [{k: float(v) for k, v in stats(statistics(quick[:, c])).items()} for c in (0, 1)]
    return {
        "date": time.strftime("%Y-%m-%d"), "commit": prov.get("git_commit"), "dirty": prov.get("git_dirty"),
        "scene": doc["scene"], "n_starts": doc["n_starts"], "perturbation_m": doc["perturbation_m"],
        "mu": first["parameters"]["contact"]["mu"],
        "weight_carried_at_start": weight_carried(snap0, mat["rho"], mat["rho_w"], mat["g"]),
        "interval": doc["interval"], "heave_time_s": stats(res["heave_time_s"]),
        "band1": {"z_m": first["band_bounds_m"][0], "sigma_v0_Pa": sv0, "overburden_Pa": ob,
                  "ru_at_heave": stats(ru), "ru_max": stats(res["bands.band1.ru_max"]),
                  "U_over_overburden_at_heave": ru["mean"] * sv0 / ob,
                  "quick_condition": {"definition": f"the first output row where the band's sigma'_v < {QUICK} x its "
                                                    "first row's", "t_s": quick_stats[0], "ru": quick_stats[1],
                                      "U_over_overburden": quick_stats[1]["mean"] * sv0 / ob}},
        "criterion": f"the bottom band's r_u at the heave lies in [{RU_HEAVE[0]}, {RU_HEAVE[1]}] (its 95 % interval)",
        "holds": bool(RU_HEAVE[0] <= ru["ci95_low"] and ru["ci95_high"] <= RU_HEAVE[1]),
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("ensemble", help="the --out folder of `quicksand.py --starts N`")
    parser.add_argument("out", help="the JSON file to write")
    a = parser.parse_args(argv)
    record = quicksand_ru(a.ensemble)
    files.write_json(a.out, record)
    b = record["band1"]
    print(f"{a.out}: bottom band r_u at the heave {b['ru_at_heave']['mean']:.3g} (95 % interval "
          f"{b['ru_at_heave']['ci95_low']:.3g} to {b['ru_at_heave']['ci95_high']:.3g}, {record['n_starts']} starts); "
          f"sigma'_v0 {b['sigma_v0_Pa']:.3g} Pa, overburden {b['overburden_Pa']:.3g} Pa; holds: {record['holds']}; "
          f"at its quick condition ({b['quick_condition']['t_s']['mean'] * 1e3:.3g} ms) r_u {b['quick_condition']['ru']['mean']:.3g} "
          f"({b['quick_condition']['ru']['ci95_low']:.3g} to {b['quick_condition']['ru']['ci95_high']:.3g})")


if __name__ == "__main__":
    main()
