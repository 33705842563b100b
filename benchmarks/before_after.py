"""An older engine (by default commit 26fe280, one Python engine) against today's, on the seismic box,
on this machine.

    git worktree add /tmp/pore-dem-26fe280 26fe280
    yade -n -x benchmarks/before_after.py --old-tree /tmp/pore-dem-26fe280 --json out/bench-before-after.json

This script runs both trees on the same discs (the liquefaction_case1 packing; spring d, Table 4
constants, eps_m = 2e-4 m, the 1500 gal 50 Hz cosine, water every step, dt = 1e-6 s; the old tree
has fixed side walls, today's preset moves them on springs), each in its own `yade` process, in
turns, ``repeats`` times, and writes the CPU microseconds per step (medians) and their ratio: the
speed-up measured on one machine, which carries over where absolute times do not.
"""
import argparse
import json
import os
import subprocess
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))
ROOT = sys.path[0]  # not engines.ROOT: engines is imported from the timed tree only (time_tree)
PACKING = os.path.join(ROOT, "yade_scripts", "scenes", "liquefaction_packing.csv")

from benchmarks import write_json

TABLE4 = {"contact": {"spring": "d", "kn": 1.4e5, "eta_n": 2.6, "ks": 3.5e4, "eta_s": 0.6, "mu": 1.0, "f_max": 1.5,
                      "eps_m": 2e-4},
          "water": {"E_w": 2400.0, "k1": 1e3, "k2": 1e2, "l_m": 3.5e-4},
          "loading": {"type": "cosine", "amplitude": 15.0, "frequency": 50.0},
          "numerics": {"dt": 1e-6, "rebuild_interval": 1000}}
WARMUP = 1100  # steps before the timing: past the first pore rebuild, whose kernels numba loads from its cache


def time_tree(tree, steps):
    """CPU microseconds per step of ``steps`` steps (after WARMUP) in this process, with the engines
    of ``tree``: a tree with the liquefaction_case1 preset runs it, an older one a scene built from
    TABLE4; a tree from before the layered engines/ imports by the old module paths."""
    sys.path.insert(0, tree)
    if os.path.isdir(os.path.join(tree, "engines", "run")):
        from engines.run import scene as scenes
        from engines.yade.coupling import YadeCoupling
    else:
        from engines import scene as scenes
        from engines.yade_coupling import YadeCoupling
    from packing.packing import Packing
    packing = Packing.load(PACKING)
    if os.path.isfile(os.path.join(tree, "yade_scripts", "scenes", "liquefaction_case1.toml")):
        scene = scenes.preset("liquefaction_case1")
    else:
        raw = {"scene": {"name": "before"}, "packing": {"source": "file", "file": PACKING},
               "output": {"snapshot_times": []}}
        raw.update(json.loads(json.dumps(TABLE4)))
        scene = scenes.validate(raw)
    cp = YadeCoupling(scene, packing)
    cp.run(WARMUP)
    c0 = time.process_time()
    cp.run(steps)
    return 1e6 * (time.process_time() - c0) / steps


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old-tree", help="a checkout of the old commit (see above)")
    ap.add_argument("--json")
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--one", help=argparse.SUPPRESS)  # internal: time one tree in this process
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps({"cpu_us": time_tree(args.one, args.steps)}))
        return
    if not (args.old_tree and args.json):
        ap.error("--old-tree and --json are required")
    old = os.path.abspath(args.old_tree)
    if not os.path.isdir(os.path.join(old, "engines")):
        ap.error(f"--old-tree {old}: no engines/ there")
    samples = {"before": [], "after": []}
    for rep in range(args.repeats):
        for name, tree in (("before", old), ("after", ROOT)):
            out = subprocess.run(["yade", "-n", "-x", os.path.abspath(sys.argv[0]), "--one", tree, "--steps", str(args.steps)],
                                 capture_output=True, text=True, check=True).stdout
            us = json.loads(out.strip().splitlines()[-1])["cpu_us"]
            samples[name].append(us)
            print(f"rep {rep + 1}/{args.repeats} {name}: {us:.1f} CPU us/step", flush=True)
    med = {k: sorted(v)[len(v) // 2] for k, v in samples.items()}
    res = {"steps": args.steps, "repeats": args.repeats, "cpu_us": med, "samples_cpu_us": samples,
           "speedup": med["before"] / med["after"], "old_tree": old}
    print(json.dumps(res, indent=1))
    write_json(args.json, res)


if __name__ == "__main__":
    main(sys.argv[1:])
