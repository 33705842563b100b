"""Contact constants for a target model ground (Murakami et al. §3(3)c, eq 5–6), verified.

    /usr/bin/python3 yade_scripts/calibrate.py --phi-star DEG --e50 PA --sigma3 PA --out DIR
                     [--fit out/biaxial_judged/judged_fit.json] [--seeds 1,2,3]
                     [--workers 2] [--scheduler ADDR] [--no-verify]

From the curves a study fitted (judged_fit.json of `biaxial_study.py --parts judged`, shipped as
docs/biaxial/judged_fit.json, or fit.json of `make biaxial`: φ*(φe), A(φe), m(φe) at kn = 1e8 Pa/m, ks/kn = 0.25), eq 5 gives φe for the
target φ* and eq 6 the kn for the target E50 at σ3. It prints both, and, when the fit carries the
scatter between packings (judged_fit.json), how well the --seeds packings can verify E50 and
how well E50 fixes kn (engines.studies.biaxial_judged.conditioning); then runs the biaxial test with them on the --seeds packings at σ3 = 100 and
400 Pa and the target σ3 (through the sweep runner), and prints the φ* and E50 obtained against
the target. Writes OUT/calibration.json and the runs under OUT/runs.
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
from engines.run.biaxial_study import calibrate
from engines.run.preflight import ArgumentParser, announce_output, number, output_dir
from engines.seeds.biaxial.calibration import Calibration


def main(argv=None):
    ap = ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1],
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--phi-star", type=number(float, 0, 90, lo_open=True, unit="deg"), required=True,
                    help="target friction angle of the model ground [deg]")
    ap.add_argument("--e50", type=number(float, 0, lo_open=True, unit="Pa"), required=True,
                    help="target E50 [Pa] at --sigma3")
    ap.add_argument("--sigma3", type=number(float, 0, lo_open=True, unit="Pa"), required=True,
                    help="confining stress of the target E50 [Pa]")
    ap.add_argument("--fit", default="out/biaxial_judged/judged_fit.json",
                    help="the study's curves (biaxial_study.py --parts judged --out out/biaxial_judged writes them)")
    ap.add_argument("--out", type=output_dir, required=True, help="output directory")
    ap.add_argument("--seeds", default="1,2,3", help="packings of the verification")
    ap.add_argument("--workers", type=number(int, 1), default=2, help="local processes (default 2)")
    ap.add_argument("--scheduler", help="Dask scheduler address")
    ap.add_argument("--no-verify", action="store_true", help="only print φe and kn")
    a = ap.parse_args(argv)
    if not os.path.exists(a.fit):
        ap.error(f"--fit {a.fit}: not found: run `/usr/bin/python3 yade_scripts/biaxial_study.py --parts judged "
                 f"--out out/biaxial_judged` first (hours), or give --fit docs/biaxial/judged_fit.json (its fit of "
                 f"docs/biaxial/judged.json)")
    announce_output(a.out)
    try:
        cal = Calibration.load(a.fit)
        phi_e, kn = cal.invert(a.phi_star, a.e50, a.sigma3)
    except ValueError as e:
        ap.error(str(e))
    record = calibrate(cal, (phi_e, kn), (a.phi_star, a.e50, a.sigma3), a.fit, a.out,
                       [int(s) for s in a.seeds.split(",")], workers=a.workers, scheduler=a.scheduler,
                       run_verification=not a.no_verify)
    return 0 if a.no_verify or record.get("verified") else 1

if __name__ == "__main__":
    sys.exit(main())
