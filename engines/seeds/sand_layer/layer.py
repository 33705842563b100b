"""Monte-Carlo model sand layer of Matsuo, Komada & Takahashi (seed 004, SPEC §5).

The layer is a grid of small cubic elements of volume V. Each element is filled with N grains
drawn from the *number-based* grain-size distribution of the sand; its void ratio follows from
the grains' total solid volume V_s (eq 3). Element void ratios outside [e_min, e_max] are
redrawn, and the layer is n_layers deep and n_columns wide.

Grain-size distributions (eq 1–2)
    The mass-based (sieve) curve is log-normal: ln D ~ N(μ, σ²) (eq 1). With the grain mass
    proportional to D³, the number of grains of size D is ∝ f_mass(D)/D³, which is log-normal with
    the same σ and ln-mean μ − 3σ² (eq 2 with a = 0, b = ∞, as in the paper).

Default sand (the paper's Fig. 1 values are not printed)
    D50 = 0.4 mm (mass-based median, μ = ln 0.4 mm): the middle of the medium-sand range.
    σ = 0.59: chosen so that the paper's own numbers hold for this D50: with N = 100 and
    V = 1.2 mm³ the median element void ratio is ≈ 0.94 (the middle of the 0.52–1.33 the
    authors measured for their sand) and ≈ 6 % of elements fall outside [0.3, 3.0] (the paper:
    "about 5.5 %"). The curve then has D10 ≈ 0.19 mm, D60 ≈ 0.47 mm, Uc ≈ 2.5: a poorly graded
    medium sand. The element void ratio is very sensitive to σ (σ = 0.55 puts 24 % of elements
    below e = 0.3), so change D50 and σ together. The calibration is for the paper's discrete
    draws: continuous draws reach the coarse tail, whose few big grains fill some elements
    (≈ 16 % of elements then fall below e = 0.3 and are redrawn).

Grain shape
    Spheres: the solid volume of a grain of diameter D is πD³/6 (the paper weighs grains as
    spheres of their sieve diameter, of constant specific gravity).

Drawing grain sizes
    "discrete" (the paper's): two-digit uniform random numbers 00…99 select one of the 100
    levels R = 0.005, 0.015, …, 0.995 of the number-based cumulative curve, and the grain has
    the diameter D(R). "continuous": D is drawn from the number-based log-normal itself.
    The 100 levels stop at D(0.995) = 0.64 mm, above which eq 1 puts 21 % of the mass; so by
    mass the drawn sand is a little finer than eq 1 (D³-weighted median 0.38 mm instead of
    0.40 mm; see the script's Fig. 1).

Truncation
    The paper drops the ≈ 5.5 % of element void ratios below 0.3 or above 3.0 and draws the
    layer's void ratios from the renormalised (truncated) cumulative curve. That is the same
    as redrawing an element until its void ratio falls inside [e_min, e_max], which is what
    `draw_void_ratios` does. The paper's second set of two-digit random numbers on that curve
    is not reproduced: it only rounds the same distribution to 1 % quantiles.

Units: SI inside (m, m³); mm and mm³ appear only where the scripts print or plot.
"""
from dataclasses import dataclass

import numpy as np
from scipy import stats

from engines.model.fields import COUNT, check_each

#: The paper's 100 levels of the cumulative number curve, R = 0.005 … 0.995.
DISCRETE_LEVELS = (np.arange(100) + 0.5) / 100
SAMPLING_METHODS = ("discrete", "continuous")
#: Rounds of redrawing before giving up on a truncation window that keeps almost nothing.
MAX_REDRAW_ROUNDS = 1000


def require(ok, name, value, expectation):
    """Raise ValueError naming the field and its value unless `ok`."""
    if not ok:
        raise ValueError(f"{name} must be {expectation}, got {value!r}")


@dataclass(frozen=True)
class GrainSizeDistribution:
    """Mass-based log-normal grain-size distribution (eq 1).

    Attributes:
        d50: mass-based median diameter exp(μ) [m].
        sigma: standard deviation σ of ln D [-].
    """
    d50: float = 0.4e-3
    sigma: float = 0.59

    def __post_init__(self):
        require(np.isfinite(self.d50) and self.d50 > 0, "d50", self.d50, "a positive length in m")
        require(np.isfinite(self.sigma) and self.sigma > 0, "sigma", self.sigma, "positive")

    @property
    def mu(self):
        """ln-mean μ of the mass-based distribution, ln of metres."""
        return np.log(self.d50)

    @property
    def number_mu(self):
        """ln-mean of the number-based distribution, μ − 3σ² (eq 2), ln of metres."""
        return self.mu - 3 * self.sigma**2


@dataclass(frozen=True)
class SandLayerSettings:
    """How elements are filled and the layer is laid out.

    Attributes:
        n_grains: grains per element N [-] (paper: 100).
        element_volume: element volume V [m³] (paper: 1.2 mm³).
        e_min, e_max: element void ratios outside [e_min, e_max] are redrawn [-] (paper: 0.3, 3.0).
        n_columns: elements across the layer (paper: 26).
        n_layers: elements down the layer (paper: 5).
        sampling: "discrete" (100 levels, the paper's) or "continuous" grain-size draws.
    """
    n_grains: int = 100
    element_volume: float = 1.2e-9
    e_min: float = 0.3
    e_max: float = 3.0
    n_columns: int = 26
    n_layers: int = 5
    sampling: str = "discrete"

    def __post_init__(self):
        check_each(self, ("n_grains", "n_columns", "n_layers"), COUNT)
        require(np.isfinite(self.element_volume) and self.element_volume > 0,
                "element_volume", self.element_volume, "a positive volume in m³")
        require(0 <= self.e_min < self.e_max, "e_min, e_max", (self.e_min, self.e_max),
                "0 <= e_min < e_max")
        require(self.sampling in SAMPLING_METHODS, "sampling", self.sampling,
                f"one of {SAMPLING_METHODS}")

    @property
    def element_size(self):
        """Edge of the cubic element V^(1/3) [m] (1.06 mm for the paper's V)."""
        return self.element_volume ** (1 / 3)


@dataclass(frozen=True)
class SandLayer:
    """One realisation of the model sand layer.

    Attributes:
        void_ratio: initial void ratio e0 of each element, shape (n_layers, n_columns) [-];
            row 0 is the surface.
        element_size: edge of the cubic elements [m].
    """
    void_ratio: np.ndarray
    element_size: float


def mass_distribution(gsd):
    """Mass-based distribution of D [m] (eq 1), a frozen scipy.stats.lognorm."""
    return stats.lognorm(s=gsd.sigma, scale=np.exp(gsd.mu))


def number_distribution(gsd):
    """Number-based distribution of D [m] (eq 2): log-normal with ln-mean μ − 3σ²."""
    return stats.lognorm(s=gsd.sigma, scale=np.exp(gsd.number_mu))


def discrete_diameters(gsd):
    """The 100 diameters D(R) [m] at the paper's levels R = 0.005 … 0.995 (eq 2 inverted)."""
    return number_distribution(gsd).ppf(DISCRETE_LEVELS)


def sample_diameters(gsd, shape, rng, sampling="discrete"):
    """Grain diameters [m] of the given shape drawn from the number-based distribution.

    "discrete": a uniform two-digit number 00…99 picks one of `discrete_diameters`;
    "continuous": drawn from the log-normal itself. `rng` is a numpy.random.Generator.
    """
    require(sampling in SAMPLING_METHODS, "sampling", sampling, f"one of {SAMPLING_METHODS}")
    if sampling == "discrete":
        return discrete_diameters(gsd)[rng.integers(0, DISCRETE_LEVELS.size, size=shape)]
    return number_distribution(gsd).rvs(size=shape, random_state=rng)


def grain_volume(diameter):
    """Solid volume of a spherical grain πD³/6 [m³] for D [m]."""
    return np.pi * np.asarray(diameter) ** 3 / 6


def solid_volumes(count, gsd, settings, rng):
    """Solid volume V_s [m³] of `count` elements, each filled with settings.n_grains grains."""
    diameters = sample_diameters(gsd, (count, settings.n_grains), rng, settings.sampling)
    return grain_volume(diameters).sum(axis=1)


def void_ratio(element_volume, solid_volume):
    """e = V/V_s − 1 (eq 3) for V, V_s in m³."""
    return element_volume / np.asarray(solid_volume) - 1


def draw_void_ratios(count, gsd, settings, rng):
    """`count` element void ratios, each redrawn until it lies in [e_min, e_max] (eq 3)."""
    kept = np.empty(0)
    for _ in range(MAX_REDRAW_ROUNDS):
        if kept.size == count:
            return kept
        e = void_ratio(settings.element_volume,
                       solid_volumes(count - kept.size, gsd, settings, rng))
        kept = np.concatenate((kept, e[(e >= settings.e_min) & (e <= settings.e_max)]))
    raise ValueError(f"e_min, e_max = ({settings.e_min}, {settings.e_max}) keep almost no "
                     f"elements for d50 = {gsd.d50} m, sigma = {gsd.sigma}")


def build_layer(gsd, settings, rng):
    """One model sand layer of n_layers × n_columns elements."""
    count = settings.n_layers * settings.n_columns
    e = draw_void_ratios(count, gsd, settings, rng)
    return SandLayer(e.reshape(settings.n_layers, settings.n_columns), settings.element_size)


def build_layers(count, gsd, settings, rng):
    """`count` independent realisations drawn in turn from one numpy.random.Generator."""
    require(isinstance(count, (int, np.integer)) and count >= 1, "count", count,
            "a positive integer")
    return [build_layer(gsd, settings, rng) for _ in range(count)]
