"""Cost of moving body state and forces between YADE and NumPy: the bulk bridge (engines/yade/yadebulk)
against YADE's per-body Python API, at several body counts.

    yade -n -x benchmarks/yade_io.py --json out/bench-yade-io.json [--sizes 240,2000,10000] [--repeats 11]

For each function: microseconds per call through the bulk wrapper, through an @njit function calling
the ctypes function (if numba is there), through the Python API one body at a time (building the
Vector3s from the NumPy array, as a coupling must), and through the Python API's best batch form
where there is one (utils.coordsAndDisplacements for positions; map(O.forces.addF) over prebuilt
Vector3s for forces). All variants are interleaved in every repeat; medians are reported with the
ratio python/bulk, and the bare YADE step (ForceResetter + NewtonIntegrator) on the same bodies.
"""
import argparse
import os
import statistics
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np
from yade import O, Vector3, utils
from yade.wrapper import ForceResetter, NewtonIntegrator

from benchmarks import write_json
from engines.yade import yadebulk


def discs(n, seed=0):
    """n free discs in the x-z plane with random velocities and spins; ids as int64."""
    O.reset()
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n)))
    O.bodies.append([utils.sphere((0.01 * (k % side), 0.0, 0.01 * (k // side)), 0.004) for k in range(n)])
    for b in O.bodies:
        b.state.vel = Vector3(*rng.normal(size=3))
        b.state.angVel = Vector3(*rng.normal(size=3))
    O.engines = [ForceResetter(), NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.81))]
    O.dt = 1e-6
    return np.arange(n, dtype=np.int64)


def njit_callers():
    """{name: @njit (ids, array) -> rc calling the ctypes function}, or {} without numba."""
    try:
        import numba
    except ImportError:
        return {}

    def make(cfn):
        @numba.njit
        def call(ids, arr):
            return cfn(ids.ctypes.data, ids.size, arr.ctypes.data)
        return call
    return {name: make(getattr(yadebulk, "c_" + name)) for name in yadebulk.NAMES}


def variants(ids, nj):
    """{function: {variant: callable()}} on the current scene."""
    n = len(ids)
    idl = ids.tolist()
    rng = np.random.default_rng(1)
    xz, y = np.empty((n, 2)), np.empty(n)
    F, T, V = rng.normal(size=(n, 2)), rng.normal(size=n), 1e-3 * rng.normal(size=(n, 2))
    B, forces = O.bodies, O.forces
    vecs = [Vector3(fx, 0.0, fz) for fx, fz in F.tolist()]

    def py_set_vel():
        for i, (vx, vz) in zip(idl, V.tolist()):
            B[i].state.vel = Vector3(vx, 0.0, vz)

    def py_add_force():
        for i, (fx, fz) in zip(idl, F.tolist()):
            forces.addF(i, Vector3(fx, 0.0, fz))

    def py_set_perm():
        for i, (fx, fz) in zip(idl, F.tolist()):
            forces.setPermF(i, Vector3(fx, 0.0, fz))

    def py_add_torque():
        for i, t in zip(idl, T.tolist()):
            forces.addT(i, Vector3(0.0, t, 0.0))

    cases = {
        "get_pos_xz": (xz, lambda: np.array([(p[0], p[2]) for p in (B[i].state.pos for i in idl)]),
                       lambda: np.column_stack((utils.coordsAndDisplacements(0)[0],
                                                utils.coordsAndDisplacements(2)[0]))),
        "get_vel_xz": (xz, lambda: np.array([(v[0], v[2]) for v in (B[i].state.vel for i in idl)]), None),
        "set_vel_xz": (V, py_set_vel, None),
        "get_angvel_y": (y, lambda: np.array([B[i].state.angVel[1] for i in idl]), None),
        "add_torque_y": (T, py_add_torque, None),
        "add_force_xz": (F, py_add_force, lambda: list(map(forces.addF, idl, vecs))),
        "set_perm_force_xz": (F, py_set_perm, None),
    }
    out = {}
    for name, (arr, python, best) in cases.items():
        bulk = getattr(yadebulk, name)
        out[name] = {"bulk": lambda bulk=bulk, arr=arr: bulk(ids, arr), "python": python}
        if name in nj:
            out[name]["njit"] = lambda call=nj[name], arr=arr: call(ids, arr)
        if best:
            out[name]["python_best"] = best
    return out


def sample(fn, calls):
    t0 = time.perf_counter()
    for _ in range(calls):
        fn()
    return 1e6 * (time.perf_counter() - t0) / calls


def yade_step_us(steps):
    """Microseconds per bare YADE step: O.run(2k) - O.run(k) cancels O.run's fixed wait."""
    t0 = time.perf_counter()
    O.run(steps, True)
    t1 = time.perf_counter()
    O.run(2 * steps, True)
    t2 = time.perf_counter()
    return 1e6 * ((t2 - t1) - (t1 - t0)) / steps


def measure(n, repeats, nj):
    ids = discs(n)
    cases = variants(ids, nj)
    calls = {}
    for name, vs in cases.items():  # warm up (numba compiles) and size each sample to ~2 ms
        for v, fn in vs.items():
            fn()
            calls[name, v] = max(1, int(2e3 / max(sample(fn, 1), 1e-3)))
    times = {key: [] for key in calls}
    steps = max(100, int(2e6 / n))
    step_times = []
    for _ in range(repeats):
        for name, vs in cases.items():
            for v, fn in vs.items():
                times[name, v].append(sample(fn, calls[name, v]))
        step_times.append(yade_step_us(steps))
    functions = {}
    for name, vs in cases.items():
        med = {f"{v}_us": statistics.median(times[name, v]) for v in vs}
        med["python_over_bulk"] = med["python_us"] / med["bulk_us"]
        if "python_best_us" in med:
            med["python_best_over_bulk"] = med["python_best_us"] / med["bulk_us"]
        functions[name] = med
    return {"n_bodies": n, "yade_step_us": statistics.median(step_times), "functions": functions}


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--sizes", default="240,2000,10000")
    ap.add_argument("--repeats", type=int, default=11)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    if not yadebulk.available():
        sys.exit(f"engines.yade.yadebulk is not available: {yadebulk.reason()}")
    probe_ms = 1e3 * (time.perf_counter() - t0)
    nj = njit_callers()
    results = [measure(int(n), args.repeats, nj) for n in args.sizes.split(",")]
    print(f"probe {probe_ms:.0f} ms (once per process); medians of {args.repeats} interleaved repeats, us per call")
    print(f"{'bodies':>7} {'function':>18} {'bulk':>8} {'njit':>8} {'python':>9} {'py best':>9} "
          f"{'py/bulk':>8} {'best/bulk':>9} {'bulk/step':>9}")
    for r in results:
        for name, m in r["functions"].items():
            best = m.get("python_best_us", float("nan"))
            print(f"{r['n_bodies']:>7} {name:>18} {m['bulk_us']:8.1f} {m.get('njit_us', float('nan')):8.1f} "
                  f"{m['python_us']:9.1f} {best:9.1f} {m['python_over_bulk']:8.1f} "
                  f"{m.get('python_best_over_bulk', float('nan')):9.1f} {m['bulk_us'] / r['yade_step_us']:9.2f}")
        print(f"{r['n_bodies']:>7} {'bare YADE step':>18} {r['yade_step_us']:8.1f}")
    out = {"probe_ms": probe_ms, "repeats": args.repeats, "layout": yadebulk.layout(), "results": results}
    write_json(args.json, out)


if __name__ == "__main__":
    main(sys.argv[1:])
