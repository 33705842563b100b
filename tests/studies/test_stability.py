"""Stability at the extremes and the automatic time step: the limits of a scene at its start
(engines.model.start), dt = "auto" in the scene schema, the refusals up front (fast, no long
runs) and the stability map's classification."""
import math
import re

import numpy as np
import pytest

from engines.model import limits as lim
from engines.model.limits import critical_time_step
from engines.model.pore_dem import disc_masses
from engines.run import scene as scenes
from engines.model.start import Start, choose
from engines.run.preflight import InputError, announce_dt, describe_auto_dt, preflight, timed
from engines.studies import stability as st
from engines.yade.deposition import scene_packing


def limits(sc, pk):
    """The Start's limits of ``sc`` on ``pk``."""
    return Start(sc.settings, pk).limits


def auto_time_step(sc, pk):
    """(dt, limits, binding name, sub-steps) of dt = "auto" by the Start."""
    s = Start(sc.settings, pk)
    dt, name, n_sub = s.auto
    assert s.settings.numerics.dt == dt
    return dt, s.limits, name, n_sub


@pytest.fixture(scope="module")
def qs():
    sc = scenes.preset("quicksand_case1")
    return sc, scene_packing(sc)


def test_choose_takes_the_smallest_limit_times_the_factor_and_caps_at_the_engine_check():
    lims = {"contact": 1e-4, "water_stiffness": 3e-4, "darcy": 5e-5, "darcy_check": 4e-5}
    dt, name, n = choose(lims, 0.5)
    assert (dt, name, n) == (pytest.approx(2.5e-5), "darcy", 1)
    dt, name, n = choose(lims, 1.0)  # 5e-5 would fail the engine's Gershgorin check
    assert (dt, name) == (4e-5, "darcy_check")
    dt, name, n = choose(lims, 1.0, substep=True)  # sub-stepped water: Darcy does not bind
    assert (dt, name, n) == (1e-4, "contact", 3)
    text = describe_auto_dt(dt, lims, name, n, 1.0)
    assert "contact" in text and re.search(r"\b(\d+) sub-steps", text).group(1) == str(int(np.ceil(1e-4 / 4e-5)))
    assert float(re.search(r"([\d.]+)x a water step", text).group(1)) == pytest.approx(1 + lim.SUBSTEP_COST * (n - 1))


def test_auto_dt_on_the_presets_is_below_every_limit_and_equals_the_binding_one(qs):
    for case in ("quicksand_case1", "liquefaction_case1"):
        sc = scenes.preset(case, {"numerics": {"dt": "auto", "dt_auto_factor": 0.3}})
        pk = scene_packing(sc)
        dt, lims, name, n_sub = auto_time_step(sc, pk)
        assert all(dt <= v for v in lims.values())
        assert dt == pytest.approx(0.3 * lims[name], rel=1e-12) and n_sub == 1
        m, _ = disc_masses(sc.settings, pk)
        assert lims["contact"] == critical_time_step(m[pk.mobile], sc.contact.kn)
    assert "ties" in lims and name == "contact"  # the seismic box: eq 52 binds at its E_w


def test_auto_dt_of_a_dry_scene_is_the_contact_limit(qs):
    sc, pk = qs
    dry = sc.with_overrides({"water": {"enabled": False}, "numerics": {"dt": "auto", "dt_auto_factor": 0.5}})
    dt, lims, name, _ = auto_time_step(dry, pk)
    assert set(lims) == {"contact"} and name == "contact"
    m, _ = disc_masses(sc.settings, pk)
    assert dt == 0.5 * 2 * math.sqrt(m[pk.mobile].min() / sc.contact.kn)


def test_water_stiffness_binds_when_E_w_is_large(qs):
    sc, pk = qs
    lims = limits(sc, pk)
    big = sc.with_overrides({"water": {"E_w": 240.0 * 1e4}})
    lims_big = limits(big, pk)
    assert lims_big["water_stiffness"] == pytest.approx(lims["water_stiffness"] / 100, rel=1e-12)  # 1/sqrt(E_w)
    assert lims_big["darcy"] == pytest.approx(lims["darcy"], rel=1e-9)  # E_w cancels in g / c
    assert auto_time_step(big.with_overrides({"numerics": {"dt": "auto"}}), pk)[2] == "water_stiffness"


def test_the_start_announces_the_choice_and_keeps_numbers(qs):
    sc, pk = qs
    said = []
    numeric = Start(sc.settings, pk)
    announce_dt(numeric, log=said.append)
    assert timed(sc, numeric) is sc and numeric.settings is sc.settings and numeric.auto is None and said == []
    auto = sc.with_overrides({"numerics": {"dt": "auto"}})
    start = Start(auto.settings, pk)
    announce_dt(start, log=said.append)
    out = timed(auto, start)
    assert isinstance(out.numerics.dt, float) and out.numerics.dt > 0
    assert out.settings == start.settings and out.numerics.dt == start.auto[0]
    assert "dt = auto" in said[0] and "bound by the" in said[0]
    assert out.overrides["numerics"]["dt"] == "auto"


def test_scene_schema_takes_auto_and_refuses_other_words():
    sc = scenes.preset("quicksand_case1", {"numerics": {"dt": "auto"}})
    assert sc.numerics.dt == "auto" and 0 < sc.numerics.dt_auto_factor <= 1
    with pytest.raises(scenes.SceneError, match=r"\[numerics\] dt: expected a number > 0 or \"auto\""):
        scenes.preset("quicksand_case1", {"numerics": {"dt": "fast"}})
    with pytest.raises(scenes.SceneError, match=r"\[numerics\] dt: must be > 0"):
        scenes.preset("quicksand_case1", {"numerics": {"dt": -1e-6}})
    with pytest.raises(scenes.SceneError, match="dt_auto_factor"):
        scenes.preset("quicksand_case1", {"numerics": {"dt_auto_factor": 0.0}})
    with pytest.raises(scenes.SceneError, match="dt_auto_factor"):
        scenes.preset("quicksand_case1", {"numerics": {"dt_auto_factor": 1.5}})


# -- refusals up front --------------------------------------------------------------------------
@pytest.mark.parametrize("over,limit", [
    (lambda lims, sc: {"numerics": {"dt": 1.05 * sc.numerics.dt_safety * lims["contact"]}}, "eq 52"),
    (lambda lims, sc: {"water": {"k1": 1e6, "substep": False}}, "exceeds the explicit Darcy limit"),  # the strict mode
    (lambda lims, sc: {"water": {"k2": 1e6, "substep": False}}, "exceeds the explicit Darcy limit"),
    (lambda lims, sc: {"water": {"k1": 1e9}}, "sub-steps under the Darcy limit .*max_substeps"),  # beyond max_substeps
    (lambda lims, sc: {"water": {"E_w": 2.4e8}}, "water-stiffness limit"),
    (lambda lims, sc: {"water": {"E_w": 1000 * sc.water.E_w},
                       "numerics": {"dt": 1.05 * lims["water_stiffness"] / math.sqrt(1000)}},
     "water-stiffness limit"),  # the limit goes as 1 / sqrt(E_w)
])
def test_extremes_are_refused_with_the_limit_named(qs, tmp_path, over, limit):
    sc, pk = qs
    with pytest.raises(InputError, match=limit):
        preflight(sc.with_overrides(over(limits(sc, pk), sc)), pk, str(tmp_path / "out"))
    assert not (tmp_path / "out").exists()


def test_auto_dt_passes_preflight_at_the_extremes(qs, tmp_path):
    sc, pk = qs
    for over in ({"water": {"k1": 1e6}}, {"water": {"E_w": 2.4e8}}, {"water": {"k2": 1e6}}):
        s = sc.with_overrides({**over, "numerics": {"dt": "auto"}})
        preflight(s, pk, str(tmp_path / "out"))  # no refusal: the chosen dt is below every limit


# -- the map's classification --------------------------------------------------------------------
def test_classify():
    assert st.classify(1.0, 1.0, 0.0, True, 0, 0.0) == ("bounded", "")
    assert st.classify(11.0, 1.0, 0.0, True, 0, 0.0)[0] == "unbounded"
    assert st.classify(11.0, 1.0, 200.0, True, 0, 0.0)[0] == "bounded"  # within the energy slack
    assert st.classify(1.0, 1.0, 0.0, False, 0, 0.0) == ("unbounded", "non-finite positions")
    assert "left the box" in st.classify(1.0, 1.0, 0.0, True, 2, 0.0)[1]
    assert "water balance" in st.classify(1.0, 1.0, 0.0, True, 0, 1e-3)[1]
    assert "stopped by an engine" in st.classify(1.0, 1.0, 0.0, True, 0, 0.0, error="Darcy")[1]


def test_box_and_escape(qs):
    _, pk = qs
    box = st.box_of(pk)
    assert st.escaped(pk.xz[pk.mobile], box) == 0
    xz = pk.xz[pk.mobile].copy()
    xz[0, 1] = box[2] - 1e-3  # below the bottom wall
    xz[1, 0] = np.nan
    assert st.escaped(xz, box) == 2


def test_substepping_by_default_keeps_the_water_bounded_and_conserved(qs, tmp_path):
    """k1 = 1e6 1/s puts the Darcy limit below dt = 1e-6 s: refused in the strict mode (above), by
    default sub-stepped. With the discs held still, n sub-steps of dt / n are n water steps of
    dt / n: the water equals a strict run at dt / n step for step, and the balance closes."""
    import math

    from engines.compiled.pore_dem import PoreDEM

    sc, pk = qs
    s = sc.with_overrides({"water": {"k1": 1e6}, "numerics": {"dt": 1e-6, "rebuild_interval": 10 ** 6}})
    assert s.water.substep
    preflight(s, pk, str(tmp_path / "out"))
    n = math.ceil(1e-6 / limits(s, pk)["darcy_check"])
    assert 2 <= n <= s.water.max_substeps
    sub = PoreDEM(s.settings, pk)
    fine = PoreDEM(s.with_overrides({"numerics": {"dt": 1e-6 / n}, "water": {"substep": False}}).settings, pk)
    for k in range(30):
        sub.step(pk.xz.copy())
        for _ in range(n):
            fine.step(pk.xz.copy())
    assert sub.water_model.substeps_max == n and fine.water_model.substeps_max == 0
    assert sub.water.balance.inflow > 0 and abs(sub.water.balance_error()) < 1e-12
    U = sub.water_model.pressures(pk.xz)
    assert np.all(np.isfinite(U))
    np.testing.assert_allclose(sub.water.W, fine.water.W, rtol=1e-9, atol=0)
