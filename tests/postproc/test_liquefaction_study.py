"""The study's measures (postproc/liquefaction.py) on signals with known answers."""
import json
import os

import numpy as np
import pytest

from engines.studies.ensemble import ensemble_statistics
from postproc.liquefaction import band_porosity, compaction_correlation, depth_figure, dominant_period, end_mean, study
from tests.figures import assert_drawn

t = np.arange(0, 0.18, 1e-4)


def test_dominant_period_of_a_ramped_cosine_is_its_period():
    y = 40 * t / 0.18 + 10 * np.cos(2 * np.pi * 50 * t) + 3 * np.cos(2 * np.pi * 170 * t)
    assert dominant_period(t, y) == pytest.approx(0.02, rel=0.02)


def test_end_mean_averages_the_last_period():
    y = 5.0 + np.sin(2 * np.pi * 50 * t)
    assert end_mean(t, y) == pytest.approx(5.0, abs=0.01)


def test_compaction_correlation():
    n = 0.47 - 0.02 * (1 - np.exp(-t / 0.05))
    assert compaction_correlation(n, 2400 * (n[0] - n) / 0.25) == pytest.approx(1.0)  # U from compaction
    assert abs(compaction_correlation(n, 50 * np.sin(2 * np.pi * 50 * t))) < 0.2  # U oscillating alone


def _write_start(path, dn, wet, rng):
    """A start's history.csv and summary.json with a porosity falling by ``dn`` over 0.18 s."""
    os.makedirs(path)
    tt = np.arange(0, 0.1801, 1e-3)
    h = {"t": tt, "porosity": 0.47 + dn * tt / tt[-1], "base_acc": 15 * np.cos(2 * np.pi * 50 * tt),
         "base_disp": 0 * tt, "side_left_dx": 0 * tt, "side_right_dx": 0 * tt, "bed_top": 0.01 + 0 * tt}
    for b in range(1, 7):
        h[f"U_block{b}"] = (100 * tt / tt[-1] + 10 * rng.standard_normal(len(tt))) if wet else np.full(len(tt), np.nan)
    with open(os.path.join(path, "history.csv"), "w") as f:
        f.write(",".join(h) + "\n")
        for row in zip(*h.values()):
            f.write(",".join(repr(float(v)) for v in row) + "\n")
    summary = {"scene": "test", "status": "completed", "steps": 180000, "wall_seconds": 1.0, "us_per_step": 1.0,
               "parameters": {"water": {"enabled": wet, "transfer": "paper"}}, "water_balance_error": 0.0, "n_rebuilds": 180}
    if wet:
        summary["water_balance"] = {"initial": 1e-5, "remesh_change": 0.0, "side_outflow": 0.0, "surface_outflow": 0.0}
    with open(os.path.join(path, "summary.json"), "w") as f:
        json.dump(summary, f)
    return h


def test_study_reads_ensembles_and_states_the_trends_with_intervals(tmp_path):
    """Cases 1 (wet) and 2 (dry) as ensembles of 4 starts: the study reads every start, the dry
    case settling 3x the wet one holds its trend, and Fig. 40 draws the means."""
    rng = np.random.default_rng(4)
    for case, dn, wet in ((1, -0.02, True), (2, -0.06, False)):
        root = tmp_path / f"case{case}"
        hists = [_write_start(str(root / f"start_{k}"), dn * (1 + 0.02 * rng.standard_normal()), wet, rng)
                 for k in range(4)]
        stats = ensemble_statistics(hists, [{} for _ in hists])
        with open(root / "ensemble.json", "w") as f:
            json.dump({"seeds": list(range(4)), **stats}, f, default=lambda a: None)
    written = study(str(tmp_path))
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["starts"] == {"case1": 4, "case2": 4}
    (row,) = [r for r in summary["trends"] if r["trend"].startswith("dry settles more than saturated-undrained (cosine")]
    cond = row["conditions"][0]
    assert cond["estimate"] == pytest.approx(3.0, rel=0.05) and cond["ci95"][0] > 2.0 and row["verdict"] == "holds"
    assert "→ holds" in (tmp_path / "trends.md").read_text()
    fig40 = [p for p in written if p.endswith("fig40_porosity_cosine_spring_d.png")]
    assert fig40 and assert_drawn(fig40[0]) is None


def _square_box(nx, nz, r, dz=0.0):
    """A square lattice of touching discs of radius r, nx wide and nz high, on a bottom row of wall
    discs and between two wall columns, every particle lifted by dz; as a snapshot dict."""
    ix, iz = np.meshgrid(np.arange(nx), np.arange(nz))
    xz = np.column_stack([(2 * ix.ravel() + 1) * r, (2 * iz.ravel() + 1) * r + dz])
    bottom = np.column_stack([(2 * np.arange(-1, nx + 1) + 1) * r, np.full(nx + 2, -r)])
    left = np.column_stack([np.full(nz, -r), xz[:nz * nx:nx, 1] - dz])
    right = np.column_stack([np.full(nz, (2 * nx + 1) * r), xz[:nz * nx:nx, 1] - dz])
    pts = np.vstack([xz, bottom, left, right])
    group = np.r_[np.zeros(len(xz)), np.ones(len(bottom)), np.full(nz, 2), np.full(nz, 3)].astype(int)
    return {"t": 0.0, "xz": pts, "r": np.full(len(pts), r), "group": group, "density_factor": np.ones(len(pts))}


def test_band_porosity_of_a_square_lattice_is_one_minus_pi_over_4():
    """Bands of two rows each hold whole discs: 1 - pi/4; a band cut through the disc centres
    holds half of each row around it, the same; a band above the bed is empty."""
    r = 1e-3
    snap = _square_box(6, 4, r)
    bands = [[0.0, 4 * r], [4 * r, 8 * r], [r, 5 * r]]
    assert band_porosity(snap, bands, top=8 * r) == pytest.approx([1 - np.pi / 4] * 3, rel=1e-9)
    assert band_porosity(snap, [[8 * r, 10 * r]], top=10 * r) == pytest.approx([1.0])
    # the bed lifted by r / 2: the second row's caps of height r / 2 leave the band [0, 4 r]
    lifted = band_porosity(_square_box(6, 4, r, dz=0.5 * r), [[0.0, 4 * r]], top=8.5 * r)[0]
    cap = np.arccos(0.5) - 0.5 * np.sqrt(0.75)  # [r^2]
    assert lifted == pytest.approx(1 - (2 * np.pi - cap) / 8, rel=1e-9)  # per column: 2 r x 4 r


def _overlap(a, b):
    return a.x0 + 1 < b.x1 and b.x0 + 1 < a.x1 and a.y0 + 1 < b.y1 and b.y0 + 1 < a.y1


def test_depth_figure_draws_pressure_and_porosity_by_height(tmp_path):
    r = 1e-3
    snaps = [_square_box(6, 4, r), {**_square_box(6, 4, r, dz=-0.1 * r), "t": 0.01}]
    tt = np.arange(0, 0.0101, 1e-3)
    h = {"t": tt, "U_block1": 50 * np.sin(300 * tt), "U_block2": -20 * tt / tt[-1]}
    fig = depth_figure(h, snaps, [[0.0, 4 * r], [4 * r, 10.0]], "square lattice")
    fig.savefig(tmp_path / "d.png")
    assert assert_drawn(str(tmp_path / "d.png")) is None
    panels = [ax for ax in fig.axes if ax.get_title().endswith("by height")]
    assert [ax.get_xlim() for ax in panels] == [(0.0, 10.0)] * 2  # both over the run's whole time
    fig.canvas.draw()  # no colour bar, nor its label, on another panel or on the other's label
    bars = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    assert [ax.get_xlabel().split(" [")[0] for ax in bars] == ["block-mean excess pore pressure U",
                                                                "porosity change since t = 0"]


def test_depth_figure_draws_ru_by_height_with_0_and_1_marked(tmp_path):
    """With the bands' r_u in the history: a fourth panel, its colour bar spanning 0 and 1, both
    marked, and the contour r_u = 1 where a band reaches it."""
    r = 1e-3
    snaps = [_square_box(6, 4, r), {**_square_box(6, 4, r, dz=-0.1 * r), "t": 0.01}]
    tt = np.arange(0, 0.0101, 1e-3)
    h = {"t": tt, "U_block1": 50 * np.sin(300 * tt), "U_block2": -20 * tt / tt[-1],
         "ru_band1": 1.1 * tt / tt[-1], "ru_band2": 0.5 * tt / tt[-1], "ru_band3": np.zeros_like(tt)}
    fig = depth_figure(h, snaps, [[0.0, 4 * r], [4 * r, 10.0]], "square lattice", [[0.0, r], [r, 2 * r], [2 * r, 3 * r]])
    fig.savefig(tmp_path / "d.png")
    assert_drawn(str(tmp_path / "d.png"))
    ru = [ax for ax in fig.axes if ax.get_title().startswith("pore-pressure ratio")]
    assert len(ru) == 1 and len(ru[0].collections) >= 2  # the colour mesh and the contour r_u = 1
    bar = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"][-1]
    lo, hi = bar.get_xlim()
    assert lo <= 0.0 and hi >= 1.0 and sorted(line.get_xdata()[0] for line in bar.lines) == [0.0, 1.0]
    boxes = [ax.get_tightbbox() for ax in fig.axes]
    assert not any(_overlap(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
