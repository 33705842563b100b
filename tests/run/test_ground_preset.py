"""The 10,000-disc wet ground (issue 25, item 3): the seismic box's grains and constants in a wide,
deep box, its packing at rest under its own weight."""
import numpy as np
import pytest
from scipy import stats

from engines.model.groups import WALL_BOTTOM
from engines.model.observe import box_window, porosity
from engines.model.pore_dem import weight_carried
from engines.run import scene as scenes
from packing.packing import Packing
from packing.psd import diameter_distribution

# the fields the ground may change from liquefaction_case1 (the box, its deposit, the run's length
# and output); every other field, grains and constants included, is case 1's
GROUND_ONLY = {("packing", f) for f in ("file", "seed", "n_particles", "n_bottom", "n_side", "cut_extra", "settle_time",
                                        "settle_loaded", "dense_top_count", "dense_top_depth", "dense_top_factor",
                                        "wall_density_factor")} | {
    ("loading", "moves"), ("loading", "side_walls"), ("numerics", "duration"), ("output", "snapshot_times"),
    ("output", "block_z"), ("scene", "name"), ("scene", "description")}


@pytest.fixture(scope="module")
def ground():
    sc = scenes.preset("ground_10000")
    return sc, Packing.load(sc.packing.file)


def test_the_ground_is_case_1_in_a_wider_box():
    g, c1 = scenes.preset("ground_10000").as_dict(), scenes.preset("liquefaction_case1").as_dict()
    changed = {(t, f) for t in g for f in g[t] if g[t][f] != c1[t][f]}
    assert changed <= GROUND_ONLY, changed - GROUND_ONLY
    assert g["packing"]["n_particles"] >= 10000 and g["numerics"]["duration"] >= 0.1
    assert (g["loading"]["moves"], g["loading"]["side_walls"], g["water"]["sides"]) == ("box", "fixed", "undrained")
    assert g["walls"]["kind"] == "discs" and g["water"]["enabled"]
    assert (g["packing"]["dense_top_factor"], g["packing"]["wall_density_factor"]) == (1.0, 1.0)


def test_the_ground_packing_has_the_seismic_grains(ground):
    sc, pk = ground
    p = sc.packing
    d = 2 * pk.r[pk.mobile]
    assert len(d) == p.n_particles and (~pk.mobile).sum() == p.n_bottom + 2 * (p.n_side - 1)
    assert np.all(pk.r[~pk.mobile] == p.wall_radius) and np.all(pk.density_factor == 1.0)
    assert len(pk.outside_box()) == 0
    assert d.min() >= p.d_min and d.max() <= p.d_max
    dist = diameter_distribution(p.mean_diameter, p.std_diameter)  # eq 53, truncated to [d_min, d_max]
    lo, hi = dist.cdf(p.d_min), dist.cdf(p.d_max)
    assert stats.kstest(d, lambda x: (dist.cdf(x) - lo) / (hi - lo)).pvalue > 0.01


def test_the_ground_is_level_and_as_porous_as_the_seismic_box(ground):
    sc, pk = ground
    m = pk.mobile
    x, top = pk.xz[m, 0], pk.xz[m, 1] + pk.r[m]
    bins = np.linspace(x.min(), x.max(), 11)  # ten columns across the box: the surface of each
    surface = [top[(x >= a) & (x <= b)].max() for a, b in zip(bins[:-1], bins[1:])]
    bottom = pk.inner_faces()[WALL_BOTTOM]
    depth = pk.bed_top - bottom
    assert np.ptp(surface) < 0.1 * depth, f"surface heights {np.round(np.asarray(surface) * 1e3, 2)} mm"
    assert pk.bed_top < (pk.xz[~m, 1] + pk.r[~m]).max()  # the side walls reach above the ground
    case1 = Packing.load(scenes.preset("liquefaction_case1").packing.file)
    n = porosity(pk.xz[m], pk.r[m], box_window(pk, sc.output.porosity_window))
    n1 = porosity(case1.xz[case1.mobile], case1.r[case1.mobile], box_window(case1, sc.output.porosity_window))
    assert abs(n - n1) < 0.05, (n, n1)


def test_the_ground_carries_its_overburden(ground):
    """At rest under gravity: the walls carry the whole weight, and at each depth the discs below
    carry the discs above, within a few per cent (the normal springs of the packing law at the
    packing's positions, engines.model.pore_dem.weight_carried; the tangential springs of the
    deposit, which this cannot recover from positions, carry the rest)."""
    sc, pk = ground
    assert weight_carried(sc.settings, pk) == pytest.approx(1.0, abs=0.05)
    m, z = pk.mobile, pk.xz[:, 1]
    for q in (0.1, 0.25, 0.5, 0.75, 0.9):
        above = m & (z > np.quantile(z[m], q))
        assert weight_carried(sc.settings, pk, above) == pytest.approx(1.0, abs=0.05), q
