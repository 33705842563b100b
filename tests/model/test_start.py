"""One start of a run (engines.model.start.Start): the pores it gives the limits are those the water
model builds first, the flat walls included; each part is computed once."""
import numpy as np
import pytest

from engines.model import limits as lim
from engines.model import pore_dem
from engines.model import pores as pg
from engines.model.start import Start
from engines.model.water_model import WaterModel
from engines.run import scene as scenes
from packing.packing import Packing


def quicksand(kind):
    sc = scenes.preset("quicksand_case1", {"walls": {"kind": kind}})
    return sc, Packing.load(sc.packing.file)


@pytest.mark.parametrize("kind", ["discs", "flat"])
def test_the_start_pores_are_the_water_models_first(kind):
    sc, pk = quicksand(kind)
    start = Start(sc.settings, pk)
    assert bool(start.flat_walls) == (kind == "flat") and start.packing.mobile.all() == (kind == "flat")
    wm = pore_dem.water_model(sc.settings, start.packing, WaterModel, tuple(start.flat_walls.values()))
    net, m, water = start.pores
    assert net.n_pores == wm.water.net.n_pores
    np.testing.assert_array_equal(net.tri, wm.water.net.tri)
    np.testing.assert_array_equal(m.void_area, wm.void_area(start.packing.xz))
    assert start.limits["darcy_check"] == water.darcy_limit(m.void_area, m.link_contact) / sc.numerics.water_interval


def test_flat_walls_change_the_start_pores_and_their_limits():
    """The flat walls close the pores at the particles' faces: fewer pores than with the wall discs,
    and a Darcy limit of their own (preflight used to report the wall discs' one for both)."""
    discs, flat = (Start(sc.settings, pk) for sc, pk in map(quicksand, ("discs", "flat")))
    assert flat.pores[0].n_pores < discs.pores[0].n_pores
    assert flat.limits["darcy"] != pytest.approx(discs.limits["darcy"], rel=0.05)
    assert flat.limits["contact"] == discs.limits["contact"]  # the same particles


def test_each_part_is_computed_once(monkeypatch):
    sc, pk = quicksand("flat")
    start = Start(sc.with_overrides({"numerics": {"dt": "auto"}}).settings, pk)
    calls = []
    eigen = lim.darcy_eigen_limit
    monkeypatch.setattr(lim, "darcy_eigen_limit", lambda *a: calls.append(1) or eigen(*a))
    built = pg.build_pores
    monkeypatch.setattr(pg, "build_pores", lambda *a, **k: calls.append(2) or built(*a, **k))
    for _ in range(3):
        start.check()
        dt = sc.numerics.dt_auto_factor * start.limits["contact"]
        assert start.settings.numerics.dt == start.auto[0] == pytest.approx(dt)
    assert sorted(calls) == [1, 2]
    assert start.given.numerics.dt == "auto"


def test_a_dry_start_has_no_pores():
    sc, pk = quicksand("discs")
    start = Start(sc.with_overrides({"water": {"enabled": False}}).settings, pk)
    assert start.pores is None and set(start.limits) == {"contact"}
