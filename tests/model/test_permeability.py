"""The permeability law as one function per implementation (eq 43, §5.1, §6.1): a toy law put in
the place of engines.model.pore_water.permeability changes the flows as it says, and nothing else.
Exchanging the law means replacing ``permeability`` in model/pore_water.py, compiled/kernels/darcy.py
and reference/model.py (the map in engines/__init__.py)."""
import numpy as np

from engines.model import pore_water
from engines.model import pores as pg
from engines.model.pore_dem import water_model
from engines.run import scene as scenes
from packing.packing import Packing

GAP, CONTACT, SURFACE, DRAINED = 3.0, 0.5, 5.0, 7.0  # the toy's factors on k1, k2, k1, k3


def toy(contact, s):
    """A toy law: 3 k1 across a gap, k2 / 2 across a contact, 5 k1 at the free surface, 7 k3
    through a drained wall [1/s]."""
    return np.where(contact, CONTACT * s.k2, GAP * s.k1), SURFACE * s.k1, DRAINED * s.k3


def quicksand_flows():
    """The flows of the quick sand's pores (drained sides, k3 > 0) with the water moved off
    equilibrium at random: (FlowState, the throats across a contact)."""
    sc = scenes.preset("quicksand_case1", {"water": {"sides": "drained", "k3": 40.0, "q_w": 1e-4}})
    pk = Packing.load(sc.packing.file)
    wm = water_model(sc.settings, pk)
    w = wm.water
    m = pg.measure(w.net, pk.xz, wm.r)
    w.W = m.void_area * (1.0 + 0.01 * np.random.default_rng(3).random(len(w.W)))
    return w.flows(m.void_area, m.link_contact), m.link_contact[w.net.throat_link]


def test_the_law_is_the_default_one():
    s = pore_water.WaterSettings(k1=200.0, k2=2.0, k3=9.0)
    k, k_surface, k_drained = pore_water.permeability(np.array([True, False]), s)
    assert k.tolist() == [2.0, 200.0] and (k_surface, k_drained) == (200.0, 9.0)


def test_a_toy_law_in_its_place_changes_the_flows_as_it_says(monkeypatch):
    before, contact = quicksand_flows()
    monkeypatch.setattr(pore_water, "permeability", toy)
    after, _ = quicksand_flows()
    flowing = before.throat_q != 0
    assert (flowing & contact).sum() > 5 and (flowing & ~contact).sum() > 5
    assert np.count_nonzero(before.surface_q) > 3 and np.count_nonzero(before.side_q) > 3
    for new, old, factor in ((after.throat_q[contact], before.throat_q[contact], CONTACT),
                             (after.throat_q[~contact], before.throat_q[~contact], GAP),
                             (after.g[contact], before.g[contact], CONTACT), (after.g[~contact], before.g[~contact], GAP),
                             (after.surface_q, before.surface_q, SURFACE), (after.side_q, before.side_q, DRAINED)):
        np.testing.assert_allclose(new, factor * old, rtol=1e-13, atol=0.0)
    assert np.array_equal(after.inflow_q, before.inflow_q) and np.array_equal(after.capacity, before.capacity)
