"""The pores in OpenPNM's vocabulary (engines.model.network_view) on a NumPy WaterModel, without YADE."""
import numpy as np
import pytest

from engines.model import network_view as nv
from engines.model import pores as pg
from engines.model.pore_water import WaterSettings
from engines.model.water_model import WaterModel
from tests.model.test_flat_walls import box, random_box


def shoelace(p):
    return 0.5 * abs(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


@pytest.mark.parametrize("seed", [1, 2])
def test_the_outlines_are_the_pores_and_the_fluxes_the_models(seed):
    """A random packing in a box of four flat walls (bottom inflow, left drained): each outline's
    area is the pore's polygon area (feet and corners included), the flags are the walls' pores,
    the throat flux is g (U_i - U_j) and the boundary flows those of the water model."""
    xz, r, _ = random_box(seed)
    walls = box(12.0, 12.0, ("inflow", "drained", "undrained", "undrained"))
    s = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, k3=50.0, q_w=1e-3)
    m = WaterModel(s, r, np.zeros(len(r), np.int64), xz, 0.0, 1.5, 1e-4, flat_walls=walls)
    m.advance(1e-4, xz)
    net = nv.pore_network(m, xz)
    n = m.water.net.n_pores
    outlines = nv.polygons(net)
    assert len(outlines) == n == len(net["pore.coords"]) and n > 20
    np.testing.assert_allclose([shoelace(p) for p in outlines], net["pore.polygon_area"], rtol=1e-9)
    assert max(len(p) for p in outlines) >= 3
    for w in range(len(walls)):  # flat_wall_<w>: the pores with a vertex on wall w
        np.testing.assert_array_equal(net[f"pore.flat_wall_{w}"], m.water.net.pore_walls[w])
    U = net["pore.pressure"]
    np.testing.assert_array_equal(U, m.pressures(xz))
    i, j = net["throat.conns"].T
    np.testing.assert_allclose(net["throat.flux"], net["throat.conductance"] * (U[i] - U[j]), rtol=1e-12, atol=0)
    geometry = pg.measure(m.water.net, xz, m.r)
    fl = m.water.flows(geometry.void_area, geometry.link_contact)
    np.testing.assert_array_equal(net["pore.side_flux"], fl.side_q)
    np.testing.assert_array_equal(net["pore.inflow_flux"], fl.inflow_q)
    assert float(net["balance.error"]) == m.water.balance_error() and float(net["balance.inflow"]) > 0
    assert set(nv.openpnm(net)) == {k for k in net if k.startswith(("pore.", "throat."))}
