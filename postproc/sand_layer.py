"""The figures of the sand-layer study (engines.seeds.sand_layer.study): grain sizes (Fig. 1–2),
element void ratios (Fig. 5–8), transmitted stress (Fig. 10), settlement (Fig. 12)."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from engines import files  # noqa: E402
from engines.seeds.sand_layer.layer import (  # noqa: E402
    DISCRETE_LEVELS,
    discrete_diameters,
    grain_volume,
    mass_distribution,
    number_distribution,
)
from engines.seeds.sand_layer.study import POOL_SIZE, pool_void_ratio  # noqa: E402

FIG7_VOLUMES = (1.0e-9, 1.1e-9, 1.2e-9, 1.3e-9)  # m³
MM, MM3, KPA, UM = 1e3, 1e9, 1e-3, 1e6           # SI → plotting units


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
    files.save_figure(fig, path, dpi=120)
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
    files.save_figure(fig, path, dpi=120)
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
    files.save_figure(fig, path, dpi=120)
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
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


def figures(study, out):
    """The four figures of ``study`` into directory ``out``."""
    plot_grain_size(study, os.path.join(out, "fig01_02_grain_size.png"))
    plot_void_ratio(study, os.path.join(out, "fig05_08_void_ratio.png"))
    plot_stress(study, os.path.join(out, "fig10_stress.png"))
    plot_settlement(study, os.path.join(out, "fig12_settlement.png"))
