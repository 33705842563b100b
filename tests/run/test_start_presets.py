"""One start of a run: on every preset scene (the flat-wall one included) the limits preflight checks,
and dt = "auto" is chosen from, are those of the network the engines run on (engines.model.start)."""
import glob
import os

import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing: make test installs it)

from engines.model import pores as pg
from engines.model.start import Start, limits
from engines.run import scene as scenes
from engines.run.preflight import preflight, timed
from engines.yade.coupling import YadeCoupling
from engines.yade.deposition import scene_packing
from packing.packing import Packing

PRESETS = sorted(os.path.basename(p)[:-len(".toml")] for p in glob.glob(os.path.join(scenes.SCENE_DIR, "*.toml")))


def packing_of(sc):
    """The preset's packing file; a preset that deposits its own on the quick-sand packing (a deposit
    is a long run; the start does not depend on where the packing came from)."""
    if sc.packing.source == "file":
        return scene_packing(sc)
    return Packing.load(os.path.join(scenes.SCENE_DIR, "quicksand_packing.csv"))


def running_limits(settings, cp):
    """The limits of the network the coupling ``cp`` built (its water model's) at its start."""
    pores = None
    if cp.water is not None:
        net = cp.water.net
        pores = net, pg.measure(net, cp.positions(), cp.packing.r), cp.water
    ties = cp.core.ties if cp.core is not None else None
    return limits(settings, cp.packing, cp.mass, ties, pores)


@pytest.mark.parametrize("name", PRESETS)
def test_preflight_limits_are_those_of_the_network_that_runs(name, tmp_path):
    sc = scenes.preset(name)
    pk = packing_of(sc)
    start = Start(sc.settings, pk)
    preflight(sc, pk, str(tmp_path / "out"), start)
    cp = YadeCoupling(timed(sc, start), pk)  # its own Start; its engines build their own (compiled) pores
    ran = running_limits(start.settings, cp)
    assert set(ran) == set(start.limits)
    for key, value in start.limits.items():
        assert ran[key] == pytest.approx(value, rel=1e-6), key  # eigsh's tolerance 1e-8
    if sc.water.enabled:
        assert cp.water.net.n_pores == start.pores[0].n_pores
    assert len(cp.packing.r) == len(start.packing.r) and len(cp.flat_walls) == len(start.flat_walls)


@pytest.mark.parametrize("name, submerged, within", [("quicksand_case1", False, 0.02), ("quicksand_case1_submerged", True, 0.02),
                                                     ("quicksand_case1_flat", False, 0.06)])
def test_the_quick_sand_starts_at_rest_on_its_contacts(name, submerged, within):
    """Case 1's deposit rests under the dry weight (the paper deposits without water, SPEC §2.4), the
    submerged variant's under the buoyant weight ([packing] settle_submerged): at the packing's
    positions the normal springs carry the bed, and its 5x denser top, within 2 %. Without the
    settle under the dense top (settle_loaded = 0) the contacts carried 0.52 of the bed's weight. On
    the flat walls within 6 % (the side walls' friction, which positions do not show, carries the
    rest); before the walls stayed where the bed had pressed into them, 0."""
    from engines.model.pore_dem import weight_carried
    from engines.yade.deposition import submerged as buoyant

    sc = scenes.preset(name)
    pk = Packing.load(sc.packing.file)
    weighed = buoyant(sc, pk) if submerged else pk
    assert weight_carried(sc.settings, weighed) == pytest.approx(1.0, abs=within)
    assert weight_carried(sc.settings, weighed, pk.mobile & (pk.density_factor > 1)) == pytest.approx(1.0, abs=within)


def test_a_submerged_settle_weighs_each_particle_by_its_buoyant_weight():
    """deposition.submerged: density factors (rho f - rho_w) / rho for particles, walls unchanged; a
    particle no denser than the water is refused, naming the field."""
    from engines.yade.deposition import submerged as buoyant

    sc = scenes.preset("quicksand_case1")
    pk = Packing.load(sc.packing.file)
    f = buoyant(sc, pk).density_factor
    rho, rho_w = sc.material.rho, sc.material.rho_w
    assert f[pk.mobile] == pytest.approx((rho * pk.density_factor[pk.mobile] - rho_w) / rho)
    assert (f[~pk.mobile] == pk.density_factor[~pk.mobile]).all()
    light = scenes.preset("quicksand_case1", {"material": {"rho": 900.0}})
    with pytest.raises(ValueError, match=r"\[packing\] settle_submerged"):
        buoyant(light, pk)
