"""Saito & Fujiwara §4: uniaxial tests on a particle-potential specimen (seed 002).

    /usr/bin/python3 yade_scripts/particle_potential.py --out out/particle-potential [--alpha 1 2]

Runs the §4 tests for each --alpha (engines.seeds.particle_potential.specimen: the half specimen,
top load and forced top displacement, the yield search) and writes into OUT/alpha<α>/
summary.json and the figures fig6_top_load.png, fig7_forced_displacement.png,
fig8_stress_strain.png, fig9_top_vs_bottom.png (postproc/particle_potential.py), and
OUT/comparison.md (E and yield beside the paper's). Stresses in t/m² as in the paper.
"""
import json
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.preflight import ArgumentParser, number, output_dir
from engines.seeds.particle_potential.specimen import MAX_INCREMENTS, SEARCH_MAX, run_study
from postproc.particle_potential import figures


def parse_args(argv=None):
    """Command line; bad values are refused in one line naming the argument and its limit."""
    ap = ArgumentParser(description=__doc__.split("\n")[0])
    positive = number(lo=0, lo_open=True)
    ap.add_argument("--alpha", type=positive, nargs="+", default=[1.0, 2.0], help="potential parameter(s) α [-]")
    ap.add_argument("--C", type=positive, default=2.0, help="potential exponent C [-]")
    ap.add_argument("--Am", type=positive, default=1.0, help="potential amplitude A_m [tf·m per m depth]")
    ap.add_argument("--load-max", type=positive, default=22.0, help="top load of Fig. 6 [t/m²]")
    ap.add_argument("--dload", type=positive, default=0.25, help="first load increment of the yield search [t/m²]")
    ap.add_argument("--disp-max", type=positive, default=0.9, help="forced top displacement of Fig. 7 [m]")
    ap.add_argument("--ddisp", type=positive, default=0.01, help="displacement increment [m]")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory (one subfolder per α)")
    args = ap.parse_args(argv)
    for end, step, name, unit in ((max(args.load_max, SEARCH_MAX), args.dload, "--dload", "t/m²"),
                                  (args.disp_max, args.ddisp, "--ddisp", "m")):
        if end / step > MAX_INCREMENTS:
            ap.error(f"argument {name}: {step:g} {unit} gives {end / step:.0f} increments up to {end:g} {unit} "
                     f"(limit {MAX_INCREMENTS})")
    return args


def main(argv=None):
    args = parse_args(argv)
    summaries, table = run_study(args.alpha, args.out, figures, C=args.C, Am=args.Am, load_max=args.load_max,
                                 dload=args.dload, disp_max=args.disp_max, ddisp=args.ddisp)
    print(json.dumps(summaries, indent=2))
    print(table)

if __name__ == "__main__":
    main()
