"""The reconstruction's table (postproc.liquefaction.reconstruction) on starts of known means."""
import numpy as np

from engines.studies.liquefaction import TRENDS, trends
from engines.studies.reconstruction import variant_cases
from postproc.liquefaction import reconstruction_figure, reconstruction_markdown
from tests.figures import assert_drawn
from tests.studies.test_liquefaction import _ensemble
from tests.studies.test_reconstruction import _base


def test_the_table_and_figure_show_each_variant_against_the_presets(tmp_path):
    rng = np.random.default_rng(5)
    base = _base(rng)
    doc = {"reference": trends(base), "variants": {"k_x10": {
        "unknown": "k x10", "reason": "r", "cases": [3], "done": [3], "changed": [3], "starts": {3: 8}, "packing": None,
        "case_means": {3: {"porosity_initial": 0.47, "porosity_change": -0.03, "U_low_mean": 11.0}},
        "trends": trends(variant_cases(base, (3,), {3: _ensemble(rng, 8, 11, 5, -0.035)}))}}}
    table = reconstruction_markdown(doc).splitlines()
    ref, var = table[2], table[3]  # columns: variant, T1 ... (T3: the drained sides)
    assert ref.startswith("| the presets") and var.startswith("| k_x10 |")
    assert ref.split("|")[4].strip().endswith("✗ **fails**") and var.split("|")[4].strip().endswith("✓ **holds**")
    assert len(ref.split("|")) == len(var.split("|")) == 2 + len(TRENDS) + 1
    fig = reconstruction_figure(doc)
    fig.savefig(tmp_path / "r.png")
    assert assert_drawn(str(tmp_path / "r.png")) is None
