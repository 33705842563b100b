"""Inflow given as a Darcy flux per unit width (SPEC §2.7, [water] inflow_velocity): the total is
v x the inflow row's span whatever the grain size; q_w stays the paper's per-pore inflow."""
import numpy as np
import pytest

from engines.compiled import water_model as compiled_water_model
from engines.model import groups
from engines.model import pores as pg
from engines.model.flat_walls import FlatWall
from engines.model.pore_water import PoreWater, WaterSettings, inflow_lengths
from engines.model.water_model import WaterModel

SPAN, HEIGHT = 0.02, 0.012  # [m]: the bottom row's span centre to centre, the bed's height
V = 1e-3  # [m/s]


def bed(r, seed=3):
    """A jittered triangular bed of discs of radius about r [m] on a touching row of bottom-wall
    discs of radius r spanning SPAN centre to centre: (xz, r, walls)."""
    rng = np.random.default_rng(seed)
    n = int(round(SPAN / (2 * r))) + 1
    rows = [np.column_stack([np.linspace(0.0, SPAN, n), np.zeros(n)])]
    for j in range(1, int(HEIGHT / (np.sqrt(3) * r))):
        x = np.arange(r * (j % 2), SPAN + 1e-12, 2 * r)
        rows.append(np.column_stack([x, np.full(len(x), j * np.sqrt(3) * r)]))
    grains = np.vstack(rows[1:]) + rng.uniform(-0.02, 0.02, (sum(map(len, rows[1:])), 2)) * r
    xz = np.vstack([rows[0], grains])
    radii = np.concatenate([np.full(n, r), r * rng.uniform(0.95, 0.99, len(grains))])
    walls = np.concatenate([np.full(n, pg.WALL_BOTTOM), np.zeros(len(grains), np.int64)])
    return xz, radii, walls


def total_inflow(xz, r, walls, settings, flat_walls=()):
    """The water's inflow rate [m^2/s] summed over the pores, and the network."""
    net = pg.build_pores(xz, r, l_m=0.3 * np.median(r), walls=walls, flat_walls=flat_walls)
    water = PoreWater(net, pg.measure(net, xz, r).void_area, settings, walls=walls)
    rate, weight = water.inflow
    return rate * weight.sum(), net


@pytest.mark.parametrize("r", [0.5e-3, 1e-3])
def test_disc_row_passes_v_times_its_span(r):
    total, net = total_inflow(*bed(r), WaterSettings(inflow_velocity=V))
    assert total == pytest.approx(V * SPAN, rel=1e-12)


def test_small_and_large_grains_take_in_the_same_water_with_a_velocity_not_with_q_w():
    small, large = bed(0.5e-3), bed(1e-3)
    v = [total_inflow(*b, WaterSettings(inflow_velocity=V))[0] for b in (small, large)]
    assert v[0] == pytest.approx(v[1], rel=1e-12)
    q = [total_inflow(*b, WaterSettings(q_w=1e-4))[0] for b in (small, large)]
    assert q[0] > 1.5 * q[1]  # the paper's q_w per pore: about twice the pores on the row of half-size grains


def test_each_row_link_feeds_the_pore_above_it_and_a_vertex_only_pore_none():
    xz, r, walls = bed(1e-3)
    net = pg.build_pores(xz, r, l_m=0.3e-3, walls=walls)
    lengths = inflow_lengths(net, walls)
    touching = net.pore_touches["bottom"]
    assert np.all(lengths[~touching] == 0)
    fed = lengths > 0
    assert fed.sum() == int(round(SPAN / 2e-3))  # one pore above each link of the row
    assert (touching & ~fed).any()  # pores touching the row at one disc only get none
    np.testing.assert_allclose(lengths[fed], 2e-3, rtol=1e-12)  # touching discs: links of 2 r


def test_flat_inflow_wall_passes_v_times_its_edges():
    for r in (0.5e-3, 1e-3):
        xz, radii, _ = bed(r)
        xz, radii = xz[1:-1], radii[1:-1]  # the row's end discs out: a flat wall under discs from r to SPAN - r
        wall = FlatWall(1, -r, +1, "inflow")
        total, net = total_inflow(xz, radii, None, WaterSettings(inflow_velocity=V), (wall,))
        bottom = xz[:, 1] - radii <= -r + 0.3 * r  # the discs linked to the wall: their feet span the edges
        assert total == pytest.approx(V * np.ptp(xz[bottom, 0]), rel=1e-12)


def test_q_w_and_inflow_velocity_are_exclusive():
    xz, r, walls = bed(1e-3)
    net = pg.build_pores(xz, r, l_m=0.3e-3, walls=walls)
    with pytest.raises(ValueError, match="q_w .* and inflow_velocity .* set one of them to 0"):
        PoreWater(net, pg.measure(net, xz, r).void_area, WaterSettings(q_w=1e-4, inflow_velocity=V), walls=walls)


def test_compiled_twin_takes_in_the_same_water():
    """One water step of the NumPy model and of its compiled twin: the same inflow volume."""
    xz, r, walls = bed(1e-3)
    s = WaterSettings(inflow_velocity=V)
    got = []
    for model in (WaterModel, compiled_water_model.WaterModel):
        m = model(s, r, walls, xz, 0.0, 0.3e-3, 1e-6)
        m.advance(1e-6, xz)
        got.append(m.water.balance.inflow)
    assert got[0] == pytest.approx(V * SPAN * 1e-6, rel=1e-12)
    assert got[1] == pytest.approx(got[0], rel=1e-12)


def test_one_pore_and_no_pore_networks_have_their_inflow_lengths():
    """Two touching discs of the bottom row and one on them: one pore, fed over the row's link 2 r;
    a network without pores has no lengths."""
    xz = np.array([[0.0, 0.0], [2e-3, 0.0], [1e-3, 1.7e-3]])
    walls = np.array([pg.WALL_BOTTOM, pg.WALL_BOTTOM, 0])
    net = pg.build_pores(xz, np.full(3, 1e-3), l_m=0.3e-3, walls=walls)
    np.testing.assert_allclose(inflow_lengths(net, walls), [2e-3], rtol=1e-12)
    empty = pg.build_pores(xz[:2], np.full(2, 1e-3), l_m=0.3e-3, walls=walls[:2])
    assert empty.n_pores == 0 and inflow_lengths(empty, walls[:2]).shape == (0,)


def test_the_row_feeds_the_same_pores_whatever_the_discs_order():
    """The bottom row's discs numbered last instead of first: each pore gets the same length."""
    xz, r, walls = bed(1e-3)
    order = np.argsort(walls == 0)[::-1]   # grains first
    net, back = pg.build_pores(xz, r, l_m=0.3e-3, walls=walls), pg.build_pores(xz[order], r[order], l_m=0.3e-3,
                                                                                walls=walls[order])
    a, b = inflow_lengths(net, walls), inflow_lengths(back, walls[order])
    key = lambda n: [tuple(sorted(order[n.vertices_of(p)] if n is back else n.vertices_of(p)))  # noqa: E731
                     for p in range(n.n_pores)]
    assert sorted(zip(key(net), a)) == sorted(zip(key(back), b)) and a.sum() > 0


def test_an_inflow_group_facing_x_feeds_the_pores_on_its_inner_side(monkeypatch):
    """The table read by kind (engines.model.groups): were the left disc group an inflow wall, the bed
    mirrored across x = z (its row now a left column, numbered top down so that each link i -> j
    points down and its inner side is on its left) would take in v x the same span, and a bed with
    both rows takes in the sum of what each row feeds alone."""
    xz, r, walls = bed(1e-3)
    toy = tuple(k._replace(water="inflow") if k.name == "left" else k for k in groups.BOUNDARY_KINDS)
    monkeypatch.setattr(groups, "BOUNDARY_KINDS", toy)
    left = np.where(walls == pg.WALL_BOTTOM, pg.WALL_LEFT, 0)
    down = np.r_[np.flatnonzero(left)[::-1], np.flatnonzero(left == 0)]   # the column numbered top down
    total, _ = total_inflow(xz[down, ::-1], r[down], left[down], WaterSettings(inflow_velocity=V))
    assert total == pytest.approx(V * SPAN, rel=1e-12)
    column = np.column_stack([np.full(6, -2e-3), 2e-3 * np.arange(1, 7)])   # a left column beside the bed
    both_xz, both_r = np.vstack([xz, column]), np.concatenate([r, np.full(6, 1e-3)])
    both = np.concatenate([walls, np.full(6, pg.WALL_LEFT)])
    net = pg.build_pores(both_xz, both_r, l_m=0.3e-3, walls=both)
    rows = [inflow_lengths(net, np.where(both == g, g, 0)) for g in (pg.WALL_BOTTOM, pg.WALL_LEFT)]
    assert rows[1].sum() > 0
    np.testing.assert_allclose(inflow_lengths(net, both), rows[0] + rows[1], rtol=1e-15)


def test_flat_walls_that_take_in_no_water_feed_no_pore():
    """An undrained flat bottom under a bed without disc groups: its edges are no inflow row."""
    xz, r, _ = bed(1e-3)
    xz, r = xz[1:-1], r[1:-1]
    net = pg.build_pores(xz, r, l_m=0.3e-3, walls=np.zeros(len(r), np.int64),
                         flat_walls=(FlatWall(1, -1e-3, +1), FlatWall(0, -1e-3, +1, "drained")))
    assert len(pg.wall_edges(net)[0]) and np.all(inflow_lengths(net, np.zeros(len(r), np.int64)) == 0)
