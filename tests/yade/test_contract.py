"""The WaterEngine's contract (engines.yade.contract): each refusal, on viscel_column's column
with one thing broken, and an engine error ending a plain `yade -x` script with status 1."""
import math
import os
import subprocess
import textwrap

import pytest
import yade  # noqa: F401  (fails loudly if YADE is missing)

from engines import ROOT
from engines.model.pore_water import WaterSettings
from engines.yade.contract import ContractError, set_disc_mass

SETTINGS = WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4)


def column():
    """viscel_column's column (fresh scene, dt = 1e-6 s): (bottom, left, right, grains) ids."""
    from yade import O

    from yade_scripts.examples import viscel_column as ex
    ids = ex.build_column()
    O.engines = ex.engines()
    O.dt = 1e-6
    return ids


def engine(bottom, left, right, grains, settings=SETTINGS, extra=(), **kw):
    from engines.yade.water_engine import WaterEngine
    """A WaterEngine over the discs and ``extra`` bodies, the walls named."""
    return WaterEngine(bottom + left + right + grains + list(extra),
                       walls={"bottom": bottom, "left": left, "right": right}, settings=settings, l_m=1.3e-4, **kw)


def test_set_disc_mass_is_per_metre_of_thickness():
    from yade import O, utils
    O.reset()
    b = utils.sphere((0, 0, 0), 0.5e-3)
    set_disc_mass(b, 2700.0, 5.0)
    m = 5 * 2700 * math.pi * 0.5e-3**2
    assert b.state.mass == pytest.approx(m, rel=1e-15)
    assert b.state.inertia[1] == pytest.approx(0.5 * m * 0.5e-3**2, rel=1e-15)


def test_the_column_and_dense_discs_are_accepted():
    """Density factors 1 (all), 5 and 10 (the paper's dense top discs) and 0.5 (the bound) pass."""
    from yade import O
    bottom, left, right, grains = column()
    for i, f in zip(grains[-3:], (5.0, 10.0, 0.5)):
        set_disc_mass(O.bodies[i], 2700.0, f)
    water = engine(bottom, left, right, grains)
    assert water.model.water.net.n_pores > 100


@pytest.mark.parametrize("make, what", [("box", r"a YADE Box in disc_ids, .*flat_walls=\{\d+: "),
                                        ("wall", r"a YADE Wall in disc_ids, .*flat_walls=\{\d+: "),
                                        ("facet", "a Facet, not a sphere")])
def test_a_body_that_is_not_a_sphere_is_refused(make, what):
    from yade import O, utils
    ids = column()
    shape = {"box": lambda: utils.box((0, 0, -1e-3), (5e-3, 5e-3, 1e-4)), "wall": lambda: utils.wall(-1e-3, axis=2),
             "facet": lambda: utils.facet([(0, 0, -1e-3), (1e-3, 0, -1e-3), (0, 0, -2e-3)])}[make]
    other = O.bodies.append(shape())
    with pytest.raises(ContractError, match=rf"^body {other}: {what}"):
        engine(*ids, extra=[other])


def test_a_missing_body_is_refused():
    from yade import O
    ids = column()
    with pytest.raises(ContractError, match=rf"^body {len(O.bodies) + 3}: not in O.bodies"):
        engine(*ids, extra=[len(O.bodies) + 3])


def test_a_disc_off_the_plane_is_refused():
    from yade import O
    bottom, left, right, grains = column()
    O.bodies[grains[7]].state.pos = O.bodies[grains[7]].state.pos + (0, 1e-6, 0)
    with pytest.raises(ContractError, match=rf"^body {grains[7]}: centre at y = 1e-06 m, off the plane y = 0 m"):
        engine(bottom, left, right, grains)


def test_discs_in_the_x_y_plane_are_refused():
    """The column laid in the x-y plane (z = 0, y the height): no common y."""
    from yade import O
    ids = column()
    for b in O.bodies:
        p = b.state.pos
        b.state.pos = (p[0], p[2], 0.0)
    with pytest.raises(ContractError, match=r"off the plane y = .* \(the WaterEngine works in the x-z plane"):
        engine(*ids)


def test_a_disc_free_to_leave_the_plane_is_refused():
    from yade import O
    bottom, left, right, grains = column()
    O.bodies[grains[3]].state.blockedDOFs = "XZ"
    with pytest.raises(ContractError, match=rf"^body {grains[3]}: free to leave the x-z plane \(blockedDOFs 'XZ'"):
        engine(bottom, left, right, grains)


def test_a_disc_moving_out_of_the_plane_is_refused():
    from yade import O
    bottom, left, right, grains = column()
    O.bodies[grains[0]].state.vel = (0, 0.01, 0)
    with pytest.raises(ContractError, match=rf"^body {grains[0]}: velocity 0.01 m/s along y"):
        engine(bottom, left, right, grains)


def test_yades_sphere_mass_is_refused():
    """YADE's own mass 4/3 pi r^3 rho (what utils.sphere sets): 6e-4 of rho pi r^2 at r = 0.45 mm."""
    from yade import O, utils
    bottom, left, right, grains = column()
    b = O.bodies[grains[5]]
    b.state.mass = utils.sphere((0, 0, 0), b.shape.radius, material=b.material).state.mass
    with pytest.raises(ContractError, match=rf"^body {grains[5]}: mass .* is YADE's 3D sphere mass 4/3 pi r\^3 rho; "
                                            r"the WaterEngine's forces are per metre of thickness"):
        engine(bottom, left, right, grains)


def test_a_mass_below_half_of_rho_pi_r2_is_refused():
    from yade import O
    bottom, left, right, grains = column()
    set_disc_mass(O.bodies[grains[2]], 2700.0, 0.4)
    with pytest.raises(ContractError, match=rf"^body {grains[2]}: mass .* is 0.4 x rho pi r\^2"):
        engine(bottom, left, right, grains)


def test_a_sphere_inertia_with_a_disc_mass_is_refused():
    """Mass set per thickness, inertia left at YADE's 2/5 m_3D r^2, spin about y free."""
    from yade import O
    bottom, left, right, grains = column()
    b = O.bodies[grains[4]]
    b.state.inertia = (0.4 * 4 / 3 * math.pi * b.shape.radius**5 * 2700,) * 3
    with pytest.raises(ContractError, match=rf"^body {grains[4]}: inertia I_y .* below 0.5 x m r\^2/2"):
        engine(bottom, left, right, grains)


def test_inflow_without_an_inflow_boundary_is_refused():
    bottom, left, right, grains = column()
    with pytest.raises(ContractError, match=r"^q_w = 0.0005 m\^2/s per inflow pore but no pore has a bottom wall disc"):
        engine([], left, right, bottom + grains)
    column()
    without = engine([], left, right, bottom + grains, settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0))
    assert without.model.water.net.n_pores > 100  # q_w = 0 needs no bottom


def test_no_pores_is_refused():
    """Three discs 10 radii apart in the x-z plane."""
    from yade import O, utils
    O.reset()
    ids = []
    for x in (0.0, 5e-3, 10e-3):
        b = utils.sphere((x, 0, 0), 0.5e-3)
        set_disc_mass(b, 2700.0)
        b.state.blockedDOFs = "yXZ"
        ids.append(O.bodies.append(b))
    O.dt = 1e-6
    with pytest.raises(ContractError, match=r"^no pores between the 3 discs"):
        engine([], [], [], ids, settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0))


def test_a_body_added_after_construction_is_refused_at_the_next_rebuild():
    from yade import O, utils
    ids = column()
    water = engine(*ids, rebuild_interval=10)
    water.drive(5, lambda: False)
    new = O.bodies.append(utils.sphere((1e-3, 0, 20e-3), 0.45e-3))
    with pytest.raises(ContractError, match=rf"^body {new}: added after the WaterEngine was made"):
        water.drive(20, lambda: False)
    assert O.iter == 10  # refused at the rebuild of step 10


def test_an_erased_disc_is_refused_at_the_next_water_step():
    from yade import O
    bottom, left, right, grains = column()
    water = engine(bottom, left, right, grains)
    water.drive(3, lambda: False)
    O.bodies.erase(grains[9])
    with pytest.raises(IndexError, match=rf"^body id {grains[9]} .*erased"):
        water.drive(3, lambda: False)


SCRIPT = """
from yade import O
from engines.model.pore_water import WaterSettings
from engines.yade.water_engine import WaterEngine
from yade_scripts.examples import viscel_column as ex
bottom, left, right, grains = ex.build_column()
O.engines = ex.engines()
O.dt = 5e-11  # within the Darcy limit of k1 = 1e8 (5.9e-9 s) at construction
water = WaterEngine(bottom + left + right + grains, walls={"bottom": bottom, "left": left, "right": right},
                    settings=WaterSettings(E_w=240.0, k1=1e8, k2=2.0, q_w=5e-4, substep=False), l_m=1.3e-4,
                    water_interval=10)
O.dt = 1e-6  # checked at the first water step
O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
O.run(200, True)
print("after the run at step", O.iter)
"""


def run_script(tmp_path, code):
    path = tmp_path / "user_script.py"
    path.write_text(textwrap.dedent(code))
    env = dict(os.environ, PYTHONPATH=ROOT)
    return subprocess.run(["yade", "-n", "-x", str(path)], capture_output=True, text=True, env=env, timeout=600,
                          cwd=tmp_path)


def test_an_engine_error_ends_a_plain_script_with_status_1(tmp_path):
    """A Darcy refusal (substep=False, k1 = 1e8, O.dt raised after the construction) in a PyRunner
    under O.run(200, True): the run stops at its first water step, the script goes on, and the
    process exits with status 1 and
    one line naming the engine's argument and the scene field."""
    p = run_script(tmp_path, SCRIPT)
    assert p.returncode == 1, p.stderr[-2000:]
    assert "after the run at step 1\n" in p.stdout
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith("error inside a YADE engine, never raised by the script: DarcyStabilityError: water step ")
    assert "WaterSettings substep=True; [water] substep = true" in last


def test_an_engine_error_the_script_raises_is_its_own(tmp_path):
    """The same script catching the error by raise_pending: its own exit status (0)."""
    p = run_script(tmp_path, SCRIPT + textwrap.dedent("""
        from engines.model.limits import DarcyStabilityError
        from engines.yade.yade_io import raise_pending
        try:
            raise_pending()
        except DarcyStabilityError:
            print("handled")
        """))
    assert p.returncode == 0, p.stderr[-2000:]
    assert "handled" in p.stdout and "never raised" not in p.stderr
