"""Examples a YADE user recognises: plain YADE scripts with the pore water added (docs/ENGINE.md).
Each ends with ``report``: the physical checks of its run, printed."""
import numpy as np


def report(water, grains, walls=None):
    """Print and return the checks of a run: the pores; the largest pore pressure U [N/m], which
    eq 32 keeps below E_w while the void areas are those of the current positions; the relative
    water balance error; the excess water the pore rebuilds changed as a fraction of the inflow,
    all of it and the part inside the region old and new pores both cover (WaterBalance: the
    transfer rule's own change); the grains (ids) whose centres left the box of the wall discs
    (walls: {"bottom"|"left"|"right": ids}) or, without them, of the engine's flat walls."""
    from yade import O
    net, U, w = water.model.water.net, water.pressures(), water.model.water
    b, inflow = w.balance, max(w.balance.inflow, 1e-300)
    xz = np.array([[O.bodies[i].state.pos[0], O.bodies[i].state.pos[2]] for i in grains])
    if walls:
        centre = {name: np.array([[O.bodies[i].state.pos[0], O.bodies[i].state.pos[2]] for i in ids])
                  for name, ids in walls.items()}
        outside = ((xz[:, 0] <= centre["left"][:, 0].max()) | (xz[:, 0] >= centre["right"][:, 0].min())
                   | (xz[:, 1] <= centre["bottom"][:, 1].max()))
    else:
        outside = np.any([wall.gap(xz, 0.0) <= 0 for wall in water.model.flat_walls], axis=0)
    checks = {"pores": net.n_pores, "rebuilds": water.model.n_rebuilds, "max_U": float(U.max()), "E_w": w.settings.E_w, "balance": w.balance_error(),
              "remesh": abs(b.remesh_excess_change) / inflow,
              "remesh_inside": abs(b.remesh_excess_change - b.remesh_excess_edge) / inflow, "outside": int(outside.sum())}
    print("checks: {pores} pores ({rebuilds} rebuilds), max U {max_U:.4g} N/m (E_w {E_w:g} N/m), water balance error {balance:.1e}, "
          "re-meshing {remesh:.1e} of the inflow ({remesh_inside:.1e} inside), {outside} grains outside the box".format(**checks))
    return checks


def wall_balance(water, grains, wall_ids, rho_w=1000.0, g=9.81):
    """Print and return the vertical load of the bed on the flat walls ``wall_ids`` (YADE's contact
    forces on them plus the water's push, WaterEngine.wall_forces) [N per m thickness] and the bed's
    buoyant weight sum (m - rho_w pi r^2) g; at rest the two balance up to the pressure the pores
    hold on their gaps between discs, which acts on no body."""
    from yade import O
    pushed = water.wall_forces()
    contact = -sum(O.forces.f(i)[2] for i in wall_ids)
    push = -sum(pushed[i][1] for i in wall_ids)
    buoyant = sum((O.bodies[i].state.mass - rho_w * np.pi * O.bodies[i].shape.radius ** 2) * g for i in grains)
    out = {"load": contact + push, "contact": contact, "water": push, "buoyant_weight": buoyant}
    print("walls: vertical load {load:.4g} N/m (contacts {contact:.4g}, water {water:.4g}), the bed's buoyant weight "
          "{buoyant_weight:.4g} N/m".format(**out))
    return out
