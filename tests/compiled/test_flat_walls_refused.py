"""Flat walls (SPEC §2.6) are the NumPy model's only: the compiled path refuses them in one line."""
import numpy as np
import pytest

from engines.compiled import pores as kp
from engines.compiled import water_model as cwm
from engines.model import pores as pg
from engines.model.flat_walls import NUMPY_ONLY, FlatWall
from engines.model.pore_water import WaterSettings

WALL = (FlatWall(1, 0.0, +1, "inflow"),)


def row():
    return np.column_stack([2.0 * np.arange(5), np.full(5, 1.05)]), np.ones(5)


def test_the_compiled_build_refuses_flat_walls():
    xz, r = row()
    with pytest.raises(ValueError, match=r"^flat walls: the NumPy model only for now \(compiled=False\)$"):
        pg.build_pores(xz, r, l_m=0.1, steps=kp.BUILD, flat_walls=WALL)
    assert pg.build_pores(xz, r, l_m=0.1, flat_walls=WALL).n_pores == 4  # the NumPy build takes them


def test_the_compiled_water_model_refuses_flat_walls():
    xz, r = row()
    with pytest.raises(ValueError) as e:
        cwm.WaterModel(WaterSettings(), r, np.zeros(5, np.int64), xz, 0.0, 0.1, 1e-6, flat_walls=WALL)
    assert str(e.value) == NUMPY_ONLY
