"""Particle-size distribution of seed 000 §4.2: log-normal diameters (eq 53-54), truncated."""
import numpy as np
from scipy import stats

from engines import files


def lognormal_parameters(mean, std):
    """(lambda, zeta) of ln d from the mean and standard deviation of d (eq 54)."""
    if not mean > 0 or not std > 0:
        raise ValueError(f"mean and std of the diameters must be > 0, got {mean}, {std}")
    zeta2 = np.log(1 + std**2 / mean**2)  # eq 54b
    return np.log(mean) - zeta2 / 2, np.sqrt(zeta2)  # eq 54a


def diameter_distribution(mean, std):
    """scipy.stats frozen log-normal of the diameters [m] (eq 53)."""
    lam, zeta = lognormal_parameters(mean, std)
    return stats.lognorm(s=zeta, scale=np.exp(lam))


def sample_diameters(n, mean, std, d_min, d_max, rng):
    """n diameters [m] from the log-normal truncated to [d_min, d_max], by inverse CDF on the
    truncated probability range (exact truncation, no rejection loop). ``rng``: numpy Generator."""
    if not 0 < d_min < d_max:
        raise ValueError(f"need 0 < d_min < d_max, got d_min = {d_min}, d_max = {d_max}")
    dist = diameter_distribution(mean, std)
    lo, hi = dist.cdf(d_min), dist.cdf(d_max)
    return dist.ppf(lo + (hi - lo) * rng.random(n))


def plot_distribution(diameters, mean, std, d_min, d_max, path):
    """Fig. 14: number-% of diameters per bin, with the truncated log-normal density."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d_mm = np.asarray(diameters) * 1e3
    bins = np.arange(np.floor(d_mm.min() * 10) / 10, d_mm.max() + 0.1, 0.1)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.hist(d_mm, bins=bins, weights=np.full(len(d_mm), 100.0 / len(d_mm)), color="0.7", edgecolor="k",
            label=f"{len(d_mm)} discs")
    dist = diameter_distribution(mean, std)
    x = np.linspace(d_min, d_max, 200)
    norm = dist.cdf(d_max) - dist.cdf(d_min)
    ax.plot(x * 1e3, dist.pdf(x) / norm * 100 * 0.1e-3, "r-", label="truncated log-normal (eq 53)")
    ax.set_xlabel("diameter [mm]")
    ax.set_ylabel("number [%] per 0.1 mm")
    ax.set_title(f"Diameter distribution (mean {mean*1e3:.2f} mm, s.d. {std*1e3:.2f} mm)")
    ax.legend()
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)
