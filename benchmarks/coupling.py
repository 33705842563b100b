"""Cost of our engines against YADE alone, at about 240, 2,000 and 10,000 bodies.

    yade -n -x benchmarks/coupling.py --json out/bench-coupling.json [--sizes 240 2000 10000] [--repeats 3]

Per size, one packing (a jittered polydisperse hexagonal packing, packing.layouts.random_discs,
radii 0.29-0.45 mm, gaps >= eps_m, a bottom row and two side columns of fixed wall discs, settled
under gravity) and the seismic constants of Table 4 with spring (b) (linear, eps_m = 2e-4 m: the
same pairs touch in every column), dt = 1e-6 s, under gravity. Columns (microseconds per step):

  yade_alone_us        YADE's collider + its linear law (ViscElMat, the scene's kn, eta_n, ks, eta_s,
                       mu), radii enlarged by eps_m/2, no Python (benchmarks.floor)
  yade_law_dry_us      [contact] law = "yade", dry: our setup, no Python engine
  yade_law_wet_us      law = "yade" + WaterEngine every step (forces as permanent forces)
  yade_law_wet_m10_us  law = "yade" + WaterEngine every 10 steps
  yade_law_wet_d_us    yade_law_wet_us with the pores rebuilt by displacement ([numerics]
                       rebuild_distance = the WaterEngine's default, REBUILD_FRACTION x l_m)
  yade_law_wet_m10_d_us  yade_law_wet_m10_us so
  paper_law_dry_us     law = "paper" (PaperLawEngine, compiled kernels), dry
  paper_law_wet_us     law = "paper" + water every step, in the paper's step order

The eight are measured interleaved (one run of each in turn, ``repeats`` times, each repeat starting
one column later: at 10,000 bodies the first column of a round ran 10-20 % slower) and the median is
kept, of wall time (the eight columns) and of the process's CPU time ("cpu_us", steadier on a shared
machine), and "cpu_ratio_paired", the ratio to yade_alone within each repeat, median over the
repeats (steadier when the load drifts); each run includes the pore rebuilds (every 1000 steps,
or by displacement) that fall in it, counted in "rebuilds" (median per timed run). Read the
ratios, not the absolute times. "yade_law_dry_paired_ab": first, YADE alone and law = "yade" dry
(the same discs and engines) alone in turns (``paired_dry``): their ratio must be 1 within its
spread, the check that the columns compare like with like; with it the touching pairs YADE
counts. The packings are settled first (``settled_packing``: SETTLE_TIME under gravity with the
deposition's law and damping), so that the columns time the engines on a packing whose contacts
carry its weight.
"""
import argparse
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from benchmarks import write_json
from benchmarks.floor import native_floor, run_steps
from engines.model import pores as pg
from engines.run import scene as scenes
from engines.yade import yade_io
from engines.yade.coupling import YadeCoupling
from engines.yade.deposition import settle
from engines.yade.water_engine import REBUILD_FRACTION
from packing.layouts import random_discs
from packing.packing import Packing

R_MEAN = 0.45e-3
TABLE4 = {"contact": {"spring": "b", "kn": 1.4e5, "eta_n": 2.6, "ks": 3.5e4, "eta_s": 0.6, "mu": 1.0,
                      "restitution": 0.001, "f_max": 1.5, "eps_m": 2e-4},
          "water": {"E_w": 2400.0, "k1": 1e3, "k2": 1e2, "k3": 0.0, "q_w": 0.0, "l_m": 3.5e-4},
          "numerics": {"dt": 1e-6, "rebuild_interval": 1000}}
COLUMNS = {
    "yade_law_dry_us": {"contact": {"law": "yade"}, "water": {"enabled": False}},
    "yade_law_wet_us": {"contact": {"law": "yade"}},
    "yade_law_wet_m10_us": {"contact": {"law": "yade"}, "numerics": {"water_interval": 10}},
    "paper_law_dry_us": {"water": {"enabled": False}},
    "paper_law_wet_us": {},
}
SETTLE_TIME = 0.15  # [s] the packing's top falls by the gaps of its rows (~15 mm at 10,000 bodies), then rests
MOVED = {"rebuild_distance": REBUILD_FRACTION * TABLE4["water"]["l_m"]}
COLUMNS["yade_law_wet_d_us"] = {"contact": {"law": "yade"}, "numerics": MOVED}
COLUMNS["yade_law_wet_m10_d_us"] = {"contact": {"law": "yade"}, "numerics": {"water_interval": 10, **MOVED}}


def box_packing(n, seed=0):
    """About n discs: random_discs with the lowest row as bottom wall and the outer columns as
    side walls (fixed), particles in between; every gap >= eps_m, so that the springs (eq 26) start
    unloaded and the packing settles under gravity instead of bursting apart."""
    grow = 0.5 * TABLE4["contact"]["eps_m"]
    xz, r = random_discs(n, np.random.default_rng(seed), r_mean=R_MEAN + grow, aspect=1.0)
    r = r - grow
    group = np.zeros(len(r), np.int64)
    group[xz[:, 1] < xz[:, 1].min() + R_MEAN] = pg.WALL_BOTTOM
    group[(xz[:, 0] < xz[:, 0].min() + R_MEAN) & (group == 0)] = pg.WALL_LEFT
    group[(xz[:, 0] > xz[:, 0].max() - R_MEAN) & (group == 0)] = pg.WALL_RIGHT
    return Packing(xz, r, group, np.ones(len(r)))


def settled_packing(n, seed=0):
    """box_packing(n, seed) at rest under gravity: SETTLE_TIME of engines.yade.deposition.settle
    (the deposition's law, time step and damping; the Table 4 kn), less the few particles that
    bounced out over the side walls (Packing.outside_box, or above the walls' top)."""
    p = settle(scene_for({}), box_packing(n, seed), SETTLE_TIME)
    keep = np.ones(len(p.r), bool)
    keep[p.outside_box()] = False
    keep &= ~p.mobile | (p.xz[:, 1] < p.xz[~p.mobile, 1].max())
    return Packing(p.xz[keep], p.r[keep], p.group[keep], p.density_factor[keep])


def scene_for(over):
    base = {"scene": {"name": "bench"}, "output": {"snapshot_times": []}}
    for table, fields in TABLE4.items():
        base[table] = dict(fields)
    for table, fields in over.items():
        base.setdefault(table, {}).update(fields)
    return scenes.validate(base)


def timed(setup, steps, warmup):
    """(wall, CPU) microseconds per step of ``steps`` steps after ``warmup``, and the pore rebuilds
    among them; setup() -> (run(n), rebuilds() -> count so far). CPU time (all threads of the
    process) is the less noisy one on a shared machine."""
    run, rebuilds = setup()
    run(warmup)
    n0, t0, c0 = rebuilds(), time.perf_counter(), time.process_time()
    run(steps)
    return 1e6 * (time.perf_counter() - t0) / steps, 1e6 * (time.process_time() - c0) / steps, rebuilds() - n0


def floor_setup(packing):
    """The (run, rebuilds) of ``timed`` for YADE alone on the packing (benchmarks.floor)."""
    native_floor(scene_for({}), packing)
    return run_steps, lambda: 0


def coupling_setup(scene, packing):
    """The (run, rebuilds) of ``timed`` for a YadeCoupling of the scene."""
    cp = YadeCoupling(scene, packing)
    return cp.run, lambda: cp.water_model.n_rebuilds if cp.water_model is not None else 0


def paired_runs(setups, steps, repeats, after=None):
    """The setups {name: setup} of ``timed`` in turns, the order swapped every repeat, nothing else
    between them: ({name: [wall us]}, {name: [CPU us]}, {name: [rebuilds]}), one sample a repeat;
    ``after(name, wall us, CPU us, rebuilds)`` is called after each run."""
    wall, cpu, built = ({k: [] for k in setups} for _ in range(3))
    for rep in range(repeats):
        for name in list(setups)[::1 if rep % 2 == 0 else -1]:
            w, c, b = timed(setups[name], steps, warmup=200)
            wall[name].append(w)
            cpu[name].append(c)
            built[name].append(b)
            if after is not None:
                after(name, w, c, b)
    return wall, cpu, built


def paired_dry(packing, steps, repeats, log):
    """YADE alone against law = "yade" dry (the same discs, the same four engines) in turns
    (``paired_runs``): {"median", "min", "max"} of the CPU ratio within each pair (it should be 1
    within the spread), and the touching pairs YADE counts at the end of its runs
    (O.interactions.countReal)."""
    from yade import O
    setups = {"yade_alone_us": lambda: floor_setup(packing),
              "yade_law_dry_us": lambda: coupling_setup(scene_for(COLUMNS["yade_law_dry_us"]), packing)}
    contacts = []
    _, cpu, _ = paired_runs(setups, steps, repeats,
                            lambda name, *_: contacts.append(O.interactions.countReal()) if name == "yade_alone_us" else None)
    ratio = np.array(cpu["yade_law_dry_us"]) / np.array(cpu["yade_alone_us"])
    log(f"  n = {len(packing.r)} yade law dry / YADE alone, paired: {np.median(ratio):.3f} "
        f"({ratio.min():.3f}-{ratio.max():.3f}), touching pairs {contacts}")
    return {"median": float(np.median(ratio)), "min": float(ratio.min()), "max": float(ratio.max()),
            "samples_cpu_us": cpu, "touching_pairs": contacts}


def bench_size(n, steps, repeats, log):
    packing = settled_packing(n)
    dry_ab = paired_dry(packing, steps, repeats, log)
    setups = {"yade_alone_us": lambda: floor_setup(packing)}
    for name, over in COLUMNS.items():
        setups[name] = (lambda over=over: coupling_setup(scene_for(over), packing))
    wall, cpu, built = ({k: [] for k in setups} for _ in range(3))
    names = list(setups)
    for rep in range(repeats):
        for name in names[rep % len(names):] + names[:rep % len(names)]:  # each column first in turn
            setup = setups[name]
            w, c, b = timed(setup, steps, warmup=200)
            wall[name].append(w)
            cpu[name].append(c)
            built[name].append(b)
            log(f"  n = {len(packing.r)} rep {rep + 1}/{repeats} {name}: {w:.1f} us/step wall, {c:.1f} CPU, "
                f"{b} rebuilds")
    row = {"n_bodies": int(len(packing.r)), "steps": steps, "repeats": repeats}
    row.update({k: float(np.median(v)) for k, v in wall.items()})
    row["cpu_us"] = {k: float(np.median(v)) for k, v in cpu.items()}
    row["rebuilds"] = {k: float(np.median(v)) for k, v in built.items()}
    row["samples_wall_us"], row["samples_cpu_us"] = wall, cpu
    # the ratio to YADE alone within each repeat (its columns run seconds apart), median over repeats:
    # steadier than a ratio of medians when the machine's load drifts
    row["cpu_ratio_paired"] = {k: float(np.median(np.array(v) / np.array(cpu["yade_alone_us"]))) for k, v in cpu.items()}
    row["yade_law_dry_paired_ab"] = dry_ab
    return row


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--sizes", type=int, nargs="+", default=[240, 2000, 10000])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--steps", type=float, default=4.8e6, help="bodies x steps per timed run")
    args = ap.parse_args(argv)
    results = []
    for n in args.sizes:
        steps = int(max(1000, args.steps / n))  # >= 1000: a pore rebuild falls in every run
        results.append(bench_size(n, steps, args.repeats, lambda s: print(s, flush=True)))
        # after each size: a long run stopped keeps the sizes done
        write_json(args.json, {"io_backend": yade_io.BACKEND, "constants": TABLE4, "results": results})
    keys = ["yade_alone_us"] + list(COLUMNS)
    print(f"I/O backend: {yade_io.BACKEND}; us/step (ratio to yade_alone), medians of {args.repeats}; "
          f"one shared machine: noisy")
    for label, get in (("wall", lambda row, k: row[k]), ("CPU", lambda row, k: row["cpu_us"][k])):
        print(f"{label:>4} {'bodies':>7} " + " ".join(f"{k[:-3]:>18}" for k in keys))
        for row in results:
            a = get(row, "yade_alone_us")
            print(f"{'':>4} {row['n_bodies']:7d} " + " ".join(f"{get(row, k):9.1f} ({get(row, k) / a:5.2f})" for k in keys))
    print("CPU ratio to yade_alone within each repeat, median over the repeats:")
    for row in results:
        print(f"{'':>4} {row['n_bodies']:7d} " + " ".join(f"{row['cpu_ratio_paired'][k]:18.2f}" for k in keys))


if __name__ == "__main__":
    main(sys.argv[1:])
