"""Which time steps let a packed seed-003 specimen stay at rest: the evidence behind the contact
width and engines.seeds.biaxial.cem_contact.stable_dt (docs/BIAXIAL.md).

A periodic block packed at rest (biaxial.py writes them) is rebuilt with each case's contact
constants and time step (the contacts' shear history is lost, so it first settles by a few per
cent) and left alone for 0.2 s. A stable step brings it to rest (YADE's unbalanced-force ratio
falls towards 1e-5 and the stresses stop changing over the second 0.1 s); an unstable one rings
(the ratio stays above 0.01, the stresses keep drifting) or blows up. yade_scripts/biaxial_stability.py
is the command line.
"""
import json
import os

from engines.seeds.biaxial.cem_contact import CemContact, add_discs, stable_dt, yade_engines
from engines.seeds.biaxial.periodic import yade_cell_stress

# (contact width factor f_w, kn [Pa/m], ks/kn, dt [s], None = stable_dt's); the paper's constants
# are (1, 1e8, 0.25), where stable_dt is 5e-5 s
CASES = [(1.0, 1e8, 0.25, 2.5e-5), (1.0, 1e8, 0.25, 5e-5), (1.0, 1e8, 0.25, 7e-5), (1.0, 1e8, 0.25, 1e-4),
         (2.0, 1e8, 0.25, 2.5e-5), (2.0, 1e8, 0.25, None), (2.0, 1e8, 0.25, 5e-5),
         (1.0, 1e8, 0.5, None), (1.0, 1e8, 0.5, 4e-5), (1.0, 1e8, 0.5, 5e-5),
         (1.0, 1e8, 1.0, None), (1.0, 1e8, 1.0, 2.9e-5),
         (1.0, 2e8, 0.25, 3.5e-5), (1.0, 2e8, 0.25, None), (1.0, 2e8, 0.25, 5e-5),
         (1.0, 1e8, 0.125, 5e-5), (1.0, 1e8, 0.1, None)]
REST_TIME = 0.2        # s
AT_REST = 0.01         # unbalanced-force ratio of a specimen at rest (the packing's criterion)


def cases(r, phi_e):
    """(contact, dt [s]) of each of CASES for discs r at the inter-element friction φe [deg]."""
    out = []
    for fw, kn, ks, dt in CASES:
        c = CemContact(kn=kn, ks_ratio=ks, phi_e_deg=phi_e, width_factor=fw)
        out.append((c, dt or stable_dt(r, c)))
    return out


def relax(block, contact, dt):
    """Unbalanced-force ratio after REST_TIME and the largest relative change of σx, σz over its
    second half."""
    from yade import O, utils

    depth = block.info["depth_m"]
    O.reset()
    O.periodic = True
    O.cell.setBox(block.cell[0], depth, block.cell[1])
    add_discs(block.xz, block.r, contact, y=depth / 2)
    O.engines = yade_engines()
    O.dt = dt
    O.run(int(REST_TIME / 2 / dt), True)
    start = yade_cell_stress(depth)
    O.run(int(REST_TIME / 2 / dt), True)
    end = yade_cell_stress(depth)
    return utils.unbalancedForce(), max(abs(b / a - 1) for a, b in zip(start, end))


def run_cases(block, name, out):
    """relax ``block`` (a PeriodicBlock, loaded from the path ``name``) at each of CASES, printing
    one line per case; writes OUT/stability.json."""
    phi_e = block.info["contact"]["phi_e_deg"]
    rows = []
    for c, dt in cases(block.r, phi_e):
        fw, kn, ks = c.width_factor, c.kn, c.ks_ratio
        unbalanced, change = relax(block, c, dt)
        rows.append({"width_factor": fw, "kn_pa_per_m": kn, "ks_ratio": ks, "dt_s": dt,
                     "stable_dt_s": stable_dt(block.r, c), "unbalanced": unbalanced,
                     "stress_change": change, "outcome": "at rest" if unbalanced < AT_REST else "rings"})
        r = rows[-1]
        print(f"f_w {fw:g}, kn {kn:.0e}, ks/kn {ks:g}, dt {dt:.2e} s: unbalanced {unbalanced:.2g}, "
              f"stress change over the last 0.1 s {100 * change:.2f} % -> {r['outcome']}", flush=True)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "stability.json"), "w") as f:
        json.dump({"block": name, "n_discs": len(block.r), "rest_time_s": REST_TIME, "at_rest_below": AT_REST,
                   "cases": rows}, f, indent=1)
