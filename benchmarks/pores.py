"""Cost of the pore core: rebuild (links, pores, re-meshing) and one water step (areas + flow + forces),
NumPy path and compiled kernels (engines.compiled.water_model.WaterModel).

    yade -n -x benchmarks/pores.py --json out/bench-pores.json [--sizes 239 2000 10000]

Packings are jittered polydisperse hexagonal packings (packing.layouts.random_discs) with the
quick-sand constants and a bottom row as wall. The floor is a dry YADE step of the same discs
(benchmarks/floor.py: collider + native linear law + NewtonIntegrator); all in one run.
Writes {"results": [{"n_discs": N, "rebuild_ms": x, "step_ms": y, "yade_dry_step_ms": z, ...}, ...]}.
"""
import argparse
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from benchmarks import write_json
from benchmarks.floor import native_floor, per_step, step_by_step
from engines.compiled.water_model import WaterModel
from engines.model import pores as pg
from engines.model.pore_water import PoreWater, WaterSettings
from engines.run import scene as scenes
from packing.layouts import random_discs
from packing.packing import Packing


def best_of(fn, repeat):
    """Smallest wall time of ``repeat`` calls [s] (the least disturbed by the machine)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def bench(n, rng, repeat_step=50, repeat_rebuild=5):
    r_mean = 0.45e-3
    xz, r = random_discs(n, rng, r_mean=r_mean)
    l_m = 1.3e-4
    walls = np.where(xz[:, 1] < xz[:, 1].min() + r_mean, pg.WALL_BOTTOM, pg.WALL_NONE)
    settings = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4)
    net = pg.build_pores(xz, r, l_m=l_m, walls=walls)
    m = pg.measure(net, xz, r)
    water = PoreWater(net, m.void_area, settings)

    def step():
        m = pg.measure(net, xz, r)
        water.advance(1e-6, m.void_area, m.link_contact)
        return pg.pressure_forces(net, r, water.pressure(m.void_area), m)

    def rebuild():
        new = pg.build_pores(xz, r, l_m=l_m, walls=walls)
        A_old = pg.measure(water.net, xz, r).void_area
        water.remesh(new, pg.measure(new, xz, r).void_area, A_old)

    step()
    t_step = best_of(step, repeat_step)
    compiled = WaterModel(settings, r, walls, xz, 0.0, l_m, 1e-6, log=lambda msg: None)
    compiled.advance(1e-6, xz)  # numba loads the cached kernels
    t_compiled = best_of(lambda: compiled.advance(1e-6, xz), repeat_step)
    t_rebuild = best_of(rebuild, repeat_rebuild)
    native_floor(scenes.preset("quicksand_case1"), Packing(xz, r, walls, np.ones(len(r))))
    floor_ms = 1e-3 * per_step(100, step_by_step, warmup=20)
    return {"n_discs": int(len(r)), "n_pores": int(net.n_pores), "n_links": int(len(net.links)),
            "rebuild_ms": 1e3 * t_rebuild, "step_ms": 1e3 * t_step, "step_compiled_ms": 1e3 * t_compiled,
            "numpy_over_compiled": t_step / t_compiled, "yade_dry_step_ms": floor_ms,
            "step_over_yade_dry": 1e3 * t_step / floor_ms, "compiled_step_over_yade_dry": 1e3 * t_compiled / floor_ms}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True, help="output JSON path")
    ap.add_argument("--sizes", type=int, nargs="+", default=[239, 2000, 10000])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    results = [bench(n, rng) for n in args.sizes]
    print(f"{'discs':>8} {'pores':>8} {'links':>8} {'rebuild ms':>11} {'step ms':>9} {'compiled ms':>12} "
          f"{'numpy/comp':>11} {'YADE dry ms':>12} {'comp/dry':>9}")
    for res in results:
        print(f"{res['n_discs']:8d} {res['n_pores']:8d} {res['n_links']:8d} {res['rebuild_ms']:11.2f} "
              f"{res['step_ms']:9.3f} {res['step_compiled_ms']:12.3f} {res['numpy_over_compiled']:11.1f} "
              f"{res['yade_dry_step_ms']:12.3f} {res['compiled_step_over_yade_dry']:9.2f}")
    write_json(args.json, {"results": results})


if __name__ == "__main__":
    main()
