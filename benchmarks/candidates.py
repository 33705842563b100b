"""Cost of the link candidates at a pore rebuild: Delaunay of the centres (the previous build) against
the regular triangulation with hidden eq 28 pairs inserted (issue 11).

    /usr/bin/python3 benchmarks/candidates.py --json out/bench-candidates.json [--sizes 239 2000]

Packings: the seismic preset (yade_scripts/scenes/liquefaction_packing.csv) at its own range, and
random sequential addition of the paper's log-normal diameters (packing.layouts), a
loose random packing with gaps of all sizes, at the seismic (eps_m = 2e-4, l_m = 3.5e-4 m) and the
quick-sand (0, 1.3e-4 m) link ranges. The two builds are timed interleaved (medians of repeats),
so the ratio is meaningful on a busy machine even when the absolute times are not. Also counts the
eq 28 pairs the Delaunay candidates leave out and the pairs the insertion puts in.
"""
import argparse
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from benchmarks import write_json
from engines.model import pores as pg
from engines.run.scene import SCENE_DIR
from packing.layouts import random_sequential
from packing.packing import Packing
from packing.psd import sample_diameters

RANGES = {"seismic": (2e-4, 3.5e-4), "quicksand": (0.0, 1.3e-4)}


def interleaved_medians(fns, repeat):
    """Median wall time [s] of each function, calls interleaved."""
    times = [[] for _ in fns]
    for _ in range(repeat):
        for k, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
    return [float(np.median(t)) for t in times]


def random_packing(n, seed):
    rng = np.random.default_rng(seed)
    side = np.sqrt(n * 1.3e-6)  # room for n discs at the coverage random addition reaches (~0.55)
    return random_sequential(sample_diameters(n, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, rng), side, side, rng)


def bench(label, xz, r, repeat, walls=None, ranges=RANGES):
    rows = []
    for name, (eps_m, l_m) in ranges.items():
        def build(cand):
            return pg.build_pores(xz, r, eps_m, l_m, walls=walls, candidates=cand)
        old, new = build("delaunay"), build("regular")
        t_old, t_new = interleaved_medians([lambda: build("delaunay"), lambda: build("regular")], repeat)
        rows.append({"packing": label, "n_discs": len(r), "range": name, "eps_m": eps_m, "l_m": l_m,
                     "delaunay_ms": 1e3 * t_old, "regular_ms": 1e3 * t_new, "ratio": t_new / t_old,
                     "links_delaunay": len(old.links), "links_regular": len(new.links),
                     "pairs_inserted": new.n_inserted})
        print(f"{label:22s} {len(r):6d} discs {name:9s}: Delaunay {1e3 * t_old:7.2f} ms, regular {1e3 * t_new:7.2f} ms "
              f"(x{t_new / t_old:.2f}); links {len(old.links)} -> {len(new.links)}, {new.n_inserted} inserted",
              flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[239, 2000])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args(argv)
    pk = Packing.load(os.path.join(SCENE_DIR, "liquefaction_packing.csv"))
    rows = bench("liquefaction_packing", pk.xz, pk.r, args.repeat, pk.group, {"seismic": RANGES["seismic"]})
    for k, n in enumerate(args.sizes):
        rows += bench("random_sequential", *random_packing(n, k), args.repeat)
    if args.json:
        write_json(args.json, {"results": rows})


if __name__ == "__main__":
    main()
