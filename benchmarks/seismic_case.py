"""The seismic-size scene at the paper's settings, timed (target <= 15 s wall).

    yade -n -x benchmarks/seismic_case.py --json out/bench-seismic.json [--steps 180000]

The liquefaction_case1 preset (seed 000 §6, SPEC §2.5) on its packing: 192 particles and 47 wall
discs, Table 4 constants, spring (d), eps_m = 2e-4 m, the top particles and walls 10x denser,
saturated and undrained (k1 = 1e3, k2 = 1e2 1/s), the base shaken by the 1500 gal, 50 Hz cosine
(engines.model.ground_motion.BaseMotion), the side-wall columns moving in x on their springs (Fig. 27),
dt = 1e-6 s, water every step, pores rebuilt every 1000 steps, 180,000 steps (0.18 s). The paper's
law runs as its engine. Writes {"steps": n, "wall_s": x, "us_per_step": y, "cpu_s": c, ...,
"comparison": {...}, "breakdown_cpu_us": {...}}: the comparison times YADE alone on the same discs
(fixed walls), our step with the compiled kernels (the steps from one pore rebuild to the next in
one compiled run: kernels.dem_drive_bulk_io), with one compiled call a step (kernels.dem_drive_bulk_io, n = 1), on the general
path (PoreDEM.step between bulk reads and writes; the side-wall ties in NumPy) and with the NumPy
path, interleaved in the same run (ratios hold on a shared machine; absolute times do not); the
breakdown splits the run's CPU time a step into its parts, their sum against the measured mean
(``breakdown``).
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
    + eps_m/2, no Python), our step with the compiled kernels (many steps in one call:
    kernels.dem_drive_bulk_io), with one compiled call a step (kernels.dem_drive_bulk_io, n = 1), on the general
    path and with the NumPy path, in turns (benchmarks.coupling.paired_runs: YADE alone and the
    compiled runs next to each other, the order swapped every repeat); medians of wall and CPU
    microseconds per step and their ratios to YADE alone. YADE alone has NewtonIntegrator's
    damping pass off, as our scenes do (engines.yade.coupling.undamped); ``yade_alone_defaults``
    is YADE with the pass on (its default), and our CPU ratio to it is given too."""
    import numpy as np

    from benchmarks.coupling import paired_runs
    from benchmarks.floor import native_floor, run_steps
    from engines.yade.coupling import YadeCoupling

    def floor(undamped=True):
        native_floor(scene, packing, undamped)
        return run_steps, lambda: 0

    def coupling(one_call=True, many=True, compiled=True):
        cp = YadeCoupling(scene, packing, compiled=compiled)
        if not many:  # a hook: the drive one step a call
            cp.engine.hooks.append(lambda: None)
        if not one_call:
            cp.core.kernel_drive_args = lambda rows, held, n: None
        return cp.run, lambda: cp.water_model.n_rebuilds

    setups = {"yade_alone": floor, "compiled": coupling, "yade_alone_defaults": lambda: floor(False),
              "compiled_one_call_a_step": lambda: coupling(many=False),
              "compiled_general_path": lambda: coupling(one_call=False, many=False),
              "numpy": lambda: coupling(compiled=False)}
    wall, cpu, built = paired_runs(setups, steps, repeats)
    out = {"steps": steps, "repeats": repeats,  # the pore rebuilds in each timed run (the run's share: steps / 1000)
           "rebuilds_per_run": {k: sorted(set(v)) for k, v in built.items() if not k.startswith("yade_alone")}}
    for label, d in (("wall_us", wall), ("cpu_us", cpu)):
        med = {k: float(np.median(v)) for k, v in d.items()}
        out[label] = med
        out[label.replace("_us", "_ratio_to_yade_alone")] = {k: v / med["yade_alone"] for k, v in med.items()}
        # the ratio within each repeat (the same minute of the machine), its median and spread
        paired = {k: [a / y for a, y in zip(v, d["yade_alone"])] for k, v in d.items() if k != "yade_alone"}
        out[label.replace("_us", "_paired_ratio")] = {k: {"median": float(np.median(v)), "min": min(v), "max": max(v)}
                                                      for k, v in paired.items()}
    to_defaults = [a / y for a, y in zip(cpu["compiled"], cpu["yade_alone_defaults"])]
    out["cpu_paired_ratio_to_yade_alone_defaults"] = {"median": float(np.median(to_defaults)), "min": min(to_defaults),
                                                      "max": max(to_defaults)}
    return out


class Clock:
    """CPU time spent in some methods of some objects, each method's own time (a timed method
    called inside another is counted for itself only): ``wrap(obj, name, label)``."""

    def __init__(self):
        self.seconds, self.calls, self._inner = {}, {}, []

    def wrap(self, obj, name, label):
        f = getattr(obj, name)
        self.seconds[label], self.calls[label] = 0.0, 0

        def timed(*args):
            c0 = time.process_time()
            self._inner.append(0.0)
            try:
                return f(*args)
            finally:
                dt, inner = time.process_time() - c0, self._inner.pop()
                self.seconds[label] += dt - inner
                self.calls[label] += 1
                if self._inner:
                    self._inner[-1] += dt
        setattr(obj, name, timed)


RUN_PARTS = {  # (object, method) of a run's parts, timed where they run (Clock)
    "compiled runs of steps (kernels.dem_drive_bulk_io: read, law, ties, water, write, base, YADE's step)":
        ("engine", "_drive_dem"),
    "steps finished in Python after a compiled run (water sub-steps: books, O.step)":
        ("engine", "_finish_in_python"),
    "steps made in Python (PoreDEM.step, bridge, O.step: none after the first)": ("engine", "_python_step"),
    "pore rebuilds, each before its step's compiled run (PoreDEM.rebuild_pores)": ("core", "rebuild_pores"),
    "pair-list rebuilds (ContactLaw._update_list)": ("contact", "_update_list"),
}


def breakdown(scene, packing, steps=3000, repeats=5, warmup=1100, calls=2000):
    """CPU microseconds a step of the seismic run, complete. The run: ``repeats`` runs of
    ``steps`` steps after ``warmup``, each part timed where it runs (RUN_PARTS, Clock), the rest
    (the Python of drive, kernel_drive_args, finish_kernel_drive, YadeCoupling.run) the residual
    of the measured mean; the same runs without timers alternate with them. A step of the
    compiled runs: its parts timed alone, ``calls`` times in a compiled loop at one state (no
    Python between calls): the law, the side-wall ties, the water (the pore measure, the flows,
    the update, the eq 33 forces, the rest), the bridge's position read, force write and the
    driven walls' velocity write, the base motion, and YADE's own step (NewtonIntegrator,
    ForceResetter: the bridge's steps());
    against the compiled runs' time a step, the residual stated. Medians."""
    import numba
    import numpy as np

    from engines.compiled import kernels
    from engines.compiled.params import WATER_PRM
    from engines.yade import yade_io, yadebulk
    from engines.yade.coupling import YadeCoupling

    @numba.njit
    def repeat(n, f, args):
        for _ in range(n):
            f(*args)

    cp = YadeCoupling(scene, packing)
    cp.run(warmup)
    eng, core = cp.engine, cp.core
    owners = {"engine": eng, "core": core, "contact": core.law.contact}
    plain = {label: getattr(owners[o], n) for label, (o, n) in RUN_PARTS.items()}
    kernel_steps = [0]
    drive = eng._drive_dem

    def counted(*args):  # the steps made in compiled runs
        out = drive(*args)
        kernel_steps[0] += out[0]
        return out
    eng._drive_dem = counted
    clock = Clock()
    for label, (o, n) in RUN_PARTS.items():
        clock.wrap(owners[o], n, label)
    timed = {label: getattr(owners[o], n) for label, (o, n) in RUN_PARTS.items()}
    run = {"timed": [], "plain": []}
    parts = {label: [] for label in RUN_PARTS}
    counts = {label: [] for label in RUN_PARTS}
    per_kernel_step = []
    for _ in range(repeats):
        for how, methods in (("timed", timed), ("plain", plain)):
            for label, (o, n) in RUN_PARTS.items():
                setattr(owners[o], n, methods[label])
            c0 = time.process_time()
            cp.run(steps)
            run[how].append(1e6 * (time.process_time() - c0) / steps)
        for label in RUN_PARTS:
            parts[label].append(1e6 * clock.seconds[label] / steps)
            counts[label].append(clock.calls[label])
            clock.seconds[label] = clock.calls[label] = 0
        per_kernel_step.append(parts[next(iter(RUN_PARTS))][-1] * steps / kernel_steps[0])
        kernel_steps[0] = 0
    med = {label: float(np.median(v)) for label, v in parts.items()}
    mean = float(np.median(run["timed"]))
    out = {"run: CPU us a step, with the timers": mean,
           "run: CPU us a step, without them": float(np.median(run["plain"])),
           "run: parts a step": dict(med, **{"Python around them (residual)": mean - sum(med.values())}),
           "run: calls of each part in %d steps" % steps: {label: float(np.median(v)) for label, v in counts.items()}}

    # a step of the compiled runs, part by part
    xz = cp.positions()
    law, wm = core.law, core.water_model
    law.contact._update_list(xz)
    law_args, water_args = law.kernel_args(), wm.kernel_args(wm.schedule.water_interval * law.dt)
    part, net = wm._part, wm.water.net
    geometry = (xz, part("r"), wm.eps_m,
                kernels.LinkGeometry(net.links, net.link_pores, part("vec0").reshape(-1, 2), part("turn_weight"),
                                     part("sector0")),
                kernels.Measures(part("poly"), part("sect"), part("void"), part("length"), part("contact"),
                                 part("vec").reshape(-1, 2), part("right").reshape(-1, 2)))
    wa = dict(zip(kernels.WATER.names, water_args))
    flow = (wm.water.W, part("void"), wa["ints"], wa["i_at"], wa["floats"], wa["f_at"])
    update = (wm.water.W, wa["h"], part("out_i"), part("out_j"), part("q_s"), part("q_d"), part("q_in"),
              part("balance"), part("void"), wm.wp[WATER_PRM.E_w], part("U"))
    forces = (net.links, net.link_pores, part("r"), part("U"), part("length"), part("vec").reshape(-1, 2), wa["F_water"],
              part("Fj").reshape(-1, 2))
    drive_args = core.kernel_drive_args(eng._dynamic, eng.held, 1)
    motion, record = drive_args[8:10]
    rows = np.arange(len(eng._F_out))
    write = yade_io._ADD_UNSYNCED if eng._reset_last else yade_io._SET_PERM  # as the run writes them
    bridge = (yade_io._GET_POS, eng.io.ids, eng._xz), (write, eng.forced.ids, eng._F_out.copy(), rows,
                                                      eng.held, eng._F_out)
    W0 = wm.water.W.copy()
    alone = {
        "law (kernels.law_step)": (kernels.law_step, (xz,) + law_args),
        "side-wall ties (kernels.tie_forces)": (kernels.tie_forces, (xz, law.du, law.dt) + core._tie_args),
        "water (kernels.water_step)": (kernels.water_step, (xz,) + water_args),
        "  of which pore measure (kernels.measure)": (kernels.measure, geometry),
        "  of which flows (kernels.darcy_flows)": (numba.njit(lambda W, A, *buffers: kernels.darcy_flows(
            W, A, kernels.water_net(*buffers))), flow),
        "  of which the update and eq 32 (kernels.darcy_update)": (kernels.darcy_update, update),
        "  of which eq 33 forces (kernels.pressure_forces)": (kernels.pressure_forces, forces),
        "bridge: read positions (get_pos)": (kernels.read_bulk_io, bridge[0]),
        "bridge: write forces (add_force_unsynced or set_perm)": (kernels.write_rows_bulk_io, bridge[1]),
        "base motion (kernels.base_step)": (kernels.base_step, (motion, *record, core.k)),
        "bridge: the driven walls' velocities (set_vel)": (kernels.read_bulk_io,  # the same bulk call, of set_vel
                                                           (yade_io._SET_VEL, eng.walls.ids, eng._wall_vel)),
    }
    times = {name: [] for name in alone}
    times["YADE's own step (NewtonIntegrator, ForceResetter: bridge steps())"] = []
    for f, args in alone.values():
        repeat(1, f, args)  # compiled for these arguments
    for _ in range(repeats):
        for name, (f, args) in alone.items():
            c0 = time.process_time()
            repeat(calls, f, args)
            times[name].append(1e6 * (time.process_time() - c0) / calls)
            wm.water.W[:] = W0  # the same state for every call
        c0 = time.process_time()
        yadebulk.steps(calls // 4)
        times["YADE's own step (NewtonIntegrator, ForceResetter: bridge steps())"].append(
            1e6 * (time.process_time() - c0) / (calls // 4))
    step = {name: float(np.median(v)) for name, v in times.items()}
    measured = float(np.median(per_kernel_step))
    named = sum(v for name, v in step.items() if not name.startswith(" "))
    step["  of which the rest (the parts' views, the sub-step count)"] = (
        step["water (kernels.water_step)"] - sum(v for name, v in step.items() if name.startswith("  of which")))
    out["a compiled run: CPU us a step (its time in the run / its steps)"] = measured
    out["a compiled run: parts a step, timed alone"] = dict(step, **{
        "residual (the loop, the pair lists rebuilt inside, the parts slower in sequence)": measured - named})
    return out


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--steps", type=int, default=180000)
    ap.add_argument("--compare-steps", type=int, default=1000,
                    help="steps of each run of the in-run comparison with YADE alone and the NumPy path (0: "
                         "skip); 1000 hold one pore rebuild, the run's share")
    ap.add_argument("--repeats", type=int, default=21,
                    help="of the comparison: the machine's speed drifts by ~25 %% within 0.1 s, so many short pairs")
    ap.add_argument("--breakdown", type=int, default=1, help="1: split a step's CPU time into its parts (0: skip)")
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
