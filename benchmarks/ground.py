"""The 10,000-disc wet ground (yade_scripts/scenes/ground_10000.toml) against YADE alone on its discs.

    yade -n -x benchmarks/ground.py --json out/bench-ground.json [--steps 1000] [--repeats 5]

Our step: the preset as it runs (the paper's law, the water every step, the pores rebuilt every
1000 steps, the box shaken by the cosine; engines.yade.coupling.YadeCoupling). YADE alone: its
collider and linear law on the same discs, radii + eps_m/2, fixed walls, no Python
(benchmarks.floor). The two run in turns (benchmarks.coupling.paired_runs), ``steps`` steps after a
warm-up (a run of 1000 steps holds one pore rebuild, the preset's share). Writes {"n_discs",
"steps", "us_per_step", "yade_alone_us", "ratio", ...}: CPU microseconds a step (medians) and the
ratio of the two within each repeat (median, with its min and max: "ratio_range").
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

from benchmarks import write_json
from benchmarks.coupling import coupling_setup, paired_runs
from benchmarks.floor import native_floor, run_steps
from engines.run import scene as scenes
from engines.yade import yade_io
from packing.packing import Packing

PRESET = "ground_10000"


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    sc = scenes.preset(PRESET)
    pk = Packing.load(sc.packing.file)

    def floor():
        native_floor(sc, pk)
        return run_steps, lambda: 0

    setups = {"yade_alone": floor, "ours": lambda: coupling_setup(sc, pk)}
    wall, cpu, built = paired_runs(setups, args.steps, args.repeats,
                                   lambda name, w, c, b: print(f"{name}: {c:.0f} CPU us/step ({w:.0f} wall), {b} rebuilds",
                                                                  flush=True))
    ratio = np.array(cpu["ours"]) / np.array(cpu["yade_alone"])
    out = {"n_discs": int(pk.mobile.sum()), "n_walls": int((~pk.mobile).sum()), "steps": args.steps,
           "repeats": args.repeats, "us_per_step": float(np.median(cpu["ours"])),
           "yade_alone_us": float(np.median(cpu["yade_alone"])), "ratio": float(np.median(ratio)),
           "ratio_range": [float(ratio.min()), float(ratio.max())],
           "wall_ratio": float(np.median(np.array(wall["ours"]) / np.array(wall["yade_alone"]))),
           "rebuilds_per_run": float(np.median(built["ours"])), "samples_cpu_us": cpu, "samples_wall_us": wall,
           "io_backend": yade_io.BACKEND, "scene": PRESET}
    write_json(args.json, out)
    print(f"{out['n_discs']} discs + {out['n_walls']} walls: ours {out['us_per_step']:.0f} CPU us/step, YADE alone "
          f"{out['yade_alone_us']:.0f}; ratio {out['ratio']:.2f} ({ratio.min():.2f}-{ratio.max():.2f}) over "
          f"{args.repeats} paired repeats -> {args.json}")


if __name__ == "__main__":
    main(sys.argv[1:])
