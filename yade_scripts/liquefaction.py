"""Tarumi & Hakuno's seismic liquefaction (seed 000 §6): the seismic box shaken at its base.

    yade -n -x yade_scripts/liquefaction.py --case N --out DIR [--duration S] [--dt S]
                                            [--transfer paper|conserving] [--scene FILE]
                                            [--set TABLE.FIELD=VALUE ...] [--vtk]
    yade -n -x yade_scripts/liquefaction.py --resume DIR [--duration S]
    yade -n -x yade_scripts/liquefaction.py --case N --starts K --out DIR [--perturbation M]
                                            [--jobs J | --scheduler tcp://HOST:PORT]

N = 1..7 are the cases of SPEC §2.5 (yade_scripts/scenes/liquefaction_case<N>.toml): 1 saturated
undrained, 2 dry, 3 drained sides (spring d, cosine); 4 saturated undrained, 5 dry (elastic
spring a, cosine); 6 saturated undrained, 7 dry (spring d, El Centro). --transfer chooses how the
water moves onto rebuilt pores ([water] transfer). Writes DIR/history.csv (t, U_block1..6,
porosity, base_acc, base_vel, base_disp, side walls, water balance ...), DIR/summary.json, the
snapshots, DIR/checkpoint.npz (Ctrl-C stops with a checkpoint; --resume continues), with --vtk a
ParaView series in DIR/vtk/, and the figures: DIR/pressure_blocks.png and DIR/blocks.png
(block pressures with the base input and the block positions of Fig. 35; Fig. 37/39/42/44), DIR/snapshots.png
(velocities, normal forces and pores; Fig. 36/38/43/45) and DIR/history_panels.png.

--starts K runs the case from K starts perturbed by M (default 1e-7 m for the seismic box), each
a run as above in DIR/start_<k>/, and writes DIR/ensemble.json (mean, standard error and 95 %
interval of every result and history column across the starts) with its figures; --resume DIR
continues the starts that did not complete (engines/run/ensemble.py, docs/SWEEPS.md).
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))
import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
# signals from here on: a Ctrl-C before the run starts ends the script at once, in one line
from engines.run.guard import catch_signals

if __name__ == "__main__":
    catch_signals()

from engines.run import scene as scenes
from engines.run.command_line import add_run_arguments, parse_run_arguments, run_script
from engines.run.preflight import ArgumentParser
from engines.studies.ensemble import SEISMIC_PERTURBATION

CASES = tuple(range(1, 8))


def parser():
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--case", type=int, choices=CASES, help="case of SPEC §2.5 (1-7)")
    which.add_argument("--scene", help="a preset name or a scene file instead of a case preset")
    ap.add_argument("--transfer", choices=("paper", "conserving"),
                    help="water at re-meshing (default: the scene's [water] transfer)")
    add_run_arguments(ap, SEISMIC_PERTURBATION)
    return ap


def main(argv):
    ap = parser()
    args = parse_run_arguments(ap, argv)
    if not (args.case or args.scene or args.resume):
        ap.error("one of --case, --scene or --resume is required")

    def load_scene(overrides):
        if args.transfer:
            overrides = {**(overrides or {}), "water": {**(overrides or {}).get("water", {}), "transfer": args.transfer}}
        if args.scene:
            return scenes.load(args.scene, overrides)
        return scenes.preset(f"liquefaction_case{args.case}", overrides)

    def check(sc):
        if args.transfer and not sc.water.enabled:
            raise ValueError(f"--transfer: {sc.scene.name} is dry (no water to transfer)")

    from postproc import liquefaction
    run_script(ap, args, load_scene, scene_given=bool(args.case or args.scene or args.transfer), check=check,
               figures=liquefaction.run_figures)


if __name__ == "__main__":
    main(sys.argv[1:])
