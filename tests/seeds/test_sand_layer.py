"""Monte-Carlo model sand layer (seed 004): distributions, load transmission, settlement."""
import json

import numpy as np
import pytest
from scipy import stats

from engines.seeds.sand_layer import study
from engines.seeds.sand_layer.layer import (
    DISCRETE_LEVELS,
    GrainSizeDistribution,
    SandLayerSettings,
    build_layers,
    discrete_diameters,
    draw_void_ratios,
    grain_volume,
    mass_distribution,
    number_distribution,
    sample_diameters,
    solid_volumes,
    void_ratio,
)
from engines.seeds.sand_layer.mechanics import (
    CompressionCurves,
    MechanicsSettings,
    analyse_layer,
    default_compression_curves,
    transmission_matrix,
    transmission_weights,
    transmit_load,
    void_ratio_reduction,
)
from postproc.sand_layer import figures

GSD = GrainSizeDistribution()
LAYER = SandLayerSettings()
MECH = MechanicsSettings()


# --- grain sizes and void ratios -------------------------------------------------------------

def test_number_density_is_mass_density_over_d_cubed():
    d = np.geomspace(1e-5, 5e-3, 50)
    ratio = number_distribution(GSD).pdf(d) * d**3 / mass_distribution(GSD).pdf(d)
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-10)  # eq 2


def test_number_ln_mean_is_mu_minus_three_sigma_squared():
    d = sample_diameters(GSD, 2_000_000, np.random.default_rng(3), "continuous")
    ln_d = np.log(d)
    assert ln_d.mean() == pytest.approx(GSD.mu - 3 * GSD.sigma**2, abs=2e-3)
    # weighting the grains by their mass ∝ D³ recovers the mass-based ln-mean μ
    assert np.average(ln_d, weights=d**3) == pytest.approx(GSD.mu, abs=0.02)


def test_continuous_draws_follow_the_number_distribution():
    d = sample_diameters(GSD, 20_000, np.random.default_rng(11), "continuous")
    assert stats.kstest(d, number_distribution(GSD).cdf).pvalue > 0.01


def test_discrete_draws_follow_their_100_levels():
    levels = discrete_diameters(GSD)
    np.testing.assert_allclose(number_distribution(GSD).cdf(levels), DISCRETE_LEVELS, rtol=1e-12)
    d = sample_diameters(GSD, 50_000, np.random.default_rng(12), "discrete")
    index = np.searchsorted(levels, d)
    np.testing.assert_array_equal(levels[index], d)
    # discrete CDF: every level R = 0.005 … 0.995 is drawn with probability 1/100
    counts = np.bincount(index, minlength=levels.size)
    assert stats.chisquare(counts).pvalue > 0.01
    empirical_cdf = np.cumsum(counts) / d.size
    np.testing.assert_allclose(empirical_cdf, np.arange(1, 101) / 100, atol=0.01)


def test_void_ratio_of_equal_spheres():
    d = 0.25e-3
    solid = grain_volume(np.full(100, d)).sum()
    assert solid == pytest.approx(100 * np.pi * d**3 / 6, rel=1e-14)
    assert void_ratio(1.2e-9, solid) == pytest.approx(1.2e-9 / solid - 1, rel=1e-14)  # eq 3


def test_truncation_redraws_into_the_window():
    e = draw_void_ratios(4000, GSD, LAYER, np.random.default_rng(5))
    assert e.min() >= LAYER.e_min and e.max() <= LAYER.e_max
    raw = void_ratio(LAYER.element_volume,
                     solid_volumes(8000, GSD, LAYER, np.random.default_rng(6)))
    kept = raw[(raw >= LAYER.e_min) & (raw <= LAYER.e_max)]
    assert stats.ks_2samp(e, kept).pvalue > 0.01


def test_same_seed_same_layers_different_seed_different_layers():
    def layers(seed):
        return np.array([layer.void_ratio for layer in
                         build_layers(3, GSD, LAYER, np.random.default_rng(seed))])
    first = layers(21)
    assert first.shape == (3, 5, 26)
    np.testing.assert_array_equal(first, layers(21))
    assert not np.array_equal(first, layers(22))


# --- stress transmission (eq 5–8) ------------------------------------------------------------

def test_uniform_layer_sends_60_16_4_percent():
    weights = transmission_weights(np.full(9, 0.8), MECH)
    np.testing.assert_allclose(weights, np.tile([0.04, 0.16, 0.6, 0.16, 0.04], (9, 1)),
                               rtol=1e-12)


def test_eq6_reaches_p_max_and_p_min():
    dense_centre = transmission_weights(np.array([3.0, 3.0, 0.3, 3.0, 3.0]), MECH)
    loose_centre = transmission_weights(np.array([0.3, 0.3, 3.0, 0.3, 0.3]), MECH)
    assert dense_centre[2, 2] == pytest.approx(0.8, rel=1e-12)
    assert loose_centre[2, 2] == pytest.approx(0.4, rel=1e-12)


def test_denser_side_receives_more():
    weights = transmission_weights(np.array([1.0, 0.5, 1.0, 2.0, 1.0]), MECH)
    assert weights[2, 1] + weights[2, 0] > weights[2, 3] + weights[2, 4]


def test_edge_load_is_reflected_into_the_layer():
    matrix = transmission_matrix(np.full(6, 1.0), MECH)
    np.testing.assert_allclose(matrix[:, 0], [0.76, 0.20, 0.04, 0, 0, 0], rtol=1e-12,
                               atol=1e-15)


@pytest.mark.parametrize("sampling", ["discrete", "continuous"])
def test_load_is_conserved_layer_by_layer(sampling):
    rng = np.random.default_rng(31)
    settings = SandLayerSettings(sampling=sampling)
    for layer in build_layers(10, GSD, settings, rng):
        np.testing.assert_allclose(transmission_matrix(layer.void_ratio[1], MECH).sum(axis=0),
                                   1.0, rtol=1e-12)
        surface = rng.random(settings.n_columns) * (rng.random(settings.n_columns) < 0.3)
        surface[[0, 1, -1]] = [2.0, 1.0, 3.0]  # loads at both side walls
        totals = transmit_load(layer.void_ratio, surface, MECH).sum(axis=1)
        np.testing.assert_allclose(totals, surface.sum(), rtol=1e-12)


# --- settlement --------------------------------------------------------------------------------

def test_interpolation_is_exact_on_a_bilinear_table():
    """void_ratio_reduction interpolates bilinearly in (e0, log p): any table whose e0 - e is
    bilinear in (e0, ln p) is reproduced exactly between its nodes (here e0 - e = (0.01 + 0.05 e0)
    ln(p / p0), unrelated to the default curves)."""
    e0 = np.array([0.3, 1.0, 2.2, 3.0])
    p = 1e3 * np.array([1.0, 3.0, 10.0, 40.0, 400.0])
    law = lambda e, q: (0.01 + 0.05 * e) * np.log(q / p[0])
    curves = CompressionCurves(e0, p, e0[:, None] - law(e0[:, None], p[None, :]))
    rng = np.random.default_rng(41)
    e = rng.uniform(0.3, 3.0, 200)
    stress = rng.uniform(0, p[-1] - p[0], 200)
    np.testing.assert_allclose(void_ratio_reduction(e, stress, curves), law(e, p[0] + stress), rtol=1e-10, atol=1e-13)


def test_default_curves_follow_their_stated_law():
    """The defaults' docstring: e = e0 - 0.1 (e0 - 0.3) log10(p/p0) on e0 = 0.3..3.0, p = p0 2^k."""
    c = default_compression_curves()
    expected = c.initial_void_ratio[:, None] - 0.1 * (c.initial_void_ratio[:, None] - 0.3) * np.log10(c.pressure / c.pressure[0])
    np.testing.assert_allclose(c.void_ratio, expected, rtol=1e-14)
    assert c.initial_void_ratio[0] == 0.3 and c.initial_void_ratio[-1] == 3.0
    np.testing.assert_allclose(c.pressure / c.pressure[0], 2.0 ** np.arange(8))


def test_settlement_is_the_column_sum_and_looser_compresses_more():
    e0 = np.full((5, 26), 0.8)
    e0[3, 16] = 2.5  # a loose element off the load
    surface = np.zeros(26)
    surface[12:14] = 98066.5
    response = analyse_layer(e0, 1.2e-3, surface, MECH)
    np.testing.assert_allclose(response.settlement, response.compression.sum(axis=0),
                               rtol=1e-14)
    assert np.all(response.compression[response.stress == 0] == 0)
    assert response.load_balance_error < 1e-12
    twin = analyse_layer(np.full((5, 26), 0.8), 1.2e-3, surface, MECH)
    # the loose element takes less stress than in a uniform layer, yet compresses more
    assert response.stress[3, 16] < twin.stress[3, 16]
    assert response.compression[3, 16] > twin.compression[3, 16]


# --- bad input ---------------------------------------------------------------------------------

@pytest.mark.parametrize("make, field", [
    (lambda: GrainSizeDistribution(sigma=0.0), "sigma"),
    (lambda: GrainSizeDistribution(d50=-1e-3), "d50"),
    (lambda: SandLayerSettings(n_grains=0), "n_grains"),
    (lambda: SandLayerSettings(element_volume=-1.0), "element_volume"),
    (lambda: SandLayerSettings(e_min=3.0, e_max=0.3), "e_min"),
    (lambda: SandLayerSettings(sampling="sobol"), "sampling"),
    (lambda: MechanicsSettings(alpha=0.0), "alpha"),
    (lambda: MechanicsSettings(p_max_ratio=0.3), "p_max_ratio"),
    (lambda: CompressionCurves([0.5, 1.0], [2e4, 1e4], [[0.5, 0.4], [1.0, 0.9]]), "pressure"),
    (lambda: transmit_load(np.full((5, 26), 0.1), np.ones(26), MECH), "void_ratio"),
    (lambda: transmit_load(np.full((5, 26), 1.0), np.ones(25), MECH), "surface_load"),
    (lambda: transmit_load(np.full((5, 26), 1.0), -np.ones(26), MECH), "surface_load"),
    (lambda: void_ratio_reduction(np.ones(3), np.full(3, 1e7), MECH.curves), "stress"),
    (lambda: build_layers(0, GSD, LAYER, np.random.default_rng(0)), "count"),
])
def test_bad_input_is_rejected_naming_the_field(make, field):
    with pytest.raises(ValueError, match=field):
        make()


# --- the study ----------------------------------------------------------------------------------

def test_study_writes_summary_and_figures(tmp_path):
    first = study.write_outputs(study.run(realisations=3, seed=4), str(tmp_path), figures)
    again = study.summary(study.run(realisations=3, seed=4))
    other = study.summary(study.run(realisations=3, seed=5))
    saved = json.loads((tmp_path / "summary.json").read_text())
    for key in ("settlement_mean", "settlement_std", "load_balance_error", "parameters"):
        assert key in saved
    assert saved["load_balance_error"] < 1e-12
    assert first["settlement_mean"] == again["settlement_mean"] != other["settlement_mean"]
    assert first["stress_fraction_under_load"] > first["settlement_fraction_under_load"]
    assert len(list(tmp_path.glob("*.png"))) == 4
    with pytest.raises(ValueError, match="load_width"):
        study.strip_load(26, 0, 1e5)
