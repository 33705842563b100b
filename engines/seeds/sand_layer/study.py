"""The study of the model sand layer (seed 004, SPEC §5): realisations of the layer under a strip
load on the surface centre (LOAD_WIDTH central columns under LOAD_STRESS), their transmitted
stress and settlement (mechanics), and the numbers of summary.json. Plain NumPy/SciPy, no YADE;
postproc/sand_layer.py draws the figures, yade_scripts/sand_layer.py is the command line.
"""
import os
from dataclasses import asdict, dataclass

import numpy as np

from engines import files
from engines.seeds.sand_layer.layer import (
    GrainSizeDistribution,
    SandLayerSettings,
    build_layers,
    grain_volume,
    require,
    sample_diameters,
    void_ratio,
)
from engines.seeds.sand_layer.mechanics import CC_REFERENCE_VOID_RATIO, CC_SLOPE, MechanicsSettings, analyse_layer

LOAD_STRESS = 98066.5      # Pa, 1 kgf/cm²
LOAD_WIDTH = 2             # elements
POOL_SIZE = 4000           # element fills for Fig. 1–2 and 5–8


@dataclass
class Study:
    """Everything one run computes.

    Attributes:
        seed: seed of the numpy.random.Generator used for everything [-].
        gsd, layer_settings, mechanics: the model's settings.
        surface_stress: stress on the surface elements, (n_columns,) [Pa].
        layers: the realisations (engines.seeds.sand_layer.layer.SandLayer).
        responses: their LayerResponse, same order.
        grain_pool: diameters of POOL_SIZE untruncated element fills, (POOL_SIZE, N) [m].
    """
    seed: int
    gsd: GrainSizeDistribution
    layer_settings: SandLayerSettings
    mechanics: MechanicsSettings
    surface_stress: np.ndarray
    layers: list
    responses: list
    grain_pool: np.ndarray

    @property
    def loaded(self):
        """Boolean mask (n_columns,) of the loaded surface columns."""
        return self.surface_stress > 0


def strip_load(n_columns, width, stress):
    """Stress (n_columns,) [Pa]: `stress` on `width` central columns (left of centre if odd)."""
    require(isinstance(width, int) and 1 <= width <= n_columns, "load_width", width,
            f"an integer in [1, {n_columns}]")
    require(np.isfinite(stress) and stress > 0, "load_stress", stress, "positive, in Pa")
    load = np.zeros(n_columns)
    start = (n_columns - width) // 2
    load[start:start + width] = stress
    return load


def run(realisations=25, seed=0, load_width=LOAD_WIDTH, load_stress=LOAD_STRESS,
        sampling="discrete"):
    """Build and load `realisations` sand layers; returns a Study."""
    rng = np.random.default_rng(seed)
    gsd = GrainSizeDistribution()
    layer_settings = SandLayerSettings(sampling=sampling)
    mechanics = MechanicsSettings(e_min=layer_settings.e_min, e_max=layer_settings.e_max)
    surface_stress = strip_load(layer_settings.n_columns, load_width, load_stress)
    layers = build_layers(realisations, gsd, layer_settings, rng)
    responses = [analyse_layer(layer.void_ratio, layer.element_size, surface_stress, mechanics)
                 for layer in layers]
    grain_pool = sample_diameters(gsd, (POOL_SIZE, layer_settings.n_grains), rng, sampling)
    return Study(seed, gsd, layer_settings, mechanics, surface_stress, layers, responses,
                 grain_pool)


def pool_void_ratio(study, element_volume):
    """Untruncated void ratios (eq 3) of the pool's elements for volume V [m³]."""
    return void_ratio(element_volume, grain_volume(study.grain_pool).sum(axis=1))


def summary(study):
    """JSON-ready dict of the parameters and results."""
    settlement = np.array([r.settlement for r in study.responses])
    stress = np.array([r.stress for r in study.responses])
    under_load = settlement[:, study.loaded].mean(axis=1)
    e_pool = pool_void_ratio(study, study.layer_settings.element_volume)
    e_layers = np.array([layer.void_ratio for layer in study.layers])
    ls, m = study.layer_settings, study.mechanics
    curves = m.curves
    return {
        "parameters": {
            "realisations": len(study.layers), "seed": study.seed,
            "d50": study.gsd.d50, "sigma": study.gsd.sigma, "mu_mass": study.gsd.mu,
            "mu_number": study.gsd.number_mu, "grain_shape": "sphere, V_s = pi D^3 / 6",
            **asdict(ls), "element_size": ls.element_size,
            "truncation": "redraw elements with e outside [e_min, e_max]",
            "load_width_elements": int(study.loaded.sum()),
            "load_columns": np.flatnonzero(study.loaded).tolist(),
            "load_stress": float(study.surface_stress.max()),
            "p_max_ratio": m.p_max_ratio, "p_min_ratio": m.p_min_ratio, "alpha": m.alpha,
            "lateral_edges": "mirror (symmetry-plane side walls): shares beyond a wall go to "
                             "the mirror-image element",
            "compression_law": f"e = e0 - Cc log10(p/p0), Cc = {CC_SLOPE} (e0 - "
                               f"{CC_REFERENCE_VOID_RATIO}), p from p0 to p0 + stress",
            "curves_initial_void_ratio": curves.initial_void_ratio.tolist(),
            "curves_pressure": curves.pressure.tolist(),
        },
        "settlement_mean": float(under_load.mean()),
        "settlement_std": float(under_load.std()),
        "settlement_definition": "surface settlement averaged over the loaded columns; "
                                 "mean and (population) std over realisations",
        "settlement_max_mean": float(settlement.max(axis=1).mean()),
        "load_balance_error": max(r.load_balance_error for r in study.responses),
        "stress_fraction_under_load": float(stress[:, :, study.loaded].sum() / stress.sum()),
        "settlement_fraction_under_load": float(settlement[:, study.loaded].sum()
                                                / settlement.sum()),
        "settlement_profile_mean": settlement.mean(axis=0).tolist(),
        "settlement_profile_std": settlement.std(axis=0).tolist(),
        "stress_mean": stress.mean(axis=0).tolist(),
        "layer_void_ratio_mean": float(e_layers.mean()),
        "layer_void_ratio_std": float(e_layers.std()),
        "pool_excluded_fraction": float(np.mean((e_pool < ls.e_min) | (e_pool > ls.e_max))),
        "pool_median_void_ratio": float(np.median(e_pool)),
        "units": {"d50": "m", "mu_mass": "ln m", "mu_number": "ln m", "element_volume": "m^3",
                  "element_size": "m", "load_stress": "Pa", "curves_pressure": "Pa",
                  "settlement_*": "m", "stress_mean": "Pa, (n_layers, n_columns)"},
    }


def write_outputs(study, out, figures=None):
    """summary.json into directory `out`, then ``figures(study, out)`` (postproc.sand_layer.figures
    draws the four); returns the summary."""
    os.makedirs(out, exist_ok=True)
    result = summary(study)
    files.write_json(os.path.join(out, "summary.json"), result)
    if figures:
        figures(study, out)
    return result
