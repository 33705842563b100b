"""The start of a run, computed once: the walls, the discs the engines move, the pores at the start,
the stability limits and the time step. No YADE.

``Start(settings, packing)`` (settings: engines.model.settings.Settings, a validated scene's
``settings``) is handed to preflight (engines.run.preflight), to ``dt = "auto"`` and to the engines
(engines.yade.coupling.YadeCoupling, engines.run.runner.run_scene), so that the limits a user is told
are those of the network that runs:

* ``flat_walls``: {wall code: FlatWall} of [walls] kind = "flat" (engines.model.pore_dem.scene_flat_walls),
  {} with wall discs; ``faces``: {wall code: position [m]} of the box (the flat walls', else the wall
  discs' inner faces); ``packing``: the discs the engines move (with flat walls the particles alone);
  ``mass``, ``inertia`` of those discs (eq 15); ``ties``: the side-wall ties or None;
* ``pores``: (network, measures, PoreWater) at the start (W = A), built as the water model builds its
  first network (engines.model.water_model.WaterModel: the same discs, flat walls and ranges), or None
  for a dry scene;
* ``limits``: {name: limit [s]} per DEM step, each computed once: contact (eq 52), ties (only with
  [loading] side_walls = "springs"), water stiffness (its limit of the water step divided by
  water_interval: the pressure forces are held for a water step), darcy (2 / lambda_max from eigsh, divided by
  water_interval since the water step is water_interval x dt) and darcy_check (the engines' Gershgorin
  check of the water step, per DEM step);
* ``settings``: the settings with their time step: ``given`` for a numeric dt, for dt = "auto" a copy
  with the chosen dt (``auto``: dt, the binding limit's name, the sub-steps per water step at the start).

dt = "auto": with [water] substep = true (the default) the Darcy limits do not bound dt: dt =
dt_auto_factor x min(contact, ties, water stiffness), the water is sub-stepped where a water step
exceeds the Darcy check, and the choice reports the sub-steps per water step at the start. With
substep = false: dt = dt_auto_factor x min(contact, ties, water stiffness, darcy), then capped by
darcy_check. The limits are those of the start and dt is not changed during the run: the pores
change as the discs move, and the engines check the Darcy limit at every water step (sub-stepping by
default); the contact and tie limits do not change; the water-stiffness limit is not refreshed.
"""
import math

from engines.model import flat_walls as fw
from engines.model import limits as lim
from engines.model import pores as pg
from engines.model.pore_dem import disc_masses, scene_flat_walls, side_wall_ties
from engines.model.pore_water import PoreWater

AUTO = "auto"


class Start:
    """The start of a run of ``settings`` on ``packing`` (its wall discs included): see the module
    docstring. The pores, limits and dt = "auto" are computed on first use, once."""

    def __init__(self, settings, packing):
        self.given = settings
        self.flat_walls = scene_flat_walls(settings, packing)
        self.faces = {code: w.position for code, w in self.flat_walls.items()} or packing.inner_faces()
        self.full_packing = packing
        self.packing = packing.particles() if self.flat_walls else packing
        self.mass, self.inertia = disc_masses(settings, self.packing)
        self.ties = side_wall_ties(settings, self.packing)
        self._pores = self._limits = self._auto = None

    @property
    def pores(self):
        """(network, measures, PoreWater) of the pores at the start (W = A), or None for a dry scene."""
        if self._pores is None and self.given.water.enabled:
            self._pores = start_pores(self.given, self.packing, self.flat_walls)
        return self._pores

    @property
    def limits(self):
        """{name: limit [s]} per DEM step at the start (module docstring)."""
        if self._limits is None:
            self._limits = limits(self.given, self.packing, self.mass, self.ties, self.pores)
        return self._limits

    @property
    def auto(self):
        """(dt [s], binding limit's name, sub-steps per water step at the start) of dt = "auto", or
        None for a numeric dt."""
        if self._auto is None and self.given.numerics.dt == AUTO:
            w = self.given.water
            self._auto = choose(self.limits, self.given.numerics.dt_auto_factor, w.enabled and w.substep)
        return self._auto

    @property
    def settings(self):
        """The settings with their time step: ``given`` for a numeric dt, else with ``auto``'s."""
        return self.given if self.auto is None else self.given.with_dt(self.auto[0])

    def check(self):
        """``check_start`` of the settings with their time step."""
        check_start(self.settings, self.packing, self.mass, self.ties, self.limits)


def start_pores(settings, packing, flat_walls):
    """(network, measures, PoreWater) of the pores of ``packing`` (the discs the engines move) and
    the FlatWalls {code: FlatWall} at the start (W = A), built as WaterModel builds its first."""
    walls = tuple(flat_walls.values())
    vertices = fw.WallVertices(walls, len(packing.r)) if walls else ()
    net = pg.build_pores(packing.xz, packing.r, eps_m=settings.contact.eps_m, l_m=settings.water.l_m, walls=packing.group,
                         flat_walls=vertices)
    m = pg.measure(net, packing.xz, packing.r)
    return net, m, PoreWater(net, m.void_area, settings.water_settings(), walls=packing.group)


def limits(settings, packing, mass, ties, pores):
    """{name: limit [s]} per DEM step (module docstring) of the discs of ``packing`` with masses
    ``mass``, the ties (or None) and the pores (``start_pores``, or None for a dry scene)."""
    mob = packing.mobile
    out = {"contact": lim.critical_time_step(mass[mob], settings.contact.kn)}
    if ties is not None:
        out["ties"] = lim.tie_limit(ties, mass)
    if pores is not None:
        net, m, water = pores
        M = settings.numerics.water_interval
        out["water_stiffness"] = lim.water_stiffness_limit(net, m.void_area, packing.r, settings.water.E_w, mass,
                                                           mob) / M
        out["darcy"] = lim.darcy_eigen_limit(water, m.void_area, m.link_contact) / M
        out["darcy_check"] = water.darcy_limit(m.void_area, m.link_contact) / M
    return out


def check_start(settings, packing, mass, ties, lims):
    """Refuse (ValueError, one line naming the field and the limit) [water] l_m outside
    pores.LINK_RANGE x the median radius or below [contact] eps_m, and settings whose numeric dt is
    above a limit at its start (``lims``, of ``limits``): eq 52 x dt_safety, the ties, the water
    stiffness, and a water step water_interval x dt above the Darcy check without [water] substep,
    or needing more than [water] max_substeps sub-steps with it."""
    num, w = settings.numerics, settings.water
    lim.check_contact(num.dt, num.dt_safety, mass[packing.mobile], settings.contact.kn)
    lim.check_ties(num.dt, ties, mass)
    if not w.enabled:
        return
    pg.check_lengths(w.l_m, settings.contact.eps_m, packing.r, ("[water] l_m", "[contact] eps_m"))
    lim.check_water_stiffness(num.dt, num.water_interval * lims["water_stiffness"], w.E_w, num.water_interval)
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
