"""The seismic study's reconstruction: the paper's unknowns varied on ensembles (docs/LIQUEFACTION.md).

    make reconstruction                                          # -> out/reconstruction/ (resumable)
    /usr/bin/python3 yade_scripts/liquefaction_reconstruction.py --out out/reconstruction \\
         [--baseline out/liquefaction] [--variants k_x10 box_wide ...] [--workers 2] [--scheduler ADDR]
    /usr/bin/python3 yade_scripts/liquefaction_reconstruction.py --out out/reconstruction --analyse-only

Each variant (engines/studies/reconstruction.py: case 3's permeabilities x3, x10, x30; E_w x3, x10;
the box wider and narrower with the same 192 discs; a denser packing) runs the cases it touches as
ensembles of 8 starts (a packing variant on its own deposit, OUT/runs/<variant>_packing/); the
trends of the paper (engines.studies.liquefaction.TRENDS) are then evaluated on the variant's cases with
the study's own ensembles (BASELINE/summary.json, make liquefaction) for the others, and written to
OUT/reconstruction.json and OUT/reconstruction.md: per variant each trend's quantities with their
95 % intervals and verdicts, the packing's porosity and whether its contacts carry its dense top.
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.preflight import ArgumentParser, number
from engines.run.reconstruction import run_study
from engines.studies.reconstruction import VARIANTS


def main(argv):
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="study folder")
    ap.add_argument("--baseline", default=os.path.join("out", "liquefaction"),
                    help="the study whose ensembles the variants are compared with (its summary.json)")
    ap.add_argument("--variants", nargs="+", choices=sorted(VARIANTS), help="run these only (default: all)")
    ap.add_argument("--workers", type=number(int, 1), default=1, help="jobs at a time")
    ap.add_argument("--scheduler", help="a Dask scheduler's address (tcp://HOST:PORT)")
    ap.add_argument("--analyse-only", action="store_true", help="the table from the jobs done, no runs")
    a = ap.parse_args(argv)
    if not os.path.exists(os.path.join(a.baseline, "summary.json")):
        ap.error(f"--baseline {a.baseline}: no summary.json (make liquefaction writes it)")
    doc = run_study(os.path.abspath(a.out), a.baseline, a.workers, a.scheduler, a.variants, a.analyse_only)
    print(os.path.join(a.out, "reconstruction.md"), f"({len(doc['variants'])} variants)")


if __name__ == "__main__":
    main(sys.argv[1:])
