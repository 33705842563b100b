"""Tarumi & Hakuno's quick sand (seed 000 §5): water flows in at the bottom until the bed boils.

    yade -n -x yade_scripts/quicksand.py --case {1,2} --out DIR [--duration S] [--dt S] [--scene FILE]

Writes DIR/history.csv, DIR/summary.json, DIR/pressure_blocks.png (Fig. 21/23),
DIR/snapshots.png (Fig. 22/24 at the scene's snapshot times) and DIR/history_panels.png.
"""
import argparse
import os
import sys

_SCRIPT = __file__ if __file__.endswith(".py") else sys.argv[0]  # under `yade -x`, __file__ is yade
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(_SCRIPT))))

from engines import scene as scenes  # noqa: E402


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", type=int, choices=(1, 2), default=1, help="Table 1 or Table 2")
    ap.add_argument("--scene", help="a scene file instead of the case preset")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--duration", type=float, help="simulated time [s] (default: the scene's)")
    ap.add_argument("--dt", type=float, help="time step [s] (default: the scene's)")
    return ap.parse_args(argv)


def main(argv):
    args = parse(argv)
    overrides = {"numerics": {"dt": args.dt}} if args.dt else None
    try:
        sc = scenes.load(args.scene, overrides) if args.scene else scenes.preset(f"quicksand_case{args.case}", overrides)
        from packing.deposition import scene_packing
        packing = scene_packing(sc)
    except ValueError as e:  # SceneError and bad packing files: one clear line
        sys.exit(f"error: {e}")
    from engines.yade_run import run_scene
    summary = run_scene(sc, packing, args.out, args.duration)
    print(f"done: {summary['steps']} steps in {summary['wall_seconds']:.1f} s "
          f"({summary['us_per_step']:.0f} us/step), water balance error {summary['water_balance_error']:.2e}")


if __name__ == "__main__":
    main(sys.argv[1:])
