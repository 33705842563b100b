"""Cost of the YADE path against YADE itself, on the quick-sand scene (76 discs).

    yade -n -x benchmarks/coupling.py --json out/bench-coupling.json [--steps 5000]

floor       YADE alone, dry: collider + Law2_ScGeom_FrictPhys_CundallStrack + NewtonIntegrator
dry         our engine, dry scene (the paper's contact law in NumPy, no water code)
wet         our engine, quick-sand case 1 (water every step)
wet_M10     the same with the water advanced every 10 DEM steps (pressure forces persist)
Prints microseconds per step and the ratios to the floor; all measured in one run.
"""
import argparse
import json
import os
import sys

_SCRIPT = __file__ if __file__.endswith(".py") else sys.argv[0]  # under `yade -x`, __file__ is yade
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(_SCRIPT))))

from yade import O  # noqa: E402

from benchmarks.floor import native_floor, per_step  # noqa: E402
from engines import scene as scenes  # noqa: E402
from engines.yade_coupling import YadeCoupling  # noqa: E402
from packing.deposition import scene_packing  # noqa: E402


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--steps", type=int, default=5000)
    args = ap.parse_args(argv)
    base = scenes.preset("quicksand_case1")
    packing = scene_packing(base)
    native_floor(base, packing)
    res = {"floor": per_step(10 * args.steps, lambda n: O.run(n, True))}  # O.run waits ~40 ms a call
    for name, over in [("dry", {"water": {"enabled": False}}), ("wet", {}),
                       ("wet_M10", {"numerics": {"water_interval": 10}})]:
        cp = YadeCoupling(base.with_overrides(over), packing)
        res[name] = per_step(args.steps, cp.run)
    out = {"n_discs": int(len(packing.r)), "steps": args.steps, "us_per_step": res,
           "ratio_to_floor": {k: v / res["floor"] for k, v in res.items()}}
    print(f"{'path':>8} {'us/step':>9} {'x floor':>8}")
    for k, v in res.items():
        print(f"{k:>8} {v:9.1f} {v / res['floor']:8.1f}")
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with open(args.json, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
