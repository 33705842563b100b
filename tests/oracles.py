"""Independent computations the tests compare the code with (slow, readable; not used by the code)."""
import numpy as np

from engines.model import pores as pg
from engines.model.pores import faces
from engines.model.ground_motion import BaseMotion


# -- pores (engines.model.pores) ----------------------------------------------------------------------
def void_area_by_triangles(net, xz, r):
    """Void area per pore from its triangles, an independent route to ``pores.measure`` (eq 29)."""
    area, sectors = faces._triangle_void(xz, r, net.tri)
    return np.bincount(net.tri_pore, area - sectors, minlength=net.n_pores)


def pore_polygon(net, p):
    """Ordered vertex discs of pore ``p``, one list per boundary cycle, counter-clockwise.

    The walk is the paper's: from a link, at each disc turn to the next link clockwise. A pore
    with an island of linked discs inside it has more than one cycle; the longest comes first.
    """
    todo = set(np.flatnonzero(net.he_left == p).tolist())
    cycles = []
    while todo:
        h0 = todo.pop()
        cycle, h = [int(net.he_org[h0])], int(net.he_next[h0])
        while h != h0:
            todo.discard(h)
            cycle.append(int(net.he_org[h]))
            h = int(net.he_next[h])
        cycles.append(cycle)
    return sorted(cycles, key=len, reverse=True)


def interior_angles(net, meas):
    """Interior angle of each pore at each of its linked vertex discs [rad] (eq 29), from the
    corners of ``pores.measure``: {pore: {disc: angle}}; a disc met twice on the walk (a pinch)
    gets the sum."""
    out = {p: {} for p in range(net.n_pores)}
    for p, v, t in zip(net.corner_pore.tolist(), net.corner_disc.tolist(), meas.corner_angle.tolist()):
        out[p][v] = out[p].get(v, 0.0) + t
    return out


# -- the driven base (engines.model.ground_motion) -----------------------------------------------------
def base_history(accel, dt, n_steps):
    """Times t_n, accelerations, velocities [m/s] and displacements [m] (n_steps + 1 each) of the
    base from rest, stepped by ``BaseMotion``."""
    bm = BaseMotion(accel, dt)
    out = np.empty((n_steps + 1, 4))
    out[0] = bm.t, bm.acc, bm.vel, bm.disp
    for n in range(1, n_steps + 1):
        bm.step()
        out[n] = bm.t, bm.acc, bm.vel, bm.disp
    return out.T


# -- side-wall ties (engines.model.side_walls.SideWallTies) -------------------------------------------
def tie_energy(ties, x):
    """Elastic energy of the ties (k'_s / 2) sum stretch^2 [J per m] at x positions (N,) [m]."""
    s = (x[ties.upper] - x[ties.lower]) - ties.rest
    return 0.5 * ties.ks * float(np.sum(s * s))


def tie_dissipation_rate(ties, vx):
    """Power taken by the dashpots eta'_s sum (v_u - v_l)^2 [W per m] (>= 0) at x velocities (N,)."""
    dv = vx[ties.upper] - vx[ties.lower]
    return ties.eta * float(np.sum(dv * dv))


# -- stresses of a disc assembly (seed 003, engines.seeds.biaxial) ------------------------------------
def love_stress(force, branch, area):
    """Mean stress (2, 2) [Pa], compression positive: (1/A) sum f (x) l over contacts, f the force on
    the second disc [N/m], l the branch vector from the first to the second centre [m]."""
    return np.einsum("ci,cj->ij", np.asarray(force, float), np.asarray(branch, float)) / area


def section_stress(xz1, branch, force, axis, at, cell):
    """The paper's sigma_x (axis 0) or sigma_z (axis 1) (seed 003 §2(1)): the components along
    ``axis`` of the contact forces acting across the line ``axis`` = ``at``, summed and divided by
    the line's length [Pa], compression positive. Periodic cell (Lx, Lz): a branch from a centre in
    the cell crosses the line or one of its images. xz1: first centres (n, 2), branch: (n, 2) to
    the second centre, force: (n, 2) on the second disc."""
    a = np.asarray(xz1, float)[:, axis]
    b = a + np.asarray(branch, float)[:, axis]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    period, length = cell[axis], cell[1 - axis]
    crosses = np.zeros(len(a), bool)
    for k in (-1, 0, 1):
        crosses |= (lo < at + k * period) & (hi >= at + k * period)
    f = np.asarray(force, float)[:, axis] * np.sign(b - a)
    return float(np.sum(f[crosses]) / length)


def contact_arrays():
    """YADE's real contacts as arrays: ids (n, 2), contact force on the second body (n, 2) [N/m] in
    (x, z), and the branch vector from the first to the second centre (n, 2) [m] including the
    periodic shift. The force is YADE's stored normal + shear force (as utils.getStress uses):
    the viscous part of the shear force of a sticking contact is not stored, which at rest is
    nothing. Needs YADE."""
    from yade import O

    ids, force, branch = [], [], []
    periodic = O.periodic
    h = O.cell.hSize if periodic else None
    for i in O.interactions:
        if not i.isReal:
            continue
        f = i.phys.normalForce + i.phys.shearForce
        p1, p2 = O.bodies[i.id1].state.pos, O.bodies[i.id2].state.pos
        d = p2 - p1
        if periodic:
            d = d + h * i.cellDist
        ids.append((i.id1, i.id2))
        force.append((f[0], f[2]))
        branch.append((d[0], d[2]))
    return (np.array(ids, np.int64).reshape(-1, 2), np.array(force, float).reshape(-1, 2),
            np.array(branch, float).reshape(-1, 2))
