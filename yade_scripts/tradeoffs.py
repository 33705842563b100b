"""Speed against accuracy: each numerical knob swept, error against a fine reference.

    make tradeoffs                                   # the study -> out/tradeoffs/ (resumable)
    /usr/bin/python3 yade_scripts/tradeoffs.py study --out out/tradeoffs [--workers 1] [--scheduler ADDR]
    /usr/bin/python3 yade_scripts/tradeoffs.py study --out out/tradeoffs --analyse-only
    make validation                                  # the fast setting on every preset -> out/validation/
    /usr/bin/python3 yade_scripts/tradeoffs.py study --validation --out out/validation [--analyse-only]
    /usr/bin/python3 yade_scripts/tradeoffs.py study --out out/tradeoffs --cases liquefaction_case1 \\
         --knobs reference dt defaults perturbation          # the judged rows only
    yade -n -j 1 -x yade_scripts/tradeoffs.py run --case liquefaction_case1 --window 0.04 \\
         --set numerics.dt=2e-5 --set numerics.rebuild_interval=50 --out out/one   # one setting
    yade -n -j 1 -x yade_scripts/tradeoffs.py speed --points dt=1e-06 defaults=fast --repeats 3 --out out/speed

``run`` (inside YADE) runs one setting of a preset from ``--starts`` perturbed starts
(engines.studies.ensemble.perturbed: start s moves the particles by ``--perturbation`` (default 1e-9 m;
the study gives the seismic case 1e-7 m, CASES) x N(0, 1), seed s; start 0 is the preset's packing)
for ``--window`` seconds and writes OUT/result.json: per start the block pressure, window porosity,
particles' mean height and kinetic energy every ``--record`` seconds, the CPU and wall seconds of
the run (after a warm-up that loads the compiled kernels), the water balance and sub-steps. The
cost leaves out the recording's own time (cpu_record_s). A start refused by preflight or by the
engines is recorded with its message.

``speed`` (inside YADE) measures speed-ups in one process: the settings interleaved, one start
each per repeat, the median CPU ratio to the first (the paper's settings).

``study`` builds the jobs of KNOBS (one per case, knob and value), runs them with the sweep runner
(yade_scripts/sweep.py: resumable, local processes or a Dask scheduler), then computes the
errors (engines.studies.tradeoffs) against each case's reference and writes out/tradeoffs/tradeoffs.json,
table.md and the error-against-cost figures (docs/TRADEOFFS.md explains them). ``study
--validation`` runs the fast setting and the paper's numerics on every preset scene over its whole
duration from 20 starts each and writes OUT/validation.json and validation.md: per scene every
metric's systematic error ± σ and the verdict (every estimate + 2σ within 5 %); a scene whose
verdict is "not resolved" is run again from the starts that would decide it with σ ∝ 1/√n
(``--first-start`` on: every setting of the scene, at most 80 starts), until it is decided or has 80.
"""
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.tradeoffs import measure_speed, run_point, run_study
from engines.studies.tradeoffs import CASES, PERTURBATION, RECORD, STARTS


def parse_set(text):
    from engines.run.command_line import scene_setting
    return scene_setting(text)


def run_main(argv):
    from engines.run.preflight import ArgumentParser, number, output_dir
    ap = ArgumentParser(prog="tradeoffs.py run")
    ap.add_argument("--case", required=True, help="a preset of yade_scripts/scenes (e.g. liquefaction_case1)")
    ap.add_argument("--set", type=parse_set, action="append", default=[], metavar="TABLE.FIELD=VALUE")
    ap.add_argument("--window", type=number(lo=0, lo_open=True, unit="s"), required=True)
    ap.add_argument("--record", type=number(lo=0, lo_open=True, unit="s"), default=RECORD)
    ap.add_argument("--starts", type=number(int, 1), default=STARTS)
    ap.add_argument("--first-start", type=number(int, 0), default=0, help="the seed of the first start")
    ap.add_argument("--perturbation", type=number(lo=0, unit="m"), default=PERTURBATION,
                    help="size of the perturbation of the starts [m] (engines.studies.ensemble.perturbed)")
    ap.add_argument("--out", type=output_dir, required=True)
    a = ap.parse_args(argv)
    over, result = run_point(a.case, a.set, a.window, a.record, a.starts, a.out, a.perturbation, a.first_start)
    print(f"{a.case} {over}: cpu {result['cpu_s']:.1f} s, wall {result['wall_s']:.1f} s, "
          f"{sum(1 for s in result['starts'] if s['status'] == 'ok')}/{a.starts} starts ok")


def speed_main(argv):
    from engines.run.preflight import ArgumentParser, number, output_dir
    ap = ArgumentParser(prog="tradeoffs.py speed")
    ap.add_argument("--case", default="liquefaction_case1", choices=sorted(CASES))
    ap.add_argument("--points", nargs="+", default=["dt=1e-06", "defaults=fast"],
                    help="KNOB=VALUE of the study (VALUE a number or a setting's name); the first is the base")
    ap.add_argument("--repeats", type=number(int, 1), default=3)
    ap.add_argument("--out", type=output_dir, required=True)
    a = ap.parse_args(argv)
    doc = measure_speed(a.case, a.points, a.repeats, a.out)
    for p in a.points:
        print(f"{p}: median {doc['median_cpu_s'][p]:.2f} CPU s, speed-up {doc['speedup'][p]:.1f}")


def study_main(argv):
    from engines.run.preflight import ArgumentParser, announce_output, number, output_dir
    ap = ArgumentParser(prog="tradeoffs.py study")
    ap.add_argument("--out", type=output_dir, required=True)
    ap.add_argument("--workers", type=number(int, 1), default=int(os.environ.get("TRADE_JOBS", "1")),
                    help="local processes at a time (default 1: the study is timed)")
    ap.add_argument("--scheduler", help="Dask scheduler address (timings then come from the workers)")
    ap.add_argument("--cases", nargs="+", choices=sorted(CASES), help="a subset of the cases")
    ap.add_argument("--knobs", nargs="+", help="a subset of the knobs (e.g. reference dt defaults)")
    ap.add_argument("--analyse-only", action="store_true", help="skip the runs, analyse what is there")
    ap.add_argument("--validation", action="store_true",
                    help="the fast setting against the paper's numerics on every preset (cases <scene>_full)")
    a = ap.parse_args(argv)
    runs = os.path.join(a.out, "runs")
    if a.analyse_only and not (os.path.isdir(runs) and os.listdir(runs)):
        ap.error(f"--analyse-only: {runs} holds no job to analyse; run the study without --analyse-only first")
    announce_output(a.out)
    run_study(a.out, workers=a.workers, scheduler=a.scheduler, cases=a.cases, knobs=a.knobs,
              analyse_only=a.analyse_only, validation=a.validation)


def main(argv):
    if argv and argv[0] == "run":
        return run_main(argv[1:])
    if argv and argv[0] == "study":
        return study_main(argv[1:])
    if argv and argv[0] == "speed":
        return speed_main(argv[1:])
    if argv and argv[0] in ("-h", "--help"):
        print(__doc__.strip() + "\n\n`tradeoffs.py run|study|speed --help` lists each command's options.")
        return
    sys.exit("usage: tradeoffs.py run ... | study ... | speed ... (see the docstring)")


if __name__ == "__main__":
    main(sys.argv[1:])
