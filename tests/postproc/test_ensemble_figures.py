"""The ensemble's figures and the comparison of perturbation sizes, on synthetic ensembles (no YADE)."""
import json

import numpy as np

from engines.studies.ensemble import ensemble_statistics
from postproc import ensemble
from tests.figures import assert_drawn

COLUMNS = ("U_block1", "U_block2", "porosity", "kinetic_energy", "fn_bottom_mean", "bed_top")


def synthetic(folder, size, n=4, seed=0):
    """An ensemble folder of n starts whose histories spread as size x exp(t / 2 ms) about one curve."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 0.0101, 5e-4)
    histories, results = [], []
    for k in range(n):
        h = {"t": t, **{c: 0.4 + t + size * np.exp(t / 2e-3) * rng.standard_normal(len(t)) for c in COLUMNS}}
        histories.append(h)
        results.append({"heave_time_s": 0.008 + 1e-4 * k, "porosity_end": float(h["porosity"][-1])})
        start = folder / f"start_{k}"
        start.mkdir(parents=True)
        (start / "summary.json").write_text(json.dumps({"parameters": {"water": {"enabled": True, "E_w": 240.0}}}))
        (start / "history.csv").write_text(",".join(h) + "\n" + "\n".join(",".join(f"{h[c][i]:.9g}" for c in h)
                                                                             for i in range(len(t))) + "\n")
    doc = {"scene": "synthetic", "n_starts": n, "perturbation_m": size, "starts": [f"start_{k}" for k in range(n)],
           **ensemble_statistics(histories, results)}
    (folder / "ensemble.json").write_text(json.dumps(doc))
    return folder


def test_the_figures_draw_the_means_with_their_bands(tmp_path):
    paths = ensemble.figures(str(synthetic(tmp_path / "e", 1e-3)))
    assert [p.rsplit("/", 1)[1] for p in paths] == ["ensemble_pressure_blocks.png", "ensemble_history.png"]
    for p in paths:
        assert_drawn(p)


def test_compare_tables_the_spreads_and_the_differences(tmp_path):
    dirs = [str(synthetic(tmp_path / f"p{k}", size, n=8, seed=k)) for k, size in enumerate((1e-6, 1e-4))]
    rows = ensemble.compare(dirs, str(tmp_path / "cmp.png"), [0.0, 0.01])
    assert_drawn(str(tmp_path / "cmp.png"))
    assert rows[2].startswith("| 1e-06 | 8 | 8.35 ± 0.09 |")  # 8.0 ... 8.7 ms: SE 0.245 / sqrt(8) and rows[3].startswith("| 0.0001 | 8 |")
    small, large = ([float(x) for x in r.strip("|").split("|")[3:5]] for r in rows[2:4])  # bed top at 0, 10 ms
    assert 10 < large[0] / small[0] < 1000 and large[1] > large[0] * 50  # the spread grows as exp(t / 2 ms)
    diff = ensemble.differences(dirs, 0.01)
    assert len(diff) == 3 and diff[2].startswith("| 0.0001 m against 1e-06 m |")
