"""The one pore-rebuild schedule of both contact laws (engines.model.schedule)."""
import itertools

import numpy as np

from engines.model import pores as pg
from engines.model.pore_dem import water_model
from engines.model.schedule import areas_in_range, rebuild_due, steps_to_rebuild
from engines.model.water_model import WaterModel
from engines.run import scene as scenes
from packing.packing import Packing


def rebuilds(k0, interval, call_interval, n):
    """The steps at which a model started at k0 and asked every call_interval steps rebuilds."""
    built, out = k0, []
    for k in range(k0, k0 + n, call_interval):
        if rebuild_due(k, built, k0, interval):
            built = k
            out.append(k)
    return out


def test_asked_every_step_the_pores_are_rebuilt_at_multiples_of_the_interval():
    for k0, interval in itertools.product((0, 7, 1000), (1, 3, 10)):
        assert rebuilds(k0, interval, 1, 50) == [k0 + j * interval for j in range(1, 50) if j * interval < 50]


def test_asked_at_water_steps_the_rebuild_is_the_first_water_step_after_each_multiple():
    assert rebuilds(0, 10, 3, 63) == [12, 21, 30, 42, 51, 60]       # no drift: 12, 24, 36, ... would
    assert rebuilds(5, 10, 4, 45) == [17, 25, 37, 45]
    for k0, interval, calls in itertools.product((0, 3), (2, 5, 10), (1, 2, 3, 7)):
        got = rebuilds(k0, interval, calls, 200)
        want = sorted({min(k for k in range(k0, k0 + 400, calls) if k >= k0 + j * interval)
                       for j in range(1, 200 // interval + 1)})
        assert got == [k for k in want if k < k0 + 200]


def test_steps_to_rebuild_counts_to_the_step_at_which_rebuild_due_holds():
    for k0, interval, calls, k_built in itertools.product((0, 4), (1, 3, 10), (1, 2, 3, 7), (0, 4, 12, 13)):
        k_built = max(k_built, k0)
        for k in range(max(k_built, k0), k_built + 30):
            if (k - k0) % calls:
                continue
            n = steps_to_rebuild(k, k_built, k0, interval, calls)
            first = next(j for j in range(k, k + 100, calls) if rebuild_due(j, k_built, k0, interval))
            assert n == first - k, (k0, interval, calls, k_built, k)


def test_the_model_records_the_step_of_its_last_build():
    sc = scenes.preset("quicksand_case1", {"numerics": {"rebuild_interval": 4, "water_interval": 1}})
    pk = Packing.load(sc.packing.file)
    wm = water_model(sc.settings, pk)
    assert isinstance(wm, WaterModel) and wm.schedule.k_built == 0
    for k in range(10):
        wm.step(k, pk.xz)
    assert (wm.n_rebuilds, wm.schedule.k_built) == (2, 8)
    assert np.isfinite(wm.F).all()


def moved_model(cls, d, interval=1000):
    """A quicksand_case1 WaterModel (class ``cls``) rebuilding by displacement d [m], with the
    packing and the index of one particle."""
    sc = scenes.preset("quicksand_case1", {"numerics": {"rebuild_interval": interval, "water_interval": 1,
                                                        "rebuild_distance": d}})
    pk = Packing.load(sc.packing.file)
    return water_model(sc.settings, pk, cls), pk, int(np.flatnonzero(pk.mobile)[0])


def shifted(xz, a, dist):
    """xz with disc a moved by dist [m] along (3, 4) / 5."""
    out = xz.copy()
    out[a] += dist * np.array([0.6, 0.8])
    return out


def rebuild_steps_by_displacement(cls):
    """The rebuild steps of a model with d = 1e-5 m asked at each step, one disc moved by hand
    just under d at step 3 and just over at step 5, back to its built place at step 7 (moved over
    d from the new build: rebuilt); the interval 20 still rebuilds at its steps 20, 40."""
    d = 1e-5
    wm, pk, a = moved_model(cls, d, interval=20)
    under, over = shifted(pk.xz, a, d * (1 - 1e-9)), shifted(pk.xz, a, d * (1 + 1e-9))
    built = []
    for k in range(41):
        xz = pk.xz if k < 3 else under if k < 5 else over if k < 7 else pk.xz
        n = wm.n_rebuilds
        wm.step(k, xz)
        if wm.n_rebuilds > n:
            built.append(k)
            assert np.array_equal(wm.xz_built, xz)
    return built


def test_a_rebuild_is_due_exactly_when_a_disc_has_moved_past_the_rebuild_distance():
    from engines.compiled.water_model import WaterModel as CompiledWaterModel
    for cls in (WaterModel, CompiledWaterModel):
        assert rebuild_steps_by_displacement(cls) == [5, 7, 20, 40], cls


def test_without_rebuild_distance_a_moved_disc_does_not_rebuild():
    wm, pk, a = moved_model(WaterModel, 0.0, interval=4)
    far = shifted(pk.xz, a, 1e-3)
    assert not wm.rebuild_due(1, far) and wm.rebuild_due(4, far)


def test_areas_are_in_range_between_zero_and_the_polygon_area():
    from engines.compiled import kernels
    poly = np.array([1.0, 2.0, 3.0])
    for void, want in (([0.0, 2.0, 1.0], True), ([-1e-30, 1.0, 1.0], False), ([0.5, 2.0 + 1e-15, 1.0], False)):
        void = np.array(void)
        assert areas_in_range(void, poly) is want
        assert kernels.areas_in_range(void, poly) is want


def test_a_void_area_out_of_range_rebuilds_at_that_step_with_a_rebuild_distance_only():
    """One disc pushed half its radius into its nearest neighbour (a void area below 0, eq 32 would
    give U > E_w), far less than d = 1 m: with d > 0 both classes rebuild at that step, to the same
    water, and after it every area is in range; with d = 0 (the paper's schedule) nothing is rebuilt
    and U exceeds E_w."""
    from engines.compiled.water_model import WaterModel as CompiledWaterModel
    W = []
    for cls in (WaterModel, CompiledWaterModel):
        for d in (1.0, 0.0):
            wm, pk, a = moved_model(cls, d, interval=1000)
            gap = np.linalg.norm(pk.xz - pk.xz[a], axis=1) - pk.r - pk.r[a]
            gap[a] = np.inf
            b = int(np.argmin(gap))
            pushed = pk.xz.copy()
            toward = (pk.xz[b] - pk.xz[a]) / np.linalg.norm(pk.xz[b] - pk.xz[a])
            pushed[a] += (gap[b] + 0.5 * pk.r[a]) * toward
            assert not areas_in_range(wm.void_area(pushed), pg.measure(wm.water.net, pushed, wm.r).polygon_area)
            for k in range(3):
                wm.step(k, pk.xz if k < 2 else pushed)
            if d:
                assert (wm.n_rebuilds, wm.schedule.k_built) == (1, 2), cls
                m = pg.measure(wm.water.net, pushed, wm.r)
                assert areas_in_range(m.void_area, m.polygon_area)
                assert np.all(wm.pressures(pushed) < wm.settings.E_w)
                W.append(wm.water.W)
            else:
                assert wm.n_rebuilds == 0 and wm.pressures(pushed).max() > wm.settings.E_w, cls
    np.testing.assert_allclose(W[1], W[0], rtol=1e-12)
