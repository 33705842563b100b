"""Cross-check of the YADE path (engines.yade_coupling) against the NumPy reference (engines.reference).

Run:  yade -n -x yade_scripts/crosscheck.py --out DIR   -> DIR/crosscheck.json, exit 1 if a case fails.
Importable headless: ``run_cases(yade_simulate, ref_simulate, cases)`` and ``precision_study`` take the
two ``simulate(scene, packing, n_steps, record_every) -> Trajectory`` functions as arguments.

Cases (every tolerance is stated with its reason in the case's ``why``):
  head_on_collision        two equal discs, linear spring-dashpot, g = 0: restitution vs analytic
  head_on_adjusted         the same with the separation adjustment: -Vn''/Vn = e (pattern d, eq 24)
  pressed_release_a..d     a disc pressed into a fixed wall disc and released, per spring of Fig. 5
  quicksand_column         the quick-sand preset with inflow, 2,000 steps
  shaken_column            the same column saturated, box shaken by a cosine, no inflow, 2,000 steps
and the precision study: the reference runs quicksand_column in float32, float64 and longdouble.
"""
import argparse
import json
import os
import sys
import time
from dataclasses import dataclass

import numpy as np

# under `yade -x` the script runs in YADE's globals, where __file__ is /usr/bin/yade
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

from engines import scene as sc  # noqa: E402
from engines.reference import simulate_reference  # noqa: E402
from packing.packing import Packing  # noqa: E402

R = 0.45e-3            # disc radius of the contact cases [m]
TINY = 1e-30
ROUNDOFF_WHY = ("float64 against float64: the two paths differ only in the order of operations "
                "(YADE's v += dt (F/m + g), bincount vs add.at, the telescoped vs per-arc eq 33), ~1e-16 "
                "relative per operation")


@dataclass
class Case:
    """One cross-check: ``build()`` -> (scene, packing); ``analyze(traj_yade, traj_ref, scene, packing)``
    -> metrics; every metric named in ``tolerances`` must be finite and <= its tolerance."""

    name: str
    build: object
    n_steps: int
    record_every: int
    tolerances: dict
    why: str
    analyze: object
    perturb: bool = False   # also run the reference from x_0 + 1e-12 r to measure round-off amplification


# -- metrics ------------------------------------------------------------------------------------------
def trajectory_diffs(ty, tr, mean_r):
    """max |x_y - x_r| / mean radius, max |dU_block| / max |U_block_ref|, max |dW| / W_ref(0)."""
    t_y, x_y, U_y, W_y, _ = ty.arrays()
    t_r, x_r, U_r, W_r, _ = tr.arrays()
    if x_y.shape != x_r.shape or not np.array_equal(t_y, t_r):
        raise ValueError(f"trajectories differ in sampling: {x_y.shape} at t {t_y[:2]}.. vs {x_r.shape} at {t_r[:2]}..")
    out = {"max_position_diff_rel": float(np.max(np.abs(x_y - x_r)) / mean_r)}
    if U_r.size and not np.all(np.isnan(U_r)):
        if not np.array_equal(np.isnan(U_y), np.isnan(U_r)):
            out["pressure_rel_diff"] = float("inf")  # a block is empty in one path only
        else:
            out["pressure_rel_diff"] = float(np.nanmax(np.abs(U_y - U_r)) / max(np.nanmax(np.abs(U_r)), TINY))
        out["water_rel_diff"] = float(np.max(np.abs(W_y - W_r)) / W_r[0])
    return out


def velocities(traj, disc):
    """Velocity of ``disc`` along x between consecutive samples [m/s] and the sample midpoints."""
    t, x, *_ = traj.arrays()
    return np.diff(x[:, disc, 0]) / np.diff(t)


def restitution(traj):
    """e = (v_B' - v_A') / (v_A - v_B) of the launcher case: v_A from the last sample interval in free
    flight before A touches B (velocities are exactly constant there: g = 0, no contact), the primed
    ones from the last interval of the run (apart again)."""
    t, x, *_ = traj.arrays()
    gap_wall = x[:, 1, 0] - x[:, 0, 0] - 2 * R
    gap_ab = x[:, 2, 0] - x[:, 1, 0] - 2 * R
    free = (gap_wall[:-1] > 0) & (gap_ab[:-1] > 0) & (gap_ab[1:] > 0) & (gap_wall[1:] > 0)
    before = np.flatnonzero(free & (np.cumsum(gap_ab < 0)[:-1] == 0))
    if not len(before) or not free[-1]:
        raise ValueError("no free flight before or after the A-B collision in the record")
    vA, vB = velocities(traj, 1), velocities(traj, 2)
    k = before[-1]
    return float((vB[-1] - vA[-1]) / (vA[k] - vB[k]))


def analytic_restitution(scene, mass):
    """exp(-zeta pi / sqrt(1 - zeta^2)), zeta = eta_n / (2 sqrt(m_eff kn)), m_eff = m/2."""
    c = scene.contact
    zeta = c.eta_n / (2 * np.sqrt(mass / 2 * c.kn))
    return float(np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))), float(zeta), float(np.sqrt(c.kn / (mass / 2)))


# -- contact cases ------------------------------------------------------------------------------------
def contact_scene(name, **contact):
    dt = contact.pop("dt", 1e-7)
    return sc.validate({"scene": {"name": name}, "material": {"g": 0.0}, "water": {"enabled": False},
                        "contact": {"separation_adjustment": False, **contact}, "numerics": {"dt": dt}})


def launcher_packing(overlap=1e-5, gap=2e-5):
    """A fixed wall disc, disc A pressed into it by ``overlap`` [m] (at x = 0), disc B at rest ``gap``
    [m] ahead: the wall launches A, which hits B head-on."""
    xz = np.array([[overlap - 2 * R, 0.0], [0.0, 0.0], [2 * R + gap, 0.0]])
    return Packing(xz, np.full(3, R), np.array([2, 0, 0]), np.ones(3))


def collision_case(adjust):
    name = "head_on_adjusted" if adjust else "head_on_collision"
    scene = contact_scene(name, spring="a", separation_adjustment=adjust)
    mass = scene.material.rho * np.pi * R**2
    e_exact, zeta, omega_n = analytic_restitution(scene, mass)
    if adjust:
        e_exact = scene.contact.restitution
        tol_e, why_e = 1e-8, ("the adjustment sets -Vn''/Vn = e exactly on v = du/dt, whose round-off is "
                              "ulp(x)/dt ~ 1e-12 m/s against Vn ~ 0.1 m/s")
    else:
        tol_e = 4 * zeta * omega_n * scene.numerics.dt
        why_e = (f"4 zeta omega_n dt = {tol_e:.1e}: first touch and separation fall inside a step, each "
                 "worth up to one step of dashpot impulse (relative 2 zeta omega_n dt; first order)")

    def analyze(ty, tr, scene, pk):
        m = trajectory_diffs(ty, tr, R)
        e_y, e_r = restitution(ty), restitution(tr)
        m.update(restitution_yade=e_y, restitution_ref=e_r, restitution_analytic=e_exact,
                 restitution_error_yade=abs(e_y - e_exact), restitution_error_ref=abs(e_r - e_exact),
                 restitution_diff=abs(e_y - e_r))
        return m

    return Case(name, lambda: (scene, launcher_packing()), 2500, 50,
                {"max_position_diff_rel": 1e-9, "restitution_diff": 1e-9,
                 "restitution_error_yade": tol_e, "restitution_error_ref": tol_e},
                f"restitution: {why_e}. Between the paths 1e-9: a smooth two-body motion accumulates "
                f"~n_steps x 1e-16 of {ROUNDOFF_WHY}", analyze)


def pressed_case(spring):
    """A disc pressed by delta0 = 2 f_max/kn into a fixed wall disc, released at rest (eta = 0)."""
    eps_m = 2e-5 if spring == "b" else 0.0
    scene = contact_scene(f"pressed_{spring}", spring=spring, eta_n=0.0, eps_m=eps_m, dt=2e-7)
    kn, f_max, dt = scene.contact.kn, scene.contact.f_max, scene.numerics.dt
    delta0 = 2 * f_max / kn
    pk = Packing(np.array([[delta0 - 2 * R - eps_m, 0.0], [0.0, 0.0]]), np.full(2, R), np.array([2, 0]), np.ones(2))
    mass = scene.material.rho * np.pi * R**2
    energy = {"a": kn * delta0**2 / 2, "b": kn * delta0**2 / 2, "c": f_max * delta0 - f_max**2 / (2 * kn),
              "d": f_max**2 / (2 * kn)}[spring]
    v_exact = np.sqrt(2 * energy / mass)

    def force_path(traj):
        """max |m x'' - F(delta)| / f_max along the release, F of the spring (module docstring of
        engines.contact), and the overlap where the force first vanished."""
        t, x, *_ = traj.arrays()
        xs = np.concatenate([pk.xz[1:2, 0], x[:, 1, 0]])
        force = mass * np.diff(xs, 2) / dt**2          # the force of step k = 1, 2, ...
        delta = 2 * R + eps_m - (xs[1:-1] - pk.xz[0, 0])
        expected = {"a": kn * delta, "b": kn * delta, "c": np.minimum(kn * delta, f_max),
                    "d": np.maximum(f_max - kn * (delta0 - delta), 0.0)}[spring]
        expected = np.where(delta >= 0, expected, 0.0)
        vanished = delta[np.flatnonzero(force <= 0)[0]]
        return float(np.max(np.abs(force - expected)) / f_max), float(vanished)

    def analyze(ty, tr, scene, pk_):
        m = trajectory_diffs(ty, tr, R)
        for tag, traj in (("yade", ty), ("ref", tr)):
            v = velocities(traj, 1)[-1]
            path, vanished = force_path(traj)
            m[f"exit_speed_{tag}"] = float(v)
            m[f"exit_speed_error_{tag}"] = float(abs(v - v_exact) / v_exact)
            m[f"force_path_error_{tag}"] = path
            if spring == "d":
                m[f"residual_overlap_{tag}"] = vanished
                m[f"residual_overlap_error_{tag}"] = float(abs(vanished - (delta0 - f_max / kn)) / (v_exact * dt))
        m["exit_speed_analytic"] = float(v_exact)
        return m

    tol = {"max_position_diff_rel": 1e-9, "exit_speed_error_yade": 1e-4, "exit_speed_error_ref": 1e-4,
           "force_path_error_yade": 1e-6, "force_path_error_ref": 1e-6}
    if spring == "d":
        tol.update(residual_overlap_error_yade=1.0, residual_overlap_error_ref=1.0)
    return Case(f"pressed_release_{spring}", lambda: (scene, pk), 450, 1, tol,
                "force path from second differences of positions, 1e-6 f_max (x round-off ~1e-21 m "
                "against a dt^2 ~ 6e-11 m); exit speed 1e-4 relative (the force is ~0 when contact ends: "
                "second order, (omega dt)^2 ~ 3e-5); residual overlap of d within one step of travel "
                f"(metric in units of v dt); between the paths 1e-9: {ROUNDOFF_WHY}", analyze)


def contact_cases():
    return [collision_case(False), collision_case(True)] + [pressed_case(s) for s in "abcd"]


# -- column cases ---------------------------------------------------------------------------------------
def quicksand_build(**overrides):
    """The quicksand_case1 preset (with ``overrides``) and its packing (packing.deposition.scene_packing)."""
    def build():
        try:
            from packing.deposition import scene_packing
        except ImportError as e:
            raise RuntimeError(f"missing prerequisite packing.deposition.scene_packing: {e}") from None
        scene = sc.preset("quicksand_case1", overrides or None)
        return scene, scene_packing(scene)
    return build


def column_case(name, packing, scene, n_steps, record_every, build=None):
    """A wet column compared sample by sample; ``packing``/``scene`` or a ``build`` callable."""
    def analyze(ty, tr, scene, pk):
        m = trajectory_diffs(ty, tr, float(np.mean(pk.r)))
        m["balance_error_yade"] = float(np.nanmax(ty.arrays()[4]))
        m["balance_error_ref"] = float(np.nanmax(tr.arrays()[4]))
        return m

    return Case(name, build or (lambda: (scene, packing)), n_steps, record_every,
                {"max_position_diff_rel": 1e-9, "pressure_rel_diff": 1e-9, "water_rel_diff": 1e-12,
                 "balance_error_yade": 1e-12, "balance_error_ref": 1e-12},
                f"positions and block pressures 1e-9 relative: {ROUNDOFF_WHY}; a settled column over "
                "2,000 steps (2 ms) amplifies that by far less than 1e7 (see roundoff_amplification: the "
                "growth of a 1e-12 r perturbation of x_0 in the reference). Water: both budgets close to "
                "round-off (1e-12), the totals agree to 1e-12 of the initial water", analyze, perturb=True)


def column_cases():
    return [column_case("quicksand_column", None, None, 2000, 100, quicksand_build()),
            column_case("shaken_column", None, None, 2000, 100,
                        quicksand_build(loading={"type": "cosine", "moves": "box"}, water={"q_w": 0.0}))]


# -- running ------------------------------------------------------------------------------------------
def _finite(v):
    return None if v is None or (isinstance(v, float) and not np.isfinite(v)) else v


def run_case(case, yade_simulate, ref_simulate):
    out = {"name": case.name, "metrics": {}, "tolerances": case.tolerances, "passed": False, "why": case.why}
    try:
        scene, pk = case.build()
        t0 = time.time()
        ty = yade_simulate(scene, pk, case.n_steps, case.record_every)
        t1 = time.time()
        tr = ref_simulate(scene, pk, case.n_steps, case.record_every)
        t2 = time.time()
        metrics = case.analyze(ty, tr, scene, pk)
        if case.perturb:
            moved = pk.xz.copy()
            mean_r = float(np.mean(pk.r))
            moved[pk.mobile] += 1e-12 * mean_r
            tp = ref_simulate(scene, Packing(moved, pk.r, pk.group, pk.density_factor), case.n_steps, case.record_every)
            diff = trajectory_diffs(tp, tr, mean_r)["max_position_diff_rel"]
            metrics["roundoff_amplification"] = diff / 1e-12
        metrics.update(seconds_yade=t1 - t0, seconds_ref=t2 - t1)
    except Exception as e:  # a case that cannot run fails, with the reason
        out["why"] = f"{type(e).__name__}: {e}. ({case.why})"
        return out
    failed = [k for k, tol in case.tolerances.items() if not (np.isfinite(metrics.get(k, np.nan)) and metrics[k] <= tol)]
    out["metrics"] = {k: _finite(float(v)) for k, v in metrics.items()}
    out["passed"] = not failed
    if failed:
        out["why"] = f"FAILED {', '.join(failed)}. ({case.why})"
    return out


def summary(case_result):
    c = case_result
    line = f"{'ok  ' if c['passed'] else 'FAIL'} {c['name']}: " + ", ".join(
        f"{k}={v:.3g}" for k, v in c["metrics"].items() if isinstance(v, float))
    return line if c["passed"] else f"{line}\n     {c['why']}"


def run_cases(yade_simulate, ref_simulate, cases=None, log=None):
    """Run ``cases`` (default: all) in both implementations: {"cases": [...], "passed": bool}.
    ``log``: optional callable given a summary line per case."""
    cases = contact_cases() + column_cases() if cases is None else cases
    results = []
    for c in cases:
        results.append(run_case(c, yade_simulate, ref_simulate))
        if log:
            log(summary(results[-1]))
    return {"cases": results, "passed": all(r["passed"] for r in results)}


def precision_study(ref_simulate=simulate_reference, build=None, n_steps=2000, record_every=100):
    """The reference on quicksand_column in float32, float64 and longdouble: max position difference
    / mean radius and block-pressure differences (max |dU| [N/m] and relative to max |U|) against
    longdouble."""
    scene, pk = (build or quicksand_build())()
    runs = {}
    for name, dtype in (("longdouble", np.longdouble), ("float64", np.float64), ("float32", np.float32)):
        t0 = time.time()
        try:
            runs[name] = ref_simulate(scene, pk, n_steps, record_every, dtype=dtype).arrays()
            runs[name + "_seconds"] = time.time() - t0
        except Exception as e:
            runs[name] = f"{type(e).__name__}: {e}"
    base = runs["longdouble"]
    out = {"against": "longdouble", "n_steps": n_steps, "mean_radius": float(np.mean(pk.r))}
    for name in ("float64", "float32", "longdouble"):
        run = runs[name]
        if isinstance(run, str) or isinstance(base, str):
            out[name] = {"error": run if isinstance(run, str) else base}
            continue
        dx = np.abs(run[1] - base[1]) / np.mean(pk.r)
        dU = np.abs(run[2] - base[2])
        out[name] = {"max_position_diff_rel": float(np.max(dx)),
                     "final_position_diff_rel": float(np.max(dx[-1])),
                     "max_block_pressure_diff": _finite(float(np.nanmax(dU))),
                     "block_pressure_rel_diff": _finite(float(np.nanmax(dU) / max(np.nanmax(np.abs(base[2])), TINY))),
                     "max_block_pressure_ref": _finite(float(np.nanmax(np.abs(base[2])))),
                     "max_balance_error": _finite(float(np.nanmax(run[4]))),
                     "seconds": runs[name + "_seconds"]}
    return out


def write_json(result, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, "crosscheck.json")
    with open(path, "w") as f:
        json.dump(result, f, indent=1)
    return path


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "crosscheck"))
    ap.add_argument("--skip-precision", action="store_true", help="leave out the float32/longdouble study")
    args = ap.parse_args(argv)
    from engines.yade_coupling import simulate  # needs YADE: run under `yade -n -x`
    result = run_cases(simulate, simulate_reference, log=lambda line: print(line, flush=True))
    if not args.skip_precision:
        try:
            result["precision"] = precision_study()
        except Exception as e:
            result["precision"] = {"error": f"{type(e).__name__}: {e}"}
        print("precision:", json.dumps(result["precision"], indent=1), flush=True)
    path = write_json(result, args.out)
    print(f"wrote {path}; {'all cases passed' if result['passed'] else 'SOME CASES FAILED'}")
    return 0 if result["passed"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
