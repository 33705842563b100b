"""Seed 003 biaxial compression test (Murakami et al. §2, SPEC §4): wall-less periodic packing to
each σ3, then the test; strength φ*, c* and stiffness E50 of the model ground.

    yade -n -x yade_scripts/biaxial.py --phi-e DEG --sigma3 100,200,300,400 --out DIR [options]
    yade-batch -j 2 yade_scripts/biaxial_sweep.table yade_scripts/biaxial.py

Writes into DIR:
    curves.csv            deviator against axial strain, per σ3 (long format, one row per record)
    summary.json          phi_star_deg, c_star_pa, per_sigma3 [{sigma3_pa, peak_deviator_pa, e50_pa, ...}],
                          the parameters, the packings and the run times
    deviator_strain.png   Fig. 9(A): deviator and volumetric strain against axial strain
    mohr.png              Fig. 9(B): Mohr circles at the peak and the failure line
    packing_sigma3_<S>.csv/.json   the packed periodic block at σ3 = S (x, z, r; cell, stresses)

Under yade-batch the parameters come from the table line (columns named as the options, with
underscores: phi_e, sigma3, seed, ...; values as literals, engines.run.table); the output directory is the
table's ``out`` column, else the sweep runner's job directory, else out/biaxial-batch/DESCRIPTION.
"""
import argparse
import math
import os
import sys
import time

import numpy as np

from engines import files
from engines.run.command_line import batch_out
from engines.run.preflight import ArgumentParser, number, output_dir
from engines.run.table import DESCRIPTION, batch_line
from engines.seeds.biaxial.cem_contact import ROTATIONS
from engines.seeds.biaxial.periodic import PACKING_PHI_E

PERCENT_PER_MIN = 1.0 / 6000.0  # 1 %/min in 1/s


def stresses(text):
    """argparse type: comma-separated stresses > 0 [Pa] (yade-batch tables give "(100, 200)")."""
    try:
        values = [float(v) for v in str(text).strip("()").split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) and v > 0 for v in values):
        raise argparse.ArgumentTypeError(f"must be comma-separated stresses > 0 Pa, got {text!r}")
    return values


def friction_angle(text):
    """argparse type: φe in (0, 90) degrees."""
    value = number(float, 0, 90, lo_open=True, unit="degrees")(text)
    if value == 90:
        raise argparse.ArgumentTypeError(f"must be in (0, 90) degrees, got {text}")
    return value


def packing_friction(text):
    """argparse type: φe while packing [deg], or "test" (the test's --phi-e; returned as None)."""
    return None if str(text) == "test" else friction_angle(text)


def parser():
    ap = ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
                        epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--phi-e", type=friction_angle, required=True, help="inter-element friction angle φe [deg], 0 < φe < 90")
    ap.add_argument("--sigma3", type=stresses, default="100,200,300,400",
                    help="confining stresses [Pa], comma-separated (default 100..400)")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory")
    ap.add_argument("--kn", type=number(float, 0, lo_open=True, unit="Pa/m"), default=1e8,
                    help="normal stiffness per unit contact area [Pa/m] (Table 2: 1e8)")
    ap.add_argument("--ks-ratio", type=number(float, 0), default=0.25, help="ks/kn [-] (Table 2: 0.25)")
    ap.add_argument("--rho", type=number(float, 0, lo_open=True, unit="kg/m^3"), default=2500.0,
                    help="disc density [kg/m^3] (Table 2: 2500)")
    ap.add_argument("--n-discs", type=number(int, 20), default=1000, help="discs in Table 1's size ratio (paper: 1000)")
    ap.add_argument("--seed", type=number(int, 0), default=1, help="seed of the random placement")
    ap.add_argument("--dt", type=number(float, 0, lo_open=True, unit="s"),
                    help="time step [s] (default: 0.45e-4 for Table 2's constants, smaller for stiffer contacts: "
                    "engines.seeds.biaxial.cem_contact.stable_dt)")
    ap.add_argument("--packing-dt", type=number(float, 0, lo_open=True, unit="s"),
                    help="time step of the packing [s] (default: --dt)")
    ap.add_argument("--strain-rate", type=number(float, 0, lo_open=True, unit="%/min"), default=100.0,
                    help="axial strain rate [%%/min] (paper: 100)")
    ap.add_argument("--max-strain", type=number(float, 0, 50, lo_open=True, unit="%"), default=6.0,
                    help="axial strain at which the test stops [%%]")
    ap.add_argument("--side-load", choices=("exposed", "diameter"), default="exposed",
                    help="σ3 on the exposed projection of the side discs, or on every side disc's diameter")
    ap.add_argument("--aspect", type=number(float, 0.25, 4), default=1.0, help="specimen height / width [-]")
    ap.add_argument("--rotation", choices=ROTATIONS, default="free",
                    help="discs turn under the contact moments (free) or not (locked)")
    ap.add_argument("--specimen", choices=("block", "periodic"), default="block",
                    help="the block out of its cell with bands (2)-(5) (Fig. 2), or the test on the periodic cell itself")
    ap.add_argument("--packing-phi-e", type=packing_friction, default=PACKING_PHI_E,
                    help=f"φe while packing [deg], or 'test' for --phi-e (default {PACKING_PHI_E:g}: friction nearly off, "
                    "a dense packing, the same for every --phi-e), then --phi-e in the test")
    ap.add_argument("--width-factor", type=number(float, 0, lo_open=True), default=1.0,
                    help="contact width w over the harmonic mean of the radii (1; 2 = the diameter)")
    return ap


def check(args, ap):
    """The contact constants and the time steps (refused in one line naming the argument, before
    anything is written; the other arguments are checked by their argparse types)."""
    from engines.seeds.biaxial.cem_contact import CemContact, check_dt, stable_dt
    from engines.seeds.biaxial.periodic import table1_radii

    contact = CemContact(kn=args.kn, ks_ratio=args.ks_ratio, phi_e_deg=args.phi_e, rho=args.rho,
                         width_factor=args.width_factor, rotation=args.rotation)
    if args.specimen == "periodic" and args.side_load != "exposed":
        ap.error("--side-load: the test on the periodic cell has no side bands to load (σ3 is the cell's stress)")
    r = table1_radii(args.n_discs)
    args.dt = args.dt or stable_dt(r, contact)
    args.packing_dt = args.packing_dt or args.dt
    for name in ("dt", "packing_dt"):
        arg = "--" + name.replace("_", "-")
        try:
            check_dt(getattr(args, name), r, contact)
        except ValueError as e:
            ap.error(f"{arg}: {e}")
        if getattr(args, name) > 1.2 * stable_dt(r, contact):
            print(f"biaxial.py: warning: {arg} {getattr(args, name):g} s is above the step measured stable for "
                  f"these constants ({stable_dt(r, contact):.3g} s): the discs may not come to rest", file=sys.stderr)
    return contact


def table_argv(ap):
    """Under yade-batch: the table line's parameters as command-line arguments (a column named as
    an option's destination; '*' or None leaves its default); refused in one line otherwise."""
    options = {a.dest: a.option_strings[0] for a in ap._actions if a.option_strings and a.dest != "help"}
    try:
        table, line, values = batch_line()
    except ValueError as e:
        ap.error(str(e))
    argv = []
    for dest, v in values.items():
        if dest == DESCRIPTION or v is None:
            continue
        if dest not in options:
            ap.error(f"yade-batch table {table}, line {line}: column {dest!r} is not an option of this script")
        argv += [options[dest], ",".join(map(str, v)) if isinstance(v, (tuple, list)) else str(v)]
    if "out" not in values:
        try:
            argv += ["--out", batch_out(os.path.join("out", "biaxial-batch"), values[DESCRIPTION])]
        except ValueError as e:
            ap.error(str(e))
    return argv


def write_outputs(out, args, contact, blocks, results, wall_s, error=None):
    from engines.seeds.biaxial.specimen import mohr_coulomb_fit
    from postproc.biaxial_plots import plot_deviator_strain, plot_mohr

    rows = []
    for res in results:
        c = res.curve
        rows.append(np.column_stack([np.full(len(c.strain), c.sigma3), c.strain, c.deviator, c.sigma1, c.sigma1_bottom,
                                     c.sigma3_applied, c.volumetric_strain]))
    with files.saved(os.path.join(out, "curves.csv")) as tmp:
        np.savetxt(tmp, np.vstack(rows), delimiter=",", comments="", fmt="%.8g",
                   header="sigma3_pa,axial_strain,deviator_pa,sigma1_pa,sigma1_bottom_pa,sigma3_applied_pa,volumetric_strain")
    per = [res.summary() for res in results]
    s3 = np.array([p["sigma3_pa"] for p in per])
    s1 = np.array([p["sigma1_at_peak_pa"] for p in per])
    if len(np.unique(s3)) >= 2:
        phi, c_star = mohr_coulomb_fit(s3, s1)
        fit = "least squares over the Mohr circles"
    else:  # one circle: the line through the origin
        phi, c_star = math.degrees(math.asin((s1[0] - s3[0]) / (s1[0] + s3[0]))), 0.0
        fit = "one circle, line through the origin (c* = 0)"
    title = (f"φe = {args.phi_e:g}°, kn = {args.kn:.3g} Pa/m, ks/kn = {args.ks_ratio:g}, "
             f"{args.n_discs} discs, seed {args.seed}")
    summary = {
        "phi_star_deg": phi, "c_star_pa": c_star, "phi_star_fit": fit, "per_sigma3": per,
        "parameters": {k: (v if not isinstance(v, list) else list(v)) for k, v in vars(args).items()},
        "contact": {"kn_pa_per_m": contact.kn, "ks_ratio": contact.ks_ratio, "phi_e_deg": contact.phi_e_deg,
                    "rho": contact.rho, "damping_ratio": contact.damping_ratio, "width_factor": contact.width_factor,
                    "rotation": contact.rotation},
        "packings": [{"sigma3_pa": b.info["sigma3_pa"], "sigma_x_pa": b.sigma[0], "sigma_z_pa": b.sigma[1],
                      "solid_fraction": b.solid_fraction, "cell_m": list(b.cell), "steps": b.info["steps"]}
                     for b in blocks],
        "wall_s": wall_s,
    }
    if error:
        summary["error"] = error
    files.write_json(os.path.join(out, "summary.json"), summary)
    plot_deviator_strain([res.curve for res in results], os.path.join(out, "deviator_strain.png"), title)
    if len(per) >= 1:
        plot_mohr(s3, s1, phi, c_star, os.path.join(out, "mohr.png"), title)
    return summary


def run_test(args, contact):
    """Pack at each σ3 of ``args`` (parser's, checked by ``check``), save the blocks, run the test
    on each and write the outputs into args.out (module docstring). Returns (summary.json's
    record, None), or (None, message) when the packing failed (nothing more written), or
    (the record of the tests done or None, message) when a test failed."""
    from dataclasses import replace

    from engines.seeds.biaxial.periodic import PackingSettings, pack_periodic, run_periodic_biaxial, table1_radii
    from engines.seeds.biaxial.specimen import BiaxialSettings, run_biaxial

    t0 = time.time()
    os.makedirs(args.out, exist_ok=True)
    log = lambda msg: print(msg, flush=True)  # noqa: E731
    packing_contact = contact if args.packing_phi_e is None else replace(contact, phi_e_deg=args.packing_phi_e)
    test = run_periodic_biaxial if args.specimen == "periodic" else run_biaxial
    try:
        blocks = pack_periodic(table1_radii(args.n_discs), packing_contact, args.sigma3,
                               PackingSettings(dt=args.packing_dt, aspect=args.aspect), np.random.default_rng(args.seed),
                               log=log)
    except (RuntimeError, ValueError) as e:
        return None, str(e)
    for b in blocks:
        b.save(os.path.join(args.out, f"packing_sigma3_{b.info['sigma3_pa']:g}"))
    results = []
    try:
        for b in blocks:
            results.append(test(b, contact, BiaxialSettings(
                sigma3=b.info["sigma3_pa"], dt=args.dt, strain_rate=args.strain_rate * PERCENT_PER_MIN,
                max_strain=args.max_strain / 100, side_load=args.side_load), log=log))
    except RuntimeError as e:  # keep what was done
        done = write_outputs(args.out, args, contact, blocks, results, time.time() - t0, error=str(e)) if results else None
        return done, str(e)
    return write_outputs(args.out, args, contact, blocks, results, time.time() - t0), None
