"""The pores as a pore network in OpenPNM's vocabulary: one read of a water model at given centres.

``pore_network(water, xz)`` gives a flat dict of arrays (units per metre of thickness, the x-z plane
as OpenPNM's x-z with y = 0):

* ``pore.coords`` (Np, 3) [m]: each pore's area-weighted centroid (x, 0, z);
* ``pore.pressure`` U [N/m] (eq 32), ``pore.water`` W [m^2], ``pore.area`` the void area A [m^2]
  (eq 29), ``pore.polygon_area`` [m^2];
* the boundaries each pore touches, (Np,) bool: ``pore.surface`` (free surface), ``pore.bottom``,
  ``pore.left``, ``pore.right`` (a disc of that wall group), ``pore.flat_wall_<w>`` (flat wall w
  of the model's flat_walls, in their order), and as the water sees them: ``pore.inflow``,
  ``pore.drained``, ``pore.undrained`` (touching a wall that passes no water);
* the boundary flows (Np,) [m^2/s]: ``pore.inflow_flux`` (in), ``pore.surface_flux`` and
  ``pore.side_flux`` (out, drained walls);
* ``throat.conns`` (Nt, 2) pore pairs, ``throat.conductance`` g [m^3/(N s)] and ``throat.flux``
  q = g (U_i - U_j) [m^2/s] from conns[:, 0] to conns[:, 1] (eq 38-43, at these areas: no
  smoothing of eq 45-46);
* each pore's outline polygon, in CSR form (not OpenPNM's: not per pore): ``polygon.xz`` (S, 2)
  [m], the boundary vertices in order (disc centres, and on flat walls the discs' feet and the
  corners), pore p's rows ``polygon.ptr[p]:polygon.ptr[p + 1]`` (``polygons(net)`` lists them),
  and ``polygon.vertex`` (S,) the vertices' ids (the discs, then the flat walls' vertices:
  engines.model.pores.vertex_positions);
* the water balance since the start [m^2]: ``balance.<field>`` of WaterBalance and
  ``balance.error`` (relative), 0-d arrays.

The snapshots of a run write the same keys (engines.run.runner.snapshot_data); ``openpnm(net)``
keeps the ``pore.*`` and ``throat.*`` arrays, the dict OpenPNM's ``Network.update`` takes.
"""
import dataclasses

import numpy as np

from engines.model import pore_water
from engines.model import pores as pg

OPENPNM_PREFIXES = ("pore.", "throat.")


def _outline(net, p, half_edges, xz):
    """The vertex ids of pore p's outer boundary: of the cycles of its half-edges ``half_edges``
    (followed by he_next), the one of the largest area (an island of linked discs inside a pore
    makes a second cycle)."""
    left = set(half_edges.tolist())
    best, best_area = [], -1.0
    while left:
        h = min(left)
        cycle = []
        while h in left:
            left.discard(h)
            cycle.append(int(net.he_org[h]))
            h = int(net.he_next[h])
        x, z = xz[cycle].T
        area = abs(float(np.sum(x * np.roll(z, -1) - np.roll(x, -1) * z)))
        if area > best_area:
            best, best_area = cycle, area
    return best


def polygon_csr(net, xz):
    """(ptr (Np+1,), vertex ids (S,)) of each pore's outline (module docstring), indices into
    pg.vertex_positions(net, xz)."""
    vertices = pg.vertex_positions(net, xz)
    h = np.flatnonzero(net.he_left >= 0)
    order = h[np.argsort(net.he_left[h], kind="stable")]
    bounds = np.searchsorted(net.he_left[order], np.arange(net.n_pores + 1))
    outlines = [_outline(net, p, order[bounds[p]:bounds[p + 1]], vertices) for p in range(net.n_pores)]
    ptr = np.concatenate([[0], np.cumsum([len(o) for o in outlines])]).astype(np.int64)
    idx = np.concatenate(outlines).astype(np.int64) if outlines else np.zeros(0, np.int64)
    return ptr, idx


def pore_network(water, xz=None):
    """The network dict (module docstring) of ``water`` — a WaterModel, or an object holding one
    as ``model`` (a WaterEngine) — at the discs' centres xz (N, 2) [m] (default: the engine's
    bodies now, ``water.io.positions()``)."""
    model = getattr(water, "model", water)
    if xz is None:
        xz = water.io.positions()
    xz = np.asarray(xz, float)
    pw, net = model.water, model.water.net
    m = pg.measure(net, xz, model.r)
    A = m.void_area
    fl = pw.flows(A, m.link_contact)
    masks = pore_water.boundary_masks(net, pw.settings.sides)
    surface, drained, inflow, undrained = (masks[w] for w in ("surface", "drained", "inflow", "undrained"))
    touches = {name: np.asarray(net.pore_touches[name], bool) for name in pg.WALL_NAMES.values()}
    walls = {f"pore.flat_wall_{w}": np.asarray(net.pore_walls[w], bool) for w in range(len(net.flat_walls))}
    c = pg.pore_centroids(net, xz)
    ptr, idx = polygon_csr(net, xz)
    out = {"pore.coords": np.column_stack([c[:, 0], np.zeros(len(c)), c[:, 1]]),
           "pore.pressure": pw.pressure(A), "pore.water": pw.W.copy(), "pore.area": A,
           "pore.polygon_area": m.polygon_area,
           "pore.surface": np.asarray(surface, bool), **{f"pore.{k}": v for k, v in touches.items()}, **walls,
           "pore.inflow": np.asarray(inflow, bool), "pore.drained": np.asarray(drained, bool),
           "pore.undrained": np.asarray(undrained, bool),
           "pore.inflow_flux": np.asarray(fl.inflow_q, float), "pore.surface_flux": fl.surface_q,
           "pore.side_flux": fl.side_q,
           "throat.conns": np.asarray(net.throat_conns, np.int64).reshape(-1, 2), "throat.conductance": fl.g,
           "throat.flux": fl.throat_q,
           "polygon.ptr": ptr, "polygon.vertex": idx, "polygon.xz": pg.vertex_positions(net, xz)[idx]}
    out.update({f"balance.{k}": np.array(float(v)) for k, v in dataclasses.asdict(pw.balance).items()})
    out["balance.error"] = np.array(pw.balance_error())
    return out


def polygons(network):
    """The outline of each pore of a network dict (``pore_network`` or a snapshot's), a list of (n, 2) arrays [m]."""
    ptr, xz = network["polygon.ptr"], network["polygon.xz"]
    return [xz[ptr[p]:ptr[p + 1]] for p in range(len(ptr) - 1)]


def openpnm(network):
    """The ``pore.*`` and ``throat.*`` arrays of a network dict: OpenPNM's dict layout."""
    return {k: v for k, v in network.items() if k.startswith(OPENPNM_PREFIXES)}
