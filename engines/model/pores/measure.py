"""The pores at the current positions: their areas and the links' state (eq 29, 43b), the pressure
forces on the discs (eq 33) and on flat walls, and the vertices' positions and radii. No YADE."""
from typing import NamedTuple

import numpy as np

from engines.model.pores.network import PoreMeasures
from engines.model.pores.triangulation import _signed_area


def measure(net, xz, r):
    """Areas of the pores and state of the links at positions ``xz`` [m] (eq 29, 43).

    Sums over each pore's boundary links, the pore on the left of i->j taking + and the one on its
    right -: the polygon area, the shoelace sum of x_i z_j - x_j z_i over 2; the sector area, the
    build-time one (sector_area0) plus link_turn_weight times the link's turn since the build
    (from ``link_vec0``). The same sectors as the interior angle of each corner (eq 29), the
    build-time angle plus the difference of its two links' turns, given as corner_angle (valid
    while no corner turns by pi between rebuilds). Flat walls: their vertices are placed from the
    discs (``vertex_positions``), with radius 0.
    """
    xz, r = vertex_positions(net, xz), vertex_radii(net, r)
    i, j = net.links[:, 0], net.links[:, 1]
    x, z = np.ascontiguousarray(xz[:, 0]), np.ascontiguousarray(xz[:, 1])
    xi, zi = x[i], z[i]
    dx, dz = x[j] - xi, z[j] - zi
    length = np.sqrt(dx * dx + dz * dz)
    d0 = net.link_vec0
    turn = np.arctan2(d0[:, 0] * dz - d0[:, 1] * dx, d0[:, 0] * dx + d0[:, 1] * dz)
    cross = xi * dz - dx * zi  # x_i z_j - x_j z_i
    poly = 0.5 * _left_minus_right(net, cross)
    sect = net.sector_area0 + _left_minus_right(net, net.link_turn_weight * turn)  # eq 29
    theta = net.corner_theta0 + turn[net.corner_link] - turn[net.corner_next_link]  # eq 29
    contact = r[i] + r[j] + net.eps_m >= length  # eq 43b
    return PoreMeasures(poly, sect, poly - sect, length, contact, theta, np.column_stack([dx, dz]))


def _left_minus_right(net, v):
    """(Np,): the sum of v (L,) over the links with the pore on their left less that over the links
    with the pore on their right."""
    left, right = net.link_pores[:, 0], net.link_pores[:, 1]
    return (np.bincount(left[left >= 0], v[left >= 0], minlength=net.n_pores)
            - np.bincount(right[right >= 0], v[right >= 0], minlength=net.n_pores))


def pressure_forces(net, r, U, meas):
    """Force of the pore pressures U (Np,) [N/m] on every disc (N, 2) [N per m thickness] (eq 33).

    Summing eq 33 over the pores around disc a gives, per link a-b with unit vector u = (b - a)/R,
    F_a += r_a (U_right - U_left) perp(u), perp(u) = (-u_z, u_x), and the same for b with r_b.
    The outer face and closed faces have U = 0. No torque (pressure acts through the centre).
    ``meas`` is the PoreMeasures of the current positions. The wall vertices of flat walls have
    r = 0 and take nothing here: their wall edges' force is ``flat_wall_forces``.
    """
    r = vertex_radii(net, r)
    n = len(r)
    F = np.zeros((n, 2))
    Uo = np.append(np.asarray(U, float), 0.0)  # index OUTER (-1) -> 0
    i, j = net.links[:, 0], net.links[:, 1]
    s = (Uo[net.link_pores[:, 1]] - Uo[net.link_pores[:, 0]]) / meas.link_length
    px, pz = -meas.link_vector[:, 1] * s, meas.link_vector[:, 0] * s
    ri, rj = r[i], r[j]
    F[:, 0] = np.bincount(i, ri * px, minlength=n) + np.bincount(j, rj * px, minlength=n)
    F[:, 1] = np.bincount(i, ri * pz, minlength=n) + np.bincount(j, rj * pz, minlength=n)
    return F[:net.n_discs]


def flat_wall_forces(net, U, meas):
    """Normal force (W,) [N per m thickness] of the pore pressures U (Np,) [N/m] on each flat wall,
    positive when it pushes the wall outward (away from the discs; SPEC §2.6): the sum over the
    wall's edges of U x edge length. A wall edge lies on the face, so its outer side is the outer
    face (U = 0) and U of its pore is the sum over both sides. ``meas``: PoreMeasures."""
    k, w = wall_edges(net)
    Uo = np.append(np.asarray(U, float), 0.0)  # index OUTER (-1) -> 0
    U_edge = Uo[net.link_pores[k, 0]] + Uo[net.link_pores[k, 1]]
    return np.bincount(w, U_edge * meas.link_length[k], minlength=len(net.flat_walls))


def wall_edges(net):
    """The wall edges of the flat walls of ``net``: (link indices (K,), their wall (K,)), a link
    once per wall it lies on (empty without flat walls)."""
    wv = net.wall_vertices
    if wv is None:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return wv.split_bits(wv.bits[net.links[:, 0]] & wv.bits[net.links[:, 1]])


class WallReactions(NamedTuple):
    """Normal forces (W,) [N per m thickness] on the flat walls, positive pushing a wall outward
    (the wall's reaction on the bed is the same along its inward normal)."""

    total: np.ndarray  # the water's part plus the discs' contact forces
    water: np.ndarray  # flat_wall_forces: the pore pressures on the wall edges


def wall_reactions(net, U, meas, contact):
    """WallReactions of the flat walls of ``net`` at pore pressures U (Np,) [N/m] (PoreMeasures
    ``meas``), ``contact`` (W,) [N/m] the normal force of the discs' contacts on each wall (from
    the DEM's contact law, positive pushing the wall outward)."""
    water = flat_wall_forces(net, U, meas)
    return WallReactions(water + np.asarray(contact, float), water)


def vertex_positions(net, xz):
    """Positions [m] of the network's vertices: the discs' xz (N, 2), then the flat walls' vertices
    (flat_walls.WallVertices.positions)."""
    return xz if net.wall_vertices is None else net.wall_vertices.positions(xz)


def vertex_radii(net, r):
    """Radii [m] of the network's vertices: the discs' r (N,), then 0 for the flat walls' vertices."""
    return r if net.wall_vertices is None else net.wall_vertices.radii(r)


def pore_centroids(net, xz):
    """Area-weighted centroid of each pore polygon (Np, 2) [m]."""
    xz = vertex_positions(net, xz)
    p = xz[net.tri]
    area = _signed_area(p)
    c = p.mean(axis=1)
    w = np.bincount(net.tri_pore, area, minlength=net.n_pores)
    cx = np.bincount(net.tri_pore, area * c[:, 0], minlength=net.n_pores)
    cz = np.bincount(net.tri_pore, area * c[:, 1], minlength=net.n_pores)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.column_stack([cx / w, cz / w])
