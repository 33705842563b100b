"""Monte-Carlo model sand layer (Matsuo, Komada & Takahashi; SPEC §5): stress and settlement.

    /usr/bin/python3 yade_scripts/sand_layer.py --realisations 25 --seed 0 --out out/sand-layer

Plain NumPy/SciPy, no YADE. Builds `--realisations` model sand layers of 26 × 5 elements
(V = 1.2 mm³, N = 100 grains, default medium sand of engines/seeds/sand_layer/layer.py), loads each with a
strip load on the surface centre and computes the transmitted vertical stress (eq 5–8) and the
surface settlement (Fig. 11–12, engines/seeds/sand_layer/mechanics.py).

Load (the paper: a unit distributed load on the central surface element; with 26 columns there
is no single centre): a strip of `--load-width` = 2 elements, columns 12 and 13 (2.1 mm wide),
under `--load-stress` = 98.0665 kPa (1 kgf/cm², the unit of the oedometer tests behind Fig. 11).

Writes into DIR:
    summary.json                 parameters and results (SI units, listed under "units")
    fig01_02_grain_size.png      cumulative grain-size curves by mass and by number
    fig05_08_void_ratio.png      V_s, element gradings, e for V = 1.0–1.3 mm³, truncated e curve
    fig10_stress.png             transmitted vertical stress
    fig12_settlement.png         layer compression and surface settlement
"""
import json
import os
import sys
from dataclasses import asdict, dataclass

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__))))

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from engines.run.preflight import ArgumentParser, number, output_dir
from engines.seeds.sand_layer.layer import (
    DISCRETE_LEVELS,
    GrainSizeDistribution,
    SandLayerSettings,
    build_layers,
    discrete_diameters,
    grain_volume,
    mass_distribution,
    number_distribution,
    require,
    sample_diameters,
    void_ratio,
)
from engines.seeds.sand_layer.mechanics import CC_REFERENCE_VOID_RATIO, CC_SLOPE, MechanicsSettings, analyse_layer

LOAD_STRESS = 98066.5      # Pa, 1 kgf/cm²
LOAD_WIDTH = 2             # elements
POOL_SIZE = 4000           # element fills for Fig. 1–2 and 5–8
FIG7_VOLUMES = (1.0e-9, 1.1e-9, 1.2e-9, 1.3e-9)  # m³
MM, MM3, KPA, UM = 1e3, 1e9, 1e-3, 1e6           # SI → plotting units


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


def column_centres_mm(study):
    """x of the column centres [mm]."""
    ls = study.layer_settings
    return (np.arange(ls.n_columns) + 0.5) * ls.element_size * MM


def shade_load(ax, study):
    """Grey band over the loaded strip, x in mm."""
    x = np.flatnonzero(study.loaded) * study.layer_settings.element_size * MM
    ax.axvspan(x[0], x[-1] + study.layer_settings.element_size * MM, color="0.85", zorder=0,
               label="loaded strip")


def plot_grain_size(study, path):
    """Fig. 1–2: cumulative grain-size curves by mass and by number."""
    d_sorted = np.sort(study.grain_pool.ravel())
    grid = np.geomspace(number_distribution(study.gsd).ppf(1e-3),
                        mass_distribution(study.gsd).ppf(1 - 1e-3), 300)
    mass_cdf = np.cumsum(grain_volume(d_sorted)) / grain_volume(d_sorted).sum()
    number_cdf = np.arange(1, d_sorted.size + 1) / d_sorted.size
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    panels = [("Fig. 1 — by mass (eq 1)", mass_distribution, mass_cdf, "D³-weighted grains"),
              ("Fig. 2 — by number (eq 2)", number_distribution, number_cdf, "drawn grains")]
    for ax, (title, dist, cdf, label) in zip(axes, panels):
        ax.semilogx(grid * MM, 100 * dist(study.gsd).cdf(grid), "k-", label="log-normal")
        ax.semilogx(d_sorted * MM, 100 * cdf, "C1--",
                    label=f"{label} ({d_sorted.size}, {study.layer_settings.sampling})")
        ax.set(title=title, xlabel="grain diameter D (mm)")
        ax.grid(True, which="both", alpha=0.3)
    axes[1].plot(discrete_diameters(study.gsd) * MM, 100 * DISCRETE_LEVELS, "C0.", ms=4,
                 label="100 levels R = 0.005…0.995")
    axes[0].set_ylabel("percent finer (%)")
    for ax in axes:
        ax.legend(loc="upper left", fontsize=8)
    fig.suptitle(f"Grain-size distribution: D50 = {study.gsd.d50 * MM:.2f} mm by mass, "
                 f"σ = {study.gsd.sigma}; number-based ln-mean = μ − 3σ²")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_void_ratio(study, path):
    """Fig. 5–8: V_s, gradings of single elements, e for several V, truncated e curve."""
    ls = study.layer_settings
    solid = grain_volume(study.grain_pool).sum(axis=1)
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    ax = axes[0, 0]
    ax.hist(solid * MM3, bins=60, color="C0")
    ax.set(title=f"Fig. 5 — solid volume V_s of N = {ls.n_grains} grains",
           xlabel="V_s (mm³)", ylabel=f"elements (of {POOL_SIZE})")
    ax = axes[0, 1]
    grid = np.geomspace(study.grain_pool.min(), study.grain_pool.max(), 200)
    for k, grains in enumerate(study.grain_pool[:5]):
        d = np.sort(grains)
        ax.step(d * MM, 100 * np.arange(1, d.size + 1) / d.size, where="post",
                label=f"element {k + 1}")
    ax.semilogx(grid * MM, 100 * number_distribution(study.gsd).cdf(grid), "k--",
                label="population (by number)")
    ax.set(title=f"Fig. 6 — grading of single elements of {ls.n_grains} grains",
           xlabel="grain diameter D (mm)", ylabel="percent finer by number (%)")
    ax.legend(fontsize=8)
    ax = axes[1, 0]
    bins = np.linspace(-0.5, 5, 56)
    for volume in FIG7_VOLUMES:
        ax.hist(pool_void_ratio(study, volume), bins=bins, histtype="step", lw=1.5,
                label=f"V = {volume * MM3:.1f} mm³")
    ax.axvspan(ls.e_min, ls.e_max, color="0.9", zorder=0, label="kept [0.3, 3.0]")
    ax.set(title="Fig. 7 — element void ratio e = V/V_s − 1 (eq 3)", xlabel="void ratio e (-)",
           ylabel=f"elements (of {POOL_SIZE})")
    ax.legend(fontsize=8)
    ax = axes[1, 1]
    e = np.sort(pool_void_ratio(study, ls.element_volume))
    kept = e[(e >= ls.e_min) & (e <= ls.e_max)]
    drawn = np.sort(np.concatenate([layer.void_ratio.ravel() for layer in study.layers]))
    ax.plot(e, 100 * np.arange(1, e.size + 1) / e.size, "k:", label="all elements")
    ax.plot(kept, 100 * np.arange(1, kept.size + 1) / kept.size, "k-",
            label=f"without e < {ls.e_min}, e > {ls.e_max} "
                  f"({100 * (1 - kept.size / e.size):.1f} % dropped)")
    ax.step(drawn, 100 * np.arange(1, drawn.size + 1) / drawn.size, "C3", where="post", lw=1,
            label=f"layer elements ({drawn.size})")
    ax.set(title=f"Fig. 8 — cumulative distribution of e, V = {ls.element_volume * MM3:.1f} mm³",
           xlabel="void ratio e (-)", ylabel="cumulative frequency (%)", xlim=(-0.2, 4))
    ax.legend(fontsize=8, loc="lower right")
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def layer_extent_mm(study):
    """imshow extent (x from 0, depth downward) in mm."""
    ls = study.layer_settings
    return (0, ls.n_columns * ls.element_size * MM, ls.n_layers * ls.element_size * MM, 0)


def annotate_cells(ax, study, values, threshold, fmt):
    """Write `values` (n_layers, n_columns) at the element centres where >= threshold."""
    size = study.layer_settings.element_size * MM
    for (k, i), value in np.ndenumerate(values):
        if value >= threshold:
            ax.text((i + 0.5) * size, (k + 0.5) * size, format(value, fmt), ha="center",
                    va="center", fontsize=6.5,
                    bbox={"facecolor": "white", "alpha": 0.7, "pad": 0.6, "linewidth": 0})


def plot_stress(study, path):
    """Fig. 10: transmitted vertical stress, one realisation and the ensemble mean by depth."""
    stress = study.responses[0].stress * KPA
    mean = np.mean([r.stress for r in study.responses], axis=0) * KPA
    fig, axes = plt.subplots(2, 1, figsize=(11, 7.5))
    ax = axes[0]
    image = ax.imshow(stress, cmap="Oranges", extent=layer_extent_mm(study), aspect="equal")
    annotate_cells(ax, study, stress, 0.5, ".0f")
    x = column_centres_mm(study)
    z = (np.arange(stress.shape[0]) + 0.5) * study.layer_settings.element_size * MM
    fig.colorbar(image, ax=ax, label="vertical stress (kPa)", shrink=0.8)
    ax.set(title="Fig. 10 — transmitted vertical stress (kPa), realisation 1",
           xlabel="x (mm)", ylabel="depth (mm)")
    ax = axes[1]
    shade_load(ax, study)
    for k, row in enumerate(mean):
        ax.plot(x, row, "o-", ms=3, label=f"layer {k + 1} (depth {z[k]:.1f} mm)")
    ax.set(title=f"ensemble mean of {len(study.responses)} realisations", xlabel="x (mm)",
           ylabel="vertical stress (kPa)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_settlement(study, path):
    """Fig. 12: layer compressions and surface settlement, and why they spread."""
    layer, response = study.layers[0], study.responses[0]
    x = column_centres_mm(study)
    width = study.layer_settings.element_size * MM
    settlement = np.array([r.settlement for r in study.responses]) * UM
    stress = np.array([r.stress for r in study.responses]) * KPA
    fig = plt.figure(figsize=(13, 11))
    grid = fig.add_gridspec(3, 2, height_ratios=(0.8, 1, 1))
    ax = fig.add_subplot(grid[0, :])
    image = ax.imshow(layer.void_ratio, cmap="YlGnBu", extent=layer_extent_mm(study))
    annotate_cells(ax, study, response.compression * UM, 0.5, ".0f")
    fig.colorbar(image, ax=ax, label="initial void ratio e0 (-)", shrink=0.9)
    ax.set(title="realisation 1: initial void ratio (colour) and compression of each element "
                 "(µm, numbers)", xlabel="x (mm)", ylabel="depth (mm)")
    ax = fig.add_subplot(grid[1, 0])
    shade_load(ax, study)
    bottom = np.zeros_like(x)
    for k, row in enumerate(response.compression * UM):
        ax.bar(x, row, width=0.9 * width, bottom=bottom, label=f"layer {k + 1}")
        bottom += row
    ax.set(title="Fig. 12(a) — compression of each layer, realisation 1", xlabel="x (mm)",
           ylabel="compression (µm)")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(grid[1, 1])
    shade_load(ax, study)
    mean, std = settlement.mean(axis=0), settlement.std(axis=0)
    ax.fill_between(x, mean - std, mean + std, color="C0", alpha=0.25, label="mean ± std")
    ax.plot(x, mean, "C0-", lw=2, label=f"mean of {len(settlement)}")
    ax.plot(x, settlement[0], "C3o-", ms=3, label="realisation 1")
    ax.invert_yaxis()
    ax.set(title="Fig. 12(b) — surface settlement", xlabel="x (mm)",
           ylabel="settlement (µm, downward)")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(grid[2, 0])
    shade_load(ax, study)
    column_stress = stress.sum(axis=1).mean(axis=0)
    ax.plot(x, column_stress / column_stress.max(), "C3s-", ms=3,
            label="stress summed down each column")
    ax.plot(x, mean / mean.max(), "C0o-", ms=3, label="surface settlement")
    ax.set(title=f"stress concentrates, settlement spreads (mean of {len(settlement)})",
           xlabel="x (mm)", ylabel="normalised by its maximum (-)")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(grid[2, 1])
    e0 = np.array([lay.void_ratio for lay in study.layers]).ravel()
    strain = np.array([r.compression for r in study.responses]).ravel() * MM / width * 100
    loaded = stress.ravel() > 0.01
    points = ax.scatter(stress.ravel()[loaded], strain[loaded], c=e0[loaded], s=8,
                        cmap="viridis")
    fig.colorbar(points, ax=ax, label="initial void ratio e0 (-)")
    ax.set(xscale="log", title="element strain vs stress: loose elements compress more",
           xlabel="transmitted vertical stress (kPa)", ylabel="vertical strain (%)")
    for ax in fig.axes:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_outputs(study, out):
    """summary.json and the four figures into directory `out`; returns the summary."""
    os.makedirs(out, exist_ok=True)
    result = summary(study)
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(result, f, indent=1)
    plot_grain_size(study, os.path.join(out, "fig01_02_grain_size.png"))
    plot_void_ratio(study, os.path.join(out, "fig05_08_void_ratio.png"))
    plot_stress(study, os.path.join(out, "fig10_stress.png"))
    plot_settlement(study, os.path.join(out, "fig12_settlement.png"))
    return result


def parse_args(argv=None):
    """Command line; bad values are refused in one line naming the argument and its limit."""
    parser = ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--realisations", type=number(int, lo=1), default=25)
    parser.add_argument("--seed", type=number(int, lo=0), default=0)
    parser.add_argument("--out", type=output_dir, default="out/sand-layer", help="output directory")
    parser.add_argument("--load-width", type=number(int, lo=1, hi=SandLayerSettings().n_columns),
                        default=LOAD_WIDTH, help="elements")
    parser.add_argument("--load-stress", type=number(lo=0, lo_open=True, unit="Pa"), default=LOAD_STRESS,
                        help="Pa")
    parser.add_argument("--sampling", default="discrete", choices=("discrete", "continuous"))
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    study = run(args.realisations, args.seed, args.load_width, args.load_stress, args.sampling)
    result = write_outputs(study, args.out)
    print(f"settlement under the load: {result['settlement_mean'] * UM:.1f} ± "
          f"{result['settlement_std'] * UM:.1f} µm; load balance error "
          f"{result['load_balance_error']:.2e}; wrote {args.out}")


if __name__ == "__main__":
    main()
