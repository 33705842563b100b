"""Error and cost of advancing the water every M DEM steps (pressure forces persist in between).

    yade -n -x benchmarks/water_interval.py --json out/bench-water-interval.json [--duration 0.005]

Runs quick-sand case 1 with M = 1, 2, 5, 10, 20 and compares with M = 1: the block pressures
(max |U_M - U_1| / max |U_1| over the samples) and the disc positions (max |x_M - x_1| / mean r).
"""
import argparse
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from benchmarks import write_json
from engines.run import scene as scenes
from engines.yade.coupling import simulate
from engines.yade.deposition import scene_packing


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--duration", type=float, default=0.005)
    ap.add_argument("--intervals", type=int, nargs="+", default=[1, 2, 5, 10, 20])
    args = ap.parse_args(argv)
    base = scenes.preset("quicksand_case1")
    packing = scene_packing(base)
    n = int(round(args.duration / base.numerics.dt))
    simulate(base, packing, 10, 10)  # numba loads its cached kernels once, outside the timings
    runs = {}
    for M in args.intervals:
        sc = base.with_overrides({"numerics": {"water_interval": M}})
        t0 = time.perf_counter()
        traj = simulate(sc, packing, n, n // 10)
        runs[M] = (traj.arrays(), (time.perf_counter() - t0) / n * 1e6)
    (_, x1, U1, _, _), cost1 = runs[args.intervals[0]]
    rows = []
    print(f"{'M':>4} {'U error':>10} {'x error / r':>12} {'us/step':>9} {'cost ratio':>10}")
    for M, ((_, x, U, _, err), cost) in runs.items():
        row = {"water_interval": M, "block_U_rel_error": float(np.nanmax(np.abs(U - U1)) / np.nanmax(np.abs(U1))),
               "position_error_rel_r": float(np.abs(x - x1).max() / packing.r.mean()),
               "us_per_step": cost, "cost_ratio": cost / cost1, "water_balance_error": float(np.nanmax(err))}
        rows.append(row)
        print(f"{M:4d} {row['block_U_rel_error']:10.2e} {row['position_error_rel_r']:12.2e} {cost:9.1f} {row['cost_ratio']:10.2f}")
    write_json(args.json, {"duration": args.duration, "results": rows})


if __name__ == "__main__":
    main(sys.argv[1:])
