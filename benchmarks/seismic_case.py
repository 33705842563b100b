"""The seismic-size scene at the paper's settings, timed (target <= 15 s wall).

    yade -n -x benchmarks/seismic_case.py --json out/bench-seismic.json [--steps 180000]

The liquefaction_case1 preset (seed 000 §6, SPEC §2.5) on its packing: 192 particles and 47 wall
discs, Table 4 constants, spring (d), eps_m = 2e-4 m, the top particles and walls 10x denser,
saturated and undrained (k1 = 1e3, k2 = 1e2 1/s), the base shaken by the 1500 gal, 50 Hz cosine
(engines.model.ground_motion.BaseMotion), the side-wall columns moving in x on their springs (Fig. 27),
dt = 1e-6 s, water every step, pores rebuilt every 1000 steps, 180,000 steps (0.18 s). The paper's
law runs as its engine. Writes {"steps": n, "wall_s": x, "us_per_step": y, "cpu_s": c, ...,
"comparison": {...}}: the comparison times YADE alone on the same discs (fixed walls), our step
with the compiled kernels (one compiled call a step: kernels.dem_step), with the compiled kernels
on the general path (PoreDEM.step between bulk reads and writes; the side-wall ties in NumPy) and
with the NumPy path, interleaved in the same run (ratios hold on a shared machine; absolute times
do not).
"""
import argparse
import json
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

from benchmarks import write_json
from engines.run import scene as scenes
from engines.yade import yade_io
from packing.packing import Packing

PRESET = "liquefaction_case1"


def compare(scene, packing, steps, repeats):
    """Same run, same machine: YADE alone (benchmarks.floor: its collider and a linear law, radii
    + eps_m/2, no Python), our step with the compiled kernels in one call, on the general path and
    with the NumPy path, interleaved;
    medians of wall and CPU microseconds per step and their ratios to YADE alone."""
    import numpy as np

    from benchmarks.floor import native_floor, run_steps
    from engines.yade.coupling import YadeCoupling

    def floor():
        native_floor(scene, packing)
        return run_steps

    def general_path():  # no one-call step (how this scene ran while its side-wall ties were NumPy)
        cp = YadeCoupling(scene, packing)
        cp.core.kernel_step_args = lambda rows, held: None
        return cp.run

    setups = {"yade_alone": floor, "compiled": lambda: YadeCoupling(scene, packing).run,
              "compiled_general_path": general_path, "numpy": lambda: YadeCoupling(scene, packing, compiled=False).run}
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


def breakdown(scene, packing, calls=2000, repeats=5, warmup=1100):
    """CPU microseconds per step of each part of a seismic step (medians of ``repeats`` runs of
    ``calls`` calls), after ``warmup`` steps of the real run. Each part is timed alone, called
    again and again at the same state (its cost, not its result, is what counts here): the
    compiled kernels from Python (each includes numba's ~1 us call and argument overhead), the
    bridge's read and write, the Python around one step (kernel_step_args, finish_kernel_step,
    hooks), the rebuilds of the pair list and of the pores spread over the steps between them, and
    YADE's own step (ForceResetter, TranslationEngine, NewtonIntegrator) last, on held forces."""
    import numpy as np
    from yade import O

    from engines.compiled import kernels
    from engines.yade.coupling import YadeCoupling

    cp = YadeCoupling(scene, packing)
    cp.run(warmup)
    eng, core = cp.engine, cp.core
    law, wm, c = core.law, core.water_model, core.law.contact
    builds0, k0 = c.list_builds, O.iter
    cp.run(2000)  # how often the pair list is rebuilt
    list_builds_per_step = (c.list_builds - builds0) / (O.iter - k0)
    xz = cp.positions()
    step_args = core.kernel_step_args(eng._dynamic, eng.held)
    law_args, water_args = law.kernel_args(), wm.kernel_args(wm.water_interval * law.dt)
    F_out = np.zeros_like(eng.held)
    part = wm._part
    net = wm.water.net
    geometry = (xz, wm.r, net.links, part("vec0").reshape(-1, 2), net.corner_pore, net.corner_sign, net.corner_link,
                net.corner_next_link, net.corner_theta0, net.corner_r2, net.rattler_area, wm.eps_m, part("poly"),
                part("sect"), part("void"), part("length"), part("contact") > 0, part("theta"),
                part("vec").reshape(-1, 2), part("rot"), part("cross"))
    flow = (wm.water.W, part("void"), geometry[16], net.throat_conns[:, 0].copy(), net.throat_conns[:, 1].copy(),
            net.throat_link, net.a_min, part("surface"), part("drained"), part("bottom"), part("wp"), part("q"),
            part("q_s"), part("q_d"), part("q_in"), part("g"), part("g_b"), part("U"), part("acc_i"), part("acc_j"))
    forces = (net.links, net.link_pores, wm.r, part("U"), part("length"), part("vec").reshape(-1, 2), np.zeros_like(wm.F),
              part("Fj").reshape(-1, 2))
    W0 = wm.water.W.copy()
    parts = {
        "law (kernels.law_step)": lambda: kernels.law_step(xz, *law_args),
        "side-wall ties (kernels.tie_forces)": lambda: kernels.tie_forces(xz, law.du, law.dt, *core._tie_args),
        "side-wall ties, NumPy path (SideWallTies.forces)": lambda: core._tie_forces(xz, law.du),
        "water (kernels.water_step)": lambda: kernels.water_step(xz, *water_args),
        "  of which pore measure": lambda: kernels.measure(*geometry),
        "  of which flows": lambda: kernels.darcy_flows(*flow),
        "  of which pressure forces": lambda: kernels.pressure_forces(*forces),
        "law + ties + water + forces to write (kernels.dem_step)": lambda: kernels.dem_step(xz, F_out, *step_args),
        "read positions (bridge)": lambda: eng.io.positions(),
        "write forces (bridge)": lambda: eng.forced.set_permanent_forces(F_out),
        "Python around a step": lambda: (core.kernel_step_args(eng._dynamic, eng.held), core.law._fixes([], None),
                                         [f() for f in eng.hooks]),
        "  of which base motion and wall velocity (BaseMotion.step, hook)":
            lambda: (core.base.step(), [f() for f in eng.hooks]),
        "whole engine step (PaperLawEngine._kernel_work)": lambda: eng._kernel_work() or eng._work(eng._write_held),
    }
    out = {}
    for name, fn in parts.items():
        times = []
        for _ in range(repeats):
            c0 = time.process_time()
            for _ in range(calls):
                fn()
            times.append(1e6 * (time.process_time() - c0) / calls)
            wm.water.W[:] = W0  # the same state for every call
        out[name] = float(np.median(times))
    c0 = time.process_time()
    for _ in range(20):
        c.xz_list = xz + 1.0  # stale: rebuilt at the next call
        c._update_list(xz)
    out["pair-list rebuilds, spread"] = 1e6 * (time.process_time() - c0) / 20 * list_builds_per_step
    c0 = time.process_time()
    for _ in range(5):
        wm.rebuild(xz)
    out["pore rebuilds, spread"] = 1e6 * (time.process_time() - c0) / 5 / wm.rebuild_interval
    times = []
    for _ in range(repeats):
        c0 = time.process_time()
        for _ in range(calls // 4):
            O.step()
        times.append(1e6 * (time.process_time() - c0) / (calls // 4))
    out["YADE's own step (O.step)"] = float(np.median(times))
    return out


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--steps", type=int, default=180000)
    ap.add_argument("--compare-steps", type=int, default=3000,
                    help="steps of the in-run comparison with YADE alone and the NumPy path (0: skip)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--breakdown", type=int, default=1, help="1: time each part of a step alone (0: skip)")
    args = ap.parse_args(argv)
    scene = scenes.preset(PRESET)
    packing = Packing.load(scene.packing.file)
    from engines.yade.coupling import YadeCoupling
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
           "scene": f"{PRESET} (side walls on springs, base driven by the cosine)"}
    if args.compare_steps:
        out["comparison"] = cmp = compare(scene, packing, args.compare_steps, args.repeats)
        # YADE alone at the compared rate for the whole run: what no engine on these discs can beat here
        cmp["yade_alone_wall_s_for_run"] = cmp["wall_us"]["yade_alone"] * args.steps / 1e6
    if args.breakdown:
        out["breakdown_cpu_us"] = breakdown(scene, packing)
    print(json.dumps(out, indent=1))
    write_json(args.json, out)


if __name__ == "__main__":
    main(sys.argv[1:])
