"""build_pores: the links (eq 28) and pores (§3.1) of discs, with or without flat walls, by the steps
of BuildSteps (NUMPY_BUILD here, engines.compiled.pores.BUILD compiled). No YADE."""
from typing import Callable, NamedTuple

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from engines.model import flat_walls as fw
from engines.model.groups import LAST_GROUP, WALL_NAMES, WALL_NONE
from engines.model.pores.checks import check_discs, check_nonnegative
from engines.model.pores.faces import _faces, _links_and_corners, _set_signatures
from engines.model.pores.links import _FlipTriangulation, _missing_pairs
from engines.model.pores.network import FLAT_VERTEX, OUTER, PoreNetwork, _empty_network
from engines.model.pores.triangulation import _lifted_points, _locate, _lower_triangles


class BuildSteps(NamedTuple):
    """The parts of ``build_pores`` that have compiled twins (engines.compiled.pores.BUILD), and a
    triangulation that spares the hull where it is certain (none in NumPy: the hull always)."""

    lifted_points: Callable      # (xz, r) -> the hull's points (N + 1, 3), or None
    lower_triangles: Callable    # (hull, n, xz) -> the lower facets (canonical_triangles), or None
    missing_pairs: Callable      # as _missing_pairs
    faces: Callable              # as _faces
    links_and_corners: Callable  # as _links_and_corners
    certain_triangles: Callable = None  # (xz, r) -> (True, regular_triangulation's answer) or (False, None)


NUMPY_BUILD = BuildSteps(_lifted_points, _lower_triangles, _missing_pairs, _faces, _links_and_corners)


def regular_triangulation(xz, r, steps=None):
    """Counter-clockwise triangles (T, 3) of the regular (power) triangulation of the discs, or None.

    The lower convex hull of the lifted points (x, z, x^2 + z^2 - r^2) (centred and scaled by the
    extent of the centres), one triangle per hull facet whose outward normal points down. An extra
    point lifted above all others, at the centroid, is never on the lower hull; it makes a 3D hull
    of three discs or of lifted points that lie in one plane (cocircular equal discs). Collinear
    centres stay flat: None. Discs whose power cell is empty are in no triangle. ``steps``:
    BuildSteps (default NUMPY_BUILD); with its certain_triangles (engines.compiled.pores.BUILD),
    the hull is built only where that answers it is not certain. The triangles in the order of
    ``canonical_triangles``.
    """
    steps = steps or NUMPY_BUILD
    n = len(xz)
    if n < 3:
        return None
    if steps.certain_triangles is not None:
        certain, tri = steps.certain_triangles(xz, r)
        if certain:
            return tri
    points = steps.lifted_points(xz, r)
    if points is None:
        return None
    try:
        hull = ConvexHull(points)
    except QhullError:
        return None
    return steps.lower_triangles(hull, n, xz)


def insert_missing_links(xz, r, tri, reach, steps=None, wall_vertices=None):
    """Make every eq 28 pair between triangulation vertices that crosses no link an edge (and so a
    link), by edge flips, the pairs in order of their gap R - r_i - r_j (then of their indices).
    Only edges that are not links are flipped, so no link is lost.

    Returns (tri, number of pairs inserted). ``reach`` = eps_m + l_m [m]; ``steps``: BuildSteps
    (default NUMPY_BUILD); ``wall_vertices``: the flat_walls.WallVertices of xz, r (their links).
    """
    wv = wall_vertices
    missing = (steps or NUMPY_BUILD).missing_pairs(xz, r, reach, tri, wv)
    if not len(missing):
        return tri, 0
    d = xz[missing[:, 1]] - xz[missing[:, 0]]  # closest gap first (of two crossing pairs, the nearer is linked)
    missing = missing[np.lexsort((missing[:, 1], missing[:, 0], np.hypot(d[:, 0], d[:, 1]) - r[missing].sum(axis=1)))]
    ft = _FlipTriangulation(xz, tri)
    rr = r.tolist()

    def is_link(a, b):  # eq 28
        eq28 = rr[a] + rr[b] + reach >= np.hypot(ft.p[b][0] - ft.p[a][0], ft.p[b][1] - ft.p[a][1])
        return eq28 if wv is None else bool(wv.is_link(a, b, eq28))

    inserted = 0
    for k, l in missing.tolist():
        edges = ft.crossed_edges(k, l)
        if edges is None or any(is_link(a, b) for a, b in edges):
            continue  # it runs through a disc centre or crosses a link
        ft.insert(k, l, edges)
        inserted += 1
    return (ft.triangles() if inserted else tri), inserted


def build_pores(xz, r, eps_m=0.0, l_m=0.0, walls=None, degenerate_fraction=1e-4, steps=None, flat_walls=()):
    """Build links (eq 28) and pores (§3.1) for discs at ``xz`` [m] with radii ``r`` [m].

    ``walls``: optional (N,) int wall code per disc (WALL_NONE, WALL_BOTTOM, WALL_LEFT, WALL_RIGHT).
    An edge between two wall discs is a wall element, not a free surface. The candidate links are
    the regular triangulation plus the eq 28 pairs it hides (module docstring).
    ``flat_walls``: flat_walls.FlatWall, ... (SPEC §2.6), or their flat_walls.WallVertices (with its
    shift: translated walls): the triangulation is that of the discs and the wall vertices of the
    build (flat_walls.WallVertices.active).
    ``steps``: the BuildSteps, by default NUMPY_BUILD, the readable NumPy functions (``_lifted_points``,
    ``_faces``, ``_links_and_corners``, ...); engines.compiled.pores.BUILD: everything but qhull by
    compiled kernels, the same network (tests/compiled/test_pores.py).
    Returns a PoreNetwork; positions may then move and ``measure`` gives the new areas.
    """
    xz, r = check_discs(xz, r)
    check_nonnegative("eps_m", eps_m)
    check_nonnegative("l_m", l_m)
    check_nonnegative("degenerate_fraction", degenerate_fraction)
    n = len(r)
    walls = np.zeros(n, np.int64) if walls is None else np.asarray(walls, np.int64)
    if walls.shape != (n,):
        raise ValueError(f"walls: expected shape ({n},), got {walls.shape}")
    bad = (walls < WALL_NONE) | (walls > LAST_GROUP)
    if bad.any():
        raise ValueError(f"walls: codes must be {WALL_NONE}-{LAST_GROUP}, got {walls[bad][0]}")
    a_min = degenerate_fraction * float(np.mean(np.pi * r**2)) if n else 0.0
    steps = steps or NUMPY_BUILD
    if flat_walls:
        wv = flat_walls if isinstance(flat_walls, fw.WallVertices) else fw.WallVertices(flat_walls, n)
        return _build_with_flat_walls(xz, r, eps_m, l_m, walls, a_min, steps, wv)
    tri = regular_triangulation(xz, r, steps)
    if tri is None:
        return _empty_network(n, a_min, eps_m, l_m)
    tri, n_inserted = insert_missing_links(xz, r, tri, eps_m + l_m, steps)
    return _network(xz, r, walls, tri, n_inserted, eps_m, l_m, a_min, steps.faces, steps.links_and_corners)


def _network(xz, r, walls, tri, n_inserted, eps_m, l_m, a_min, faces, links_and_corners):
    """The PoreNetwork of the vertices at xz with radii r and wall codes ``walls`` on the
    triangulation ``tri`` (links inserted), by the steps ``faces`` and ``links_and_corners``."""
    nb, is_link, tri_pore_all, bounded, n_pores, n_closed, off_mesh = faces(xz, r, tri, eps_m + l_m, a_min)
    t_in = _locate(xz, tri, xz[off_mesh]) if len(off_mesh) else off_mesh  # empty power cells: rattlers where they lie
    p_in = np.where(t_in >= 0, tri_pore_all[t_in], OUTER)
    arrays = links_and_corners(xz, r, walls, tri, nb, is_link, tri_pore_all, bounded, n_pores,
                               off_mesh[p_in >= 0], p_in[p_in >= 0])._asdict()
    touches = arrays.pop("touches")
    links = arrays["links"]
    return PoreNetwork(
        n_discs=len(r), **arrays, link_vec0=xz[links[:, 1]] - xz[links[:, 0]], **_sector_terms(r, arrays),
        pore_touches={name: touches[code] for code, name in WALL_NAMES.items()},
        a_min=a_min, n_closed=int(n_closed), eps_m=float(eps_m), l_m=float(l_m), n_inserted=n_inserted,
    )


def _sector_terms(r, a):
    """sector_area0 (Np,) and link_turn_weight (L,) [m^2] of PoreNetwork from the radii r of its
    vertices and the arrays ``a`` of ``_links_and_corners`` (by name). The corner at the end d of
    a half-edge turns by the turn of its link minus that of the next link (eq 29), so over a pore's
    corners each link's turn counts with r^2 of the disc it leads to (+) and of the disc it leaves
    (-): (r_j^2 - r_i^2) / 2 for the pore on the left of i->j, the opposite on its right."""
    links, n_p = a["links"], len(a["pore_surface"])
    sector0 = 0.5 * np.bincount(a["corner_pore"], a["corner_theta0"] * a["corner_r2"], minlength=n_p)
    return {"sector_area0": sector0 + a["rattler_area"],
            "link_turn_weight": 0.5 * (r[links[:, 1]] ** 2 - r[links[:, 0]] ** 2)}


def _build_with_flat_walls(xz, r, eps_m, l_m, walls, a_min, steps, wv):
    """build_pores with the flat walls of the flat_walls.WallVertices ``wv``: the network of the
    discs and the wall vertices (flat_walls module docstring), whose vertex sets count each wall
    as one vertex (``_wall_vertex_sets``)."""
    wv.check_inside(xz)
    n, reach = wv.n, eps_m + l_m
    points, radii = wv.positions(xz), wv.radii(r)
    active = wv.active(xz, r, reach)
    tri = regular_triangulation(points[active], radii[active], steps)
    if tri is None:
        net = _empty_network(n, a_min, eps_m, l_m)
    else:
        tri, n_inserted = insert_missing_links(points, radii, active[tri], reach, steps, wv)
        codes = np.concatenate([walls, np.full(wv.n_vertices - n, FLAT_VERTEX)])

        def faces(*args):  # the wall vertices that are no vertex of the build are no rattlers
            *out, off_mesh = steps.faces(*args, wall_vertices=wv)
            return *out, off_mesh[off_mesh < n]

        net = _network(points, radii, codes, tri, n_inserted, eps_m, l_m, a_min, faces, steps.links_and_corners)
    net.n_discs, net.wall_vertices = n, wv
    net.pore_vertex_ptr, net.pore_vertex_idx, net.pore_signature, net.pore_walls = _wall_vertex_sets(
        wv, net.pore_vertex_ptr, net.pore_vertex_idx)
    return net


def _wall_vertex_sets(wv, ptr, idx):
    """The pores' vertex sets (CSR ptr, idx over the vertices of flat_walls.WallVertices ``wv``) with
    the vertices on flat wall w counted as one, N + w (re-meshing rules (a)-(d)): (ptr, idx,
    signature, pore_walls (W, Np) bool: the pore has a vertex on wall w)."""
    n, n_p = wv.n, len(ptr) - 1
    pore = np.repeat(np.arange(n_p), np.diff(ptr))
    disc = idx < n
    k, w = wv.split_bits(wv.bits[idx])
    pore_walls = np.zeros((len(wv.walls), n_p), bool)
    pore_walls[w, pore[k]] = True
    m = n + len(wv.walls)
    key = np.unique(np.concatenate([pore[disc] * m + idx[disc], pore[k] * m + n + w]))
    ptr = np.searchsorted(key // m, np.arange(n_p + 1))
    return ptr, key % m, _set_signatures(ptr, key % m), pore_walls
