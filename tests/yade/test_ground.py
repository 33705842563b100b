"""The 10,000-disc wet ground preset (yade_scripts/scenes/ground_10000.toml) runs in YADE."""
import numpy as np
import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing: make test installs it)

from engines.run import scene as scenes
from engines.yade.coupling import YadeCoupling
from packing.packing import Packing


def test_the_ground_runs_shaken_as_one_box():
    """The whole box follows the base ([loading] moves = "box", side walls fixed): every wall
    disc, bottom and side columns, is displaced by the base's displacement and by nothing else; the
    discs stay inside the moved box; the water of the undrained ground is conserved to round-off."""
    sc = scenes.preset("ground_10000")
    pk = Packing.load(sc.packing.file)
    cp = YadeCoupling(sc, pk)
    cp.run(500)
    xz = cp.positions()
    shift = xz - pk.xz
    base = cp.core.base
    walls = ~pk.mobile
    assert base.disp > 0 and np.ptp(shift[walls, 0]) < 1e-12 and np.abs(shift[walls, 1]).max() < 1e-15
    assert shift[walls, 0].mean() == pytest.approx(base.disp, rel=0.01)
    moved = Packing(xz, pk.r, pk.group, pk.density_factor)
    assert len(moved.outside_box()) == 0
    assert cp.water.balance_error() < 1e-12
