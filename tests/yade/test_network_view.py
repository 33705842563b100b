"""The pores in OpenPNM's vocabulary (engines.model.network_view), and docs/ENGINE.md's plotting example
on both wall kinds: wall discs (viscel_column's column) and flat walls (aabb_box's box of utils.aabbWalls)."""
import os
import re

import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing)

from engines.model import network_view as nv

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def engine_snippet():
    """The python block after "**Plotting the pores**" in docs/ENGINE.md."""
    with open(os.path.join(ROOT, "docs", "ENGINE.md")) as f:
        text = f.read()
    return re.search(r"\*\*Plotting the pores\*\*.*?```python\n(.*?)```", text, re.S).group(1)


def column():
    from engines.model.pore_water import WaterSettings
    from tests.yade.test_water_engine import column_engine
    water = column_engine(WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4, transfer="conserving"), 1000, 10, 3e-5)
    return water, 300


def flat_box():
    from yade import O

    from engines.model.pore_water import WaterSettings
    from engines.yade.water_engine import WaterEngine
    from yade_scripts.examples import aabb_box
    bottom, left, right, grains = aabb_box.build_box()
    O.run(1000, True)
    water = WaterEngine(grains, walls={}, flat_walls={bottom: "inflow", left: "undrained", right: "undrained"},
                        settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=1e-5, transfer="conserving"),
                        l_m=1.3e-4, water_interval=4)
    return water, 300


@pytest.mark.parametrize("make", [column, flat_box], ids=["wall discs", "flat walls"])
def test_the_plotting_example_runs_and_the_network_is_the_models(make, tmp_path, monkeypatch):
    from yade import O

    from engines.yade.yade_io import raise_pending
    water, steps = make()
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
    O.run(steps, True)
    raise_pending()
    monkeypatch.chdir(tmp_path)
    exec(engine_snippet(), {"water": water})
    assert (tmp_path / "pores.png").stat().st_size > 1000

    net, m = water.network(), water.model
    n = m.water.net.n_pores
    assert net["pore.coords"].shape == (n, 3) and np.all(net["pore.coords"][:, 1] == 0)
    np.testing.assert_array_equal(net["pore.pressure"], water.pressures())
    np.testing.assert_array_equal(net["pore.water"], m.water.W)
    outlines = nv.polygons(net)
    assert len(outlines) == n
    shoelace = [0.5 * abs(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])) for p in outlines]
    np.testing.assert_allclose(shoelace, net["pore.polygon_area"], rtol=1e-9)  # the outlines are the pores
    inflow = net["pore.inflow"]
    assert inflow.any() and np.all(net["pore.inflow_flux"][inflow] == m.settings.q_w)
    assert np.all(net["pore.inflow_flux"][~inflow] == 0)
    if m.water.net.flat_walls:  # the bottom box is the inflow wall: its pores, and the feet on it
        np.testing.assert_array_equal(net["pore.flat_wall_0"], inflow)
        bottom = m.water.net.wall_vertices.faces()[0]
        feet = np.concatenate([p for p, on in zip(outlines, inflow) if on])
        assert np.isclose(feet[:, 1], bottom).any()
        assert not net["pore.bottom"].any()
    else:
        np.testing.assert_array_equal(net["pore.bottom"], inflow)
    i, j = net["throat.conns"].T
    U = net["pore.pressure"]
    np.testing.assert_allclose(net["throat.flux"], net["throat.conductance"] * (U[i] - U[j]), rtol=1e-12, atol=1e-300)
    assert float(net["balance.error"]) < 1e-12 and float(net["balance.inflow"]) > 0
    assert set(nv.openpnm(net)) == {k for k in net if k.split(".")[0] in ("pore", "throat")}
