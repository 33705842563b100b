"""The demo's numbers quoted in README.md and docs/OUTPUTS.md (``make demo-numbers``, a few minutes).

    /usr/bin/python3 yade_scripts/demo_numbers.py [--out out/demo-numbers] [--docs-only]

Runs the demo (quick sand, case 1) timed as a whole command and an ensemble of 8 perturbed starts
of it in OUT, writes docs/demo/demo.json (date, commit, machine and its load, the demo's results,
the 8 starts' 95 % intervals) and rewrites the paragraph between the demo-numbers marks of
README.md and docs/OUTPUTS.md from it (engines/run/demo_numbers.py). --docs-only rewrites the
paragraphs from the committed JSON without running anything.
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))
import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines import files  # noqa: E402
from engines.run import demo_numbers  # noqa: E402
from engines.run.preflight import output_dir  # noqa: E402

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=output_dir, default=os.path.join("out", "demo-numbers"),
                    help="where the runs are written (default out/demo-numbers)")
    ap.add_argument("--docs-only", action="store_true", help="rewrite the documents from docs/demo/demo.json only")
    args = ap.parse_args()
    try:
        if args.docs_only:
            with open(demo_numbers.JSON) as f:
                doc = json.load(f)
        else:
            print(f"output: {os.path.abspath(args.out)} (the demo, then {demo_numbers.STARTS} starts)", flush=True)
            doc = demo_numbers.measure(args.out)
            os.makedirs(os.path.dirname(demo_numbers.JSON), exist_ok=True)
            files.write_json(demo_numbers.JSON, doc)
        for path in demo_numbers.DOCS:
            demo_numbers.update(path, doc)
    except (OSError, ValueError, RuntimeError) as e:
        sys.exit(f"error: {e}")
    print(demo_numbers.text(doc))
    print("written: " + ", ".join(([] if args.docs_only else [demo_numbers.JSON]) + list(demo_numbers.DOCS)))
