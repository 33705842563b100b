"""The resistance curve's figure draws what the study's JSON holds: one marker per row and packing at
its median N_L (censored rows open, at the runs' cycles), on a log N_L axis."""
import json
import os

import numpy as np
from matplotlib.figure import Figure

from engines import ROOT
from engines.studies.resistance import read_rows
from postproc import resistance

STUDY = os.path.join(ROOT, "docs", "resistance", "resistance.json")


def drawn(doc, tmp_path, monkeypatch):
    figures = []
    monkeypatch.setattr(resistance.plt, "close", figures.append)
    resistance.resistance_figure(doc, str(tmp_path / "r.png"))
    return [f for f in figures if isinstance(f, Figure)][-1].axes[0]


def test_each_row_is_drawn_at_its_median_or_open_at_the_runs_end(tmp_path, monkeypatch):
    doc = json.load(open(STUDY))
    rows = [r for p in doc["packings"].values() for r in read_rows(p)]
    doc["packings"]["loose"]["rows"][0]["n_l"].update(median=7.0, low=5.0, high=9.0)  # one liquefied row
    ax = drawn(doc, tmp_path, monkeypatch)
    assert ax.get_xscale() == "log"
    marks = [c.lines[0] for c in ax.containers]  # the errorbars' data markers, one per row
    assert len(marks) == len(rows)
    xs = [float(m.get_xdata()[0]) for m in marks]
    assert xs.count(7.0) == 1 and xs.count(doc["cycles"]) == len(rows) - 1
    filled = [m.get_markerfacecolor() != "white" for m in marks]
    assert filled == [x == 7.0 for x in xs], "censored rows open, liquefied ones filled"
    ys = sorted(float(m.get_ydata()[0]) for m in marks)
    assert np.allclose(ys, sorted(r["csr"]["mean"] for r in rows)), "each row at its mean CSR"


def test_the_ground_run_is_a_star_at_its_n_l_and_csr_without_bars(tmp_path, monkeypatch):
    doc = json.load(open(STUDY))
    doc["ground"] = {"n_particles": 10000, "void_ratio": 0.25, "censored": False, "n_l": 12.0, "csr": 0.07}
    ax = drawn(doc, tmp_path, monkeypatch)
    stars = [ln for ln in ax.lines if ln.get_marker() == "*"]
    assert len(stars) == 1 and list(stars[0].get_xydata()[0]) == [12.0, 0.07]
    assert "10,000-disc ground, one run (e = 0.250)" in [t.get_text() for t in ax.get_legend().get_texts()]
    doc["ground"].update(censored=True, n_l=None)
    star, = [ln for ln in drawn(doc, tmp_path, monkeypatch).lines if ln.get_marker() == "*"]
    assert star.get_xdata()[0] == doc["cycles"] and star.get_markerfacecolor() == "white"
