"""Cross-check of the YADE path (engines.yade.coupling) against the NumPy reference (engines.reference.model):
the cases and their tolerances are in engines/run/crosscheck.py.

Run:  yade -n -x yade_scripts/crosscheck.py --out DIR [--only CASE ...]   -> DIR/crosscheck.json, exit 1 if a case fails
      yade -n -x yade_scripts/crosscheck.py --precision --out DIR        -> DIR/precision.json (make precision)
"""
import argparse
import json
import os
import sys

# under `yade -x` the script runs in YADE's globals, where __file__ is /usr/bin/yade
# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines import files
from engines.run.crosscheck import crosscheck, precision_study
from engines.run.preflight import announce_output


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="output directory (make test: out/crosscheck)")
    ap.add_argument("--precision", action="store_true",
                    help="run only the reference in float32, float64 and longdouble (make precision): DIR/precision.json")
    ap.add_argument("--only", nargs="+", metavar="CASE", help="run only these cases (names in engines/run/crosscheck.py)")
    args = ap.parse_args(argv)
    announce_output(args.out)
    if args.precision:
        result = precision_study()
        print("precision:", json.dumps(result, indent=1), flush=True)
        os.makedirs(args.out, exist_ok=True)
        files.write_json(os.path.join(args.out, "precision.json"), result)
        print("every precision within its bound" if result["passed"] else f"PRECISION OUT OF BOUND: {result['why']}")
        return 0 if result["passed"] else 1
    from engines.yade.coupling import simulate  # needs YADE: run under `yade -n -x`
    try:
        result, path = crosscheck(simulate, args.out, args.only, log=lambda line: print(line, flush=True))
    except ValueError as e:
        ap.error(str(e))
    print(f"wrote {path}; {'all cases passed' if result['passed'] else 'SOME CASES FAILED'}")
    return 0 if result["passed"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
