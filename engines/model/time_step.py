"""The stability limits of a scene at its start, and the automatic time step ``[numerics] dt =
"auto"``: the smallest of them times ``[numerics] dt_auto_factor``. No YADE.

``limits(scene, packing)`` gives every limit of engines.model.limits for the scene's discs and
the pores the engines build at the start (W = A): contact (eq 52), ties (only with [loading]
side_walls = "springs"), water stiffness, darcy (2 / lambda_max from eigsh, per DEM step: divided
by water_interval, since the water step is water_interval x dt) and darcy_check (the engines'
Gershgorin check of the water step, per DEM step).

With [water] substep = true (the default) the Darcy limits do not bound dt: dt = dt_auto_factor x
min(contact, ties, water stiffness), the water is sub-stepped where a water step exceeds the
Darcy check, and the choice reports the sub-steps per water step at the start and their cost.
With substep = false: dt = dt_auto_factor x min(contact, ties, water stiffness, darcy), then
capped by darcy_check.
The limits are those of the start and dt is not changed during the run: the pores change as the
discs move, and the engines check the Darcy limit at every water step (sub-stepping by default,
which is the Darcy limit refreshed at every water step rather than at rebuilds); the contact and
tie limits do not change; the water-stiffness limit is not refreshed.
"""
import math

from engines.model import limits as lim
from engines.model import pores as pg
from engines.model.pore_dem import disc_masses, side_wall_ties
from engines.model.pore_water import PoreWater

AUTO = "auto"
# The default dt_auto_factor, and per factor tried the preset scenes on which dt = "auto" at that factor,
# with the pores rebuilt every 50 steps and the water every step, is within 5 % of the paper's numerics
# (dt = 1e-6 s, rebuilds every 1000 steps) on every judged statistic over the whole run (docs/TRADEOFFS.md,
# "Validation"; tests/studies/test_tradeoffs.py ties them to docs/tradeoffs/validation.json).
VALIDATED_FACTOR = 0.36
VALIDATED_ON = {0.36: ("liquefaction_case2", "liquefaction_case7"), 0.18: ("liquefaction_case2",)}
SHORT_WINDOW_EVIDENCE = {0.36: "within 5 % over the first 0.04 s of liquefaction_case1 only (the trade study)"}


def start_pores(scene, packing):
    """(network, measures, PoreWater) of the pores at the start (W = A), as the engines build them."""
    net = pg.build_pores(packing.xz, packing.r, eps_m=scene.contact.eps_m, l_m=scene.water.l_m, walls=packing.group)
    m = pg.measure(net, packing.xz, packing.r)
    return net, m, PoreWater(net, m.void_area, scene.water_settings())


def limits(scene, packing):
    """{name: limit [s]} of the scene at the start, per DEM step (module docstring)."""
    mass, _ = disc_masses(scene, packing)
    mob = packing.mobile
    out = {"contact": lim.critical_time_step(mass[mob], scene.contact.kn)}
    ties = side_wall_ties(scene, packing)
    if ties is not None:
        out["ties"] = lim.tie_limit(ties, mass)
    if scene.water.enabled:
        net, m, water = start_pores(scene, packing)
        M = scene.numerics.water_interval
        out["water_stiffness"] = lim.water_stiffness_limit(net, m.void_area, packing.r, scene.water.E_w, mass, mob)
        out["darcy"] = lim.darcy_eigen_limit(water, m.void_area, m.link_contact) / M
        out["darcy_check"] = water.darcy_limit(m.void_area, m.link_contact) / M
    return out


def check_start(scene, packing, lims=None):
    """Refuse (ValueError, one line naming the field and the limit) a scene whose numeric dt is
    above a limit at its start: eq 52 x dt_safety, the ties, the water stiffness, and a water step
    water_interval x dt above the Darcy check without [water] substep, or needing more than
    [water] max_substeps sub-steps with it. ``lims``: ``limits(scene, packing)`` if known."""
    lims = limits(scene, packing) if lims is None else lims
    num, w = scene.numerics, scene.water
    mass, _ = disc_masses(scene, packing)
    lim.check_contact(num.dt, num.dt_safety, mass[packing.mobile], scene.contact.kn)
    lim.check_ties(num.dt, side_wall_ties(scene, packing), mass)
    if not w.enabled:
        return
    lim.check_water_stiffness(num.dt, lims["water_stiffness"], w.E_w)
    h, limit = num.water_interval * num.dt, num.water_interval * lims["darcy_check"]
    where = f"[numerics] dt = {num.dt:.3g} s, water_interval = {num.water_interval}: at the start (k1 = {w.k1:g}, k2 = {w.k2:g} 1/s) the"
    try:
        n_sub = lim.substeps(h, limit, w.substep, w.E_w)
    except lim.DarcyStabilityError as e:
        raise ValueError(f"{where} {e}") from None
    if n_sub > w.max_substeps:
        raise ValueError(f"{where} water step {h:.3g} s needs {n_sub} sub-steps under the Darcy limit {limit:.3g} s, "
                         f"more than [water] max_substeps = {w.max_substeps}; reduce dt or the permeabilities, "
                         f"or raise max_substeps")


def choose(lims, factor, substep=False):
    """(dt, binding limit's name, sub-steps per water step at the start) from ``limits``."""
    scaled = {k: factor * v for k, v in lims.items() if k != "darcy_check" and not (substep and k == "darcy")}
    name = min(scaled, key=scaled.get)
    dt = scaled[name]
    check = lims.get("darcy_check", math.inf)
    if not substep and check < dt:
        dt, name = check, "darcy_check"
    return dt, name, lim.substep_count(dt, check) if substep else 1


def auto_time_step(scene, packing):
    """(dt [s], {name: limit [s]}, binding name, sub-steps per water step at the start)."""
    lims = limits(scene, packing)
    dt, name, n_sub = choose(lims, scene.numerics.dt_auto_factor, scene.water.enabled and scene.water.substep)
    return dt, lims, name, n_sub


def describe(dt, lims, name, n_sub, factor):
    """The lines a run prints about its automatic time step."""
    shown = ", ".join(f"{k} {v:.3g} s" for k, v in lims.items())
    text = (f"dt = auto: {dt:.3g} s, bound by the {name} limit"
            + ("" if name == "darcy_check" else f" x dt_auto_factor {factor:g}") + f" (limits at the start: {shown})")
    text += "\n" + validation_note(factor)
    if n_sub > 1:
        text += (f"\nwater: {n_sub} sub-steps per water step at the start (substep = true, Gershgorin Darcy limit "
                 f"{lims['darcy_check']:.3g} s per DEM step); each costs about {lim.SUBSTEP_COST:.0%} of a water step, "
                 f"so the water costs about {lim.substep_cost(n_sub):.2g}x a water step without sub-steps")
    return text


def validation_note(factor):
    """Where the automatic time step's factor was validated (VALIDATED_ON)."""
    if factor not in VALIDATED_ON:
        return f"dt_auto_factor {factor:g} is not validated (docs/TRADEOFFS.md, Validation)"
    where = ", ".join(VALIDATED_ON[factor]) or "no preset scene"
    extra = f"; {SHORT_WINDOW_EVIDENCE[factor]}" if factor in SHORT_WINDOW_EVIDENCE else ""
    return (f"dt_auto_factor {factor:g} with rebuild_interval 50 and water_interval 1 against the paper's numerics: "
            f"validated over the whole run on {where} (other scenes: not validated){extra} (docs/TRADEOFFS.md, Validation)")


def resolve_dt(scene, packing, log=print):
    """``scene`` itself when its dt is a number; for dt = "auto" a copy with the chosen dt (the
    choice printed through ``log``; None: silent)."""
    if scene.numerics.dt != AUTO:
        return scene
    dt, lims, name, n_sub = auto_time_step(scene, packing)
    if log is not None:
        log(describe(dt, lims, name, n_sub, scene.numerics.dt_auto_factor))
    out = scene.with_overrides({"numerics": {"dt": dt}})
    out.overrides = scene.overrides  # "auto" stays the recorded choice; parameters hold the number
    return out
