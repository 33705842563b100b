"""What YADE's law with the water costs beyond the water step, part by part.

    yade -n -x benchmarks/water_in_situ.py --json out/bench-water-in-situ.json [--size 2000] [--repeats 5]

One scene: benchmarks.coupling's settled packing of about ``size`` bodies with [contact] law =
"yade" and the water every step (its column yade_law_wet_us). Variants of a step, each a compiled
loop of ``steps`` steps (no Python between steps), interleaved, CPU microseconds a step, medians
of ``repeats`` and "minus_steps_us", the median within a repeat of the variant less YADE's steps:

  steps                YADE's steps alone (the bridge's steps(): O.step())
  steps_write          + the permanent-force write of the water's forces
  steps_read_write     + the position read
  water_read_steps     the position read, the water step, YADE's step (no force write)
  water_drive          kernels.water_drive_bulk_io: read, water step, write, YADE's step
  water_alone          the water step alone, at one state
  flush                16 MB written (one double a 64-byte line)
  flush_water          16 MB written, then the water step: the water step with cold caches
  flush_steps          16 MB written, then YADE's step: YADE's step with cold caches

flush_water - flush against water_alone says how much the water step suffers from cold caches,
flush_steps - flush against steps how much YADE's step does. No rebuild of the pores among the
steps (the packing is at rest).
"""
import argparse
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numba as nb
import numpy as np

from benchmarks import write_json
from benchmarks.coupling import COLUMNS, scene_for, settled_packing
from engines.compiled import kernels
from engines.yade import yade_io
from engines.yade.coupling import YadeCoupling

FLUSH_DOUBLES = 2 << 20  # 16 MB


@nb.njit
def _flush(junk):
    for a in range(0, len(junk), 8):
        junk[a] += 1.0


@nb.njit
def _loop(n, bridge, junk, read, water, write, steps, ids_in, xz, ids_out, F_out, rows, held,
          h, W, A_prev, q_prev, smoothing, substep, F_water, ints, i_at, floats, f_at):
    """n steps of the chosen parts: junk written (if not empty), the position read, the water step
    (kernels.water_forces_step), the force write, YADE's step."""
    for _ in range(n):
        if len(junk):
            _flush(junk)
        if read:
            kernels._read_positions(bridge[kernels.BRIDGE.get_pos], ids_in, xz)
        if water:
            kernels.water_forces_step(xz, F_out, rows, held, (h, W, A_prev, q_prev, smoothing, substep, F_water,
                                                              ints, i_at, floats, f_at))
        if write:
            kernels._write_forces(0, bridge[kernels.BRIDGE.write_forces], ids_out, F_out)
        if steps:
            kernels._c_bulk_call(bridge[kernels.BRIDGE.steps], 0, 1, 0)


VARIANTS = {  # (flush, read, water, write, steps) of _loop
    "steps": (False, False, False, False, True),
    "steps_write": (False, False, False, True, True),
    "steps_read_write": (False, True, False, True, True),
    "water_read_steps": (False, True, True, False, True),
    "water_alone": (False, False, True, False, False),
    "flush": (True, False, False, False, False),
    "flush_water": (True, False, True, False, False),
    "flush_steps": (True, False, False, False, True),
}


def measure(size, steps, repeats, log):
    packing = settled_packing(size)
    cp = YadeCoupling(scene_for(COLUMNS["yade_law_wet_us"]), packing)
    cp.run(300)
    we, m = cp.water_engine, cp.water_model
    args = we._forces_step_args(m.kernel_args(m.water_interval * cp.scene.numerics.dt))
    io = (we.io.ids, we._xz, we.forced.ids, we._F_out)
    junk, none = np.zeros(FLUSH_DOUBLES), np.zeros(0)
    totals = np.zeros(3)

    def variant(flush, read, water, write, steps_):
        return lambda: _loop(steps, yade_io._BRIDGE, junk if flush else none, read, water, write, steps_, *io, *args)
    runs = {name: variant(*how) for name, how in VARIANTS.items()}
    runs["water_drive"] = lambda: kernels.water_drive_bulk_io(yade_io._BRIDGE, steps, 0, 1, totals, m.xz_built,
                                                              0.0, *io, *args)
    W0 = m.water.W.copy()
    for run in runs.values():
        run()  # compiled for these arguments
    cpu = {name: [] for name in runs}
    for rep in range(repeats):
        for name, run in runs.items():
            c0 = time.process_time()
            run()
            cpu[name].append(1e6 * (time.process_time() - c0) / steps)
            m.water.W[:] = W0  # the same water for every variant
        log(f"  rep {rep + 1}/{repeats}: " + ", ".join(f"{k} {v[-1]:.1f}" for k, v in cpu.items()))
    base = np.array(cpu["steps"])
    return {"n_bodies": int(len(packing.r)), "n_pores": int(m.water.net.n_pores), "steps": steps, "repeats": repeats,
            "cpu_us": {k: float(np.median(v)) for k, v in cpu.items()},
            "minus_steps_us": {k: float(np.median(np.array(v) - base)) for k, v in cpu.items()},
            "samples_cpu_us": cpu}


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--size", type=int, default=2000)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    out = measure(args.size, args.steps, args.repeats, lambda s: print(s, flush=True))
    for k in out["cpu_us"]:
        print(f"{k:18s} {out['cpu_us'][k]:9.1f} us a step, minus YADE's steps {out['minus_steps_us'][k]:9.1f}")
    write_json(args.json, out)


if __name__ == "__main__":
    main(sys.argv[1:])
