"""The re-meshing transfers measured on the four examples as ensembles of perturbed starts
(docs/ENGINE.md, "Which transfer is the default": the decision rule, written before the runs).

    yade -n -x benchmarks/remesh_transfer.py --json docs/engine/remesh_transfer.json [--starts 8]

Each run is one example of yade_scripts/examples/ (its own steps and settings) in a YADE process of
its own, with WaterSettings transfer set to "paper" or "conserving" and, for start k > 0, its
grains moved by PERTURBATION x the grains' median radius times a standard normal in x and z
(numpy's Generator(k); start 0 is the example as it is) before the example's first O.run (its dry
settling: moved at the engine's construction, a settled FrictMat bed was thrown apart and the
accuracy watch stopped the run), or at the engine's construction where there is none. Per run:
|re-meshing change| / inflow (WaterBalance.remesh_excess_change, all of it, as the examples'
checks print it) and the heave time [s] (from the engine's construction to the first water step at
which the bed top, max z + r over the grains, stands one median radius above its value then;
None when it never does). The runs done are kept in the JSON after each one: a second call goes
on with those missing (resumable). The JSON's "summary" holds, per example and transfer, the
statistics over the starts (engines.studies.ensemble.statistics: mean and 95 % interval) and
"decision" the rule's verdict.
"""
import argparse
import builtins
import dataclasses
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened)
# isort: split
import numpy as np

from benchmarks import write_json
from engines import ROOT

EXAMPLES = ("frictmat_box", "viscel_column", "makecloud_discs", "aabb_box")
TRANSFERS = ("paper", "conserving")
PERTURBATION = 0.02  # of the grains' median radius
QUANTITIES = ("remesh_over_inflow", "heave_time")


def one(example, transfer, start, out):
    """Run ``example`` with ``transfer`` from ``start`` in this YADE process; its numbers to ``out``."""
    from yade import O
    from yade.wrapper import Omega

    from engines.yade import water_engine
    made, perturbed = [], [start == 0]

    def perturb(ids):
        """Move the grains ``ids`` of start k > 0, once: before the example's first O.run (its dry
        settling), or at the engine's construction where it has none."""
        if perturbed[0]:
            return
        perturbed[0] = True
        r = np.array([O.bodies[i].shape.radius for i in ids])
        rng = np.random.default_rng(start)
        for i in ids:
            p = O.bodies[i].state.pos
            dx, dz = PERTURBATION * np.median(r) * rng.standard_normal(2)
            O.bodies[i].state.pos = (p[0] + dx, p[1], p[2] + dz)

    run = Omega.run

    def first_run(self, *args, **kw):
        perturb([b.id for b in O.bodies if b is not None and b.dynamic and type(b.shape).__name__ == "Sphere"])
        return run(self, *args, **kw)

    Omega.run = first_run

    class Measured(water_engine.WaterEngine):
        """The example's WaterEngine with the study's transfer, start and heave clock."""

        def __init__(self, disc_ids, walls, settings, *args, **kw):
            grains = [i for i in disc_ids if O.bodies[i].dynamic]
            r = np.array([O.bodies[i].shape.radius for i in grains])
            perturb(grains)
            super().__init__(disc_ids, walls, dataclasses.replace(settings, transfer=transfer), *args, **kw)
            self.rise, self.t0, self.heave = float(np.median(r)), O.time, None
            self.top0 = self.top()
            made.append(self)

        def top(self):
            """The bed top [m]: max z + r over the dynamic discs."""
            return float(np.max(self.io.positions()[self._dynamic, 1] + self.model.r[self._dynamic]))

        def __call__(self):
            super().__call__()
            if self.heave is None and self.top() - self.top0 >= self.rise:
                self.heave = O.time - self.t0

    water_engine.WaterEngine = Measured
    sys.argv = [example]
    t0 = time.process_time()
    path = os.path.join(ROOT, "yade_scripts", "examples", example + ".py")
    # as `yade -x` runs a script: YADE's engine labels set attributes of the module __builtins__
    exec(compile(open(path).read(), path, "exec"), {"__name__": "__main__", "__file__": path, "__builtins__": builtins})
    water = made[-1]
    b, w = water.model.water.balance, water.model.water
    write_json(out, {"example": example, "transfer": transfer, "start": start,
                     "remesh_over_inflow": abs(b.remesh_excess_change) / max(b.inflow, 1e-300),
                     "heave_time": water.heave, "rebuilds": water.model.n_rebuilds, "balance_error": w.balance_error(),
                     "max_U_over_E_w": float(water.pressures().max() / w.settings.E_w), "steps": int(O.iter),
                     "cpu_s": time.process_time() - t0})


def _stats(values):
    """engines.studies.ensemble.statistics of values (starts,), None for a missing (NaN) entry."""
    from engines.studies.ensemble import statistics
    return {k: (float(v) if np.isfinite(v) else None) for k, v in statistics(np.array(values, float)).items()}


def summary(runs, starts):
    """({example: {transfer: {quantity: statistics, "starts": n}, "winner": transfer or None}}, the
    rule's decision) over the runs of starts 0 ... starts - 1."""
    out, wins = {}, {t: 0 for t in TRANSFERS}
    for example in EXAMPLES:
        out[example] = {}
        for transfer in TRANSFERS:
            got = [r for r in runs if r["example"] == example and r["transfer"] == transfer and r["start"] < starts]
            out[example][transfer] = {q: _stats([np.nan if r[q] is None else r[q] for r in got]) for q in QUANTITIES}
            out[example][transfer]["starts"] = len(got)
        a, c = (out[example][t]["remesh_over_inflow"] for t in TRANSFERS)
        apart = None not in (a["ci95_low"], a["ci95_high"], c["ci95_low"], c["ci95_high"]) and (
            a["ci95_high"] < c["ci95_low"] or c["ci95_high"] < a["ci95_low"])
        winner = (TRANSFERS[0] if a["mean"] < c["mean"] else TRANSFERS[1]) if apart else None
        out[example]["winner"] = winner
        if winner:
            wins[winner] += 1
    default = max(TRANSFERS, key=wins.get) if wins["paper"] != wins["conserving"] else "conserving"
    return out, {"wins": wins, "default": default,
                 "rule": "per example the transfer with the smaller mean |re-meshing change| / inflow wins when the two "
                         "95 % intervals do not overlap; the default is the transfer that wins on more examples; a tie "
                         "(overlaps included) goes to conserving"}


def table(path):
    """ENGINE.md's table of the study in the JSON ``path``: each number with its marker (tests/test_doc_numbers.py)."""
    doc = json.load(open(path))

    def cell(example, transfer, q, scale=1.0):
        keys = f"summary/{example}/{transfer}/{q}"
        st = doc["summary"][example][transfer][q]
        if st["mean"] is None:
            return "none"
        num = [f"{st[k] * scale:.3g}<!--json:{path}#{keys}/{k}{'' if scale == 1 else f'*{scale:g}'}-->"
               for k in ("mean", "ci95_low", "ci95_high") if st[k] is not None]
        n = f" (n = {st['n']:.0f}<!--json:{path}#{keys}/n-->)" if q == "heave_time" else ""
        return num[0] + (f" [{num[1]}, {num[2]}]" if len(num) == 3 else "") + n

    lines = ["| example | starts | `\"paper\"`: re-meshing / inflow | `\"conserving\"`: re-meshing / inflow | wins | "
             "heave time [ms], `\"paper\"` | `\"conserving\"` |", "|---|---|---|---|---|---|---|"]
    for e in EXAMPLES:
        n = doc["summary"][e]["paper"]["starts"]
        lines.append(f"| `{e}.py` | {n}<!--json:{path}#summary/{e}/paper/starts--> | "
                     f"{cell(e, 'paper', 'remesh_over_inflow')} | {cell(e, 'conserving', 'remesh_over_inflow')} | "
                     f"{doc['summary'][e]['winner'] or 'overlap'} | {cell(e, 'paper', 'heave_time', 1000.0)} | "
                     f"{cell(e, 'conserving', 'heave_time', 1000.0)} |")
    return "\n".join(lines)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", required=True)
    ap.add_argument("--starts", type=int, default=8)
    ap.add_argument("--examples", nargs="+", default=list(EXAMPLES), choices=EXAMPLES)
    ap.add_argument("--table", action="store_true", help="print ENGINE.md's table of the JSON and stop")
    ap.add_argument("--one", nargs=4, metavar=("EXAMPLE", "TRANSFER", "START", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        example, transfer, start, out = args.one
        return one(example, transfer, int(start), out)
    if args.table:
        return print(table(args.json))
    runs = json.load(open(args.json))["runs"] if os.path.exists(args.json) else []
    done = {(r["example"], r["transfer"], r["start"]) for r in runs}
    todo = [(e, t, s) for s in range(args.starts) for e in args.examples for t in TRANSFERS if (e, t, s) not in done]
    for e, t, s in todo:
        tmp = f"{args.json}.run.json"
        p = subprocess.run(["yade", "-n", "-x", os.path.join(ROOT, "benchmarks", "remesh_transfer.py"), "--json",
                            args.json, "--one", e, t, str(s), tmp], capture_output=True, text=True)
        if p.returncode != 0 or not os.path.exists(tmp):
            print(f"{e} {t} start {s}: failed (exit {p.returncode}): {(p.stderr.strip().splitlines() or [''])[-1]}",
                  flush=True)
            continue
        runs.append(json.load(open(tmp)))
        os.remove(tmp)
        r = runs[-1]
        print(f"{e} {t} start {s}: re-meshing {r['remesh_over_inflow']:.3g} of the inflow, heave "
              f"{r['heave_time']}, max U/E_w {r['max_U_over_E_w']:.3g}, balance {r['balance_error']:.1e}, "
              f"{r['cpu_s']:.0f} CPU s", flush=True)
        per_example, decision = summary(runs, args.starts)
        write_json(args.json, {"what": __doc__.strip().splitlines()[0], "perturbation": PERTURBATION,
                               "starts": args.starts, "summary": per_example, "decision": decision, "runs": runs})


if __name__ == "__main__":
    main(sys.argv[1:])
