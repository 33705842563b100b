"""Link candidates (SPEC §2.2): the regular triangulation plus the eq 28 pairs it hides.

The checks here are brute force over all disc pairs, with their own segment-crossing test, so they
do not share code with engines.model.pores.
"""
import os

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from engines.model import pores as pg
from engines.run.scene import SCENE_DIR
from packing.packing import Packing
from packing.psd import sample_diameters
from tests.layouts import random_sequential
from tests.oracles import void_area_by_triangles

SEISMIC = (2e-4, 3.5e-4)    # eps_m, l_m of seed 000 §6 (Table 4)
QUICKSAND = (0.0, 1.3e-4)   # eps_m, l_m of §5 (Table 1)


def _packing(seed, n=450, side=0.021):
    rng = np.random.default_rng(seed)
    d = sample_diameters(n, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, rng)
    return random_sequential(d, side, side, rng)


def _proper_cross(p1, p2, q1, q2):
    """Segments p1-p2 and q1-q2 (arrays of points) cross at one interior point of both."""
    def side(a, b, c):
        return np.sign((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))
    return (side(p1, p2, q1) * side(p1, p2, q2) < 0) & (side(q1, q2, p1) * side(q1, q2, p2) < 0)


def _all_eq28_pairs(xz, r, reach):
    i, j = np.triu_indices(len(r), 1)
    keep = r[i] + r[j] + reach >= np.hypot(*(xz[j] - xz[i]).T)
    return np.column_stack([i[keep], j[keep]])


def missed_pairs(xz, r, reach, links):
    """eq 28 pairs that are not links and cross no link (sharing no disc with them)."""
    linked = set(map(tuple, np.sort(links, axis=1).tolist()))
    out = []
    for a, b in _all_eq28_pairs(xz, r, reach).tolist():
        if (a, b) in linked:
            continue
        other = ~np.isin(links, [a, b]).any(axis=1)
        if not _proper_cross(xz[a], xz[b], xz[links[other, 0]], xz[links[other, 1]]).any():
            out.append((a, b))
    return out


def crossing_links(xz, links):
    """Number of pairs of links sharing no disc that cross (0 for a planar link graph)."""
    i, j = np.triu_indices(len(links), 1)
    a, b = links[i], links[j]
    apart = (a[:, :, None] != b[:, None, :]).all(axis=(1, 2))
    a, b = a[apart], b[apart]
    return int(_proper_cross(xz[a[:, 0]], xz[a[:, 1]], xz[b[:, 0]], xz[b[:, 1]]).sum())


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("eps_m,l_m", [SEISMIC, QUICKSAND], ids=["seismic", "quicksand"])
def test_every_eq28_pair_crossing_no_link_is_a_link(seed, eps_m, l_m):
    xz, r = _packing(seed)
    net = pg.build_pores(xz, r, eps_m=eps_m, l_m=l_m)
    reach = eps_m + l_m
    d = np.hypot(*(xz[net.links[:, 1]] - xz[net.links[:, 0]]).T)
    assert np.all(r[net.links[:, 0]] + r[net.links[:, 1]] + reach >= d)  # every link is an eq 28 pair
    assert missed_pairs(xz, r, reach, net.links) == []
    assert crossing_links(xz, net.links) == 0
    # Euler's formula for the planar link graph: bounded faces = E - V + C
    n = len(r)
    g = coo_matrix((np.ones(len(net.links)), (net.links[:, 0], net.links[:, 1])), shape=(n, n))
    c, _ = connected_components(g, directed=False)
    assert net.n_pores + net.n_closed == len(net.links) - n + c
    m = pg.measure(net, xz, r)
    np.testing.assert_allclose(m.void_area, void_area_by_triangles(net, xz, r), rtol=1e-9, atol=1e-15)


def test_the_check_catches_pairs_the_triangulation_hides_at_the_seismic_range():
    """The brute-force check is not vacuous: the eq 28 pairs among the regular triangulation's edges
    leave out pairs at the seismic l_m, and every pair the insertion puts in was one of them."""
    eps_m, l_m = SEISMIC
    xz, r = _packing(0)
    reach = eps_m + l_m
    edges = np.array(sorted({tuple(sorted(e)) for t in pg.regular_triangulation(xz, r).tolist()
                             for e in zip(t, t[1:] + t[:1])}))
    eq28 = r[edges[:, 0]] + r[edges[:, 1]] + reach >= np.hypot(*(xz[edges[:, 1]] - xz[edges[:, 0]]).T)
    hidden = set(missed_pairs(xz, r, reach, edges[eq28]))
    net = pg.build_pores(xz, r, eps_m=eps_m, l_m=l_m)
    inserted = set(map(tuple, np.sort(net.links, axis=1).tolist())) - set(map(tuple, edges.tolist()))
    assert len(hidden) >= net.n_inserted == len(inserted) > 0
    assert inserted <= hidden


def _kite():
    """Four equal discs (r = 1) whose Delaunay diagonal 2-3 (gap 1.3) is longer than the other,
    0-1 (gap 1.2): at reach 1.25 the pair 0-1 satisfies eq 28 and 2-3 does not. The kite's
    diagonals are 3.2 and 3.3 long, its area 3.2 x 3.3 / 2."""
    xz = np.array([[-1.6, 0.0], [1.6, 0.0], [0.0, 1.2], [0.0, -2.1]])
    return xz, np.ones(4)


def test_kite_the_hidden_diagonal_is_inserted():
    xz, r = _kite()
    assert pg.regular_triangulation(xz, r) is not None
    edges = {tuple(sorted(e)) for t in pg.regular_triangulation(xz, r).tolist() for e in zip(t, t[1:] + t[:1])}
    assert (2, 3) in edges and (0, 1) not in edges  # equal radii: regular = Delaunay, diagonal 2-3
    net = pg.build_pores(xz, r, l_m=1.25)
    assert [0, 1] in net.links.tolist() and net.n_inserted == 1 and net.n_pores == 2
    m = pg.measure(net, xz, r)
    # the two triangles fill the kite; their corner sectors add up to the kite's angles, 2 pi
    np.testing.assert_allclose(m.void_area.sum(), 3.2 * 3.3 / 2 - np.pi, rtol=1e-12)


def test_disc_with_empty_power_cell_is_a_rattler():
    """A small disc mostly inside a large one has an empty power cell: it is no vertex of the regular
    triangulation, gets no link, and its whole area is subtracted from the pore around its centre."""
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, np.sqrt(3)], [0.3, 0.2]])
    r = np.array([1.0, 1.0, 1.0, 0.1])
    assert 3 not in pg.regular_triangulation(xz, r)
    net = pg.build_pores(xz, r, l_m=0.05)
    assert net.n_pores == 1 and not np.isin(3, net.links).any()
    assert 3 in net.vertices_of(0)
    m = pg.measure(net, xz, r)
    np.testing.assert_allclose(m.void_area[0], np.sqrt(3) - np.pi / 2 - np.pi * 0.01, rtol=1e-12)


def test_coincident_centres_and_cocircular_discs():
    """A disc at the centre of another is dropped as a rattler; four cocircular equal discs (coplanar
    lifted points) still triangulate."""
    xz = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, np.sqrt(3)], [2.0, 0.0]])
    r = np.array([1.0, 1.0, 1.0, 0.5])
    net = pg.build_pores(xz, r, l_m=0.05)
    assert net.n_pores == 1 and not np.isin(3, net.links).any()
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    net = pg.build_pores(square, np.ones(4), l_m=0.1)  # diagonals 2.83 are not links: one square pore
    assert net.n_pores == 1 and len(net.links) == 4
    np.testing.assert_allclose(pg.measure(net, square, np.ones(4)).void_area, [4.0 - np.pi], rtol=1e-12)


def test_quicksand_preset_every_eq28_pair_crossing_no_link_is_a_link():
    """The same on the quick-sand packing with its wall discs, at its own eps_m, l_m."""
    pk = Packing.load(os.path.join(SCENE_DIR, "quicksand_packing.csv"))
    eps_m, l_m = QUICKSAND
    net = pg.build_pores(pk.xz, pk.r, eps_m=eps_m, l_m=l_m, walls=pk.group)
    assert net.n_pores > 0
    assert missed_pairs(pk.xz, pk.r, eps_m + l_m, net.links) == []
    assert crossing_links(pk.xz, net.links) == 0
