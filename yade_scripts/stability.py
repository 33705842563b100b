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
import json
import os
import sys
import time

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import numpy as np

QS, LIQ = "quicksand_case1", "liquefaction_case1"
DT_RATIOS = (0.25, 0.5, 0.75, 0.9, 0.99, 1.05)
DT_WINDOW = 0.01
REF_DIVISOR = 4  # a point's reference: the same setting at dt / 4 (the dt points: the preset's dt)


def resolved(num, divisor):
    """Overrides of [numerics] for dt / divisor with the same rebuild period (and water_interval,
    so the water step shrinks with dt)."""
    return {"numerics": {"dt": num.dt / divisor, "rebuild_interval": num.rebuild_interval * divisor}}


def map_points():
    """[(case, knob, value, overrides)]: the knob's value and the scene overrides of each point
    (dt/dt_crit points get their dt from the packing at run time)."""
    pts = [(case, "dt/dt_crit", x, {}) for case in (QS, LIQ) for x in DT_RATIOS]
    pts += [(QS, "E_w", e, {"water": {"E_w": e}}) for e in (24.0, 2.4e3, 2.4e4, 2.4e5, 2.4e6, 2.4e7, 2.4e8)]
    pts += [(QS, "E_w", e, {"water": {"E_w": e}, "numerics": {"dt": 1e-5, "rebuild_interval": 100}})
            for e in (2.4e4, 2.4e5, 2.4e6)]
    pts += [(QS, "k1", k, {"water": {"k1": k}}) for k in (0.0, 1e3, 1e4, 1e5, 1e6, 1e9)]
    pts += [(QS, "k1", 1e6, {"water": {"k1": 1e6, "substep": False}})]  # the strict mode
    pts += [(QS, "k2", k, {"water": {"k2": k}}) for k in (0.0, 1e3, 1e5, 1e6)]
    pts += [(QS, "k2", 1e6, {"water": {"k2": 1e6, "substep": False}})]
    pts += [(QS, "eps_m", e, {"contact": {"eps_m": e}}) for e in (1e-5, 1e-4, 3e-4, 1e-3)]
    pts += [(QS, "f_max", f, {"contact": {"f_max": f}}) for f in (0.01, 0.1, 10.0, 1000.0)]
    return pts


def run_point(sc, packing, window, out_dir):
    """Run ``sc`` for ``window`` seconds; the record of the run, or {"outcome": "refused", "reason"}."""
    from yade import O

    from engines.run.preflight import InputError, preflight
    from engines.studies import stability as st
    from engines.yade.coupling import YadeCoupling

    try:
        preflight(sc, packing, out_dir)
    except InputError as e:
        return {"outcome": "refused", "reason": str(e)}
    box = st.box_of(packing)
    n = int(round(window / sc.numerics.dt))
    every = max(1, n // 50)
    ke, error, xz = [0.0], None, packing.xz
    c0 = time.process_time()
    try:
        cp = YadeCoupling(sc, packing)
        while O.iter < n:
            cp.run(min(every, n - O.iter))
            xz = cp.positions()
            ke.append(cp.kinetic_energy())
            if not np.all(np.isfinite(xz)) or st.escaped(xz[packing.mobile], box):
                break
        w, wm = cp.water, cp.water_model
        balance = w.balance_error() if w else 0.0
        sub = wm.substeps_max if wm else 0
    except (ValueError, FloatingPointError, ZeroDivisionError) as e:
        error, balance, sub = f"{type(e).__name__}: {e}", np.nan, 0
    return {"ke_max": float(np.nanmax(ke)), "finite": bool(np.all(np.isfinite(xz))), "steps": int(O.iter),
            "escaped": st.escaped(xz[packing.mobile], box), "balance_error": float(balance), "error": error,
            "substeps_max": int(sub), "cpu_s": time.process_time() - c0}


def main(argv):
    from engines.model.limits import critical_time_step
    from engines.model.pore_dem import disc_masses
    from engines.run import scene as scenes
    from engines.run.preflight import output_dir
    from engines.studies import stability as st
    from engines.yade.deposition import scene_packing

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=output_dir, default=os.path.join("out", "stability"))
    ap.add_argument("--window", type=float, default=0.003, help="simulated seconds per point (dt points: 0.01)")
    ap.add_argument("--plot-only", action="store_true", help="redraw OUT/map.png from OUT/map.json")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    if a.plot_only:
        with open(os.path.join(a.out, "map.json")) as f:
            print("figure:", figure(json.load(f)["points"], os.path.join(a.out, "map.png")))
        return
    points = []
    for case, knob, value, over in map_points():
        sc0 = scenes.preset(case, {"output": {"progress_seconds": 1e9}})
        packing = scene_packing(sc0)
        mass, _ = disc_masses(sc0, packing)
        dt_crit = critical_time_step(mass[packing.mobile], sc0.contact.kn)
        window = DT_WINDOW if knob == "dt/dt_crit" else a.window
        if knob == "dt/dt_crit":
            dt = value * dt_crit
            over = {"numerics": {"dt": dt, "rebuild_interval": max(1, int(round(1e-3 / dt)))}}
        sc = sc0.with_overrides(over)
        rec = run_point(sc, packing, window, a.out)
        if rec.get("outcome") != "refused":
            ref_sc = sc0 if knob == "dt/dt_crit" else sc.with_overrides(resolved(sc.numerics, REF_DIVISOR))
            ref = run_point(ref_sc, packing, window, a.out)
            rec["reference"] = {"dt": ref_sc.numerics.dt, **{k: ref.get(k) for k in ("ke_max", "error", "outcome", "reason")}}
            ke_ref = ref.get("ke_max", np.nan)
            rec["ke_ratio"] = rec["ke_max"] / ke_ref if ke_ref and ke_ref > 0 else np.nan
            rec["outcome"], rec["reason"] = st.classify(rec["ke_max"], ke_ref, st.energy_scale(mass, packing, sc.material.g),
                                                        rec["finite"], rec["escaped"], rec["balance_error"], rec["error"])
        point = {"case": case, "knob": knob, "value": value, "dt": sc.numerics.dt, "dt_over_dt_crit": sc.numerics.dt / dt_crit,
                 "window_s": window, "overrides": over, **rec}
        points.append(point)
        print(f"{case} {knob} = {value:g}: {point['outcome']} {point['reason'][:150]} (ke ratio "
              f"{point.get('ke_ratio', np.nan):.3g}, reference {(point.get('reference', {}).get('reason') or '')[:80]})", flush=True)
    doc = {"points": points, "reference_divisor": REF_DIVISOR,
           "criteria": {"ke_factor": st.KE_FACTOR, "ke_slack": st.KE_SLACK, "escape_radii": st.ESCAPE_RADII,
                        "balance_tol": st.BALANCE_TOL}}
    with open(os.path.join(a.out, "map.json"), "w") as f:
        json.dump(doc, f, indent=1, default=float)
    print("figure:", figure(points, os.path.join(a.out, "map.png")))
    counts = {o: sum(p["outcome"] == o for p in points) for o in ("bounded", "refused", "unbounded")}
    print(f"{len(points)} points: {counts}")


COLORS = {"bounded": "tab:green", "refused": "tab:orange", "unbounded": "tab:red"}
MARKERS = {QS: "o", LIQ: "s"}


def figure(points, path):
    """One panel per knob: the peak kinetic energy over its reference's (log), coloured by outcome;
    refused points drawn on the panel's top edge."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    knobs = list(dict.fromkeys(p["knob"] for p in points))
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5))
    for ax, knob in zip(axes.flat, knobs):
        sel = [p for p in points if p["knob"] == knob]
        ratios = [p.get("ke_ratio", np.nan) for p in sel if p["outcome"] != "refused"]
        top = max([r for r in ratios if np.isfinite(r)] + [10.0]) * 5
        for p in sel:
            x = max(p["value"], 1e-1 if knob in ("k1", "k2") else 0) if knob != "dt/dt_crit" else p["value"]
            y = top if p["outcome"] == "refused" else p.get("ke_ratio", np.nan)
            if not np.isfinite(y):
                y = top / 2
            ax.scatter(x, y, c=COLORS[p["outcome"]], marker=MARKERS[p["case"]], s=55, edgecolors="k", linewidths=0.5,
                       zorder=3)
            if p["overrides"].get("water", {}).get("substep") is False:
                ax.annotate("substep = false", (x, y), fontsize=7, xytext=(-30, -12), textcoords="offset points")
            elif "max_substeps" in p.get("reason", ""):
                ax.annotate("> max_substeps", (x, y), fontsize=7, xytext=(-50, -24), textcoords="offset points")
            elif p.get("substeps_max", 0) > 1:
                ax.annotate(f"{p['substeps_max']} sub-steps", (x, y), fontsize=7, xytext=(-20, -14), textcoords="offset points")
            if p["overrides"].get("numerics", {}).get("dt") == 1e-5 and knob == "E_w":
                ax.annotate("dt 1e-5", (x, y), fontsize=7, xytext=(4, 4), textcoords="offset points")
        ax.axhline(10, color="0.5", ls=":", lw=0.8)
        ax.set_yscale("log")
        if knob != "dt/dt_crit":
            ax.set_xscale("log")
        ax.set_xlabel({"dt/dt_crit": "dt / dt_crit (eq 52)", "E_w": "E_w [N/m]", "k1": "k1 [1/s] (0 drawn at 0.1)",
                       "k2": "k2 [1/s] (0 drawn at 0.1)", "eps_m": "eps_m [m]", "f_max": "f_max [N]"}[knob])
        ax.set_ylabel("peak kinetic energy / reference's")
        ax.set_title(knob + " (refused: top edge)", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes.flat[len(knobs):]:
        ax.axis("off")
    handles = [plt.Line2D([], [], ls="", marker="o", color=c, mec="k", label=o) for o, c in COLORS.items()]
    handles += [plt.Line2D([], [], ls="", marker=m, color="w", mec="k", label=c) for c, m in MARKERS.items()]
    handles += [plt.Line2D([], [], ls=":", color="0.5", label="bound: 10x the reference's (dt / 4; dt points: the preset)")]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=9)
    fig.suptitle("Stability map: short runs at the extremes (quick-sand case 1; dt also on the seismic box)")
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


if __name__ == "__main__":
    main(sys.argv[1:])
