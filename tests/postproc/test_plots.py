"""Figures that do not mislead: U on a scale centred on 0 shared by all panels (one colour bar),
each panel titled with its own maxima, equal axis limits, a key; gaps in block pressures shown."""
import json
import os
import re

import numpy as np
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.quiver import QuiverKey

from engines.model import pores as pg
from engines.run import scene as scenes
from engines.yade.deposition import scene_packing
from postproc import plots
from tests.figures import assert_drawn

NUMBER = r"([-+]?[0-9.]+(?:e[-+]?[0-9]+)?)"


def shown(text, pattern):
    """The numbers a reader reads in ``text`` where ``pattern`` (a regex with NUMBER groups) matches."""
    m = re.search(pattern, text)
    assert m, (pattern, text)
    return [float(g) for g in m.groups()]


@pytest.fixture(scope="module")
def snaps():
    """Three snapshots of the preset's packing with made-up motions, forces and pressures."""
    pk = scene_packing(scenes.preset("quicksand_case1"))
    net = pg.build_pores(pk.xz, pk.r, l_m=1.3e-4, walls=pk.group)
    rng = np.random.default_rng(0)
    out = []
    for k, (u_lo, u_hi, v) in enumerate([(0.0, 5.0, 0.0), (-60.0, 100.0, 0.05), (-20.0, 220.0, 0.3)]):
        vel = np.where(pk.mobile[:, None], rng.normal(size=(len(pk.r), 2)), 0.0)
        vel *= v / max(np.hypot(*vel.T).max(), 1e-300)
        xz = pk.xz + [0.0, 1e-3 * k] * pk.mobile[:, None]
        U = np.linspace(u_lo, u_hi, net.n_pores)
        out.append(dict(t=np.float64(0.02 * k), xz=xz, r=pk.r, group=pk.group, density_factor=pk.density_factor,
                        vel=vel, pairs=net.links[:10], f_n=np.linspace(0, 1 + k, 10), tri=net.tri,
                        tri_pore=net.tri_pore, U=U))
    return out


def test_snapshot_panels_share_a_centred_scale_and_limits_and_title_their_own_maxima(snaps):
    fig = plots.snapshot_figure(snaps, "test", blocks=[[0.0, 1e-3], [2e-3, 5e-3]])
    panels = [ax for ax in fig.axes if ax.get_title().startswith("t = ")]
    assert len(panels) == 3
    for ax, s in zip(panels, snaps):
        pores = [c for c in ax.collections if isinstance(c, PolyCollection) and c.get_array() is not None]
        norm = pores[0].norm
        assert (norm.vmin, norm.vmax) == (-220.0, 220.0)  # +-max|U| over all panels: U = 0 is the centre
        title = ax.get_title()
        assert shown(title, r"t = " + NUMBER + " ms") == pytest.approx([s["t"] * 1e3], abs=0.5)
        v = np.hypot(*s["vel"][s["group"] == 0].T).max()
        assert shown(title, r"max \|v\| = " + NUMBER + " m/s") == pytest.approx([v], rel=5e-3, abs=1e-300)
        assert shown(title, r"max f_n = " + NUMBER + " N") == pytest.approx([s["f_n"].max()], rel=5e-3)
        U_range = shown(title, r"U in \[" + NUMBER + ", " + NUMBER + r"\] N/m")
        assert U_range == pytest.approx([s["U"].min(), s["U"].max()], abs=0.5)
        assert ax.get_xlim() == panels[0].get_xlim() and ax.get_ylim() == panels[0].get_ylim()
    top = max((s["xz"][:, 1] + s["r"]).max() for s in snaps) * 1e3
    assert panels[0].get_ylim()[1] > top  # the highest disc of any panel is inside every panel
    bars = [ax for ax in fig.axes if "pore excess pressure" in ax.get_ylabel()]
    assert len(bars) == 1
    labels = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    for word in ("particle", "wall disc", "z range of block 1", "z range of block 2"):
        assert any(word in lab for lab in labels), (word, labels)
    dense = [shown(lab, r"dense top particle \(density x " + NUMBER + r"\)") for lab in labels if "dense" in lab]
    assert dense == [[max(s["density_factor"].max() for s in snaps)]]
    forces = [shown(lab, r"normal force " + NUMBER + " N")[0] for lab in labels if lab.startswith("normal force")]
    assert max(forces) == pytest.approx(max(s["f_n"].max() for s in snaps), rel=5e-3)  # the widest line
    (key,) = [a for ax in fig.axes for a in ax.artists if isinstance(a, QuiverKey)]
    assert shown(key.text.get_text(), r"^particle velocity " + NUMBER + " m/s$") == [key.U]  # the arrow is as long as it says
    v_max = max(np.hypot(*s["vel"][s["group"] == 0].T).max() for s in snaps)
    mantissa = key.U / 10 ** np.floor(np.log10(key.U))
    assert v_max / 10 <= key.U <= v_max and mantissa == pytest.approx(round(mantissa)) and round(mantissa) in (1, 2, 5)


def test_snapshots_draw_flat_walls_and_key_only_what_is_there(snaps):
    """A scene of flat walls and no wall discs: each face drawn (a line at its position [mm]), the
    key names the flat wall and no wall disc."""
    flat = [dict(s, group=np.zeros_like(s["group"]), flat_walls=np.array([[1, 0.0, 1], [0, -1e-3, 1]])) for s in snaps]
    fig = plots.snapshot_figure(flat, "test")
    labels = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert "flat wall" in labels and "wall disc" not in labels
    panel = next(ax for ax in fig.axes if ax.get_title().startswith("t = "))
    lines = [ln.get_xydata() for ln in panel.get_lines()]
    assert any(np.allclose(xy[:, 1], 0.0) for xy in lines) and any(np.allclose(xy[:, 0], -1.0) for xy in lines)


def suptitle(fig):
    return " ".join(t.get_text() for t in fig.texts)  # the figure's own texts: its suptitle


def test_a_large_scene_is_drawn_in_a_window_of_its_middle(snaps, monkeypatch):
    """More discs than WINDOW_DISCS: the panels show the middle WINDOW_DISCS / N of the scene's
    width, full height, and the title says which x range of which."""
    monkeypatch.setattr(plots, "WINDOW_DISCS", 10)
    fig = plots.snapshot_figure(snaps, "test")
    panel = next(ax for ax in fig.axes if ax.get_title().startswith("t = "))
    lo = min((s["xz"][:, 0] - s["r"]).min() for s in snaps) * 1e3
    hi = max((s["xz"][:, 0] + s["r"]).max() for s in snaps) * 1e3
    x0, x1 = panel.get_xlim()
    n = len(snaps[0]["r"])
    assert x1 - x0 == pytest.approx((hi - lo) * 10 / n + 0.6) and (x0 + x1) / 2 == pytest.approx((lo + hi) / 2)
    shown_range = shown(suptitle(fig), r"x = " + NUMBER + " to " + NUMBER + " mm of " + NUMBER + " to " + NUMBER)
    assert shown_range == pytest.approx([x0 + 0.3, x1 - 0.3, lo, hi], abs=0.5)
    monkeypatch.setattr(plots, "WINDOW_DISCS", n)  # no more discs than that: the whole scene
    fig = plots.snapshot_figure(snaps, "test")
    panel = next(ax for ax in fig.axes if ax.get_title().startswith("t = "))
    assert panel.get_xlim() == pytest.approx((lo - 0.3, hi + 0.3)) and "x = " not in suptitle(fig)


@pytest.mark.parametrize("n", [1, 2])
def test_one_or_two_snapshots_fill_their_figure_and_the_key_fits(snaps, n):
    """A run of one or two snapshots with the seismic box's six blocks: each panel spans a good part
    of the figure's width and the key lies inside the figure."""
    fig = plots.snapshot_figure(snaps[:n], "test", blocks=[[1e-3 * k, 1e-3 * (k + 1)] for k in range(6)])
    fig.canvas.draw()
    box = fig.bbox
    panels = [ax for ax in fig.axes if ax.get_title().startswith("t = ")]
    assert len(panels) == n
    for ax in panels:
        assert ax.get_window_extent().width > 0.3 * box.width
    (legend,) = [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    ext = legend.get_window_extent()
    assert box.x0 <= ext.x0 and ext.x1 <= box.x1 and box.y0 <= ext.y0 and ext.y1 <= box.y1


def test_block_pressures_name_every_block_by_position_and_span_the_data():
    t = np.linspace(0, 0.01, 101)
    hist = {"t": t, **{f"U_block{k}": (k - 3) * 4.0 * np.sin(2 * np.pi * 100 * t) for k in range(1, 7)}}
    bounds = [[1e-3 * k, 1e-3 * (k + 1)] for k in range(5)] + [[5e-3, 0.1]]
    ax = plots.block_pressure_figure(hist, 2400.0, "test", bounds).axes[0]
    labels = [x.get_text() for x in ax.get_legend().get_texts()]
    assert labels[:6] == ["block 1 (bottom, z 0.0–1.0 mm)"] + [f"block {k} (z {k - 1:.1f}–{k:.1f} mm)" for k in range(2, 6)] \
        + ["block 6 (surface, z > 5.0 mm)"]
    peak = max(np.abs(hist[c]).max() for c in hist if c != "t")
    lo, hi = ax.get_ylim()
    assert -1.2 * peak < lo < -peak and peak < hi < 1.2 * peak  # the data, not the bound E_w
    assert any("E_w = 2400 N/m" in lab and "above the axis" in lab for lab in labels)
    ax = plots.block_pressure_figure(hist, 14.0, "test").axes[0]  # a bound near the data (12 N/m) is drawn
    assert ax.get_ylim()[1] > 14.0 and plots.block_label(2, 6) == "block 3"


def test_nan_runs():
    t = np.arange(10.0)
    y = np.array([0, 1, np.nan, np.nan, 4, 5, np.nan, 7, 8, np.nan])
    assert plots.nan_runs(t, y) == [(1.0, 4.0), (5.0, 7.0), (8.0, 9.0)]
    assert plots.nan_runs(t, np.zeros(10)) == []


def test_block_pressure_gaps_are_drawn_and_explained():
    t = np.linspace(0, 0.01, 101)
    b1 = np.where((t > 0.003) & (t < 0.005), np.nan, 100 * t / 0.01)
    hist = {"t": t, "U_block1": b1, "U_block2": 0.1 * np.nan_to_num(b1)}
    fig = plots.block_pressure_figure(hist, 240.0, "test")
    ax = fig.axes[0]
    labels = [x.get_text() for x in ax.get_legend().get_texts()]
    (gap,) = [lab for lab in labels if "block 1 (bottom): no pore" in lab]
    assert shown(gap, NUMBER + " % of the time") == pytest.approx([100 * np.isnan(b1).mean()], abs=0.5)
    assert not any("block 2 (surface): no pore" in lab for lab in labels)
    hatched = [p for p in ax.patches if p.get_hatch()]
    assert len(hatched) == 1 and any("no mean U" in x.get_text() for x in ax.texts)
    fig = plots.block_pressure_figure({**hist, "U_block1": np.nan_to_num(b1)}, 240.0, "test")
    assert not [p for p in fig.axes[0].patches if p.get_hatch()] and not fig.axes[0].texts


def test_figures_of_a_run_from_its_files(snaps, tmp_path):
    t = np.linspace(0, 0.04, 5)
    with open(tmp_path / "history.csv", "w") as f:
        f.write("t,U_block1,U_block2,porosity,kinetic_energy,water_balance_error,total_water,n_pores,"
                "fn_bottom_mean,bed_top,p_band1,q_band1\n")
        for k, tk in enumerate(t):
            f.write(f"{tk},{10 * k if k != 2 else 'nan'},{k},0.2,0,0,1e-5,60,0.1,0.004,{50 - k},{k}\n")
    for s in snaps:
        np.savez(tmp_path / f"snapshot_{float(s['t']) * 1e3:06.2f}ms.npz", **s)
    json.dump({"scene": "test", "parameters": {"water": {"enabled": True, "E_w": 240.0}},
               "block_bounds_m": [[0.0, 1e-3], [2e-3, 1e-2]]}, open(tmp_path / "summary.json", "w"))
    written = plots.figures_of_run(str(tmp_path))
    assert [os.path.basename(p) for p in written] == ["pressure_blocks.png", "history_panels.png", "stress_paths.png",
                                                      "snapshots.png"]
    for path in written:
        assert_drawn(path)


def test_stress_paths_have_a_panel_per_band_from_the_surface_down(tmp_path):
    t = np.linspace(0, 0.02, 30)
    h = {"t": t}
    for k in range(1, 4):
        h[f"p_band{k}"] = 100.0 * (4 - k) * (1 - 0.8 * t / t[-1])
        h[f"q_band{k}"] = 20.0 * (4 - k) * (1 + np.sin(200 * t))
    fig = plots.stress_path_figure(h, "test", [[0.0, 1e-3], [1e-3, 2e-3], [2e-3, 3e-3]])
    fig.savefig(tmp_path / "s.png")
    assert_drawn(str(tmp_path / "s.png"))
    panels = [ax for ax in fig.axes if ax.get_title().startswith("band")]
    assert [ax.get_title().split("\n")[0] for ax in panels] == ["band 3 (surface)", "band 2", "band 1 (bottom)"]
    assert panels[2].get_xlim()[1] >= 300.0 and panels[0].get_xlim()[1] < 150.0  # each band on its own scale


def _overlap(a, b):
    """Do two display-space boxes overlap (by more than a pixel each way)?"""
    return a.x0 + 1 < b.x1 and b.x0 + 1 < a.x1 and a.y0 + 1 < b.y1 and b.y0 + 1 < a.y1


@pytest.mark.parametrize("n, cols", [(3, 3), (4, 2), (5, 3), (6, 3)])
def test_snapshot_panels_leave_the_fewest_cells_empty(snaps, n, cols):
    many = [dict(s, t=np.float64(0.01 * k)) for k, s in enumerate((snaps * 2)[:n])]
    fig = plots.snapshot_figure(many, "test")
    panels = [ax for ax in fig.axes if ax.get_title().startswith("t = ")]
    assert len(panels) == n
    assert len({round(ax.get_position().x0, 3) for ax in panels}) == cols


def test_the_gap_note_lies_under_the_key_and_inside_the_saved_figure(tmp_path):
    t = np.linspace(0, 0.01, 101)
    gappy = np.where((t > 0.003) & (t < 0.005), np.nan, 100 * t / 0.01)
    hist = {"t": t, **{f"U_block{k}": gappy * k for k in range(1, 7)}}
    fig = plots.block_pressure_figure(hist, 2400.0, "test", [[1e-3 * k, 1e-3 * (k + 1)] for k in range(6)])
    fig.canvas.draw()
    ax = fig.axes[0]
    (note,) = [x for x in ax.texts if "no mean U" in x.get_text()]
    key = ax.get_legend().get_window_extent()
    assert not _overlap(note.get_window_extent(), key) and note.get_window_extent().y1 <= key.y0 + 1
    path = tmp_path / "p.png"
    plots.plot_block_pressures(hist, 2400.0, str(path), "test")
    assert_drawn(str(path))
