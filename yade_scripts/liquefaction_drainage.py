"""How fast the seismic box drains: a uniform excess pore pressure U0 in the still packing, the
water advanced alone (engines.compiled.water_model.WaterModel, the compiled kernels) with the surface at
U = 0 and undrained (case 1) or drained (case 3) sides, at Table 5's permeabilities and at
``--k-scale`` times them. Tells whether drained sides can keep U small within the 0.18-s run
(docs/LIQUEFACTION.md, trend 2). No YADE:

    /usr/bin/python3 yade_scripts/liquefaction_drainage.py --json out/liquefaction/drainage.json

Writes {case: {k_scale: {"t": [...], "U_low": [...], "tau": [...]}}}: the mean U of the pores in
blocks 1-4 [N/m] at the times t [s], and the three slowest drainage time constants of the network
[s] (``time_constants``), to set against the input period (0.02 s) and the run (0.18 s).
"""
import os
import sys

import numpy as np

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines import files
from engines.compiled.water_model import WaterModel
from engines.model import pores as pg
from engines.model.pore_dem import water_model
from engines.run import scene as scenes
from engines.run.preflight import ArgumentParser, number
from packing.packing import Packing

TIMES = (0.02, 0.06, 0.18)  # one input period, a third of the run, the run [s]
LOW_BLOCKS = 4


def drainage(case, k_scale, U0=100.0, times=TIMES):
    """Mean U [N/m] of the pores whose centroid lies in blocks 1-4 at ``times``, from U0 everywhere,
    and the slowest drainage time constants [s] (``time_constants``)."""
    sc = scenes.preset(f"liquefaction_case{case}")
    w = sc.water
    sc = sc.with_overrides({"water": {"k1": w.k1 * k_scale, "k2": w.k2 * k_scale, "k3": w.k3 * k_scale}})
    pk = Packing.load(sc.packing.file)
    wm = water_model(sc.settings, pk, WaterModel)
    water = wm.water
    A = pg.measure(water.net, pk.xz, pk.r).void_area
    water.W = A * sc.water.E_w / (sc.water.E_w - U0)  # eq 32 inverted: U = U0 in every pore
    bounds = pk.block_bounds(sc.output.block_z)
    cz = pg.pore_centroids(water.net, pk.xz)[:, 1]
    low = (cz >= bounds[0][0]) & (cz < bounds[LOW_BLOCKS - 1][1])
    tau = time_constants(water, A, pg.measure(water.net, pk.xz, pk.r).link_contact)
    dt, out, k = sc.numerics.dt, [], 0
    for t in times:
        while k < int(round(t / dt)):
            wm.advance(dt, pk.xz)
            k += 1
        out.append(float(water.pressure(A)[low].mean()))
    return out, tau


def time_constants(water, A, link_contact, n=3):
    """The n slowest time constants 1/lambda [s] of the linearised drainage dU/dt = -C^-1 G U
    (engines.model.pore_water, Stability): G the conductance Laplacian of the throats plus the boundary
    conductances, C the capacities; the symmetric form C^-1/2 G C^-1/2 has the same eigenvalues."""
    fl = water.flows(A, link_contact)
    i, j = water.net.throat_conns.T
    G = np.diag(np.bincount(i, fl.g, len(A)) + np.bincount(j, fl.g, len(A)) + fl.g_b)
    np.add.at(G, (i, j), -fl.g)
    np.add.at(G, (j, i), -fl.g)
    s = 1 / np.sqrt(fl.capacity)  # pinched pores (capacity inf) drop out
    lam = np.linalg.eigvalsh(s[:, None] * G * s[None, :])
    return [float(1 / x) for x in lam[lam > 1e-12 * lam.max()][:n]]  # no drain: no decaying mode 0


def main(argv):
    ap = ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", required=True)
    ap.add_argument("--k-scale", type=number(lo=0, lo_open=True), default=10.0,
                    help="the second permeability factor tried (default 10)")
    args = ap.parse_args(argv)
    result = {}
    for case in (1, 3):
        result[f"case{case}"] = {}
        for scale in (1.0, args.k_scale):
            U, tau = drainage(case, scale)
            result[f"case{case}"][f"{scale:g}"] = {"t": list(TIMES), "U_low": U, "tau": tau}
            print(f"case {case}, k x {scale:g}: mean U of blocks 1-{LOW_BLOCKS} from 100 N/m: " +
                  ", ".join(f"{u:.1f} at {t:g} s" for t, u in zip(TIMES, U)) +
                  "; slowest time constants " + ", ".join(f"{x:.3g}" for x in tau) + " s", flush=True)
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    files.write_json(args.json, result)


if __name__ == "__main__":
    main(sys.argv[1:])
