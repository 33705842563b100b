"""Stability at the extremes and the automatic time step: the limits of
engines.model.time_step on analytic cases, dt = "auto" in the scene schema, the refusals up front
(fast, no long runs) and the stability map's classification (no YADE)."""
import math
import re

import numpy as np
import pytest

from engines.model import pores as pg
from engines.model import time_step as ts
from engines.model.contact import critical_time_step
from engines.model.pore_dem import disc_masses
from engines.model.pore_water import PoreWater, WaterSettings
from engines.run import scene as scenes
from engines.run.preflight import InputError, preflight
from engines.studies import stability as st
from engines.yade.deposition import scene_packing
from packing.layouts import random_discs


@pytest.fixture(scope="module")
def qs():
    sc = scenes.preset("quicksand_case1")
    return sc, scene_packing(sc)


def _two_pores():
    """Rhombus of four wall discs: two equal triangular pores sharing a gap link."""
    xz = np.array([[-1.2, 0.0], [1.2, 0.0], [0.0, 1.0], [0.0, -1.0]])
    r = np.full(4, 0.5)
    net = pg.build_pores(xz, r, l_m=1.5, walls=np.full(4, pg.WALL_LEFT))
    return xz, r, net


# -- the limits -----------------------------------------------------------------------------------
def test_darcy_limit_of_two_equal_pores_is_two_over_k():
    """Two equal pores at W = A: G = g [[1, -1], [-1, 1]], c equal, lambda_max = 2 g / c = k, so
    2 / lambda_max = 2 / k exactly (the Gershgorin bound is exact here too)."""
    xz, r, net = _two_pores()
    m = pg.measure(net, xz, r)
    w = PoreWater(net, m.void_area, WaterSettings(E_w=1000.0, k1=50.0, k2=0.5))
    assert ts.darcy_limit(w, m.void_area, m.link_contact) == pytest.approx(2 / 50.0, rel=1e-12)
    assert w.darcy_limit(m.void_area, m.link_contact) == pytest.approx(2 / 50.0, rel=1e-12)


def test_darcy_limit_eigsh_matches_dense_and_bounds_gershgorin():
    rng = np.random.default_rng(3)
    xz, r = random_discs(300, rng)
    walls = np.where(xz[:, 1] < xz[:, 1].min() + 1.0, pg.WALL_BOTTOM, 0)
    net = pg.build_pores(xz, r, l_m=0.7 * r.mean(), walls=walls)
    m = pg.measure(net, xz, r)
    w = PoreWater(net, m.void_area, WaterSettings(E_w=240.0, k1=200.0, k2=2.0), W=m.void_area * (1 + 0.2 * rng.random(net.n_pores)))
    S, open_ = ts.exchange_matrix(w, m.void_area, m.link_contact)
    assert S.shape[0] >= 50  # the eigsh path
    dense = np.linalg.eigvalsh(S.toarray())
    assert dense[0] > -1e-9 * dense[-1]  # positive semi-definite
    assert ts.lambda_max(S) == pytest.approx(dense[-1], rel=1e-7)
    exact = ts.darcy_limit(w, m.void_area, m.link_contact)
    gersh = w.darcy_limit(m.void_area, m.link_contact)
    assert gersh <= exact * (1 + 1e-12) and gersh > 0.3 * exact
    # forward Euler on the linearised exchange: just below 2 / lambda_max decays, just above grows
    lam = dense[-1]
    for h, grows in ((0.99 * 2 / lam, False), (1.01 * 2 / lam, True)):
        assert (abs(1 - h * lam) > 1) == grows


def test_water_stiffness_by_hand_on_two_pores():
    xz, r, net = _two_pores()
    A = pg.measure(net, xz, r).void_area
    k = ts.water_stiffness(net, A, r, 240.0)
    # discs 0 and 1 (the short diagonal's ends... the rhombus' far corners) bound one pore each or both
    expected = np.zeros(4)
    for p in range(net.n_pores):
        expected[net.vertices_of(p)] += 240.0 * (2 * 0.5) ** 2 / A[p]
    np.testing.assert_allclose(k, expected, rtol=1e-12)
    assert sorted(np.round(k / (240.0 / A[0]), 12).tolist()) == [1.0, 1.0, 2.0, 2.0]  # equal pores: 1 or 2 each
    mass = np.array([1.0, 2.0, 3.0, 4.0])
    mobile = np.array([True, True, False, False])
    lim = ts.water_stiffness_limit(net, A, r, 240.0, mass, mobile)
    assert lim == pytest.approx(min(2 * np.sqrt(mass[mobile] / k[mobile])), rel=1e-12)


def test_choose_takes_the_smallest_limit_times_the_factor_and_caps_at_the_engine_check():
    lims = {"contact": 1e-4, "water_stiffness": 3e-4, "darcy": 5e-5, "darcy_check": 4e-5}
    dt, name, n = ts.choose(lims, 0.5)
    assert (dt, name, n) == (pytest.approx(2.5e-5), "darcy", 1)
    dt, name, n = ts.choose(lims, 1.0)  # 5e-5 would fail the engine's Gershgorin check
    assert (dt, name) == (4e-5, "darcy_check")
    dt, name, n = ts.choose(lims, 1.0, substep=True)  # sub-stepped water: Darcy does not bind
    assert (dt, name, n) == (1e-4, "contact", 3)
    text = ts.describe(dt, lims, name, n, 1.0)
    assert "contact" in text and re.search(r"\b(\d+) sub-steps", text).group(1) == str(int(np.ceil(1e-4 / 4e-5)))
    assert float(re.search(r"([\d.]+)x a water step", text).group(1)) == pytest.approx(1 + ts.SUBSTEP_COST * (n - 1))


def test_auto_dt_on_the_presets_is_below_every_limit_and_equals_the_binding_one(qs):
    for case in ("quicksand_case1", "liquefaction_case1"):
        sc = scenes.preset(case, {"numerics": {"dt": "auto", "dt_auto_factor": 0.3}})
        pk = scene_packing(sc)
        dt, lims, name, n_sub = ts.auto_time_step(sc, pk)
        assert all(dt <= v for v in lims.values())
        assert dt == pytest.approx(0.3 * lims[name], rel=1e-12) and n_sub == 1
        m, _ = disc_masses(sc, pk)
        assert lims["contact"] == critical_time_step(m[pk.mobile], sc.contact.kn)
    assert "ties" in lims and name == "contact"  # the seismic box: eq 52 binds at its E_w


def test_auto_dt_of_a_dry_scene_is_the_contact_limit(qs):
    sc, pk = qs
    dry = sc.with_overrides({"water": {"enabled": False}, "numerics": {"dt": "auto", "dt_auto_factor": 0.5}})
    dt, lims, name, _ = ts.auto_time_step(dry, pk)
    assert set(lims) == {"contact"} and name == "contact"
    m, _ = disc_masses(sc, pk)
    assert dt == 0.5 * 2 * math.sqrt(m[pk.mobile].min() / sc.contact.kn)


def test_water_stiffness_binds_when_E_w_is_large(qs):
    sc, pk = qs
    lims = ts.limits(sc, pk)
    big = sc.with_overrides({"water": {"E_w": 240.0 * 1e4}})
    lims_big = ts.limits(big, pk)
    assert lims_big["water_stiffness"] == pytest.approx(lims["water_stiffness"] / 100, rel=1e-12)  # 1/sqrt(E_w)
    assert lims_big["darcy"] == pytest.approx(lims["darcy"], rel=1e-9)  # E_w cancels in g / c
    assert ts.auto_time_step(big.with_overrides({"numerics": {"dt": "auto"}}), pk)[2] == "water_stiffness"


def test_resolve_dt_prints_the_choice_and_keeps_numbers(qs):
    sc, pk = qs
    assert ts.resolve_dt(sc, pk) is sc
    said = []
    auto = sc.with_overrides({"numerics": {"dt": "auto"}})
    out = ts.resolve_dt(auto, pk, log=said.append)
    assert isinstance(out.numerics.dt, float) and out.numerics.dt > 0
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
    ({"numerics": {"dt": 1.05 * 3.2565e-5}}, "eq 52"),
    ({"water": {"k1": 1e6, "substep": False}}, "exceeds the explicit Darcy limit"),  # the strict mode
    ({"water": {"k2": 1e6, "substep": False}}, "exceeds the explicit Darcy limit"),
    ({"water": {"k1": 1e9}}, "sub-steps at the explicit Darcy limit"),                 # sub-stepping, beyond max_substeps
    ({"water": {"E_w": 2.4e8}}, "water-stiffness limit"),
    ({"water": {"E_w": 2.4e5}, "numerics": {"dt": 3.2e-5}}, "water-stiffness limit"),
])
def test_extremes_are_refused_with_the_limit_named(qs, tmp_path, over, limit):
    sc, pk = qs
    with pytest.raises(InputError, match=limit):
        preflight(sc.with_overrides(over), pk, str(tmp_path / "out"))
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

    from engines.model.pore_dem import PoreDEM
    from engines.run.preflight import start_darcy_limit

    sc, pk = qs
    s = sc.with_overrides({"water": {"k1": 1e6}, "numerics": {"dt": 1e-6, "rebuild_interval": 10 ** 6}})
    assert s.water.substep
    preflight(s, pk, str(tmp_path / "out"))
    n = math.ceil(1e-6 / start_darcy_limit(s, pk))
    assert 2 <= n <= s.water.max_substeps
    sub = PoreDEM(s, pk)
    fine = PoreDEM(s.with_overrides({"numerics": {"dt": 1e-6 / n}, "water": {"substep": False}}), pk)
    for k in range(30):
        sub.step(pk.xz.copy())
        for _ in range(n):
            fine.step(pk.xz.copy())
    assert sub.water_model.substeps_max == n and fine.water_model.substeps_max == 0
    assert sub.water.balance.inflow > 0 and abs(sub.water.balance_error()) < 1e-12
    U = sub.water_model.pressures(pk.xz)
    assert np.all(np.isfinite(U))
    np.testing.assert_allclose(sub.water.W, fine.water.W, rtol=1e-9, atol=0)
