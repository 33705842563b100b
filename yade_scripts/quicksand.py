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
from engines.preflight import ArgumentParser, number, output_dir, scene_and_packing  # noqa: E402


def parse(argv):
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--case", type=int, choices=(1, 2), help="Table 1 or Table 2 (default 1)")
    which.add_argument("--scene", help="a scene file instead of the case preset")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory")
    ap.add_argument("--duration", type=number(lo=0, lo_open=True, unit="s"),
                    help="simulated time [s] (default: the scene's)")
    ap.add_argument("--dt", type=number(lo=0, lo_open=True, unit="s"), help="time step [s] (default: the scene's)")
    return ap.parse_args(argv)


def overrides_of(args):
    """The command line's changes to the scene, {table: {field: value}} (recorded in summary.json)."""
    num = {k: v for k, v in (("dt", args.dt), ("duration", args.duration)) if v is not None}
    return {"numerics": num} if num else None


def main(argv):
    args = parse(argv)
    sc, packing = scene_and_packing(lambda: scenes.load(args.scene, overrides_of(args)) if args.scene else
                                    scenes.preset(f"quicksand_case{args.case or 1}", overrides_of(args)), args.out)
    from engines.yade_run import done_line, run_scene
    print(done_line(run_scene(sc, packing, args.out)))


if __name__ == "__main__":
    main(sys.argv[1:])
