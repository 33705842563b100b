"""Which time steps let a packed seed-003 specimen stay at rest: the evidence behind the contact
width and engines.seeds.biaxial.cem_contact.stable_dt (docs/BIAXIAL.md).

    yade -n -x yade_scripts/biaxial_stability.py --block DIR/packing_sigma3_200 --out DIR2

Relaxes a block packed by biaxial.py at each case of engines.seeds.biaxial.stability (contact
width, kn, ks/kn, Δt; its docstring says how a case is judged). Writes DIR2/stability.json and
prints a table.
"""
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.preflight import ArgumentParser, output_dir


def main(argv):
    ap = ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--block", required=True, help="a packed block, path without .csv/.json")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory")
    args = ap.parse_args(argv)
    from engines.seeds.biaxial.periodic import PeriodicBlock
    from engines.seeds.biaxial.stability import run_cases

    try:
        block = PeriodicBlock.load(args.block)
    except (OSError, ValueError, KeyError) as e:
        ap.error(f"--block {args.block}: {e}")
    run_cases(block, args.block, args.out)


if __name__ == "__main__":
    main(sys.argv[1:])
