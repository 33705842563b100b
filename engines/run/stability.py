"""The stability map run (yade_scripts/stability.py): each point of engines.studies.stability's map
for a short window inside YADE against its reference, classified; OUT/map.json and the figure
(postproc.stability).
"""
import os
import time

import numpy as np

from engines import files
from engines.studies import stability as st
from engines.studies.stability import DT_WINDOW, REF_DIVISOR, map_points, resolved


def run_point(sc, packing, window, out_dir):
    """Run ``sc`` for ``window`` seconds; the record of the run, or {"outcome": "refused", "reason"}."""
    from yade import O

    from engines.model.start import Start
    from engines.run.preflight import InputError, preflight
    from engines.yade.coupling import YadeCoupling

    prepared = Start(sc.settings, packing)
    try:
        preflight(sc, packing, out_dir, prepared)
    except InputError as e:
        return {"outcome": "refused", "reason": str(e)}
    box = st.box_of(packing)
    n = int(round(window / sc.numerics.dt))
    every = max(1, n // 50)
    ke, error, xz = [0.0], None, packing.xz
    c0 = time.process_time()
    try:
        cp = YadeCoupling(sc, packing, prepared=prepared)
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


def run_map(out, window_s):
    """Each point of map_points, ``window_s`` simulated seconds (the dt points: DT_WINDOW), against
    its reference (the same setting at dt / REF_DIVISOR; the dt points: the preset at its own dt),
    classified (engines.studies.stability), one line printed per point; writes OUT/map.json and
    OUT/map.png. Returns (the points, the figure's path)."""
    from engines.model.limits import critical_time_step
    from engines.model.pore_dem import disc_masses
    from engines.run import scene as scenes
    from engines.yade.deposition import scene_packing
    from postproc.stability import figure

    points = []
    for case, knob, value, over in map_points():
        sc0 = scenes.preset(case, {"output": {"progress_seconds": 1e9}})
        packing = scene_packing(sc0)
        mass, _ = disc_masses(sc0.settings, packing)
        dt_crit = critical_time_step(mass[packing.mobile], sc0.contact.kn)
        window = DT_WINDOW if knob == "dt/dt_crit" else window_s
        if knob == "dt/dt_crit":
            dt = value * dt_crit
            over = {"numerics": {"dt": dt, "rebuild_interval": max(1, int(round(1e-3 / dt)))}}
        sc = sc0.with_overrides(over)
        rec = run_point(sc, packing, window, out)
        if rec.get("outcome") != "refused":
            ref_sc = sc0 if knob == "dt/dt_crit" else sc.with_overrides(resolved(sc.numerics, REF_DIVISOR))
            ref = run_point(ref_sc, packing, window, out)
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
    files.write_json(os.path.join(out, "map.json"), doc, default=float)
    return points, figure(points, os.path.join(out, "map.png"))
