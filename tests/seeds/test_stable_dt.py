"""Seed 003's time step without YADE: the leapfrog limit of one damped mode, the fastest modes
of disc lattices against disc_dt_bound, and stable_dt against them for ks/kn = 0.1–1."""
import math

import numpy as np
import pytest

from engines.seeds.biaxial.cem_contact import (
    PAPER_DT,
    TABLE2_DT,
    CemContact,
    disc_dt_bound,
    disc_mass,
    leapfrog_dt,
    pair_constants,
    stable_dt,
)
from engines.seeds.biaxial.periodic import table1_radii

R = table1_radii(1000)
RMIN = 1.4e-3


def grows(k, c, m, dt, steps=4000):
    """Leapfrog with the dashpot on the previous half-step velocity, as YADE: does |x| pass 10
    within ``steps`` from x = 1 at rest?"""
    x_old, x = 1.0, 1.0
    for _ in range(steps):
        x, x_old = 2 * x - x_old - dt * dt * k / m * x - dt * c / m * (x - x_old), x
        if abs(x) > 10:
            return True
    return False


@pytest.mark.parametrize("zeta", [0.0, 0.3, 1.0, 3.0])
def test_leapfrog_limit_of_one_damped_mode(zeta):
    k, m = 2.0e5, 0.015
    c = 2 * zeta * math.sqrt(m * k)
    dt = leapfrog_dt(k, c, m)
    assert dt == pytest.approx(2 * math.sqrt(m / k) * (math.sqrt(1 + zeta * zeta) - zeta))
    assert not grows(k, c, m, 0.98 * dt) and grows(k, c, m, 1.02 * dt)


def lattice_limit(c, neighbours):
    """Exact leapfrog limit [s] of a periodic lattice of equal discs (radius RMIN, translation and
    rotation, mass m, inertia m r²/2) whose contact directions are ``neighbours`` (unit vectors,
    each contact once): the largest dt with 4 M − dt² K − 2 dt C >= 0, from the Bloch matrices of
    K and C at a grid of wave vectors (one disc per cell)."""
    kn, ks, cn, cs = pair_constants(RMIN, RMIN, c)
    m = float(disc_mass(RMIN, c.rho))
    mass = np.array([m, m, m * RMIN ** 2 / 2])
    scale = 1 / np.sqrt(mass)
    worst = 0.0
    for q1 in np.linspace(0, 2 * np.pi, 13):
        for q2 in np.linspace(0, 2 * np.pi, 13):
            K = np.zeros((3, 3), complex)
            C = np.zeros((3, 3), complex)
            for n, phase in neighbours(q1, q2):
                t = np.array([-n[1], n[0]])
                # (δn, δt) of the contact with the neighbour displaced by the phase: δn = (u' − u)·n,
                # δt = (u' − u)·t − r θ − r θ'
                gn = np.array([*((phase - 1) * n), 0])
                gt = np.array([*((phase - 1) * t), -RMIN * (1 + phase)])
                for g, k_, c_ in ((gn, kn, cn), (gt, ks, cs)):
                    K += k_ * np.outer(g.conj(), g)
                    C += c_ * np.outer(g.conj(), g)
            lo, hi = 0.0, 1e-3
            for _ in range(60):
                dt = 0.5 * (lo + hi)
                a = (dt * dt * K + 2 * dt * C) * scale[:, None] * scale[None, :]
                lo, hi = (dt, hi) if np.linalg.eigvalsh(a).max() <= 4 else (lo, dt)
            worst = lo if worst == 0 else min(worst, lo)
    return worst


def square(q1, q2):
    return [(np.array([1.0, 0.0]), np.exp(1j * q1)), (np.array([0.0, 1.0]), np.exp(1j * q2))]


def triangular(q1, q2):
    s = math.sqrt(3) / 2
    return [(np.array([1.0, 0.0]), np.exp(1j * q1)), (np.array([0.5, s]), np.exp(1j * q2)),
            (np.array([-0.5, s]), np.exp(1j * (q2 - q1)))]


@pytest.mark.parametrize("ks_ratio", [0.1, 0.25, 0.5, 1.0])
def test_disc_bound_is_the_fastest_mode_of_a_square_lattice_and_bounds_a_triangular_one(ks_ratio):
    """Square lattice (Z = 4): the co-rotating and the alternating translation modes are exact
    modes, so disc_dt_bound is its limit; triangular (Z = 6): the co-rotation is exact, the
    alternating translation cannot exist, so the bound is at or below the limit."""
    c = CemContact(ks_ratio=ks_ratio)
    assert disc_dt_bound(R, c, contacts=4) == pytest.approx(lattice_limit(c, square), rel=1e-6)
    tri = lattice_limit(c, triangular)
    assert disc_dt_bound(R, c, contacts=6) <= tri * (1 + 1e-9)
    assert disc_dt_bound(R, c, contacts=6) == pytest.approx(tri, rel=1e-6) or ks_ratio < 0.2


def old_rule(c):
    """The former stable_dt: the paper's step scaled as 1/√(kn (1 + 4 ks/kn) / (ρ r_min))."""
    stiff = c.kn * c.width_factor * (1 + 4 * c.ks_ratio) / (c.rho * RMIN)
    return PAPER_DT * min(1.0, math.sqrt(1e8 * 2 / (2500.0 * RMIN) / stiff))


def test_stable_dt_stays_below_the_square_lattice_limit_where_the_old_factor_did_not():
    """A square lattice of the lightest discs (the assembly disc_dt_bound describes at Z = 4):
    stable_dt lies below its exact limit for ks/kn = 0.1–1 and kn × 2; the old factor
    (1 + 4 ks/kn) gave more than the limit at ks/kn = 0.5 and 1, where packings rang."""
    for ks_ratio in (0.1, 0.25, 0.5, 1.0):
        c = CemContact(ks_ratio=ks_ratio)
        assert stable_dt(R, c) <= lattice_limit(c, square)
    assert stable_dt(R, CemContact(kn=2e8)) <= lattice_limit(CemContact(kn=2e8), square)
    for ks_ratio in (0.5, 1.0):
        c = CemContact(ks_ratio=ks_ratio)
        assert old_rule(c) > lattice_limit(c, square)
    assert stable_dt(R, CemContact()) == TABLE2_DT  # Table 1–2: below the paper's step (the dense packings' limit)


def test_locked_rotation_leaves_the_translation():
    c, locked = CemContact(ks_ratio=0.5), CemContact(ks_ratio=0.5, rotation="locked")
    assert disc_dt_bound(R, locked) > disc_dt_bound(R, c)
    assert stable_dt(R, locked) == TABLE2_DT
    with pytest.raises(ValueError, match="rotation"):
        CemContact(rotation="rolling")


def periodic_square_lattice(n, overlap=1e-6):
    """n × n equal discs (RMIN) on a square grid of spacing 2 RMIN − overlap in its periodic cell."""
    a = 2 * RMIN - overlap
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    return np.column_stack([i.ravel(), j.ravel()]) * a + a / 2, np.full(n * n, RMIN), (n * a, n * a)


@pytest.mark.parametrize("ks_ratio", [0.25, 1.0])
def test_network_limit_of_a_square_lattice_is_the_lattice_limit(ks_ratio):
    """network_dt_limit on a periodic square lattice (even side: the alternating modes fit) gives
    the Bloch limit of the lattice (lattice_limit, found independently); with the rotation
    locked the translation's, leapfrog_dt of the alternating mode (4 (k_n + k_s), dashpots alike)."""
    from engines.seeds.biaxial.stability import network_dt_limit

    xz, r, cell = periodic_square_lattice(6)
    c = CemContact(ks_ratio=ks_ratio)
    assert network_dt_limit(xz, r, cell, c) == pytest.approx(lattice_limit(c, square), rel=3e-4)
    locked = CemContact(ks_ratio=ks_ratio, rotation="locked")
    kn, ks, cn, cs = pair_constants(RMIN, RMIN, locked)
    alternating = leapfrog_dt(4 * (kn + ks), 4 * (cn + cs), float(disc_mass(RMIN, locked.rho)))
    assert network_dt_limit(xz, r, cell, locked) == pytest.approx(alternating, rel=3e-4)
    # apart by more than the overlap: no contact, no limit from the springs (the bisection's ceiling)
    assert network_dt_limit(xz * 1.01, r, (cell[0] * 1.01, cell[1] * 1.01), c) == pytest.approx(1e-3, rel=1e-3)
