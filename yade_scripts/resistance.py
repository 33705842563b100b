"""The liquefaction resistance curve of the seismic box (issue 42 item 3; engines/studies/resistance.py).

    make resistance                                   # -> out/resistance/, docs/resistance/ (resumable)
    make resistance SHORT=1                           # a few milliseconds: the pipeline end to end
    /usr/bin/python3 yade_scripts/resistance.py --out out/resistance [--starts 8] [--amplitudes 15 30 ...]
         [--workers 2] [--scheduler ADDR] [--docs docs/resistance] [--pilot] [--short] [--analyse-only]
         [--ground out/resistance-ground]
    make resistance-ground                            # the 10,000-disc ground, one run of 30 cycles (~1 h)

Seismic case 1's saturated undrained box under its 50 Hz cosine at 5 amplitudes (1500 gal x
sqrt(2)^k, k = -2..2), each an ensemble of 8 perturbed starts run for 30 cycles, on the preset's
(loose) packing and on one deposited with mu = 0 (dense), through the sweep runner (local or Dask;
a re-run skips the finished ensembles). Writes OUT/resistance.json (per amplitude and packing: N_L
or censored with its interval, CSR, the simplified CSR, the void ratio, n starts) and
OUT/resistance.png (CSR against N_L, log axis).
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.preflight import ArgumentParser, number
from engines.run.resistance import Plan, run_study, short_plan


def main(argv):
    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="study folder")
    ap.add_argument("--starts", type=number(int, 1), help="starts per ensemble (default 8; --short: 2)")
    ap.add_argument("--amplitudes", type=number(float, 0, lo_open=True, unit="m/s^2"), nargs="+",
                    help="base accelerations [m/s^2] (default: 15 x sqrt(2)^k, k = -2..2)")
    ap.add_argument("--short", action="store_true", help="milliseconds runs: the pipeline only")
    ap.add_argument("--pilot", action="store_true", help="mark the JSON and figure as a pilot")
    ap.add_argument("--docs", help="also write resistance.json and resistance.png into this folder")
    ap.add_argument("--workers", type=number(int, 1), default=1, help="jobs at a time")
    ap.add_argument("--scheduler", help="a Dask scheduler's address (tcp://HOST:PORT)")
    ap.add_argument("--analyse-only", action="store_true", help="the JSON and figure from the runs done, no runs")
    ap.add_argument("--ground", help="a completed run of the 10,000-disc ground (make resistance-ground) to read "
                                     "beside the curve, as an illustration")
    a = ap.parse_args(argv)
    if a.analyse_only and not os.path.isdir(os.path.join(a.out, "runs")):
        ap.error(f"--analyse-only: {os.path.join(a.out, 'runs')} holds no runs of the study (run it first, "
                 "without --analyse-only: make resistance)")
    plan = short_plan() if a.short else Plan()
    plan = Plan(tuple(a.amplitudes or plan.amplitudes), a.starts or plan.starts, plan.duration, plan.deposit, a.pilot)
    try:
        doc = run_study(os.path.abspath(a.out), plan, a.workers, a.scheduler, a.analyse_only, a.docs, a.ground)
    except ValueError as e:
        ap.error(str(e))
    n = sum(len(p["rows"]) for p in doc["packings"].values())
    print(os.path.join(a.out, "resistance.json"), f"({n} rows)", os.path.join(a.out, "resistance.png"))


if __name__ == "__main__":
    main(sys.argv[1:])
