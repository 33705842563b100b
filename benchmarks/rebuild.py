"""Cost of a pore rebuild (engines.model.water_model.WaterModel.rebuild) by part, the readable NumPy path
against the compiled one (engines.compiled.pores), at about 240, 2,000 and 10,000 discs.

    yade -n -x benchmarks/rebuild.py --json out/bench-rebuild.json [--sizes 240 2000 10000]

Packing: the box of benchmarks/coupling.py (random_discs with wall rows and columns), the seismic
link range (eps_m = 2e-4 m, l_m = 3.5e-4 m); the old network is built at the packing, the new one
after every disc moved by a Gaussian of ``--jitter`` mean radii (0.02: about what 1000 steps of
1e-6 s move the grains of the seismic case). The two paths are timed interleaved, part by part
(medians of repeats), so the ratios hold on a busy machine even when the absolute times do not.
Parts: triangulation (qhull and the lower facets), insertion of hidden eq 28 pairs, the rest of
build_pores (faces, links, corners), the void areas of the new and the old network, the rules
(a)-(d), the overlaps, and the whole rebuild. Writes {"results": [{"n_discs": N,
"<part>_numpy_ms": x, "<part>_compiled_ms": y, "<part>_ratio": x / y, ...}, ...]}.
"""
import argparse
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from benchmarks import write_json
from benchmarks.coupling import box_packing
from engines.compiled import water_model as cw
from engines.model import pore_water as pw
from engines.model import pores as pg
from engines.model import water_model as mw

EPS_M, L_M = 2e-4, 3.5e-4
SETTINGS = pw.WaterSettings(E_w=2400.0, k1=1e3, k2=1e2)


def parts(packing, xz, compiled):
    """{part: function} of one path; xz: the moved centres the rebuild sees."""
    r, walls = packing.r, packing.group
    model = (cw if compiled else mw).WaterModel(SETTINGS, r, walls, packing.xz, EPS_M, L_M, 1e-6, log=lambda msg: None)
    build, remesh = model.build_steps, model.remesh_steps
    old, W_old = model.water.net, model.water.W.copy()
    tri = pg.regular_triangulation(xz, r, build)
    new = pg.build_pores(xz, r, EPS_M, L_M, walls=walls, steps=build)
    A_old = pg.measure(old, xz, r).void_area
    U_old = pw.pressure(W_old, A_old, SETTINGS.E_w)

    def rebuild():
        model.water.net, model.water.W = old, W_old
        model.rebuild(xz)

    return {
        "triangulation": lambda: pg.regular_triangulation(xz, r, build),
        "insertion": lambda: pg.insert_missing_links(xz, r, tri, EPS_M + L_M, build),
        "build_pores": lambda: pg.build_pores(xz, r, EPS_M, L_M, walls=walls, steps=build),
        "measures": lambda: (model._void_area(new, xz), model._void_area(old, xz)),
        "rules": lambda: pw.pressures_by_rule(old, U_old, A_old > old.a_min, new, remesh),
        "overlaps": lambda: remesh.pore_overlaps(old, new, xz),
        "rebuild": rebuild,
    }


def bench(n, jitter, repeat):
    packing = box_packing(n)
    xz = packing.xz + jitter * packing.r.mean() * np.random.default_rng(1).standard_normal(packing.xz.shape)
    paths = {"numpy": parts(packing, xz, False), "compiled": parts(packing, xz, True)}
    for fns in paths.values():  # warm up (numba loads its cache)
        for fn in fns.values():
            fn()
    times = {(path, part): [] for path in paths for part in paths[path]}
    for _ in range(repeat):
        for part in paths["numpy"]:
            for path in paths:
                t0 = time.perf_counter()
                paths[path][part]()
                times[path, part].append(time.perf_counter() - t0)
    new = pg.build_pores(xz, packing.r, EPS_M, L_M, walls=packing.group)
    row = {"n_discs": int(len(packing.r)), "n_pores": int(new.n_pores), "n_inserted": int(new.n_inserted),
           "jitter": jitter, "repeat": repeat}
    for part in paths["numpy"]:
        a, b = (1e3 * float(np.median(times[path, part])) for path in paths)
        row.update({f"{part}_numpy_ms": a, f"{part}_compiled_ms": b, f"{part}_ratio": a / b})
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True, help="output JSON path")
    ap.add_argument("--sizes", type=int, nargs="+", default=[240, 2000, 10000])
    ap.add_argument("--jitter", type=float, default=0.02, help="displacement between builds [mean radii]")
    ap.add_argument("--repeat", type=int, default=0, help="repeats (default: 41, 15, 5 by size)")
    args = ap.parse_args(argv)
    results = []
    for n in args.sizes:
        row = bench(n, args.jitter, args.repeat or (41 if n < 1000 else 15 if n < 5000 else 5))
        results.append(row)
        print(f"{row['n_discs']} discs, {row['n_pores']} pores (medians of {row['repeat']}, interleaved):")
        for part in ("triangulation", "insertion", "build_pores", "measures", "rules", "overlaps", "rebuild"):
            print(f"  {part:14s} NumPy {row[f'{part}_numpy_ms']:8.3f} ms  compiled {row[f'{part}_compiled_ms']:8.3f} ms"
                  f"  x{row[f'{part}_ratio']:.2f}", flush=True)
    write_json(args.json, {"results": results})


if __name__ == "__main__":
    main()
