"""`make biaxial`: seed 003's study (Murakami et al. §3) through the sweep runner.

    /usr/bin/python3 yade_scripts/biaxial_study.py --out out/biaxial [--workers 2] [--scheduler ADDR]
                     [--parts main,calibration,stiffness,discs,rate,dt,stability,hypotheses,judged] [--seeds 1,2,3]
                     [--estimate] [--analyse-only] [--quick]

Runs yade_scripts/biaxial.py jobs (one directory each under OUT/runs/, resumable) with Table 2's
constants (kn = 1e8 Pa/m, ks/kn = 0.25, ρ = 2500, 100 %/min) on the default reading (Δt =
0.45e-4 s, packed with friction nearly off: docs/BIAXIAL.md), every point on 3
packings (seeds), in this order (the judged comparisons first):
    main        φe = 5, 10, 15° × σ3 = 100, 200, 300, 400 Pa to 5 % strain on the paper's
                1000-disc specimen (Table 1) (Fig. 9–12, 15, 19–21)
    calibration target φ*, E50 → φe, kn (eq 5–6) → the biaxial test again (yade_scripts/calibrate.py)
    stiffness   kn ×0.5, ×2 and ks/kn ×0.5, ×2 (Fig. 13–14, 17)     } φe = 10°, σ3 = 200 Pa, to 4 %,
    dt          Δt = 0.25e-4, 0.5e-4, 1e-4 s in the test            } on SMALL_DISCS = 500 discs
                (Fig. 6)                                            } (the budget: docs/BIAXIAL.md)
    discs       125, 250, 500, 1000 discs (Fig. 7–8)                } φe = 10°, σ3 = 200 Pa, to 4 %
    rate        axial strain rate 25, 50, 100 %/min (the paper's three) on 1000 discs (Fig. 5)
    stability   time steps and contact widths at which a packed specimen stays at rest
                (yade_scripts/biaxial_stability.py on the 1000-disc reference packing of the first seed)
    hypotheses  (not in the default) the readings of the paper that may change strength, each against
                the reference on 3 packings, one job per σ3 = 100–400 Pa, 1000 discs, 5 %: rotation
                locked, the side load on every side disc's diameter, the test on the periodic cell,
                a denser packing (φe = 0.5° while packing), the contact width = the diameter; at
                φe = 15° (and 5° for rotation and packing); the size effect (250 against 1000 discs)
                of the block and of the periodic cell -> OUT/hypotheses.json, hypotheses.md
    judged      (not in the default) the judged command (biaxial.py --phi-e P --sigma3 100,200,300) at
                φe = 15° then 5° (and 10°, the middle of f1 for the calibration) on 5 packings (seeds 1–5
                whatever --seeds), means with 95 % intervals beside the paper, and the calibration round
                trip on its curves with E50's conditioning
                -> OUT/judged.json, judged.md, judged_fit.json (calibrate.py --fit), fig_judged.png
then writes into OUT: study.json (every number, the CPU cost), fit.json (the eq 2/4 curves calibrate.py
reads), table.md (side by side with the paper, and the time steps) and the figures
fig05_strain_rate.png, fig06_dt.png, fig08_discs.png, fig09_11_curves.png, fig12_phi_star.png,
fig13_kn.png, fig14_ks.png, fig15_e50_sigma3.png, fig18_sigma3_over_kn.png, fig19_eq4.png,
fig20_21_A_m.png. ``--estimate`` prints the predicted CPU cost of the jobs still to run, and stops.
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.biaxial_study import run_study
from engines.run.preflight import ArgumentParser, announce_output, output_dir
from engines.seeds.biaxial.study import DEFAULT_PARTS, PARTS


def main(argv=None):
    ap = ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=output_dir, required=True, help="output directory (runs in OUT/runs)")
    ap.add_argument("--workers", type=int, default=2, help="local processes (default 2)")
    ap.add_argument("--scheduler", help="Dask scheduler address: run the jobs on that cluster")
    ap.add_argument("--parts", default=",".join(DEFAULT_PARTS),
                    help=f"comma-separated parts of the study, of {', '.join(PARTS)} (default: all but hypotheses)")
    ap.add_argument("--seeds", default="1,2,3", help="packings per point (placement seeds)")
    ap.add_argument("--estimate", action="store_true", help="print the predicted CPU cost of what is to run, and stop")
    ap.add_argument("--analyse-only", action="store_true", help="do not run anything, analyse what is there")
    ap.add_argument("--quick", action="store_true",
                    help="150 discs, 1.5 %% strain, 400 %%/min: checks the pipeline in minutes (numbers meaningless)")
    a = ap.parse_args(argv)
    parts = set(a.parts.split(","))
    unknown = parts - set(PARTS)
    if unknown:
        ap.error(f"--parts: unknown {', '.join(sorted(unknown))}")
    seeds = [int(s) for s in a.seeds.split(",")]
    runs = os.path.join(a.out, "runs")
    if a.analyse_only and not (os.path.isdir(runs) and os.listdir(runs)):
        ap.error(f"--analyse-only: {runs} holds no job to analyse; run the study without --analyse-only first")
    announce_output(a.out)
    table = run_study(a.out, parts, seeds, workers=a.workers, scheduler=a.scheduler, estimate_only=a.estimate,
                      analyse_only=a.analyse_only, quick=a.quick)
    if table is not None:
        print(table)

if __name__ == "__main__":
    main()
