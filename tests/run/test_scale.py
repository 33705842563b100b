"""A sense of scale before a run (issue 37, item 7): the estimate of CPU time and outputs from the
stated cost model, within 3x of what two presets cost; refusals above 24 h or 10 GB without
--force; an ensemble's starts checked all up to 64, beyond that a seeded sample that the output
names."""
import pytest

from engines.model.start import Start
from engines.run.preflight import timed
from engines.run import ensemble
from engines.run import scene as scenes
from engines.run.preflight import CPU_LIMIT, OUTPUT_LIMIT, InputError, check_scale, cost_per_step, estimate, preflight
from engines.yade.deposition import scene_packing


@pytest.fixture(scope="module")
def case1():
    sc = scenes.preset("quicksand_case1")
    return sc, scene_packing(sc)


def test_the_cost_model_is_read_from_the_benchmark():
    for law in ("paper", "yade"):
        c_law, c_water = cost_per_step(law)
        assert 0.01 < c_law < 1 and 0.01 < c_water < 1  # us per body and step
    assert cost_per_step("yade")[0] > 3 * cost_per_step("paper")[0]  # YADE's own law, with its collider


def test_the_estimate_follows_the_model(case1):
    sc, pk = case1
    e = estimate(sc, pk)
    c_law, c_water = cost_per_step("paper")
    assert e["steps"] == 60000 and e["bodies"] == len(pk.r) == 76
    assert e["cpu_s"] == pytest.approx(60000 * 76 * (c_law + c_water) * 1e-6)
    assert e["rows"] == 601 and e["snapshots"] == len(sc.output.snapshot_times) == 4 and e["frames"] == 0
    dry = estimate(sc.with_overrides({"water": {"enabled": False}, "output": {"vtk": True}}), pk)
    assert dry["cpu_s"] == pytest.approx(60000 * 76 * c_law * 1e-6) and dry["frames"] == 4 and dry["bytes"] > e["bytes"]
    assert estimate(sc.with_overrides({"numerics": {"water_interval": 10}}), pk)["cpu_s"] == \
        pytest.approx(60000 * 76 * (c_law + c_water / 10) * 1e-6)
    auto = sc.with_overrides({"numerics": {"dt": "auto"}})
    assert estimate(auto, pk)["steps"] == round(0.06 / timed(auto, Start(auto.settings, pk)).numerics.dt)
    assert "starts x" in ensemble.check_starts(auto, pk, "out", range(2), 1e-7)[0]


def test_a_trillion_steps_are_refused_without_force(case1):
    sc, pk = case1
    huge = sc.with_overrides({"numerics": {"duration": 1e6}})  # 1e12 steps of 1 us
    with pytest.raises(InputError) as e:
        preflight(huge, pk, "out")
    msg = str(e.value)
    assert "\n" not in msg and "of CPU is above 24 h and" in msg and "of outputs is above 10 GB" in msg
    assert "1000000000000 steps" in msg and "--force" in msg
    assert preflight(huge, pk, "out", force=True)[0].startswith("estimate: ")


def test_each_limit_alone(case1):
    sc, pk = case1
    per_step = estimate(sc, pk)["cpu_s"] / 60000
    long = sc.with_overrides({"numerics": {"duration": 1.2 * CPU_LIMIT / per_step * 1e-6},
                              "output": {"history_interval": 10 ** 9}})
    with pytest.raises(InputError, match=r"^[\d.]+ h of CPU is above 24 h \(the estimate"):
        check_scale(long, pk)
    rows = OUTPUT_LIMIT / (16 * 22)
    big = sc.with_overrides({"numerics": {"duration": 1.2 * rows * 1e-6}, "output": {"history_interval": 1}})
    assert estimate(big, pk)["cpu_s"] < CPU_LIMIT
    with pytest.raises(InputError, match=r"^1[12](.\d)? GB of outputs is above 10 GB \(the estimate"):
        check_scale(big, pk)
    assert "starts x" in check_scale(sc, pk, starts=8)
    with pytest.raises(InputError, match="100000 starts x"):  # an ensemble's total counts
        check_scale(sc.with_overrides({"numerics": {"duration": 1.0}}), pk, starts=100000)


def test_up_to_64_starts_are_all_checked_beyond_that_a_seeded_sample(case1, monkeypatch):
    sc, pk = case1
    assert ensemble.checked_seeds(range(64)) == list(range(64))
    sample = ensemble.checked_seeds(range(100000))
    assert len(sample) == 64 and sample[0] == 0 and sample == sorted(set(sample)) and sample[-1] > 1000
    assert ensemble.checked_seeds(range(100000)) == sample  # seeded
    checked = []
    monkeypatch.setattr(ensemble, "preflight", lambda s, p, out, **kw: checked.append(out) or [])
    notes = ensemble.check_starts(sc, pk, "out", range(100000), 1e-7, force=True)
    assert len(checked) == 64 and checked[0].endswith("start_0")
    assert notes[0].startswith("estimate: ") and "100000 starts x" in notes[0]
    assert notes[1] == ("note: checked 64 of the 100000 starts before the run (a sample drawn by numpy Generator(0), "
                        "start 0 among them); each start is checked again as it begins")
    checked.clear()
    assert len(ensemble.check_starts(sc, pk, "out", range(5), 1e-7)) == 1 and len(checked) == 5


@pytest.mark.check
@pytest.mark.parametrize("name,over", [
    ("liquefaction_case1", {"numerics": {"duration": 0.02}}),
    ("quicksand_case1", {"numerics": {"duration": 0.03}, "contact": {"law": "yade", "spring": "b"}}),
])
def test_the_estimate_is_within_3x_of_a_run(tmp_path, name, over):
    from engines.run.runner import run_scene
    sc = scenes.preset(name, over)
    pk = scene_packing(sc)
    guess = estimate(sc, pk)
    run_scene(sc, pk, str(tmp_path / "warm-up"), figures=False)  # the same run first: numba compiles (or loads) every kernel it takes
    summary = run_scene(sc, pk, str(tmp_path / "run"), figures=False)
    assert summary["status"] == "completed"
    ratio = summary["cpu_seconds"] / guess["cpu_s"]
    written = sum(p.stat().st_size for p in (tmp_path / "run").rglob("*") if p.is_file())
    print(f"{name}: CPU {summary['cpu_seconds']:.3g} s, estimated {guess['cpu_s']:.3g} s; outputs {written} bytes, "
          f"estimated {guess['bytes']}")
    assert 1 / 3 < ratio < 3, (summary["cpu_seconds"], guess["cpu_s"])
    assert 1 / 3 < written / guess["bytes"] < 3, (written, guess["bytes"])
