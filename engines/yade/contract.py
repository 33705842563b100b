"""What the WaterEngine needs of a YADE scene, checked: each broken rule is refused in one line
naming the body id (``ContractError``), and ``set_disc_mass`` gives a sphere the mass it needs.

The rules (docs/ENGINE.md):

* every body of ``disc_ids`` exists (an erased one is refused with the remedy), is listed once, is a
  sphere (a YADE Box or Wall belongs in ``flat_walls``, engines.yade.walls) and is no clump nor a
  clump's member (a clump moves its members as one body);
* the scene is not periodic (``check_scene``);
* gravity is read from the NewtonIntegrator in O.engines (``gravity_of``; none there and no
  ``gravity=`` is refused; a y component is refused);
* the discs lie in one plane y = const (the median y of the discs, to 1e-6 of each radius) and stay
  there: every dynamic disc has y among its blockedDOFs, and no disc has a velocity along y;
* the masses are per metre of thickness (SPEC §1): m = f rho pi r^2 with rho the density of the
  body's material and f its density factor (the paper's dense top discs: f = 5 and 10). A dynamic
  disc with m < MIN_FACTOR rho pi r^2 is refused; YADE's own 3D sphere mass 4/3 pi r^3 rho is
  4/3 r [m] of that (6.7e-4 at r = 0.5 mm), the message says when the mass is that one. A disc free
  to spin about y needs I_y >= MIN_FACTOR m r^2 / 2 (the disc's m r^2/2, eq 15; YADE's sphere
  inertia 2/5 m r^2 with its 3D mass is far below);
* a drained flat wall needs k3 > 0 (``check_flat_boundaries``);
* q_w > 0 needs an inflow boundary: a pore with a bottom wall disc or an inflow flat wall as a vertex;
* the discs build pores;
* O.dt may change between steps: the engines' models follow it (``follow_dt``) before their next
  step, their limits checked again;
* bodies are not added after the engine is made (refused at its next pore rebuild, ``check_added``);
  an erased disc is refused by the next read of the positions (engines.yade.yade_io), which names it.
"""
import math

import numpy as np

from engines.model import groups
from engines.model.pore_water import boundary_masks

MIN_FACTOR = 0.5  # the smallest accepted m / (rho pi r^2) and I_y / (m r^2 / 2) of a dynamic disc


class ContractError(ValueError):
    """A scene the WaterEngine cannot take; the message names the body and what is wrong."""


def set_disc_mass(body, rho, factor=1.0, r=None):
    """Per-thickness mass m = factor rho pi r^2 [kg/m] and inertia m r^2 / 2 [kg m] (SPEC §1,
    eq 15) of the YADE sphere ``body`` of radius r (default its shape's radius)."""
    r = body.shape.radius if r is None else r
    body.state.mass = factor * rho * math.pi * r**2
    body.state.inertia = (0.5 * body.state.mass * r**2,) * 3


def check_discs(bodies, ids, radii=None):
    """Refuse the bodies ``ids`` of O.bodies ``bodies`` that are not discs of the engine (the rules
    above), with radii (n,) [m] the true ones (None: the spheres'). Returns the radii."""
    found, seen = [], set()
    for i in ids:
        if i in seen:
            raise ContractError(f"body {i}: listed twice in disc_ids (each disc bounds the pores once; drop the "
                                f"repeats, e.g. disc_ids = sorted(set(disc_ids)))")
        seen.add(i)
        b = bodies[i] if 0 <= i < len(bodies) else None
        if b is None:
            raise ContractError(f"body {i}: not in O.bodies (erased, or never made): disc_ids must be existing "
                                f"spheres; drop it, e.g. disc_ids = [i for i in disc_ids if O.bodies[i]]")
        shape = type(b.shape).__name__
        if shape in ("Box", "Wall"):
            raise ContractError(f"body {i}: a YADE {shape} in disc_ids, which takes spheres only; give it as a flat "
                                f"wall: flat_walls={{{i}: {' | '.join(map(repr, groups.words()))}}}")
        if b.isClump or b.isClumpMember:
            check_clump(bodies, i, b)
        if shape != "Sphere":
            raise ContractError(f"body {i}: a {shape}, not a sphere (disc_ids must be spheres)")
        found.append(b)
    if radii is None:
        radii = [b.shape.radius for b in found]
    y = np.array([b.state.pos[1] for b in found])
    plane = float(np.median(y)) if len(y) else 0.0
    for i, b, yi, r in zip(ids, found, y.tolist(), radii):
        if abs(yi - plane) > 1e-6 * r:
            raise ContractError(f"body {i}: centre at y = {yi:.6g} m, off the plane y = {plane:.6g} m of the discs "
                                f"(the WaterEngine works in the x-z plane: put every disc at the same y)")
        if b.state.vel[1] != 0:
            raise ContractError(f"body {i}: velocity {b.state.vel[1]:.3g} m/s along y, out of the x-z plane")
        if b.dynamic:
            check_dynamic(i, b, r)
    return radii


def check_clump(bodies, i, b):
    """Refuse the clump or clump member b (id i): a clump moves its members as one body (its mass
    and inertia are the clump's, the members carry none of their own), so the pores' discs and the
    forces the engine writes on them would not be the bodies YADE moves."""
    c = b if b.isClump else bodies[b.clumpId]
    members = sorted(c.shape.members.keys()) if c is not None else []
    mass = f"{c.state.mass:.3g} kg" if c is not None else "unknown"
    what = f"clump {c.id if c is not None else b.clumpId}" if b.isClump else f"a member of clump {b.clumpId}"
    raise ContractError(f"body {i}: {what} (members {members[:6]}{' ...' if len(members) > 6 else ''}, the clump's "
                        f"mass {mass} moves them as one body): the WaterEngine moves each disc by its own mass and "
                        f"forces and takes no clumps; build the discs as single spheres (no O.bodies.appendClumped "
                        f"or clump()), or leave the clump's members out of disc_ids")


def check_scene(O):
    """Refuse a scene the engine cannot describe: a periodic cell (the pores are built in a plain
    box: the seam would be taken for a free surface)."""
    if O.periodic:
        raise ContractError("O.periodic is True: the WaterEngine builds its pores in a plain box and would take the "
                            "periodic seam for a free surface at U = 0 (periodic pores do not exist yet); bound the "
                            "discs with walls and set O.periodic = False")


def gravity_of(engines, given=None):
    """The gravity (gx, gz) [m/s^2] in the x-z plane: ``given`` [m/s^2] along -z when a number, else
    that of the NewtonIntegrator among ``engines`` (O.engines). Refuses a y component, and no
    integrator without ``given``."""
    if given is not None:
        return np.array([0.0, -float(given)])
    newton = newton_of(engines)
    if newton is None:
        raise ContractError("no NewtonIntegrator in O.engines to read gravity from (the WaterEngine adds buoyancy "
                            "rho_w pi r^2 g): put the NewtonIntegrator in O.engines before making the WaterEngine, "
                            "or give gravity=9.81 [m/s^2, along -z] (gravity=0: no buoyancy)")
    return plane_gravity(newton.gravity)


def newton_of(engines):
    """The NewtonIntegrator among ``engines``, or None."""
    return next((e for e in engines if type(e).__name__ == "NewtonIntegrator"), None)


def plane_gravity(g):
    """(gx, gz) [m/s^2] of a NewtonIntegrator's gravity g (3,); refuses a y component."""
    if g[1] != 0:
        raise ContractError(f"NewtonIntegrator gravity {tuple(g)} m/s^2 has a y component {g[1]:g}: the WaterEngine "
                            f"works in the x-z plane; set NewtonIntegrator(gravity=(gx, 0, gz))")
    return np.array([float(g[0]), float(g[2])])


def check_dynamic(i, b, r):
    """Refuse the dynamic disc b (id i, radius r) when free to leave the plane or not massed per
    metre of thickness."""
    s = b.state
    if "y" not in s.blockedDOFs:
        raise ContractError(f"body {i}: free to leave the x-z plane (blockedDOFs {s.blockedDOFs!r} lacks 'y'; "
                            f"use 'yXZ')")
    rho = b.material.density
    per_thickness = rho * math.pi * r**2
    if s.mass < MIN_FACTOR * per_thickness:
        looks = ("YADE's 3D sphere mass 4/3 pi r^3 rho" if math.isclose(s.mass, 4 / 3 * r * per_thickness, rel_tol=1e-3)
                 else f"{s.mass / per_thickness:.3g} x rho pi r^2")
        raise ContractError(f"body {i}: mass {s.mass:.3g} kg is {looks}; the WaterEngine's forces are per metre of "
                            f"thickness: m = f rho pi r^2 = {per_thickness:.3g} f kg/m (rho = {rho:g} of its material, "
                            f"f >= {MIN_FACTOR:g} its density factor; engines.yade.contract.set_disc_mass sets it)")
    if "Y" not in s.blockedDOFs and s.inertia[1] < MIN_FACTOR * 0.5 * s.mass * r**2:
        raise ContractError(f"body {i}: inertia I_y {s.inertia[1]:.3g} kg m below {MIN_FACTOR:g} x m r^2/2 = "
                            f"{MIN_FACTOR * 0.5 * s.mass * r**2:.3g} of a disc of its mass (engines.yade.contract."
                            f"set_disc_mass sets it)")


def check_pores(net, settings, n_discs, l_m):
    """Refuse a pore network ``net`` (engines.model.pores) without pores, or without an inflow
    boundary when settings.q_w > 0 or settings.inflow_velocity > 0."""
    if net.n_pores == 0:
        raise ContractError(f"no pores between the {n_discs} discs: the WaterEngine needs discs in the x-z plane that "
                            f"touch or lie within l_m = {l_m:g} m of each other")
    inflow = settings.q_w > 0 or settings.inflow_velocity > 0
    if inflow and not boundary_masks(net, settings.sides)["inflow"].any():
        given = (f"q_w = {settings.q_w:g} m^2/s per inflow pore" if settings.q_w > 0 else
                 f"inflow_velocity = {settings.inflow_velocity:g} m/s")
        raise ContractError(f"{given} but no pore has a bottom wall disc or an inflow flat wall as "
                            f"a vertex: the inflow needs walls={{'bottom': ids}} under the discs or "
                            f"flat_walls={{id: 'inflow'}} (or no inflow)")


def check_flat_boundaries(flat_walls, settings):
    """Refuse a "drained" flat wall with settings.k3 = 0 (it would pass no water)."""
    drained = [i for i, b in flat_walls.items() if b in groups.words() and groups.kind(b).water == "drained"]
    if drained and settings.k3 == 0:
        raise ContractError(f"body {drained[0]}: a drained flat wall with k3 = 0, which passes no water; set "
                            f"WaterSettings k3 > 0 [1/s] (the wall's permeability) or call it 'undrained'")


def check_added(bodies, n_bodies):
    """Refuse bodies added to O.bodies ``bodies`` since it held ``n_bodies`` slots."""
    added = [i for i in range(n_bodies, len(bodies)) if bodies[i] is not None]
    if added:
        raise ContractError(f"body {added[0]}: added after the WaterEngine was made; its discs are fixed at "
                            f"construction (add the bodies first, then make the WaterEngine)")


def follow_dt(model):
    """Before a step of an engine (PaperLawEngine, WaterEngine): when the script changed O.dt since
    the model's last step, ``model.set_dt(O.dt)`` (its dt-dependent quantities, its limits)."""
    from yade import O
    dt = O.dt
    if dt != model.dt:
        model.set_dt(dt)
