"""Tarumi & Hakuno's quick sand (seed 000 §5): water flows in at the bottom until the bed boils.

    yade -n -x yade_scripts/quicksand.py --case {1,2} --out DIR [--duration S] [--dt S] [--scene FILE]
                                         [--set TABLE.FIELD=VALUE ...] [--vtk]
    yade -n -x yade_scripts/quicksand.py --resume DIR [--duration S]
    yade -n -x yade_scripts/quicksand.py --case {1,2} --starts K --out DIR [--perturbation M]
                                         [--jobs J | --scheduler tcp://HOST:PORT]
    yade-batch -j 2 yade_scripts/quicksand_sweep.table yade_scripts/quicksand.py

Writes DIR/history.csv, DIR/summary.json, DIR/pressure_blocks.png (Fig. 21/23),
DIR/snapshots.png (Fig. 22/24 at the scene's snapshot times), DIR/history_panels.png,
DIR/checkpoint.npz and with --vtk DIR/vtk/*.pvd. Ctrl-C (or SIGTERM) stops the run after the
current step with a checkpoint; --resume DIR continues it.

--starts K runs the scene from K starts perturbed by M (default 1e-8 m for the quick sand), each a
run as above in DIR/start_<k>/, and writes DIR/ensemble.json (mean, standard error and 95 %
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
from engines.studies.ensemble import QUICKSAND_PERTURBATION


def parser():
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--case", type=int, choices=(1, 2), help="Table 1 or Table 2 (default 1)")
    which.add_argument("--scene", help="a preset name or a scene file instead of the case preset")
    add_run_arguments(ap, QUICKSAND_PERTURBATION)
    return ap


def main(argv):
    ap = parser()
    args = parse_run_arguments(ap, argv)

    def load_scene(overrides):
        if args.scene:
            return scenes.load(args.scene, overrides)
        return scenes.preset(f"quicksand_case{args.case or 1}", overrides)

    run_script(ap, args, load_scene, scene_given=bool(args.case or args.scene))


if __name__ == "__main__":
    main(sys.argv[1:])
