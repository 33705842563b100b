"""Seed 003 biaxial compression test (Murakami et al. §2, SPEC §4): wall-less periodic packing to
each σ3, then the test; strength φ*, c* and stiffness E50 of the model ground.

    yade -n -x yade_scripts/biaxial.py --phi-e DEG --sigma3 100,200,300,400 --out DIR [options]
    yade-batch -j 2 yade_scripts/biaxial_sweep.table yade_scripts/biaxial.py

The command line, the files written into DIR and the yade-batch parameters: engines/run/biaxial.py
(its docstring is this script's --help).
"""
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.biaxial import check, parser, run_test, table_argv


def main(argv):
    ap = parser()
    if os.environ.get("YADE_BATCH"):
        argv = table_argv(ap)
    args = ap.parse_args(argv)
    summary, error = run_test(args, check(args, ap))
    if error:
        sys.exit(f"biaxial.py: error: {error}")
    print(f"phi* = {summary['phi_star_deg']:.2f} deg, c* = {summary['c_star_pa']:.2f} Pa; "
          + ", ".join(f"sigma3 {p['sigma3_pa']:g}: peak {p['peak_deviator_pa']:.1f} Pa, E50 {p['e50_pa']:.4g} Pa"
                      for p in summary["per_sigma3"]) + f"; {summary['wall_s']:.0f} s -> {args.out}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
