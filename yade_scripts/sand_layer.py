"""Monte-Carlo model sand layer (Matsuo, Komada & Takahashi; SPEC §5): stress and settlement.

    /usr/bin/python3 yade_scripts/sand_layer.py --realisations 25 --seed 0 --out out/sand-layer

Plain NumPy/SciPy, no YADE. Builds `--realisations` model sand layers of 26 × 5 elements
(V = 1.2 mm³, N = 100 grains, default medium sand of engines/seeds/sand_layer/layer.py), loads each with a
strip load on the surface centre and computes the transmitted vertical stress (eq 5–8) and the
surface settlement (Fig. 11–12, engines/seeds/sand_layer/mechanics.py).

Load (the paper: a unit distributed load on the central surface element; with 26 columns there
is no single centre): a strip of `--load-width` = 2 elements, columns 12 and 13 (2.1 mm wide),
under `--load-stress` = 98.0665 kPa (1 kgf/cm², the unit of the oedometer tests behind Fig. 11).

Writes into DIR:
    summary.json                 parameters and results (SI units, listed under "units")
    fig01_02_grain_size.png      cumulative grain-size curves by mass and by number
    fig05_08_void_ratio.png      V_s, element gradings, e for V = 1.0–1.3 mm³, truncated e curve
    fig10_stress.png             transmitted vertical stress
    fig12_settlement.png         layer compression and surface settlement
"""
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.preflight import ArgumentParser, InputError, announce_output, check_fresh_output, number, output_dir
from engines.seeds.sand_layer.layer import SandLayerSettings
from engines.seeds.sand_layer.study import LOAD_STRESS, LOAD_WIDTH, run, write_outputs
from postproc.sand_layer import UM, figures


def parse_args(argv=None):
    """Command line; bad values are refused in one line naming the argument and its limit."""
    parser = ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--realisations", type=number(int, lo=1), default=25)
    parser.add_argument("--seed", type=number(int, lo=0), default=0)
    parser.add_argument("--out", type=output_dir, required=True, help="output directory")
    parser.add_argument("--overwrite", action="store_true", help="replace the outputs of an earlier run in --out")
    parser.add_argument("--load-width", type=number(int, lo=1, hi=SandLayerSettings().n_columns),
                        default=LOAD_WIDTH, help="elements")
    parser.add_argument("--load-stress", type=number(lo=0, lo_open=True, unit="Pa"), default=LOAD_STRESS,
                        help="Pa")
    parser.add_argument("--sampling", default="discrete", choices=("discrete", "continuous"))
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    if not args.overwrite:
        try:
            check_fresh_output(args.out)
        except InputError as e:
            sys.exit(f"error: {e}")
    announce_output(args.out)
    study = run(args.realisations, args.seed, args.load_width, args.load_stress, args.sampling)
    result = write_outputs(study, args.out, figures)
    print(f"settlement under the load: {result['settlement_mean'] * UM:.1f} ± "
          f"{result['settlement_std'] * UM:.1f} µm; load balance error "
          f"{result['load_balance_error']:.2e}; wrote {args.out}")


if __name__ == "__main__":
    main()
