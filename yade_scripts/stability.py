"""The stability map: short runs at the extremes of dt/dt_crit, E_w, k1, k2,
eps_m and f_max; each is refused up front, bounded, or unbounded (engines.studies.stability).

    yade -n -j 1 -x yade_scripts/stability.py --out out/stability [--window 0.003]
    make stability

The water is sub-stepped where a step exceeds the Darcy limit (the default, [water] substep =
true; refused up front beyond [water] max_substeps); two points run the strict mode (substep =
false), which refuses such a step. Quick-sand case 1 (spring c) for every knob, the seismic box (liquefaction case 1, spring d) for
dt/dt_crit too; dt_crit is eq 52's 2 sqrt(m_min / kn). Each point runs --window seconds (10 ms for
the dt points) from the preset's packing; its kinetic energy is compared with its reference: the
same setting at dt / 4 (rebuild period kept), or for the dt points the preset at
its own dt, so that a setting whose physics moves the discs hard (a large E_w under inflow, an
eps_m that the packing was not made with) is not taken for an instability. Writes OUT/map.json {"points": [{case, knob, value,
the overrides, dt, "outcome", "reason", ke_max, ke_ratio, cpu_s, ...}]} and OUT/map.png.
"""
import argparse
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)


def main(argv):
    from engines.run.preflight import ArgumentParser, announce_output, number, output_dir
    from engines.run.stability import run_map
    from postproc.stability import replot

    ap = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=output_dir, required=True)
    ap.add_argument("--window", type=number(lo=0, lo_open=True, unit="s"), default=0.003, help="simulated seconds per point (dt points: 0.01)")
    ap.add_argument("--plot-only", action="store_true", help="redraw OUT/map.png from OUT/map.json")
    a = ap.parse_args(argv)
    if a.plot_only and not os.path.isfile(os.path.join(a.out, "map.json")):
        ap.error(f"--plot-only: {os.path.join(a.out, 'map.json')} not found; run the map without --plot-only first")
    announce_output(a.out)
    os.makedirs(a.out, exist_ok=True)
    if a.plot_only:
        print("figure:", replot(a.out))
        return
    points, path = run_map(a.out, a.window)
    print("figure:", path)
    counts = {o: sum(p["outcome"] == o for p in points) for o in ("bounded", "refused", "unbounded")}
    print(f"{len(points)} points: {counts}")


if __name__ == "__main__":
    main(sys.argv[1:])
