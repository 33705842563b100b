"""Deposit a scene's packing in YADE and save it as CSV (x, z, r, group, density_factor), with the
size distribution (Fig. 14) and a drawing of the packing (Fig. 15) beside it.

    yade -n -x yade_scripts/deposit.py --scene quicksand_case1 [--out FILE | --replace] [--from CSV]
                                       [--set TABLE.FIELD=VALUE ...]

``--from CSV``: instead of a fresh deposit, the packing of CSV settled again against the scene's
flat walls ([walls] kind = "flat": quicksand_case1_flat's packing is case 1's, settled on them).
``--set``: a change to the scene, as in the run scripts (e.g. ``--set packing.n_bottom=37``).

By default the packing goes to out/packings/<scene name>.csv (the name is one plain name: the
scene schema refuses separators, ``..`` and a leading dot); ``--replace`` overwrites the packing
file the scene names (a tracked preset file: check the diff before committing it). The two
figures are written beside the CSV, named after it.
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.model.pore_dem import scene_flat_walls
from engines.run import scene as scenes
from engines.run.command_line import overrides_of, scene_setting
from engines.run.preflight import ArgumentParser, InputError, check_output_dir
from engines.yade.deposition import deposit, settle_on_flat_walls
from packing.packing import Packing
from packing.psd import plot_distribution
from postproc.plots import plot_packing


def main(argv):
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True, help="preset name or scene file path")
    where = ap.add_mutually_exclusive_group()
    where.add_argument("--out", help="CSV path (default: out/packings/<scene name>.csv)")
    where.add_argument("--replace", action="store_true", help="overwrite the packing file the scene names")
    ap.add_argument("--from", dest="source", metavar="CSV",
                    help="settle this packing against the scene's flat walls instead of depositing one")
    ap.add_argument("--set", type=scene_setting, action="append", default=[], metavar="TABLE.FIELD=VALUE",
                    help="change a scene field (repeatable)")
    args = ap.parse_args(argv)
    try:
        over = overrides_of(args)
        sc = scenes.load(args.scene, over)
        if args.replace and (not sc.packing.file or over):
            raise InputError("--replace: the scene names no [packing] file" if not sc.packing.file else
                             "--replace with --set: a changed scene does not replace the preset's packing; use --out")
        out = sc.packing.file if args.replace else args.out or os.path.join("out", "packings", sc.scene.name + ".csv")
        check_output_dir(os.path.dirname(os.path.abspath(out)), "--out")
        if os.path.exists(out) and not os.path.isfile(out):
            raise InputError(f"--out {out} is a directory or a special file: name the CSV file to write")
        if args.source and sc.walls.kind != "flat":
            raise InputError(f"--from: the scene's [walls] kind is {sc.walls.kind!r}; a packing is settled again only "
                             f"against flat walls")
        source = Packing.load(args.source) if args.source else None
    except ValueError as e:
        sys.exit(f"error: {e}")
    pk = settle_on_flat_walls(sc, source) if source is not None else deposit(sc)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    pk.save(out)
    p = sc.packing
    stem = os.path.splitext(out)[0]
    plot_distribution(2 * pk.r[pk.mobile], p.mean_diameter, p.std_diameter, p.d_min, p.d_max, stem + "_fig14_diameters.png")
    faces = [(w.axis, w.position) for w in scene_flat_walls(sc.settings, pk).values()]  # none with wall discs
    plot_packing(pk, stem + "_fig15_packing.png", sc.scene.name, faces)
    print(f"deposited {int(pk.mobile.sum())} particles + {int((~pk.mobile).sum())} wall discs -> {out} "
          f"(figures {stem}_fig14_diameters.png, {stem}_fig15_packing.png)")
    if sc.packing.file and not args.replace:
        print(f"the scene still runs on {sc.packing.file}; --replace overwrites it")


if __name__ == "__main__":
    main(sys.argv[1:])
