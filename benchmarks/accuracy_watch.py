"""The accuracy watch's thresholds (engines.model.limits.WATCH_WARN, WATCH_STOP): how far the water
of a water step of M DEM steps strays from that of M = 1, against the watch's max |dA| / A.

    yade -n -x benchmarks/accuracy_watch.py --json docs/engine/accuracy_watch.json [--starts 3]

viscel_column's column (YADE's ViscEl law, q_w = 5e-4 m^2/s per inflow pore, dt = 1e-6 s; E_w
given) from ``--starts`` starts (the grains moved by up to 2 % of R, seeds 0, 1, ...), each run
for ``--steps`` steps with water every M steps (drive from Python: the watch sees every water
step, ``accept_inaccurate``: none stops); per run the watch's largest ratio and lowest U / E_w,
and the error against M = 1 of the same start: max over the samples of |mean U of the bottom pores
- that of M = 1| / E_w.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from benchmarks import write_json


def run(start, M, steps, E_w, samples=20):
    """(watch worst ratio, lowest U / E_w, bottom-pore mean U (samples,) [N/m]) of one run."""
    from yade import O

    from engines.model.pore_water import WaterSettings
    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import viscel_column as ex
    bottom, left, right, grains = ex.build_column()
    rng = np.random.default_rng(start)
    for i in grains:
        p = O.bodies[i].state.pos
        O.bodies[i].state.pos = (p[0] + rng.uniform(-0.02, 0.02) * ex.R, p[1], p[2] + rng.uniform(-0.02, 0.02) * ex.R)
    O.engines = ex.engines()
    O.dt = 1e-6
    water = WaterEngine(bottom + left + right + grains, walls={"bottom": bottom, "left": left, "right": right},
                        settings=WaterSettings(E_w=E_w, k1=200.0, k2=2.0, q_w=5e-4, transfer="conserving"),
                        l_m=1.3e-4, water_interval=M, accept_inaccurate=True)
    U_bottom = []
    for _ in range(samples):
        water.drive(steps // samples, lambda: False)
        U = water.pressures()
        U_bottom.append(float(U[water.model.water.net.pore_touches["bottom"]].mean()))
    w = water.model.watch
    return w.worst, w.lowest, np.array(U_bottom)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--starts", type=int, default=3)
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--E_w", type=float, default=240.0)
    ap.add_argument("--intervals", type=int, nargs="+", default=[1, 10, 40, 100, 200])
    args = ap.parse_args(argv)
    rows = []
    for start in range(args.starts):
        ref = None
        for M in args.intervals:
            worst, lowest, U = run(start, M, args.steps, args.E_w)
            ref = U if ref is None else ref
            err = float(np.max(np.abs(U - ref)) / args.E_w)
            rows.append({"start": start, "water_interval": M, "watch_worst": worst, "lowest_U_over_E_w": lowest,
                         "error_over_E_w": err})
            print(f"start {start} M {M}: watch {worst:.3g}, lowest U/E_w {lowest:.3g}, error {err:.3g}", flush=True)
    write_json(args.json, {"what": __doc__.strip().splitlines()[0], "E_w": args.E_w, "steps": args.steps,
                           "dt": 1e-6, "runs": rows})


if __name__ == "__main__":
    main(sys.argv[1:])
