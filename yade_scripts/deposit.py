"""Deposit a scene's packing in YADE and save it as CSV (x, z, r, group, density_factor), with the
size distribution (Fig. 14) and a drawing of the packing (Fig. 15) beside it.

    yade -n -x yade_scripts/deposit.py --scene quicksand_case1 [--out FILE]
"""
import argparse
import os
import sys

_SCRIPT = __file__ if __file__.endswith(".py") else sys.argv[0]  # under `yade -x`, __file__ is yade
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(_SCRIPT))))

from engines import scene as scenes  # noqa: E402
from packing.deposition import deposit  # noqa: E402
from packing.psd import plot_distribution  # noqa: E402
from postproc.plots import plot_packing  # noqa: E402


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True, help="preset name or scene file path")
    ap.add_argument("--out", help="CSV path (default: the scene's packing file)")
    args = ap.parse_args(argv)
    sc = scenes.load(args.scene) if args.scene.endswith(".toml") else scenes.preset(args.scene)
    out = args.out or sc.packing.file
    if not out:
        raise SystemExit("--out is required when the scene names no packing file")
    pk = deposit(sc)
    pk.save(out)
    p = sc.packing
    stem = os.path.splitext(out)[0]
    plot_distribution(2 * pk.r[pk.mobile], p.mean_diameter, p.std_diameter, p.d_min, p.d_max, stem + "_fig14_diameters.png")
    plot_packing(pk, stem + "_fig15_packing.png", sc.scene.name)
    print(f"deposited {int(pk.mobile.sum())} particles + {int((~pk.mobile).sum())} wall discs -> {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
