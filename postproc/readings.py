"""The effective-stress readings judged on a preset (SPEC §2.8; docs/READINGS.md, E1-E8), from an
ensemble's files: ``quicksand_ru(ENSEMBLE_DIR)`` the quick-sand bed's bottom band at the heave's
onset, the first output row where its contacts carry less than postproc.run_files.QUICK of their
start's σ'_v (the base lifted by its water, Terzaghi's heave; summary.json's ``t_quick_s``): r_u there
with its 95 % interval over the starts, and the check r_u in [0.8, 1.2]; beside it σ'_v0 from the
contacts and the buoyant overburden, r_u when the surface has risen by [output] heave_rise
(``heave_time_s``), the bottom block's peak U beside the bound E_w that eq 32 sets, and how much of
the bed's buoyant weight the walls carry at t = 0 (``weight_carried``: 1 when the bed starts at rest
in its water, the dry over the buoyant weight when it rests under its dry weight). ``make readings``
runs the ensemble of case 1 -> docs/readings/quicksand_ru.json, again with every contact
frictionless ([contact] mu = 0; the record's ``mu``) -> quicksand_ru_mu0.json, and on the bed
settled in its water (quicksand_case1_submerged) -> quicksand_ru_submerged.json:

    /usr/bin/python3 -m postproc.readings ENSEMBLE_DIR OUT.json
"""
import argparse
import json
import os
import time

import numpy as np

from engines import files
from engines.model.effective_stress import pair_contacts
from postproc.run_files import QUICK, read_snapshot, read_summary, run_folders, snapshot_files

RU_HEAVE = (0.8, 1.2)  # the bottom band's r_u expected at the heave's onset (issue 42)


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
    none = {"n": 0, "mean": None, "ci95_low": None, "ci95_high": None}  # a run too short for the surface's heave
    stats = lambda key: {k: res[key][k] for k in none} if key in res else none  # noqa: E731
    onset, surface = stats("bands.band1.ru_at_quick"), stats("bands.band1.ru_at_heave")
    over = lambda ru: None if ru["mean"] is None else ru["mean"] * sv0 / ob  # noqa: E731
    return {
        "date": time.strftime("%Y-%m-%d"), "commit": prov.get("git_commit"), "dirty": prov.get("git_dirty"),
        "scene": doc["scene"], "n_starts": doc["n_starts"], "perturbation_m": doc["perturbation_m"],
        "mu": first["parameters"]["contact"]["mu"],
        "weight_carried_at_start": weight_carried(snap0, mat["rho"], mat["rho_w"], mat["g"]),
        "interval": doc["interval"],
        "band1": {"z_m": first["band_bounds_m"][0], "sigma_v0_Pa": sv0, "overburden_Pa": ob,
                  "heave_onset": {"definition": f"the first output row where the band's sigma'_v < {QUICK} x its "
                                                "first row's (its contacts let go)",
                                  "t_s": stats("bands.band1.t_quick_s"), "ru": onset,
                                  "U_over_overburden": over(onset)},
                  "surface_heave": {"definition": f"the first output row where the bed top has risen by "
                                                  f"{first['results']['heave_rise_m']} m",
                                    "t_s": stats("heave_time_s"), "ru": surface,
                                    "U_over_overburden": over(surface)},
                  "ru_max": stats("bands.band1.ru_max")},
        "block1_U_max_N_per_m": stats("peak_block_pressures.U_block1.U_max_N_per_m"),
        "E_w_N_per_m": first["parameters"]["water"]["E_w"],
        "criterion": f"the bottom band's r_u at the heave's onset lies in [{RU_HEAVE[0]}, {RU_HEAVE[1]}] (its 95 % interval)",
        "holds": onset["n"] > 1 and bool(RU_HEAVE[0] <= onset["ci95_low"] and onset["ci95_high"] <= RU_HEAVE[1]),
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("ensemble", help="the --out folder of `quicksand.py --starts N`")
    parser.add_argument("out", help="the JSON file to write")
    a = parser.parse_args(argv)
    record = quicksand_ru(a.ensemble)
    files.write_json(a.out, record)
    b = record["band1"]
    interval = lambda r: ("none" if r["mean"] is None else  # noqa: E731
                          f"{r['mean']:.3g} (95 % interval {r['ci95_low']:.3g} to {r['ci95_high']:.3g})")
    ms = lambda t: "none" if t["mean"] is None else f"{t['mean'] * 1e3:.3g} ms"  # noqa: E731
    print(f"{a.out}: bottom band r_u at the heave's onset ({ms(b['heave_onset']['t_s'])}) "
          f"{interval(b['heave_onset']['ru'])}, {record['n_starts']} starts; holds: {record['holds']}; "
          f"sigma'_v0 {b['sigma_v0_Pa']:.3g} Pa, overburden {b['overburden_Pa']:.3g} Pa; at the surface's heave "
          f"({ms(b['surface_heave']['t_s'])}) r_u {interval(b['surface_heave']['ru'])}")


if __name__ == "__main__":
    main()
