"""Particle sizes (eq 53-54) and packing files."""
import numpy as np
import pytest
from scipy import stats

from packing.packing import Packing
from packing.psd import diameter_distribution, lognormal_parameters, sample_diameters


def test_eq54_parameters_give_the_mean_and_std():
    dist = diameter_distribution(0.9e-3, 0.25e-3)
    assert dist.mean() == pytest.approx(0.9e-3, rel=1e-12) and dist.std() == pytest.approx(0.25e-3, rel=1e-12)
    lam, zeta = lognormal_parameters(0.9e-3, 0.25e-3)
    assert zeta**2 == pytest.approx(np.log(1 + (0.25 / 0.9) ** 2))


def test_truncated_samples_match_the_truncated_distribution():
    rng = np.random.default_rng(0)
    d = sample_diameters(5000, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, rng)
    assert d.min() >= 0.4e-3 and d.max() <= 2e-3
    dist = diameter_distribution(0.9e-3, 0.25e-3)
    lo, hi = dist.cdf(0.4e-3), dist.cdf(2e-3)
    p = stats.kstest(d, lambda x: (dist.cdf(x) - lo) / (hi - lo)).pvalue
    assert p > 0.01
    assert np.array_equal(d, sample_diameters(5000, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, np.random.default_rng(0)))


def test_packing_roundtrip_and_validation(tmp_path):
    pk = Packing(np.array([[0.0, 1e-3], [1e-3, 0.0]]), [0.4e-3, 0.5e-3], [0, 1], [5.0, 1.0])
    pk.save(str(tmp_path / "p.csv"))
    back = Packing.load(str(tmp_path / "p.csv"))
    np.testing.assert_allclose(back.xz, pk.xz, rtol=1e-12)
    assert list(back.group) == [0, 1] and list(back.density_factor) == [5.0, 1.0]
    with pytest.raises(ValueError, match="group"):
        Packing(pk.xz, pk.r, [0, 7], [1.0, 1.0])
    with pytest.raises(ValueError, match="r must be > 0"):
        Packing(pk.xz, [0.0, 1e-3], [0, 1], [1.0, 1.0])
