"""Cross-check of the YADE path (engines.yade.coupling) against the NumPy reference (engines.reference.model).

The library of yade_scripts/crosscheck.py (make test runs it: DIR/crosscheck.json, exit 1 if a case
fails). Headless: ``run_cases(yade_simulate, ref_simulate, ...)`` and ``precision_study`` take the
``simulate(scene, packing, n_steps, record_every) -> Trajectory`` functions as arguments (the YADE
side also gets ``hooks=``).

Every metric is judged or says why not: a tolerance with its reason (the case's ``why``), or its reason
in the case's ``not_judged`` (a case with a metric that has neither fails).
Contact cases (short, deterministic):
  head_on_collision        two equal discs, linear spring-dashpot, g = 0: restitution vs analytic
  head_on_adjusted         the same with the separation adjustment: -Vn''/Vn = e (pattern d, eq 24)
  pressed_release_a..d     a disc pressed into a fixed wall disc and released, per spring of Fig. 5
Feature cases (1,050-5,000 steps, >= 20 pore rebuilds each; chaotic, see FEATURE_WHY):
  settling_rules           loose discs falling into a wet box under 1000 m/s^2: re-meshing rules a-d
  quicksand_smoothing      the quick-sand column with 10x inflow and eq 45-46 smoothing
  quicksand_displacement   the same inflow, the pores rebuilt by displacement (5 um, SPEC §2.6): the
                           reference is handed the rebuild steps of the YADE run
  flat_walls_box           the column in a box of flat walls (SPEC §2.6) in place of the wall discs
                           (quicksand_case1_flat: the bed settled on them): an inflow bottom (4x case
                           1's), drained sides (k3); the paper's law against them
  flat_walls_shaken        that box with case 1's inflow shaken by the cosine as one (moves = box):
                           the side faces translate, the bottom slides under the bed; drained sides
  shaken_drained_wet_d     the column shaken by a cosine, drained sides with k3 (!= k1), spring d with
                           eps_m > 0, water_interval 2, smoothing
  elcentro_column          the column shaken by the El Centro record (time x 0.001, amplitude x 5)
  seismic_box              the liquefaction_case1 box: base shaken by the cosine, side-wall columns
                           moving in x on the ties of Fig. 27 (k's, eta's), spring d, eps_m > 0
``precision_study`` (make precision, not part of make test): the reference runs the quick-sand preset
in float32, float64 and longdouble, a measurement reported in DIR/precision.json and judged against
PRECISION_BOUNDS (yade_scripts/crosscheck.py --precision exits 1 on a miss). ``crosscheck`` runs
every case (or some) against the YADE path and writes DIR/crosscheck.json. No YADE import here:
the YADE side is given (engines.yade.coupling.simulate).
"""
import os
import time
from dataclasses import dataclass, field

import numpy as np

from engines import files
from engines.model.flat_walls import as_tables
from engines.model.pore_dem import moving_flat_walls, scene_flat_walls
from engines.reference.model import mesh_void_fraction, simulate_reference
from engines.reference.trajectory import Trajectory
from engines.run import scene as sc
from packing.packing import Packing

R = 0.45e-3            # disc radius of the contact cases [m]
TINY = 1e-30
ROUNDOFF_WHY = ("float64 against float64: the two paths differ only in the order of operations "
                "(YADE's v += dt (F/m + g), bincount vs add.at, the telescoped vs per-arc eq 33), ~1e-16 "
                "relative per operation")
COST_WHY = "wall-clock seconds on this machine, which depend on its load: for the record, not a result"


@dataclass
class Case:
    """One cross-check: ``build()`` -> (scene, packing); ``analyze(traj_yade, traj_ref, scene, packing)``
    -> metrics; every metric named in ``tolerances`` must be finite and <= its tolerance, every other
    one needs its reason in ``not_judged`` (metric -> why it is not judged; seconds_* have COST_WHY)."""

    name: str
    build: object
    n_steps: int
    record_every: int
    tolerances: dict
    why: str
    analyze: object
    not_judged: dict = field(default_factory=dict)


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

    behind = "the value behind restitution_error_yade, restitution_error_ref and restitution_diff, which are judged"
    return Case(name, lambda: (scene, launcher_packing()), 2500, 50,
                {"max_position_diff_rel": 1e-9, "restitution_diff": 1e-9,
                 "restitution_error_yade": tol_e, "restitution_error_ref": tol_e},
                f"restitution: {why_e}. Between the paths 1e-9: a smooth two-body motion accumulates "
                f"~n_steps x 1e-16 of {ROUNDOFF_WHY}", analyze,
                dict.fromkeys(("restitution_yade", "restitution_ref", "restitution_analytic"), behind))


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
        engines.model.contact), and the overlap where the force first vanished."""
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
    speed = "the value behind exit_speed_error_yade and exit_speed_error_ref, which are judged"
    reported = dict.fromkeys(("exit_speed_yade", "exit_speed_ref", "exit_speed_analytic"), speed)
    if spring == "d":
        tol.update(residual_overlap_error_yade=1.0, residual_overlap_error_ref=1.0)
        reported.update({f"residual_overlap_{tag}": f"the value behind residual_overlap_error_{tag}, which is judged"
                         for tag in ("yade", "ref")})
    return Case(f"pressed_release_{spring}", lambda: (scene, pk), 450, 1, tol,
                "force path from second differences of positions, 1e-6 f_max (x round-off ~1e-21 m "
                "against a dt^2 ~ 6e-11 m); exit speed 1e-4 relative (the force is ~0 when contact ends: "
                "second order, (omega dt)^2 ~ 3e-5); residual overlap of d within one step of travel "
                f"(metric in units of v dt); between the paths 1e-9: {ROUNDOFF_WHY}", analyze, reported)


def contact_cases():
    return [collision_case(False), collision_case(True)] + [pressed_case(s) for s in "abcd"]


# -- feature cases: long runs over every feature of the model -----------------------------------------
TRAJ_TOL = 1e-9        # positions / mean radius while the runs are comparable
PRESSURE_TOL = 1e-9    # block pressures / max |U| of the reference over the comparable window
WATER_TOL = 1e-12      # each run's own water budget, relative to its initial water
PERTURBATION = 1e-12   # of a mean radius, added to every particle's start to time the divergence
MIN_WINDOW = 3         # samples the comparable window must hold for the case to check anything
STAT_FACTOR, STAT_FLOOR = 4.0, 0.02   # statistics after divergence: see compare_statistics
FEATURE_WHY = (f"trajectories (positions {TRAJ_TOL:g} of a mean radius, block pressures {PRESSURE_TOL:g} of "
               f"max |U|, total water {TRAJ_TOL:g} of the initial: it changes only through the areas at a "
               "re-meshing, eq 32) compared up to the divergence time, when the reference "
               f"started from x_0 + {PERTURBATION:g} r departs from the reference by {TRAJ_TOL:g} in positions / mean "
               "radius, block pressures / E_w or total water / initial water: until then "
               "both paths differ only by round-off, which grows no faster than that perturbation; both "
               f"water budgets close to {WATER_TOL:g}; after the divergence, time means of block pressures "
               f"and mesh void fraction agree within {STAT_FACTOR:g} x the spread between the two reference runs "
               f"(at least {STAT_FLOOR:g} of their scale); re-meshing rule counts agree rebuild by rebuild "
               f"before the divergence. Every rule the case is built for must fire. {ROUNDOFF_WHY}")
FEATURE_NOT_JUDGED = {   # the entries of a feature case's result that no check reads, and why
    "divergence_time_s": "when the perturbed reference departs from the reference: the scene's chaos, which ends "
                         "the comparable window; judged through checks.window_samples (at least MIN_WINDOW samples "
                         "before it)",
    "perturbation_growth": "max |x_perturbed - x_ref| over the run over the perturbation: how strongly the scene "
                           "amplifies a difference, a property of the scene, not of either implementation",
    "counts": "totals over the whole run: after the divergence the two paths follow different trajectories, so "
              "their rules are compared rebuild by rebuild before it (checks.rules_rebuild_by_rebuild_in_window); "
              "the reference's totals are judged by checks.rebuilds and checks.rules_fired; the separation "
              "patterns (eq 18-24) are counted by the reference only",
    "seconds": COST_WHY,
}


@dataclass
class FeatureCase:
    """A long run of one scene: ``build()`` -> (scene, packing); ``rules``: the re-meshing rules it
    must fire (on the reference side)."""

    name: str
    build: object
    n_steps: int
    record_every: int
    rules: str = ""
    min_rebuilds: int = 20


def preset_build(name, **overrides):
    """The preset ``name`` (with ``overrides``) and its packing (engines.yade.deposition.scene_packing)."""
    def build():
        try:
            from engines.yade.deposition import scene_packing
        except ImportError as e:
            raise RuntimeError(f"missing prerequisite engines.yade.deposition.scene_packing: {e}") from None
        scene = sc.preset(name, overrides or None)
        return scene, scene_packing(scene)
    return build


def quicksand_build(**overrides):
    """The quicksand_case1 preset (with ``overrides``) and its packing."""
    return preset_build("quicksand_case1", **overrides)


def settling_box(seed=3, nx=8, nz=8, spacing=2.2 * R):
    """Particles on a jittered hexagonal lattice with gaps about l_m wide, radii 0.8-1 R, in a box of
    wall discs (bottom row, side columns; open top): under strong gravity they fall, collide and
    link up, so pores appear, split, merge and flip, and isolated ones form (rules a-d)."""
    rng = np.random.default_rng(seed)
    xz = np.array([[spacing * (i + 0.5 * (j % 2)), spacing * np.sqrt(3) / 2 * j] for j in range(nz) for i in range(nx)])
    col, row = np.arange(len(xz)) % nx, np.arange(len(xz)) // nx
    group = np.where(row == 0, 1, np.where(col == 0, 2, np.where(col == nx - 1, 3, 0)))
    mob = group == 0
    r = np.where(mob, R * (0.8 + 0.2 * rng.random(len(xz))), R)
    xz[mob] += 0.1 * R * rng.standard_normal((int(mob.sum()), 2))
    return Packing(xz, r, group, np.ones(len(xz)))


def settling_build(**overrides):
    def build():
        raw = {"scene": {"name": "settling_box"}, "material": {"g": 1000.0},
               "water": {"enabled": True, "q_w": 0.0, "k1": 200.0, "k2": 2.0, "E_w": 240.0, "transfer": "paper"},
               "numerics": {"dt": 1e-6, "rebuild_interval": 100}}
        for table, fields in overrides.items():
            raw.setdefault(table, {}).update(fields)
        return sc.validate(raw), settling_box()
    return build


ELCENTRO = os.path.join(sc.SCENE_DIR, "elcentro_ns_1940.txt")   # the 1940 N-S record, in g


def feature_cases():
    """Each feature of the model in at least one case of >= 20 pore rebuilds (see FEATURE_WHY)."""
    shaken = {"loading": {"type": "cosine", "moves": "box", "amplitude": 15.0, "frequency": 50.0}}
    return [
        FeatureCase("settling_rules", settling_build(), 5000, 50, rules="abcd"),
        FeatureCase("quicksand_smoothing", quicksand_build(water={"q_w": 5e-3, "smoothing": True},
                                                           numerics={"rebuild_interval": 100}), 2100, 50),
        FeatureCase("quicksand_displacement", quicksand_build(
            water={"q_w": 5e-3}, numerics={"rebuild_interval": 10**6, "rebuild_distance": 5e-6}), 2100, 10),
        FeatureCase("flat_walls_box", preset_build(
            "quicksand_case1_flat", water={"q_w": 2e-3, "sides": "drained", "k3": 400.0},
            numerics={"rebuild_interval": 100}), 2100, 5),
        FeatureCase("flat_walls_shaken", preset_build(
            "quicksand_case1_flat", water={"sides": "drained", "k3": 400.0},
            numerics={"rebuild_interval": 100}, **shaken), 2100, 5),
        FeatureCase("shaken_drained_wet_d", quicksand_build(
            water={"q_w": 0.0, "sides": "drained", "k1": 1000.0, "k2": 100.0, "k3": 400.0, "smoothing": True},
            contact={"spring": "d", "eps_m": 2e-5, "f_max": 1.5},
            numerics={"rebuild_interval": 100, "water_interval": 2}, **shaken), 2100, 50),
        FeatureCase("elcentro_column", quicksand_build(
            water={"q_w": 0.0, "E_w": 2400.0, "k1": 100.0, "k2": 100.0},
            loading={"type": "record", "record": ELCENTRO, "moves": "box", "time_scale": 0.001,
                     "amplitude_scale": 5.0},
            numerics={"rebuild_interval": 100}), 2100, 50),
        FeatureCase("seismic_box", preset_build("liquefaction_case1", numerics={"rebuild_interval": 50}), 1050, 50),
    ]


def reference_inputs(scene, packing):
    """(tables, packing) of the reference for a scene and its packing: with [walls] kind = "flat",
    its flat walls (engines.model.pore_dem.scene_flat_walls) as the tables' list and the particles
    alone (the YADE side replaces the wall discs so); else the scene and packing as they are."""
    walls = scene_flat_walls(scene.settings, packing)
    if not walls:
        return scene, packing
    tables = scene.as_dict()
    walls = tuple(walls.values())
    tables["walls"] = {"flat": as_tables(walls, moving_flat_walls(scene.settings, walls))}
    return tables, packing.particles()


def features_of(scene):
    """What a scene exercises, for crosscheck.json."""
    w, c, n, ld = scene.water, scene.contact, scene.numerics, scene.loading
    out = {"spring": c.spring, "eps_m": c.eps_m, "separation_adjustment": c.separation_adjustment,
           "water": w.enabled, "rebuild_interval": n.rebuild_interval, "rebuild_distance": n.rebuild_distance,
           "walls": scene.walls.kind}
    if w.enabled:
        out.update(inflow_q_w=w.q_w, smoothing_eq45_46=w.smoothing, sides=w.sides,
                   k3=w.k3 if w.sides == "drained" else None, water_interval=n.water_interval)
    if ld.type == "cosine":
        out["input"] = f"cosine {ld.amplitude} m/s^2 at {ld.frequency} Hz, moves {ld.moves}"
    elif ld.type == "record":
        out["input"] = (f"record {os.path.basename(ld.record)} x time {ld.time_scale} x amplitude "
                        f"{ld.amplitude_scale}, moves {ld.moves}")
    if ld.type != "none":
        out["side_walls"] = ld.side_walls
        if ld.side_walls == "springs":
            out.update(ks_wall=c.ks_wall, eta_s_wall=c.eta_s_wall)
    return out


def yade_remesh_counter():
    """A hook of engines.yade.coupling.simulate (called after each recorded chunk, so at most one rebuild
    in between when record_every <= rebuild_interval, or small enough for the rebuilds by
    displacement) counting the fast code's re-meshing rules per rebuild and its step; (hook, counts)."""
    counts = {"rebuilds": 0, "remesh": dict.fromkeys("abcd", 0), "history": [], "separation": None}

    def hook(cp):
        model = cp.water_model
        if model is not None and model.n_rebuilds > counts["rebuilds"]:
            if model.n_rebuilds > counts["rebuilds"] + 1:
                raise RuntimeError("more than one rebuild between two hook calls: record_every too long")
            counts["rebuilds"] = model.n_rebuilds
            this = {r: int(model.water.remesh_counts.get(r, 0)) for r in "abcd"}
            for r, v in this.items():
                counts["remesh"][r] += v
            counts["history"].append((model.schedule.k_built, this))
    return hook, counts


def divergence(ta, tb, mean_r, E_w):
    """(index of the first sample where the runs differ by more than TRAJ_TOL, its time); (n, inf)
    if never. Differences: positions / mean_r, block pressures / E_w (U / E_w = W/A - 1, the water's
    strain, follows the areas as the positions do; relative to max |U| it would magnify round-off
    by E_w / max |U|, 4e3 in a still column), total water / W_b(0) (the water and pressures jump at
    a rebuild by amounts that can be more sensitive to the positions than the positions are)."""
    t, xa, Ua, Wa, _ = ta.arrays()
    _, xb, Ub, Wb, _ = tb.arrays()
    over = np.max(np.abs(xa - xb), axis=(1, 2)) / mean_r > TRAJ_TOL
    if Ub.size and not np.all(np.isnan(Ub)):
        with np.errstate(invalid="ignore"):
            dU = np.nanmax(np.abs(Ua - Ub), axis=1, initial=0.0) / E_w
        over |= (dU > TRAJ_TOL) | (np.isnan(Ua) != np.isnan(Ub)).any(axis=1)
        over |= np.abs(Wa - Wb) / Wb[0] > TRAJ_TOL
    first = np.flatnonzero(over)
    return (int(first[0]), float(t[first[0]])) if len(first) else (len(t), float("inf"))


def rules_before(history, t_end, dt):
    """[(step, {rule: count})] of the rebuilds at times before t_end [s]."""
    return [(int(k), {r: int(n) for r, n in c.items()}) for k, c in history if k * dt < t_end]


def compare_window(ty, tr, n, mean_r):
    """Trajectory differences over the first n samples (trajectory_diffs restricted to them)."""
    cut = lambda tj: Trajectory(t=tj.t[:n], xz=tj.xz[:n], block_U=tj.block_U[:n], water=tj.water[:n],
                                balance_error=tj.balance_error[:n])
    return trajectory_diffs(cut(ty), cut(tr), mean_r)


def statistics(traj, start, pk, scene):
    """Time means over the samples from ``start`` on: block pressures (B,) [N/m] and the void
    fraction of the pore mesh (engines.reference.model.mesh_void_fraction)."""
    _, xz, U, *_ = traj.arrays()
    if start >= len(xz):
        return None
    c, w = scene.contact, scene.water
    por = [mesh_void_fraction(x, pk.r, pk.group, c.eps_m, w.l_m) for x in xz[start:]]
    with np.errstate(all="ignore"):
        return {"block_U": np.nanmean(U[start:], axis=0) if w.enabled else np.array([]), "mesh_void_fraction": float(np.nanmean(por))}


def compare_statistics(sy, sr, sp):
    """|S_y - S_r| against the chaotic spread |S_p - S_r| of each statistic (y: the run judged,
    r: the reference, p: the reference perturbed): pass when within STAT_FACTOR x that spread or
    STAT_FLOOR x the statistic's scale."""
    out, ok = {}, True
    for key in ("block_U", "mesh_void_fraction"):
        y, r, p = (np.atleast_1d(np.asarray(v[key], float)) for v in (sy, sr, sp))
        if not y.size:
            continue
        scale = max(np.nanmax(np.abs(r)), TINY) if key == "mesh_void_fraction" else max(np.nanmax(np.abs(r)), 1.0)
        allowed = np.maximum(STAT_FACTOR * np.abs(p - r), STAT_FLOOR * scale)
        diff = np.abs(y - r)
        good = bool(np.all(np.isnan(diff) == np.isnan(allowed)) and np.all((diff <= allowed) | np.isnan(diff)))
        out[key] = {"yade": y.tolist(), "ref": r.tolist(), "perturbed_ref": p.tolist(),
                    "diff": diff.tolist(), "allowed": allowed.tolist(), "passed": good}
        ok &= good
    return out, ok


def run_feature_case(case, yade_simulate, ref_simulate):
    """One FeatureCase: YADE, the reference and the reference perturbed."""
    out = {"name": case.name, "passed": False, "why": FEATURE_WHY}
    try:
        scene, full = case.build()
        mean_r = float(np.mean(full.r[full.mobile]))
        hook, ycounts = yade_remesh_counter()
        t0 = time.time()
        ty = yade_simulate(scene, full, case.n_steps, case.record_every, hooks=[hook])
        t1 = time.time()
        tables, pk = reference_inputs(scene, full)
        ycounts = ty.info.get("counts", ycounts)   # a stand-in implementation may report its own
        # rebuilds by displacement (SPEC §2.6): the reference rebuilds at the steps the YADE run did
        steps = {"rebuild_steps": [k for k, _ in ycounts["history"]]} if scene.numerics.rebuild_distance > 0 else {}
        tr = ref_simulate(tables, pk, case.n_steps, case.record_every, **steps)
        t2 = time.time()
        moved = pk.xz.copy()
        moved[pk.mobile] += PERTURBATION * mean_r
        tp = ref_simulate(tables, Packing(moved, pk.r, pk.group, pk.density_factor), case.n_steps, case.record_every,
                          **steps)
        t3 = time.time()
        rcounts = tr.info["counts"]
        n_win, t_div = divergence(tp, tr, mean_r, scene.water.E_w)
        win = compare_window(ty, tr, n_win, mean_r) if n_win else {}
        same_rules = (rules_before(ycounts["history"], t_div, scene.numerics.dt)
                      == rules_before(rcounts["history"], t_div, scene.numerics.dt))
        stats = [statistics(tj, n_win, pk, scene) for tj in (ty, tr, tp)]
        stat_cmp, stat_ok = compare_statistics(*stats) if stats[0] is not None else ({}, True)
        t4 = time.time()
        balance = {"yade": float(np.nanmax(ty.arrays()[4])), "ref": float(np.nanmax(tr.arrays()[4]))}
        checks = {
            "window_samples": n_win >= MIN_WINDOW,
            "positions_in_window": win.get("max_position_diff_rel", np.inf) <= TRAJ_TOL,
            "pressures_in_window": win.get("pressure_rel_diff", 0.0) <= PRESSURE_TOL,
            "water_in_window": win.get("water_rel_diff", 0.0) <= TRAJ_TOL,
            "balance": not scene.water.enabled or max(balance.values()) <= WATER_TOL,
            "rules_rebuild_by_rebuild_in_window": same_rules,
            "statistics_after_divergence": stat_ok,
            "rebuilds": not scene.water.enabled or rcounts["rebuilds"] >= case.min_rebuilds,
            "rules_fired": all(rcounts["remesh"][r] > 0 for r in case.rules),
        }
        out.update(features=features_of(scene), n_steps=case.n_steps, record_every=case.record_every,
                   divergence_time_s=_finite(t_div), window_samples=n_win, window=win, balance_error=balance,
                   perturbation_growth=float(np.max(np.abs(np.array(tp.xz) - np.array(tr.xz)))
                                             / (PERTURBATION * mean_r)),
                   counts={"ref": {k: v for k, v in rcounts.items() if k != "history"},
                           "yade": {k: v for k, v in ycounts.items() if k != "history"}},
                   statistics=stat_cmp, checks=checks,
                   seconds={"yade": t1 - t0, "ref": t2 - t1, "ref_perturbed": t3 - t2, "statistics": t4 - t3},
                   not_judged=FEATURE_NOT_JUDGED)
        out["passed"] = all(checks.values())
        if not out["passed"]:
            out["why"] = f"FAILED {', '.join(k for k, v in checks.items() if not v)}. ({FEATURE_WHY})"
    except Exception as e:  # a case that cannot run fails, with the reason
        out["why"] = f"{type(e).__name__}: {e}. ({FEATURE_WHY})"
    return out


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
        metrics.update(seconds_yade=t1 - t0, seconds_ref=t2 - t1)
    except Exception as e:  # a case that cannot run fails, with the reason
        out["why"] = f"{type(e).__name__}: {e}. ({case.why})"
        return out
    failed = [k for k, tol in case.tolerances.items() if not (np.isfinite(metrics.get(k, np.nan)) and metrics[k] <= tol)]
    why_not = {**case.not_judged, "seconds_yade": COST_WHY, "seconds_ref": COST_WHY}
    unexplained = [k for k in metrics if k not in case.tolerances and k not in why_not]
    failed += [f"{k} (neither judged nor explained)" for k in unexplained]
    out["metrics"] = {k: _finite(float(v)) for k, v in metrics.items()}
    out["not_judged"] = {k: why_not[k] for k in metrics if k in why_not and k not in case.tolerances}
    out["passed"] = not failed
    if failed:
        out["why"] = f"FAILED {', '.join(failed)}. ({case.why})"
    return out


def summary(case_result):
    c = case_result
    line = f"{'ok  ' if c['passed'] else 'FAIL'} {c['name']}: " + ", ".join(
        f"{k}={v:.3g}" for k, v in c["metrics"].items() if isinstance(v, float))
    return line if c["passed"] else f"{line}\n     {c['why']}"


def run_cases(yade_simulate, ref_simulate=simulate_reference, cases=None, log=None, features=None):
    """Run ``cases`` (default: the contact cases) and ``features`` (default: feature_cases()) in both
    implementations: {"cases": [...], "feature_cases": [...], "passed": bool}. ``log``: optional
    callable given a line per case."""
    cases = contact_cases() if cases is None else cases
    features = feature_cases() if features is None else features
    results, long = [], []
    for c in cases:
        results.append(run_case(c, yade_simulate, ref_simulate))
        if log:
            log(summary(results[-1]))
    for c in features:
        long.append(run_feature_case(c, yade_simulate, ref_simulate))
        if log:
            log(feature_summary(long[-1]))
    return {"cases": results, "feature_cases": long,
            "passed": all(r["passed"] for r in results) and all(r["passed"] for r in long)}


def feature_summary(c):
    """One line per feature case: divergence time, window, rule counts, cost."""
    if "checks" not in c:
        return f"FAIL {c['name']}: {c['why']}"
    rc = c["counts"]["ref"]
    line = (f"{'ok  ' if c['passed'] else 'FAIL'} {c['name']}: diverges at {c['divergence_time_s']} s "
            f"({c['window_samples']} samples compared, max dx/r {c['window'].get('max_position_diff_rel', float('nan')):.2g}), "
            f"rebuilds {rc['rebuilds']}, rules {rc['remesh']}, separations {rc['separation']}, "
            f"seconds {', '.join(f'{k} {v:.1f}' for k, v in c['seconds'].items())}")
    return line if c["passed"] else f"{line}\n     {c['why']}"


# The bounds make precision judges against longdouble (over 2,000 steps of the quick-sand column):
# float64 round-off (measured ~6e-13) a thousand times over; float32 (measured 0.73 % of a radius,
# 0.31 % in block pressure) within 5 %, the size of a change nobody would call round-off.
PRECISION_BOUNDS = {"float64": {"max_position_diff_rel": 1e-9, "block_pressure_rel_diff": 1e-9},
                    "float32": {"max_position_diff_rel": 0.05, "block_pressure_rel_diff": 0.05}}


def precision_study(ref_simulate=simulate_reference, build=None, n_steps=2000, record_every=100,
                    bounds=PRECISION_BOUNDS):
    """The reference on quicksand_column in float32, float64 and longdouble: max position difference
    / mean radius and block-pressure differences (max |dU| [N/m] and relative to max |U|) against
    longdouble; "passed" when every precision ran and each difference in ``bounds`` is within its
    bound ("why" names those that are not)."""
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
    why = [f"{name}: {out[name]['error']}" for name in ("float64", "float32", "longdouble") if "error" in out[name]]
    why += [f"{name} {key} = {out[name][key]} (bound {bound})" for name, limits in bounds.items()
            if "error" not in out[name] for key, bound in limits.items()
            if out[name][key] is None or not out[name][key] <= bound]
    out.update(bounds=bounds, passed=not why, why="; ".join(why))
    return out


def write_json(result, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, "crosscheck.json")
    files.write_json(path, result)
    return path


def crosscheck(yade_simulate, out_dir, only=None, log=print):
    """Run the cases named in ``only`` (default: all) with the YADE side ``yade_simulate``, write
    out_dir/crosscheck.json; returns (result, path). Raises ValueError for an unknown case name."""
    t0 = time.time()
    cases, features = contact_cases(), feature_cases()
    if only:
        unknown = set(only) - {c.name for c in cases + features}
        if unknown:
            raise ValueError(f"unknown cases {sorted(unknown)}")
        cases, features = ([c for c in group if c.name in only] for group in (cases, features))
    result = run_cases(yade_simulate, cases=cases, features=features, log=log)
    result["seconds"] = time.time() - t0
    result["not_judged"] = {"seconds": COST_WHY}
    return result, write_json(result, out_dir)
