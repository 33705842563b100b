"""Side-wall ties of the seismic box (seed 000 §6.1, Fig. 27)."""
import numpy as np
import pytest

from engines.model import pores as pg
from engines.model.limits import tie_limit
from engines.model.side_walls import SideWallTies
from engines.yade.deposition import wall_box
from tests.oracles import tie_dissipation_rate, tie_energy

KS, ETA = 1.5e5, 0.6   # Table 4: k'_s [N/m], eta'_s [N s/m]
R_W = 0.55e-3


def _box():
    xz, group = wall_box(25, 12, R_W)
    return xz, group, SideWallTies(xz, group, KS, ETA)


def test_columns_tied_bottom_to_top_from_the_corners():
    xz, group, ties = _box()
    assert set(ties.columns) == {"left", "right"} and len(ties.lower) == 22
    for name, code, x in (("left", pg.WALL_LEFT, 0.0), ("right", pg.WALL_RIGHT, 24 * 2 * R_W)):
        chain = ties.columns[name]
        assert group[chain[0]] == pg.WALL_BOTTOM and np.all(group[chain[1:]] == code)
        assert np.allclose(xz[chain, 0], x) and np.all(np.diff(xz[chain, 1]) > 0)
    assert ties.moving.sum() == 22 and not ties.moving[group == pg.WALL_BOTTOM].any()


def test_rigid_motion_with_the_base_gives_no_force():
    xz, group, ties = _box()
    x = xz[:, 0] + 1.234e-4
    v = np.full(len(x), 0.37)
    np.testing.assert_allclose(ties.forces(x, v), 0.0, atol=1e-12 * KS * 1e-4)


def test_one_displaced_disc_feels_two_springs():
    xz, group, ties = _box()
    col = ties.columns["left"]
    mid, top = col[5], col[-1]
    dx = 2e-6
    x = xz[:, 0].copy()
    x[mid] += dx
    F = ties.forces(x, np.zeros(len(x)))
    assert F[mid] == pytest.approx(-KS * 2 * dx, rel=1e-9)
    assert F[col[4]] == pytest.approx(KS * dx, rel=1e-9) and F[col[6]] == pytest.approx(KS * dx, rel=1e-9)
    x = xz[:, 0].copy()
    x[top] += dx
    F = ties.forces(x, np.zeros(len(x)))
    assert F[top] == pytest.approx(-KS * dx, rel=1e-9)  # the top disc has one neighbour


def test_dashpot_opposes_relative_motion():
    xz, group, ties = _box()
    col = ties.columns["right"]
    v = np.zeros(len(xz))
    v[col[3]] = 0.01
    F = ties.forces(xz[:, 0], v)
    assert F[col[3]] == pytest.approx(-2 * ETA * 0.01)
    assert F[col[2]] == pytest.approx(ETA * 0.01) and F[col[4]] == pytest.approx(ETA * 0.01)


def test_forces_sum_to_zero():
    xz, group, ties = _box()
    rng = np.random.default_rng(0)
    F = ties.forces(xz[:, 0] + 1e-5 * rng.standard_normal(len(xz)), rng.standard_normal(len(xz)))
    assert abs(F.sum()) < 1e-12 * np.abs(F).max()


def _free_column_run(eta, n_steps=4000):
    """A column released from a bent shape above a fixed base, velocity Verlet: returns the energy
    and the integrated dashpot work histories."""
    xz, group = wall_box(25, 12, R_W)
    ties = SideWallTies(xz, group, KS, eta)
    m = np.full(len(xz), 10 * 2700 * np.pi * R_W**2)  # the paper's 10x denser walls
    mov = ties.moving
    dt = 0.05 * tie_limit(ties, m)
    x = xz[:, 0].copy()
    x[mov] += 1e-5 * np.sin(np.linspace(0, np.pi, mov.sum()))
    v = np.zeros(len(x))
    a = np.where(mov, ties.forces(x, v) / m, 0.0)
    E, work = [], [0.0]
    for _ in range(n_steps):
        E.append(0.5 * np.sum(m[mov] * v[mov] ** 2) + tie_energy(ties, x))
        p0 = tie_dissipation_rate(ties, v)
        v_half = v + 0.5 * dt * a
        x = x + dt * np.where(mov, v_half, 0.0)
        a = np.where(mov, ties.forces(x, v_half) / m, 0.0)
        v = np.where(mov, v_half + 0.5 * dt * a, 0.0)
        work.append(work[-1] + 0.5 * dt * (p0 + tie_dissipation_rate(ties, v)))
    return np.array(E), np.array(work[:-1])


def test_energy_conserved_without_dashpots_and_dissipated_with():
    E, _ = _free_column_run(0.0)
    assert E[0] > 0 and np.abs(E / E[0] - 1).max() < 1e-3
    E, work = _free_column_run(ETA)
    assert E[-1] < 0.9 * E[0]
    assert np.all(np.diff(E) < 1e-9 * E[0])
    # the energy lost is the dashpots' work (to the integrator's accuracy)
    np.testing.assert_allclose(E[0] - E[-1], work[-1], rtol=0.02)


def test_bad_constants_and_missing_bottom():
    xz, group = wall_box(5, 3, R_W)
    with pytest.raises(ValueError, match="ks_wall"):
        SideWallTies(xz, group, -1.0, ETA)
    with pytest.raises(ValueError, match="bottom wall"):
        SideWallTies(xz[group != pg.WALL_BOTTOM], group[group != pg.WALL_BOTTOM], KS, ETA)
