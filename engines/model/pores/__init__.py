"""Pore polygons between discs (seed 000 §3.1, SPEC §2.2). Pure NumPy/SciPy, no YADE.

Vocabulary (per unit thickness, SI): discs have centres ``xz`` (N, 2) [m] and radii ``r`` (N,) [m].

* A *link* joins two discs i, j when r_i + r_j + eps_m + l_m >= R_ij (eq 28). Candidates are the
  edges of a triangulation of the centres, so links never cross and the link graph is planar.
  The triangulation is the regular (radius-weighted, power) triangulation: the lower convex hull
  of the lifted points (x, z, x^2 + z^2 - r^2), its triangles in a canonical order
  (``canonical_triangles``), so that networks are numbered alike however it was found. Where one
  of its edges that is not a link hides an eq 28 pair (the other diagonal of a quadrilateral,
  which a Delaunay or regular triangulation can leave out at a long l_m), that pair is put in by
  edge flips (``insert_missing_links``), so that *every eq 28 pair that crosses no link is a
  link*; of two such pairs that cross each other, the one with the smaller gap R - r_i - r_j is
  put in first.
* A *pore* is a bounded face of the link graph. It is stored as the set of triangles that lie in
  it (triangles joined across non-link edges). The unbounded outer face is not a pore.
* Void area A = polygon area - sum of the disc sectors theta * r^2 / 2 inside it (eq 29); overlaps
  are neglected, as in the paper. The pore's boundary is walked as in the paper (turn clockwise at
  each disc) at the build, which gives each corner its interior angle theta0; a rattler inside a
  pore (a disc without links) is subtracted whole. Each step, both areas are sums over the pore's
  boundary links (``measure``): the polygon area the shoelace sum, and the sectors their build-time
  area plus the links' turns since the build, each corner's angle having changed by the
  difference of its two links' turns (eq 29 telescoped over links, as eq 33 is). The tests check
  these areas against the pore's triangles.
* The pressure force of eq 33 on the arc of a disc inside a pore, summed over the pores around the
  disc, telescopes to a sum over the disc's links of (U_right - U_left) * r * perp(u_link):
  a uniform pressure gives exactly zero net force.
* Flat walls (engines.model.flat_walls, SPEC §2.6) add zero-radius vertices on the faces: the feet of
  the discs linked to a wall and the corners of two walls. The link arrays index these vertices
  after the N discs (``vertex_positions``); the pores' vertex sets count each wall as one vertex.

Every step of a build but qhull (``BuildSteps``), and of the re-meshing in engines.model.pore_water, has
a compiled twin in engines.compiled.pores (``steps=engines.compiled.pores.BUILD``, what the water engine
uses), tested to give the same network.

Degenerate pores: a face whose void area is <= ``a_min`` when the pores are built is *closed*: it is
not a pore (no water, U = 0). ``a_min = degenerate_fraction * mean(pi r^2)``.
Fewer than three discs or collinear centres give a network with no pores. A disc whose power cell
is empty (a small disc deep inside a larger one) is not a vertex of the regular triangulation: it
gets no links and counts as a rattler of the pore that contains its centre.

The modules, one concept each (the names below are this package's public ones):

  network        PoreNetwork, PoreMeasures, OUTER, FLAT_VERTEX, CHECKPOINT_SHAPES
  checks         check_discs, check_lengths, check_finite_array, check_nonnegative
  triangulation  the regular triangulation's NumPy steps, canonical_triangles, point location
  links          eq28_pairs, the edge flips that put in the eq 28 pairs a triangulation hides
  faces          the faces of the link graph (pores, eq 29 closing), links, throats, surface,
                 vertex sets and the paper's walk (``_links_and_corners``)
  build          build_pores, regular_triangulation, insert_missing_links, BuildSteps, NUMPY_BUILD
  measure        measure (eq 29, 43b), pressure_forces (eq 33), the flat walls' forces, vertices
  overlaps       pore_overlaps: the re-meshing's water-conserving transfer
"""
from engines.model.groups import LAST_GROUP, WALL_BOTTOM, WALL_CODES, WALL_LEFT, WALL_NAMES, WALL_NONE, WALL_RIGHT  # noqa: F401
from engines.model.pores.build import (BuildSteps, NUMPY_BUILD, build_pores, insert_missing_links,  # noqa: F401
                                       regular_triangulation)
from engines.model.pores.checks import LINK_RANGE, check_discs, check_finite_array, check_lengths, check_nonnegative  # noqa: F401
from engines.model.pores.faces import NetworkArrays  # noqa: F401
from engines.model.pores.links import eq28_pairs  # noqa: F401
from engines.model.pores.measure import (WallReactions, flat_wall_forces, measure, pore_centroids,  # noqa: F401
                                         pressure_forces, vertex_positions, vertex_radii, wall_edges, wall_reactions)
from engines.model.pores.network import CHECKPOINT_SHAPES, FLAT_VERTEX, OUTER, PoreMeasures, PoreNetwork  # noqa: F401
from engines.model.pores.overlaps import pore_overlaps  # noqa: F401
from engines.model.pores.triangulation import LOWER_FACET_TOL, canonical_triangles  # noqa: F401
