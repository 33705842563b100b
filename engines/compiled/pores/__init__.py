"""Compiled (numba) kernels of the pore rebuild: the network of engines.model.pores.build_pores and
the re-meshing of engines.model.pore_water.PoreWater.remesh. No YADE.

Each kernel repeats, loop by loop, the arithmetic of a readable NumPy function, which stays the
reference path and is tested against it (tests/compiled/test_pores.py: integer arrays equal, floats
to 1e-12 relative). The modules are the twins of engines.model.pores' (twin of model.pores.X:
compiled.pores.X), and remesh those of engines.model.pore_water:

  triangulation.lifted_points      triangulation._lifted_points     the points of the regular triangulation's hull
  triangulation.lower_ccw          triangulation._lower_triangles   the lower hull facets, counter-clockwise
  links.missing_pairs              links._missing_pairs             the eq 28 pairs that are no edge
  faces.faces                      faces._faces                     neighbours, eq 28 links, faces (a union-find
                                                                    over triangles across non-link edges), eq 29
  faces.links_and_corners          faces._links_and_corners         links, throats, surface, vertex sets, the
                                                                    half-edge walk, corner angles (eq 29)
  remesh.near_vertex_sets          pore_water.near_vertex_sets      rule (b): old vertex sets that contain or are
                                                                    contained in a new one
  remesh.spread_to_neighbours      pore_water.spread_to_neighbours  rule (c)
  overlaps.pore_overlaps           overlaps.pore_overlaps           overlap areas of old and new pores (clipping
                                                                    as overlaps._clip_areas)

Flat walls (engines.model.flat_walls): the kernels run over the discs and the wall vertices, with
the links of flat_walls.WallVertices.is_link (``links._is_link``, from the vertices' owner and bits).

Numbering follows the NumPy functions (pores in the order of their first triangle, links by (i, j),
half-edges sorted by disc then angle), so the networks are the same array for array. Sorting is by
counting sort over discs or pores and insertion sort of the few entries of each (the sorts of the
NumPy path cost more than the rest at these sizes); pairs are found on grids of cells. Sums that
NumPy makes in another order (means of rules (b), (c), overlap sums) agree to round-off. numba
compiles on first use and caches the machine code (``cache=True``, engines.compiled.cache); fastmath is off.

``BUILD`` and ``REMESH`` are these kernels as the steps of engines.model.pores.build_pores and
engines.model.pore_water.PoreWater.remesh (``steps=``), what the compiled WaterModel uses. BUILD
triangulates by engines.compiled.regular where that is certain (the same triangles as the hull's,
without Qhull), else by the hull.
"""
import numpy as np

from engines.compiled import regular
from engines.compiled.pores.faces import faces, links_and_corners
from engines.compiled.pores.links import missing_pairs
from engines.compiled.pores.overlaps import pore_overlaps
from engines.compiled.pores.remesh import near_vertex_sets, spread_to_neighbours
from engines.compiled.pores.triangulation import lifted_points, lower_ccw
from engines.model import pore_water
from engines.model import pores as pg

NO_WALL_VERTICES = np.zeros(0, np.int64)  # owner and bits of links._is_link without flat walls


def _lifted_points(xz, r):
    return lifted_points(xz, r, xz.mean(axis=0))


def _lower_triangles(hull, n, xz):
    tri = lower_ccw(hull.simplices, hull.equations[:, 2], n, xz, pg.LOWER_FACET_TOL)
    return regular.canonical(tri) if len(tri) else None


def _certain_triangles(xz, r):
    answer, tri = regular.regular_triangles(np.ascontiguousarray(xz, float), np.ascontiguousarray(r, float))
    if answer == regular.UNSURE:
        return False, None
    return True, (tri if answer == regular.DONE else None)


def _wall_rule(wall_vertices, n):
    """The arguments (owner, bits, n_discs) of ``_is_link`` for the flat_walls.WallVertices of n
    vertices (None: n discs)."""
    if wall_vertices is None:
        return NO_WALL_VERTICES, NO_WALL_VERTICES, n
    return wall_vertices.owner, wall_vertices.bits, wall_vertices.n


def _missing_pairs(xz, r, reach, tri, wall_vertices=None):
    return missing_pairs(xz, r, float(reach), tri, *_wall_rule(wall_vertices, len(r)))


def _faces(xz, r, tri, reach, a_min, wall_vertices=None):
    return faces(xz, r, tri, float(reach), a_min, *_wall_rule(wall_vertices, len(r)))


def _near_vertex_sets(old_net, U_old, old_valid, new_net, todo):
    n_vertices = new_net.n_discs + len(new_net.flat_walls)  # flat wall w is vertex N + w of the sets
    return near_vertex_sets(old_net.pore_vertex_ptr, old_net.pore_vertex_idx, np.asarray(old_valid, bool),
                            new_net.pore_vertex_ptr, new_net.pore_vertex_idx, todo, U_old, n_vertices)


def _pore_overlaps(old_net, new_net, xz):
    return pore_overlaps(old_net.tri, old_net.tri_pore, new_net.tri, new_net.tri_pore,
                         pg.vertex_positions(old_net, xz), new_net.n_pores)


BUILD = pg.BuildSteps(_lifted_points, _lower_triangles, _missing_pairs, _faces, links_and_corners, _certain_triangles)
REMESH = pore_water.RemeshSteps(_pore_overlaps, _near_vertex_sets, spread_to_neighbours)
