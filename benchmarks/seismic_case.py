"""The seismic-size scene at the paper's settings, timed (issue 10 item 5; target <= 15 s wall).

    yade -n -x benchmarks/seismic_case.py --json out/bench-seismic.json [--steps 180000]

192 particles and 47 wall discs (15 bottom, two side columns of 17 sharing the corners), Table 4
constants, spring (d), eps_m = 2e-4 m, the top particles and walls 10x denser, saturated and
undrained (k1 = 1e3, k2 = 1e2 1/s), cosine input 1500 gal at 50 Hz, dt = 1e-6 s, water every
step, pores rebuilt every 1000 steps, 180,000 steps (0.18 s). The paper's law runs as its engine.

Until the seismic box of issue 11 lands (its side-wall springs, Fig. 27), the packing is our
deposition into a box of 47 fixed wall discs (cached in out/seismic_size/packing.csv) and the
whole box follows the input ([loading] moves = "box"), so the step does the same work per disc.
Writes {"steps": n, "wall_s": x, "us_per_step": y, "cpu_s": c, ..., "comparison": {...}}: the
comparison times YADE alone on the same discs, our step with the compiled kernels and with the
NumPy path, interleaved in the same run (ratios hold on a shared machine; absolute times do not).
"""
import argparse
import json
import os
import sys
import time

_SCRIPT = __file__ if __file__.endswith(".py") else sys.argv[0]  # under `yade -x`, __file__ is yade
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(_SCRIPT)))
sys.path.insert(0, ROOT)

from engines import scene as scenes  # noqa: E402
from engines import yade_io  # noqa: E402
from packing.packing import Packing  # noqa: E402

SCENE = {
    "scene": {"name": "seismic-size", "description": "Table 4, spring d, cosine 1500 gal 50 Hz, case 1 water"},
    "packing": {"source": "deposit", "seed": 5, "n_particles": 192, "n_bottom": 15, "n_side": 17,
                "dense_top_depth": 2.7e-3, "dense_top_factor": 10.0, "settle_time": 0.3},
    "contact": {"spring": "d", "kn": 1.4e5, "eta_n": 2.6, "ks": 3.5e4, "eta_s": 0.6, "mu": 1.0,
                "restitution": 0.001, "f_max": 1.5, "eps_m": 2e-4},
    "water": {"E_w": 2400.0, "k1": 1e3, "k2": 1e2, "k3": 0.0, "q_w": 0.0, "sides": "undrained", "l_m": 3.5e-4},
    "loading": {"type": "cosine", "amplitude": 15.0, "frequency": 50.0, "moves": "box"},
    "numerics": {"dt": 1e-6, "duration": 0.18, "water_interval": 1, "rebuild_interval": 1000},
    "output": {"snapshot_times": []},
}


def seismic_packing(scene, path):
    """The deposited packing, cached at ``path``."""
    if os.path.exists(path):
        return Packing.load(path)
    from packing.deposition import deposit
    pk = deposit(scene)
    pk.save(path)
    return pk


def compare(scene, packing, steps, repeats):
    """Same run, same machine: YADE alone (benchmarks.floor: its collider and a linear law, radii
    + eps_m/2, no Python), our step with the compiled kernels and with the NumPy path, interleaved;
    medians of wall and CPU microseconds per step and their ratios to YADE alone."""
    import numpy as np
    from benchmarks.floor import native_floor, run_steps
    from engines.yade_coupling import YadeCoupling

    def floor():
        native_floor(scene, packing)
        return run_steps

    setups = {"yade_alone": floor, "compiled": lambda: YadeCoupling(scene, packing).run,
              "numpy": lambda: YadeCoupling(scene, packing, compiled=False).run}
    wall, cpu = {k: [] for k in setups}, {k: [] for k in setups}
    for _ in range(repeats):
        for name, setup in setups.items():
            run = setup()
            run(200)
            t0, c0 = time.perf_counter(), time.process_time()
            run(steps)
            wall[name].append(1e6 * (time.perf_counter() - t0) / steps)
            cpu[name].append(1e6 * (time.process_time() - c0) / steps)
    out = {"steps": steps, "repeats": repeats}
    for label, d in (("wall_us", wall), ("cpu_us", cpu)):
        med = {k: float(np.median(v)) for k, v in d.items()}
        out[label] = med
        out[label.replace("_us", "_ratio_to_yade_alone")] = {k: v / med["yade_alone"] for k, v in med.items()}
    return out


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--steps", type=int, default=180000)
    ap.add_argument("--packing", default=os.path.join(ROOT, "out", "seismic_size", "packing.csv"))
    ap.add_argument("--compare-steps", type=int, default=3000,
                    help="steps of the in-run comparison with YADE alone and the NumPy path (0: skip)")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    scene = scenes.validate(SCENE)
    packing = seismic_packing(scene, args.packing)
    from engines.yade_coupling import YadeCoupling
    cp = YadeCoupling(scene, packing)
    cp.run(10)  # numba loads its cached kernels on the first call
    t0, c0 = time.perf_counter(), time.process_time()
    cp.run(args.steps)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    w = cp.water
    out = {"steps": args.steps, "wall_s": wall, "us_per_step": 1e6 * wall / args.steps, "cpu_s": cpu,
           "n_particles": int(packing.mobile.sum()), "n_walls": int((~packing.mobile).sum()),
           "n_pores": int(w.net.n_pores), "n_rebuilds": cp.water_model.n_rebuilds,
           "water_balance_error": w.balance_error(), "io_backend": yade_io.BACKEND,
           "packing": "deposited in a 47-disc fixed-wall box (not yet the seismic box of issue 11)"}
    if args.compare_steps:
        out["comparison"] = compare(scene, packing, args.compare_steps, args.repeats)
    print(json.dumps(out, indent=1))
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with open(args.json, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
