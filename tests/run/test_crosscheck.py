"""The cross-check's machinery (engines.run.crosscheck), with the reference standing in for YADE."""
import json

import numpy as np

from engines.reference import model as ref
from engines.run import crosscheck as cc
from packing.packing import Packing


def test_crosscheck_plumbing_with_the_reference_on_both_sides(tmp_path):
    """The cross-check's machinery with the reference standing in for YADE: every case passes with
    identical trajectories, the JSON holds the features and counts, and a deliberately different
    'other implementation' (start moved by 1e-9 m) fails."""

    def stand_in(scene, pk, n, every, hooks=(), **kw):
        return ref.simulate_reference(scene, pk, n, every, **kw)

    shaken = {"loading": {"type": "cosine", "amplitude": 200.0, "frequency": 300.0, "moves": "bottom"},
              "numerics": {"rebuild_interval": 5}}
    small = cc.FeatureCase("small_settling", cc.settling_build(**shaken), 150, 5, rules="a")
    contact = [c for c in cc.contact_cases() if c.name in ("head_on_collision", "pressed_release_d")]
    result = cc.run_cases(stand_in, cases=contact, features=[small])
    assert result["passed"], [c["why"] for c in result["cases"] + result["feature_cases"] if not c["passed"]]
    for case in result["cases"]:
        assert case["metrics"]["max_position_diff_rel"] == 0.0
        assert set(case["metrics"]) == set(case["tolerances"]) | set(case["not_judged"])   # each judged or explained
    feat = result["feature_cases"][0]
    assert set(feat["not_judged"]) <= set(feat) - {"checks", "passed", "why"}
    assert feat["window"]["max_position_diff_rel"] == 0.0 and feat["counts"]["ref"]["rebuilds"] >= 20
    assert feat["features"]["water"] and feat["features"]["rebuild_interval"] == 5
    path = cc.write_json(result, str(tmp_path))
    with open(path) as f:
        back = json.load(f)
    assert {c["name"] for c in back["cases"]} >= {"head_on_collision", "pressed_release_d"}
    assert back["feature_cases"][0]["name"] == "small_settling"

    unexplained = cc.Case("unexplained", contact[0].build, 10, 5, {}, "a metric without a tolerance or a reason",
                          lambda ty, tr, scene, pk: {"max_position_diff_rel": 0.0})
    bad = cc.run_cases(stand_in, cases=[unexplained], features=[])
    assert not bad["passed"] and "max_position_diff_rel (neither judged nor explained)" in bad["cases"][0]["why"]

    def moved(scene, pk, n, every, hooks=(), **kw):
        return stand_in(scene, Packing(pk.xz + 1e-9, pk.r, pk.group, pk.density_factor), n, every)
    for case in (small, cc.FeatureCase("still", cc.settling_build(numerics={"rebuild_interval": 5}), 150, 10,
                                       rules="a")):
        bad = cc.run_cases(moved, cases=[], features=[case])
        assert not bad["passed"] and not bad["feature_cases"][0]["checks"]["positions_in_window"]


class _Run:
    """A stand-in trajectory: positions and block pressures off longdouble's by ``off`` (relative)."""

    def __init__(self, off):
        self.off = off

    def arrays(self):
        xz = np.ones((3, 4, 2)) * 1e-3 * (1 + self.off)
        block_U = np.full((3, 2), 100.0) * (1 + self.off)
        return np.arange(3.0), xz, block_U, np.zeros(3), np.zeros(3)


def _precision(offsets):
    """precision_study on stand-in runs: {dtype name: relative offset, or an exception to raise}."""
    pk = Packing(np.c_[np.arange(4.0) * 3e-3, np.zeros(4)], np.full(4, 1e-3), np.zeros(4, dtype=int), np.ones(4))

    def simulate(scene, packing, n, every, dtype):
        off = offsets[{np.longdouble: "longdouble", np.float64: "float64", np.float32: "float32"}[dtype]]
        if isinstance(off, Exception):
            raise off
        return _Run(off)
    return cc.precision_study(ref_simulate=simulate, build=lambda: (None, pk), n_steps=3, record_every=1)


def test_make_precision_fails_when_a_precision_misses_its_bound(tmp_path, monkeypatch, capsys):
    """Within the bounds it passes; float32 off by 6 % of a radius, float64 by 1e-6 or a precision
    that did not run fails, naming each; yade_scripts/crosscheck.py --precision then exits 1."""
    ok = _precision({"longdouble": 0.0, "float64": 1e-12, "float32": 0.01})
    assert ok["passed"] and ok["why"] == "" and ok["bounds"] == cc.PRECISION_BOUNDS
    bad = _precision({"longdouble": 0.0, "float64": 1e-6, "float32": 0.06})
    assert not bad["passed"]
    for needle in ("float64 max_position_diff_rel", "float64 block_pressure_rel_diff", "float32 max_position_diff_rel"):
        assert needle in bad["why"]
    broken = _precision({"longdouble": 0.0, "float64": 0.0, "float32": FloatingPointError("overflow")})
    assert not broken["passed"] and "float32: FloatingPointError: overflow" in broken["why"]

    from yade_scripts import crosscheck as script
    for result, status in ((ok, 0), (bad, 1)):
        monkeypatch.setattr(script, "precision_study", lambda result=result: result)
        assert script.main(["--precision", "--out", str(tmp_path)]) == status
    assert "PRECISION OUT OF BOUND: float64 max_position_diff_rel" in capsys.readouterr().out
