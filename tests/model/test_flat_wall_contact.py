"""The paper's law against flat walls (engines.model.paper_law, SPEC §2.6, READINGS F7): a particle
touches a flat wall as a fixed wall disc of radius 0 at its foot, at rest."""
import numpy as np
import pytest

from engines.model.contact import E_S, ContactSettings
from engines.model.flat_walls import FlatWall
from engines.model.paper_law import PaperLaw

R, RHO, DT = 0.45e-3, 2650.0, 1e-6
M = RHO * np.pi * R**2


def law(radii, flat=(), spring="d", mu=0.5, spin=1.0, adjust=True):
    """The paper's law for disc 0 (mobile; inertia ``spin`` x m r^2 / 2) and fixed discs of
    ``radii`` after it, and flat walls; ``adjust``: eq 18-24 on."""
    s = ContactSettings(spring=spring, kn=1.4e5, eta_n=2.6, ks=3.5e4, eta_s=0.6, mu=mu, f_max=1.5, eps_m=2e-5,
                        restitution=0.3, separation_adjustment=adjust)
    r = np.array([R, *radii])
    return PaperLaw(s, r, np.arange(len(r)) == 0, np.full(len(r), M), np.full(len(r), spin * M * R**2 / 2), DT,
                    flat_walls=flat)


def drop(lw, z_of, steps, x_of=lambda k: 0.0, extra=()):
    """Step the law with disc 0 at (x_of(k), z_of(k)) (and fixed discs ``extra``): forces, fixes."""
    out = []
    for k in range(steps):
        xz = np.array([[x_of(k), z_of(k)], *extra])
        F, fixes = lw.step(xz)
        out.append((F[0].copy(), lw.omega[0], dict(fixes)))
    return out


@pytest.mark.parametrize("spring", ["b", "d"])
def test_a_disc_on_a_flat_wall_is_a_disc_on_a_wall_disc_below_it(spring):
    """Moving along the normal only, a disc meets a flat face z = 0 as it meets a fixed wall disc
    of any radius right below it (the same R - r sums, normal and increments): the same forces at
    every step of a press and release, and the same eq 18-24 adjustment (pattern (a)) on leaving."""
    path = lambda k: R + 2e-5 - 1e-8 * k if k < 300 else R + 2e-5 - 3e-6 + 2e-8 * (k - 300)  # in, then out
    flat = drop(law([], (FlatWall(1, 0.0, +1),), spring), path, 600)
    Rw = 5 * R
    disc = drop(law([Rw], spring=spring), path, 600, extra=([0.0, -Rw],))
    f = np.array([a[0] for a in flat])
    g = np.array([a[0] for a in disc])
    np.testing.assert_allclose(f, g, rtol=1e-12, atol=1e-15)
    assert f[:, 1].max() > 0.1  # pressed: the wall pushes up [N]
    fixed_flat = [a[2] for a in flat if a[2]]
    fixed_disc = [a[2] for a in disc if a[2]]
    assert len(fixed_flat) == len(fixed_disc) == 1
    np.testing.assert_allclose(fixed_flat[0][0], fixed_disc[0][0], rtol=1e-12)


def test_a_disc_dragged_on_a_flat_wall_slides_at_coulomb_friction_or_rolls():
    """Pressed into z = 0 by a fixed overlap and dragged along x at 1 cm/s: with its spin held (a
    huge inertia) the tangential spring reaches the Coulomb limit -mu f_n (eq 11); free to spin, the
    friction's moment turns it clockwise (eq 13c: rolling towards +x)."""
    z = R + 2e-5 - 2e-6  # overlap 2 um (with eps_m 20 um)
    held = law([], (FlatWall(1, 0.0, +1),), spring="b", mu=0.5, spin=1e12)
    Fx, Fz = drop(held, lambda k: z, 1000, x_of=lambda k: 1e-8 * k)[-1][0]
    assert Fz == pytest.approx(1.4e5 * 2e-6, rel=1e-9)  # f_n = kn u_n, no approach
    assert Fx == pytest.approx(-0.5 * Fz, rel=1e-9)
    np.testing.assert_allclose(held.wall_forces(), [Fz], rtol=1e-12)
    free = law([], (FlatWall(1, 0.0, +1),), spring="b", mu=0.5)
    out = drop(free, lambda k: z, 50, x_of=lambda k: 1e-8 * k)
    assert out[-1][1] < 0 and out[-1][0][0] < 0


def test_a_disc_touches_only_its_own_foot():
    """Two walls at a corner and a disc near each: every contact pair is a disc and its own foot."""
    walls = (FlatWall(1, 0.0, +1), FlatWall(0, 0.0, +1))
    s = ContactSettings(spring="b", kn=1.4e5, eps_m=2e-5)
    lw = PaperLaw(s, np.full(2, R), np.ones(2, bool), np.full(2, M), np.full(2, M * R**2 / 2), DT, flat_walls=walls)
    xz = np.array([[R - 1e-6, 5 * R], [5 * R, R - 1e-6]])  # disc 0 on the left wall, disc 1 on the bottom
    F, _ = lw.step(xz)
    c, wv = lw.contact, lw.walls
    touching = c.touching
    pairs = set(zip(c.i[touching].tolist(), c.j[touching].tolist()))
    assert pairs == {(0, int(wv.foot(1, 0))), (1, int(wv.foot(0, 1)))}
    assert F[0, 0] > 0 and F[1, 1] > 0 and abs(F[0, 1]) < 1e-12 and abs(F[1, 0]) < 1e-12
    np.testing.assert_allclose(lw.wall_forces(), [F[1, 1], F[0, 0]], rtol=1e-12)


@pytest.mark.parametrize("spin", [1.0, 1e12])
def test_a_wall_sliding_under_a_disc_is_the_disc_sliding_over_the_wall(spin):
    """PaperLaw.move_walls: the bottom face translated by +d(k) in x (its feet moving with it) gives
    the disc the contact forces and spin that the disc moved by -d(k) over a fixed face gets: only
    the relative motion enters eq 1-13 (Galilean invariance). A foot left at rest would give no
    tangential force at all. A side face translated inwards by s(k) presses as the disc moved
    outwards by s(k)."""
    z = R + 2e-5 - 2e-6  # pressed 2 um into the face
    d = lambda k: 2e-9 * k + 1e-10 * k * k
    moving = law([], (FlatWall(1, 0.0, +1),), spring="d", mu=0.5, spin=spin)
    got = []
    for k in range(400):
        moving.move_walls([[d(k), 0.0]])
        F, _ = moving.step(np.array([[0.0, z]]))
        got.append((*F[0], moving.omega[0]))
    want = [(*a[0], a[1]) for a in drop(law([], (FlatWall(1, 0.0, +1),), spring="d", mu=0.5, spin=spin),
                                         lambda k: z, 400, x_of=lambda k: -d(k))]
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-18)
    assert np.abs(np.array(got)[:, 0]).max() > 0.01  # the dragging force [N]
    x0 = R + 2e-5 + 1e-6  # 1 um off contact (eps_m = 20 um): touched after 50 steps
    side = law([], (FlatWall(0, 0.0, +1),), spring="d")
    pressed = []
    for k in range(200):
        side.move_walls([[2e-8 * k, 0.0]])
        pressed.append(side.step(np.array([[x0, 0.0]]))[0][0])
    still = drop(law([], (FlatWall(0, 0.0, +1),), spring="d"), lambda k: 0.0, 200, x_of=lambda k: x0 - 2e-8 * k)
    np.testing.assert_allclose(pressed, [a[0] for a in still], rtol=1e-9, atol=1e-15)  # x0 - s and s: round-off
    assert np.array(pressed)[-1, 0] > 0.1  # pushed away from the face [N]


def test_a_disc_leaving_a_moving_face_is_adjusted_as_one_leaving_a_fixed_face():
    """Eq 18-24 with a translated wall (pattern (a), the wall at its velocity): a disc pressed into
    a face rising at 2 mm/s and leaving it gets the adjusted velocity of the same relative motion
    against a fixed face plus the face's velocity; with the feet's velocity taken as zero, or as
    du dt, the adjustment would differ."""
    V = 2e-3  # m/s, the face's speed along its normal
    top = R + 2e-5 + 1e-6  # 1 um off contact: it touches at 1 cm/s (the approach velocity of eq 21)
    path = lambda k: top - 1e-8 * k if k < 300 else top - 3e-6 + 2e-8 * (k - 300)  # in, then out
    fixed = [a[2] for a in drop(law([], (FlatWall(1, 0.0, +1),), spring="b"), path, 600) if a[2]]
    lw, moving = law([], (FlatWall(1, 0.0, +1),), spring="b"), []
    for k in range(600):
        lw.move_walls([[0.0, V * DT * k]])
        _, fixes = lw.step(np.array([[0.0, path(k) + V * DT * k]]))
        if fixes:
            moving.append(fixes)
    assert len(fixed) == len(moving) == 1 and 0 < fixed[0][0][1] < 0.5 * 2e-8 / DT  # slowed from 2 cm/s
    np.testing.assert_allclose(moving[0][0], fixed[0][0] + [0.0, V], rtol=1e-6)
    assert not any(a[2] for a in drop(law([], (FlatWall(1, 0.0, +1),), spring="b", adjust=False), path, 600))


def test_two_discs_parting_beside_a_wall_keep_their_momentum():
    """Eq 24 (pattern (d)) in a law with flat walls: two free discs that collided and fly apart too
    fast, near but not touching a wall, get the adjustment of the law without walls."""
    s = ContactSettings(spring="a", kn=1.4e5, eta_n=0.0, restitution=0.3)
    r, m = np.array([R, 0.7 * R]), np.array([M, 0.49 * M])
    laws = [PaperLaw(s, r, np.ones(2, bool), m, m * r**2 / 2, DT, flat_walls=f) for f in ((), (FlatWall(1, 0.0, +1),))]
    z = 3 * R  # 2 R above the face
    got = []
    for lw in laws:
        for gap in (5e-9, -5e-9):  # approach at 10 mm/s: contact
            lw.step(np.array([[0.0, z], [r.sum() + gap, z]]))
        _, fixes = lw.step(np.array([[0.0, z], [r.sum() + 5e-9, z]]), vel=np.array([[-0.3, 0.0], [0.5, 0.0]]))
        got.append(fixes)
    assert set(got[0]) == set(got[1]) == {0, 1}
    for d in (0, 1):
        np.testing.assert_allclose(got[1][d], got[0][d], rtol=1e-12)


def test_contact_pairs_are_the_disc_pairs_the_next_step_finds():
    """PaperLaw.contact_pairs with flat walls: the pairs of two discs touching at xz, with the
    normal and elastic shear forces the next step computes there (eq 17: du and dpsi = omega dt
    of that step; the spin set so that it matters), the disc-foot pairs left out, ``keep``
    applied; without walls the same pairs."""
    s = ContactSettings(spring="b", kn=1.4e5, ks=3.5e4, mu=0.5, eps_m=2e-5)
    r = np.full(3, R)
    xz0 = np.array([[R, R], [3 * R - 1e-6, R], [5 * R - 2e-6, R]])  # a row on the bottom face, pressed together
    xz1 = xz0 + [[1e-8, -1e-7], [0.0, -1e-7], [-1e-8, -1e-7]]
    for walls in ((), (FlatWall(1, 0.0, +1),)):
        lw = PaperLaw(s, r, np.ones(3, bool), np.full(3, M), np.full(3, M * R**2 / 2), DT, flat_walls=walls)
        assert lw.contact_pairs(xz0)[0].tolist() == [[0, 1], [1, 2]]  # before any step, as a run's first snapshot
        lw.step(xz0)
        lw.omega[:] = [50.0, -30.0, 10.0]
        pairs, fn, es = lw.contact_pairs(xz1)
        kept = lw.contact_pairs(xz1, keep=lambda i, j: (i == 1) & (j == 2))[0]
        lw.step(xz1)
        c = lw.contact
        t = c.touching & (c.j < 3)
        assert pairs.tolist() == np.column_stack([c.i[t], c.j[t]]).tolist() == [[0, 1], [1, 2]]
        np.testing.assert_allclose(fn, c.f_n[t], rtol=1e-12)
        np.testing.assert_allclose(es, c.state[t, E_S], rtol=1e-12)
        assert np.all(np.abs(es) > 0) and kept.tolist() == [[1, 2]]


def test_wall_forces_has_a_row_for_every_wall():
    """A wall no disc touches pushes with 0: wall_forces is (W,) in the walls' order."""
    lw = law([], (FlatWall(1, 0.0, +1), FlatWall(0, -5 * R, +1)), spring="b")
    lw.step(np.array([[0.0, R + 2e-5 - 2e-6]]))
    f = lw.wall_forces()
    assert f.shape == (2,) and f[0] > 0 and f[1] == 0.0
