"""Tarumi & Hakuno's seismic liquefaction (seed 000 §6): the seismic box shaken at its base.

    yade -n -x yade_scripts/liquefaction.py --case N --out DIR [--duration S] [--dt S]
                                            [--transfer paper|conserving] [--scene FILE]

N = 1..7 are the cases of SPEC §2.5 (yade_scripts/scenes/liquefaction_case<N>.toml): 1 saturated
undrained, 2 dry, 3 drained sides (spring d, cosine); 4 saturated undrained, 5 dry (elastic
spring a, cosine); 6 saturated undrained, 7 dry (spring d, El Centro). --transfer chooses how the
water moves onto rebuilt pores ([water] transfer). Writes DIR/history.csv (t, U_block1..6,
porosity, base_acc, base_vel, base_disp, side walls, water balance ...), DIR/summary.json, the
snapshots, and the figures: DIR/pressure_blocks_fig37.png (block pressures with the base input and
the block positions of Fig. 35; Fig. 37/39/42/44), DIR/snapshots.png (velocities, normal forces
and pores; Fig. 36/38/43/45) and DIR/history_panels.png.
"""
import argparse
import os
import sys

_SCRIPT = __file__ if __file__.endswith(".py") else sys.argv[0]  # under `yade -x`, __file__ is yade
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(_SCRIPT))))

from engines import scene as scenes  # noqa: E402
from engines.preflight import ArgumentParser, number, output_dir, scene_and_packing  # noqa: E402

CASES = tuple(range(1, 8))


def parse(argv):
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    which = ap.add_mutually_exclusive_group(required=True)
    which.add_argument("--case", type=int, choices=CASES, help="case of SPEC §2.5 (1-7)")
    which.add_argument("--scene", help="a scene file instead of a case preset")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory")
    ap.add_argument("--duration", type=number(lo=0, lo_open=True, unit="s"),
                    help="simulated time [s] (default: the scene's, 0.18)")
    ap.add_argument("--dt", type=number(lo=0, lo_open=True, unit="s"), help="time step [s] (default: the scene's)")
    ap.add_argument("--transfer", choices=("paper", "conserving"),
                    help="water at re-meshing (default: the scene's [water] transfer)")
    return ap.parse_args(argv)


def overrides_of(args):
    """The command line's changes to the scene, {table: {field: value}} (recorded in summary.json)."""
    out = {}
    num = {k: v for k, v in (("dt", args.dt), ("duration", args.duration)) if v is not None}
    if num:
        out["numerics"] = num
    if args.transfer:
        out["water"] = {"transfer": args.transfer}
    return out or None


def refuse_dry_transfer(args):
    def check(sc):
        if args.transfer and not sc.water.enabled:
            raise ValueError(f"--transfer: {sc.scene.name} is dry (no water to transfer)")
    return check


def main(argv):
    args = parse(argv)
    sc, packing = scene_and_packing(lambda: scenes.load(args.scene, overrides_of(args)) if args.scene else
                                    scenes.preset(f"liquefaction_case{args.case}", overrides_of(args)), args.out,
                                    refuse_dry_transfer(args))
    from engines.yade_run import done_line, run_scene
    from postproc import liquefaction
    summary = run_scene(sc, packing, args.out)
    for path in liquefaction.run_figures(args.out):
        print("figure:", path)
    print(done_line(summary))


if __name__ == "__main__":
    main(sys.argv[1:])
