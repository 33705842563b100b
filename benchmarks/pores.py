"""Cost of the pore core: rebuild (links, pores, re-meshing) and one water step (areas + flow + forces),
NumPy path and compiled kernels (engines.compiled.water_model.WaterModel).

    yade -n -x benchmarks/pores.py --json out/bench-pores.json [--sizes 239 2000 10000]

Packings are jittered polydisperse hexagonal packings (packing.layouts.random_discs) with the
quick-sand constants and a bottom row as wall. The floor is a dry YADE step of the same discs
(benchmarks/floor.py: collider + native linear law + NewtonIntegrator); all in one run.
Writes {"results": [{"n_discs": N, "rebuild_ms": x, "rebuild_compiled_ms": x', "step_ms": y,
"step_compiled_ms": y', "yade_dry_step_ms": z, "water_model_mb": m, ...}, ...], "growth_exponents":
{key: [b, ...]}}: water_model_mb is the memory the compiled water model holds after it is made and
has stepped once (its arrays and the kernels' buffers, traced by tracemalloc; _peak_mb: the most
while making it); process_rss_mb the process's resident memory at the end of the size (YADE's
scene of it included; the sizes run from small to large); b of each key ~ n_discs^b between
successive sizes.
"""
import argparse
import os
import sys
import time
import tracemalloc

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


def growth(results, key):
    """The exponent b of key ~ n_discs^b between each two successive sizes."""
    n = np.array([res["n_discs"] for res in results], float)
    y = np.array([res[key] for res in results], float)
    return [float(b) for b in np.diff(np.log(y)) / np.diff(np.log(n))]


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
    tracemalloc.start()  # numpy's arrays are traced too
    compiled = WaterModel(settings, r, walls, xz, 0.0, l_m, 1e-6, log=lambda msg: None)
    compiled.advance(1e-6, xz)
    water_mb, water_peak_mb = (b / 2**20 for b in tracemalloc.get_traced_memory())
    tracemalloc.stop()
    t_compiled = best_of(lambda: compiled.advance(1e-6, xz), repeat_step)
    t_rebuild = best_of(rebuild, repeat_rebuild)
    t_rebuild_compiled = best_of(lambda: compiled.rebuild(xz), repeat_rebuild)
    native_floor(scenes.preset("quicksand_case1"), Packing(xz, r, walls, np.ones(len(r))))
    floor_ms = 1e-3 * per_step(100, step_by_step, warmup=20)
    with open("/proc/self/statm") as f:  # everything of this size still held: YADE's scene, the water
        rss_mb = int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    return {"n_discs": int(len(r)), "n_pores": int(net.n_pores), "n_links": int(len(net.links)),
            "rebuild_ms": 1e3 * t_rebuild, "rebuild_compiled_ms": 1e3 * t_rebuild_compiled,
            "water_model_mb": water_mb, "water_model_peak_mb": water_peak_mb, "process_rss_mb": rss_mb,
            "step_ms": 1e3 * t_step, "step_compiled_ms": 1e3 * t_compiled,
            "numpy_over_compiled": t_step / t_compiled, "yade_dry_step_ms": floor_ms,
            "step_over_yade_dry": 1e3 * t_step / floor_ms, "compiled_step_over_yade_dry": 1e3 * t_compiled / floor_ms}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True, help="output JSON path")
    ap.add_argument("--sizes", type=int, nargs="+", default=[239, 2000, 10000])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    bench(50, np.random.default_rng(1), 2, 1)  # numba loads the cached kernels before anything is measured
    results = [bench(n, rng) for n in args.sizes]
    print(f"{'discs':>8} {'pores':>8} {'links':>8} {'rebuild ms':>11} {'compiled':>9} {'step ms':>9} "
          f"{'compiled ms':>12} {'numpy/comp':>11} {'YADE dry ms':>12} {'comp/dry':>9} {'water MB':>9}")
    for res in results:
        print(f"{res['n_discs']:8d} {res['n_pores']:8d} {res['n_links']:8d} {res['rebuild_ms']:11.2f} "
              f"{res['rebuild_compiled_ms']:9.2f} {res['step_ms']:9.3f} {res['step_compiled_ms']:12.3f} "
              f"{res['numpy_over_compiled']:11.1f} {res['yade_dry_step_ms']:12.3f} "
              f"{res['compiled_step_over_yade_dry']:9.2f} {res['water_model_mb']:9.1f}")
    keys = ("rebuild_ms", "rebuild_compiled_ms", "step_compiled_ms", "yade_dry_step_ms", "water_model_mb")
    exponents = {k: growth(results, k) for k in keys} if len(results) > 1 else {}
    for k, b in exponents.items():
        print(f"{k} ~ n^b between successive sizes: b = " + ", ".join(f"{x:.2f}" for x in b))
    write_json(args.json, {"results": results, "growth_exponents": exponents})


if __name__ == "__main__":
    main()
