"""Which time steps let a packed seed-003 specimen stay at rest: the evidence behind the contact
width and engines.seeds.biaxial.cem_contact.stable_dt (docs/BIAXIAL.md).

A periodic block packed at rest (biaxial.py writes them) is rebuilt with each case's contact
constants and time step (the contacts' shear history is lost, so it first settles by a few per
cent) and left alone for 0.2 s. A stable step brings it to rest (YADE's unbalanced-force ratio
falls towards 1e-5 and the stresses stop changing over the second 0.1 s); an unstable one rings
(the ratio stays above 0.01, the stresses keep drifting) or blows up. yade_scripts/biaxial_stability.py
is the command line.
"""
import os

import numpy as np

from engines import files
from engines.seeds.biaxial.cem_contact import CemContact, add_discs, disc_mass, pair_constants, stable_dt, yade_engines
from engines.seeds.biaxial.periodic import yade_cell_stress

# (contact width factor f_w, kn [Pa/m], ks/kn, dt [s], None = stable_dt's); the paper's constants
# are (1, 1e8, 0.25), where stable_dt is 4.5e-5 s
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
    files.write_json(os.path.join(out, "stability.json"),
                     {"block": name, "n_discs": len(block.r), "rest_time_s": REST_TIME, "at_rest_below": AT_REST,
                      "cases": rows})


def network_dt_limit(xz, r, cell, contact, rel_tol=1e-4):
    """Exact leapfrog limit [s] of a periodic disc network at rest: the largest dt with
    4 M − dt² K − 2 dt C >= 0 (cem_contact.leapfrog_dt for many degrees of freedom), every
    contact (overlap in the cell ``cell`` = (Lx, Lz) [m], nearest image) sticking, with the
    springs and dashpots YADE builds (pair_constants). Degrees of freedom x, z and, unless
    ``contact.rotation`` is "locked", θ with the inertia m r²/2; a contact's normal and shear
    displacements δn = (u_j − u_i)·n, δt = (u_j − u_i)·t − r_i θ_i − r_j θ_j. Bisection on dt
    with a Cholesky test, to ``rel_tol``."""
    from scipy.spatial import cKDTree

    r = np.asarray(r, float)
    cell = np.asarray(cell, float)
    xz = np.mod(np.asarray(xz, float), cell)
    pairs = cKDTree(xz, boxsize=cell).query_pairs(2 * r.max(), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    d = xz[j] - xz[i]
    d -= np.round(d / cell) * cell
    dist = np.hypot(d[:, 0], d[:, 1])
    touch = dist < r[i] + r[j]
    i, j, d, dist = i[touch], j[touch], d[touch], dist[touch]
    n = d / dist[:, None]
    t = np.column_stack([-n[:, 1], n[:, 0]])
    kn, ks, cn, cs = pair_constants(r[i], r[j], contact)
    dof = 2 if contact.rotation == "locked" else 3
    size = dof * len(r)
    K, C = np.zeros((size, size)), np.zeros((size, size))
    for vec, rot, k, c in ((n, False, kn, cn), (t, True, ks, cs)):
        g = np.zeros((len(i), size))  # each contact's displacement in terms of the degrees of freedom
        rows = np.arange(len(i))
        for a in range(2):
            g[rows, dof * i + a] -= vec[:, a]
            g[rows, dof * j + a] += vec[:, a]
        if rot and dof == 3:
            g[rows, 3 * i + 2] -= r[i]
            g[rows, 3 * j + 2] -= r[j]
        K += g.T @ (k[:, None] * g)
        C += g.T @ (c[:, None] * g)
    m = disc_mass(r, contact.rho)
    mass = np.column_stack([m, m, m * r ** 2 / 2][:dof]).ravel()
    s = 1 / np.sqrt(mass)
    K, C = K * s[:, None] * s[None, :], C * s[:, None] * s[None, :]
    eye = 4 * np.eye(size)

    def stable(dt):
        try:
            np.linalg.cholesky(eye - dt * dt * K - 2 * dt * C)
            return True
        except np.linalg.LinAlgError:
            return False

    lo, hi = 0.0, 1e-3
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo
