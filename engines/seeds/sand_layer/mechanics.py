"""Stress transmission and settlement of the Monte-Carlo model sand layer (seed 004, SPEC §5).

Only vertical loads are considered. A load P on element i of one layer passes to elements
i, i±1, i±2 of the layer below, with shares set by the void ratios e of those receiving
elements (eq 5–8):

    P_i    = (P_max − P_min)/(1/e_min − 1/e_max) · (1/(2e_i) − 1/(e_{i−1} + e_{i+1}))
             + (P_max + P_min)/2                                                    (eq 6)
    P_{i±1} = s_± f_± (P − P_i),   P_{i±2} = s_± (1 − f_±)(P − P_i)                  (eq 7)
    s_±    = e_{i∓1}/(e_{i−1} + e_{i+1})      (= (1/e_{i±1}) / (1/e_{i−1} + 1/e_{i+1}))
    f_±    = α e_{i±2}/(e_{i±1} + α e_{i±2})  (= (1/e_{i±1}) / (1/e_{i±1} + 1/(α e_{i±2})))  (eq 8)

with P_max = 0.8P, P_min = 0.4P, α = 4: on a uniform layer 60 % of P goes straight down, 16 %
to each of i±1 and 4 % to each of i±2. e_min, e_max in eq 6 are the bounds of the element void
ratios (the truncation window 0.3, 3.0), so P_min <= P_i <= P_max always.

Where the paper is unclear (OCR) we read it as follows, and say so:
  * eq 7 as printed weights the two sides by e_{i±1} and uses a different denominator for
    P_{i±2}; that neither conserves the load nor follows the paper's premise that denser
    elements carry more. We use the side share s_± ∝ 1/e_{i±1} (as eq 5 and eq 8 do) and the
    same s_± for i±1 and i±2, so that P_i + Σ P_{i±1} + Σ P_{i±2} = P exactly.
  * The void ratios are those of the receiving elements in the layer below.
  * The surface layer carries the applied load itself.
Lateral edges: the side walls are symmetry planes (smooth rigid walls). A receiver beyond the
wall is the mirror image of an element inside (column −1 ↔ 0, −2 ↔ 1, n ↔ n−1, n+1 ↔ n−2); it
has that element's void ratio in eq 6–8 and its share is given to that element. No load leaves
the layer, so every layer carries the applied total to round-off.

Settlement (Fig. 11–12): each element compresses one-dimensionally along the e–log p curve of
its initial void ratio e0, from the curves' first (seating) pressure p0 to p0 + σ, σ being the
transmitted vertical stress; self-weight (≈ 0.1 kPa at 5 mm depth) is neglected beside p0. The
element of height H shortens by H (e0 − e)/(1 + e0) and a column's surface settlement is the sum
over its elements. Curves are a table (`CompressionCurves`, bilinear in e0 and log p between
curves). The default table follows Cc(e0) = 0.1 (e0 − 0.3), e = e0 − Cc log10(p/p0), for
e0 = 0.3 … 3.0 (step 0.1) and p = p0·2^k, p0 = 0.1 kgf/cm² = 9.80665 kPa, k = 0…7 (the usual
oedometer steps up to 12.8 kgf/cm²). It gives Cc ≈ 0.03–0.1 over the e0 = 0.55–1.35 the paper
measured (typical of clean sand), grows with looseness as the paper's extrapolation must, and
vanishes at e = 0.3, the densest element allowed.

Units: stresses and pressures in Pa, lengths in m, loads in any consistent unit (all element tops
have the same area, so force and stress transmit alike).
"""
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from engines.seeds.sand_layer.layer import require

#: Column offsets of the receivers i−2 … i+2 in the layer below.
OFFSETS = np.arange(-2, 3)
#: Default compression curves: seating pressure p0 [Pa] and the law Cc = slope (e0 − e_ref).
SEATING_PRESSURE = 9806.65
CC_SLOPE = 0.1
CC_REFERENCE_VOID_RATIO = 0.3


@dataclass(frozen=True)
class CompressionCurves:
    """Table of one-dimensional compression curves e(p), one per initial void ratio (Fig. 11).

    Attributes:
        initial_void_ratio: e0 of each curve, strictly increasing, shape (K,) [-].
        pressure: vertical stress, strictly increasing and positive, shape (M,) [Pa];
            pressure[0] is the seating pressure at which every curve starts at its e0.
        void_ratio: e of curve k at pressure[j], shape (K, M) [-]; void_ratio[:, 0] equals
            initial_void_ratio and each row does not increase with pressure.
    """
    initial_void_ratio: np.ndarray
    pressure: np.ndarray
    void_ratio: np.ndarray

    def __post_init__(self):
        e0, p, e = (np.asarray(a, dtype=float) for a in
                    (self.initial_void_ratio, self.pressure, self.void_ratio))
        require(e0.ndim == 1 and e0.size >= 2 and np.all(np.diff(e0) > 0),
                "initial_void_ratio", e0, "a strictly increasing 1-D array of >= 2 values")
        require(p.ndim == 1 and p.size >= 2 and p[0] > 0 and np.all(np.diff(p) > 0),
                "pressure", p, "a strictly increasing 1-D array of >= 2 positive values in Pa")
        require(e.shape == (e0.size, p.size), "void_ratio.shape", e.shape,
                f"(len(initial_void_ratio), len(pressure)) = {(e0.size, p.size)}")
        require(np.allclose(e[:, 0], e0, rtol=0, atol=1e-12), "void_ratio[:, 0]", e[:, 0],
                "equal to initial_void_ratio")
        require(np.all(np.diff(e, axis=1) <= 0) and np.all(e >= 0), "void_ratio", e,
                "non-negative and non-increasing with pressure")


def compression_index(e0):
    """Default compression index Cc(e0) = 0.1 (e0 − 0.3) [-]."""
    return CC_SLOPE * (np.asarray(e0) - CC_REFERENCE_VOID_RATIO)


def default_compression_curves():
    """Default table: e = e0 − Cc(e0) log10(p/p0), e0 = 0.3…3.0, p = p0·2^k, k = 0…7."""
    e0 = np.linspace(0.3, 3.0, 28)
    pressure = SEATING_PRESSURE * 2.0 ** np.arange(8)
    e = e0[:, None] - compression_index(e0)[:, None] * np.log10(pressure / pressure[0])
    return CompressionCurves(e0, pressure, e)


@dataclass(frozen=True)
class MechanicsSettings:
    """Settings of stress transmission (eq 5–8) and settlement (Fig. 11).

    Attributes:
        p_max_ratio, p_min_ratio: P_max/P and P_min/P of eq 6 [-] (paper: 0.8, 0.4).
        alpha: α of eq 8 [-] (paper: 4).
        e_min, e_max: E_min, E_max of eq 6, the bounds of the element void ratios [-].
        curves: the e–log p curves used for settlement.
    """
    p_max_ratio: float = 0.8
    p_min_ratio: float = 0.4
    alpha: float = 4.0
    e_min: float = 0.3
    e_max: float = 3.0
    curves: CompressionCurves = field(default_factory=default_compression_curves)

    def __post_init__(self):
        require(0 <= self.p_min_ratio <= self.p_max_ratio <= 1, "p_min_ratio, p_max_ratio",
                (self.p_min_ratio, self.p_max_ratio), "0 <= p_min_ratio <= p_max_ratio <= 1")
        require(np.isfinite(self.alpha) and self.alpha > 0, "alpha", self.alpha, "positive")
        require(0 < self.e_min < self.e_max, "e_min, e_max", (self.e_min, self.e_max),
                "0 < e_min < e_max")


@dataclass(frozen=True)
class LayerResponse:
    """Response of one sand layer to a surface load.

    Attributes:
        stress: transmitted vertical stress on each element, (n_layers, n_columns) [Pa].
        void_ratio: void ratio after loading, (n_layers, n_columns) [-].
        compression: shortening of each element, (n_layers, n_columns) [m] (Fig. 12a).
        settlement: surface settlement of each column, (n_columns,) [m] (Fig. 12b).
        load_balance_error: max over layers of |layer total − applied total| / applied total [-].
    """
    stress: np.ndarray
    void_ratio: np.ndarray
    compression: np.ndarray
    settlement: np.ndarray
    load_balance_error: float


def check_void_ratio(void_ratio, settings):
    """Raise ValueError unless every void ratio lies in [e_min, e_max]."""
    e = np.asarray(void_ratio, dtype=float)
    require(e.size > 0, "void_ratio.size", e.size, "positive")
    require(np.all((e >= settings.e_min) & (e <= settings.e_max)), "void_ratio",
            f"range [{e.min()}, {e.max()}]",
            f"within [e_min, e_max] = [{settings.e_min}, {settings.e_max}]")


def reflect(column, n_columns):
    """Column index of the in-layer image of `column` across the side walls."""
    column = np.mod(column, 2 * n_columns)
    return np.where(column < n_columns, column, 2 * n_columns - 1 - column)


def _side_shares(e_near, e_far, alpha):
    """f and 1 − f of eq 8: split of one side's share between i±1 (near) and i±2 (far)."""
    f = alpha * e_far / (e_near + alpha * e_far)  # eq 8
    return f, 1 - f


def transmission_weights(void_ratio_below, settings):
    """Shares of a load on element i passed to i−2 … i+2 below, shape (n, 5), rows sum to 1.

    `void_ratio_below`: void ratios (n,) of the receiving layer; beyond the side walls the
    mirror images' void ratios are used.
    """
    n = len(void_ratio_below)
    e_pad = np.pad(np.asarray(void_ratio_below, dtype=float), 2, mode="symmetric")
    e_m2, e_m1, e_i, e_p1, e_p2 = (e_pad[k:k + n] for k in range(5))
    s = settings
    slope = (s.p_max_ratio - s.p_min_ratio) / (1 / s.e_min - 1 / s.e_max)
    mid = (s.p_max_ratio + s.p_min_ratio) / 2
    centre = slope * (1 / (2 * e_i) - 1 / (e_m1 + e_p1)) + mid  # eq 6: P_i / P
    rest = 1 - centre
    left, right = e_p1 / (e_m1 + e_p1), e_m1 / (e_m1 + e_p1)  # eq 7: s_± ∝ 1/e_{i±1}
    f_left, g_left = _side_shares(e_m1, e_m2, s.alpha)
    f_right, g_right = _side_shares(e_p1, e_p2, s.alpha)
    return np.stack([left * g_left * rest, left * f_left * rest, centre,  # eq 7
                     right * f_right * rest, right * g_right * rest], axis=1)


def transmission_matrix(void_ratio_below, settings):
    """T (n, n) with load_below = T @ load_above; shares beyond a wall go to the mirror image."""
    n = len(void_ratio_below)
    source = np.arange(n)[:, None]
    matrix = np.zeros((n, n))
    np.add.at(matrix, (reflect(source + OFFSETS, n), np.broadcast_to(source, (n, OFFSETS.size))),
              transmission_weights(void_ratio_below, settings))
    return matrix


def transmit_load(void_ratio, surface_load, settings):
    """Vertical load on every element, (n_layers, n_columns), row 0 = `surface_load` (eq 5–8).

    `void_ratio`: (n_layers, n_columns) element void ratios [-], row 0 at the surface.
    `surface_load`: (n_columns,) non-negative load on the surface elements (N, or Pa).
    """
    e = np.asarray(void_ratio, dtype=float)
    load = np.asarray(surface_load, dtype=float)
    require(e.ndim == 2, "void_ratio.ndim", e.ndim, "2 (n_layers, n_columns)")
    check_void_ratio(e, settings)
    require(load.shape == (e.shape[1],), "surface_load.shape", load.shape,
            f"(n_columns,) = ({e.shape[1]},)")
    require(np.all(np.isfinite(load) & (load >= 0)), "surface_load", load,
            "finite and non-negative")
    loads = [load]
    for e_below in e[1:]:
        loads.append(transmission_matrix(e_below, settings) @ loads[-1])
    return np.array(loads)


def load_balance_error(load):
    """max_k |Σ load[k] − Σ load[0]| / Σ load[0] over the layers k [-]."""
    totals = np.asarray(load).sum(axis=1)
    require(totals[0] > 0, "total surface load", totals[0], "positive")
    return float(np.max(np.abs(totals - totals[0])) / totals[0])


def void_ratio_reduction(initial_void_ratio, stress, curves):
    """Decrease of void ratio e0 − e on compression from p0 to p0 + `stress` (Fig. 11) [-].

    Bilinear interpolation of the table's e0 − e in (e0, log p). `stress` [Pa] >= 0, same shape
    as `initial_void_ratio`; both must stay inside the table.
    """
    e0 = np.asarray(initial_void_ratio, dtype=float)
    pressure = curves.pressure[0] + np.asarray(stress, dtype=float)
    require(e0.shape == pressure.shape, "stress.shape", pressure.shape,
            f"the shape of initial_void_ratio {e0.shape}")
    levels = curves.initial_void_ratio
    require(np.all((e0 >= levels[0]) & (e0 <= levels[-1])), "initial_void_ratio",
            f"range [{e0.min()}, {e0.max()}]", f"within the curves' [{levels[0]}, {levels[-1]}]")
    require(np.all((pressure >= curves.pressure[0]) & (pressure <= curves.pressure[-1])),
            "stress", f"range [{np.min(stress)}, {np.max(stress)}] Pa",
            f"within [0, {curves.pressure[-1] - curves.pressure[0]}] Pa (the curves' range)")
    reduction = levels[:, None] - curves.void_ratio
    table = RegularGridInterpolator((levels, np.log(curves.pressure)), reduction)
    return table(np.stack([e0.ravel(), np.log(pressure).ravel()], axis=-1)).reshape(e0.shape)


def analyse_layer(void_ratio, element_size, surface_stress, settings):
    """Transmitted stress, compression and surface settlement of one sand layer.

    `void_ratio`: (n_layers, n_columns) initial void ratios e0 [-]; `element_size`: element
    height H [m]; `surface_stress`: (n_columns,) vertical stress on the surface elements [Pa].
    """
    require(np.isfinite(element_size) and element_size > 0, "element_size", element_size,
            "a positive length in m")
    e0 = np.asarray(void_ratio, dtype=float)
    stress = transmit_load(e0, surface_stress, settings)
    reduction = void_ratio_reduction(e0, stress, settings.curves)
    compression = element_size * reduction / (1 + e0)
    return LayerResponse(stress, e0 - reduction, compression, compression.sum(axis=0),
                         load_balance_error(stress))
