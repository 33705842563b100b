"""Flat walls as pore boundaries in the reference (SPEC §2.6, READINGS F1-F8), against answers
computed by hand: the void areas of wall and corner pores, a uniform pressure (no net force on a
disc, U x wetted length on each wall), the boundary fluxes of drained, inflow and undrained walls,
the water budget of a run, re-meshing with a wall as a vertex, and the contact with a wall.
"""

import numpy as np
import pytest

from engines.reference import model as ref
from packing.layouts import hex_lattice
from packing.packing import Packing
from tests.reference.test_reference import non_overlapping_discs
from tests.scene_helpers import make_scene

R = 0.45e-3  # disc radius [m]


def wall(axis, position, inward, boundary="undrained"):
    return {"axis": axis, "position": position, "inward": inward, "boundary": boundary, "moves": False}


def flat(*walls):
    return ref.read_flat_walls({"walls": {"flat": list(walls)}})


def square_box(boundaries=("undrained",) * 4, m=3):
    """m x m equal discs of radius R on a square lattice of spacing 2R, each touching its neighbours,
    in a box of four flat walls touching the outer discs: left x = 0, right x = 2mR, bottom z = 0,
    top z = 2mR. Returns centres, radii, walls."""
    x = np.array([[R + 2 * R * i, R + 2 * R * j] for j in range(m) for i in range(m)])
    side = 2 * m * R
    walls = flat(wall("x", 0.0, 1, boundaries[0]), wall("x", side, -1, boundaries[1]),
                 wall("z", 0.0, 1, boundaries[2]), wall("z", side, -1, boundaries[3]))
    return x, np.full(len(x), R), walls


def pores_of(x, r, walls, l_m=0.1 * R):
    pores = ref.build_pores(x, r, np.zeros(len(r), int), 0.0, l_m, walls)
    return pores, ref.measure(pores, x, r, 0.0)


# -- geometry ---------------------------------------------------------------------------------------
def test_wall_pores_of_a_square_row_on_a_wall():
    """Five touching discs on the wall z = 0: four pores, each the rectangle c_k, c_k+1 and their
    foot points, 2R x R, minus a quarter disc at each centre: A = 2 R^2 - pi R^2 / 2, one wall edge
    of length 2R; a wall counts as one vertex of the pore."""
    x = np.array([[2 * R * k, R] for k in range(5)])
    pores, geo = pores_of(x, np.full(5, R), flat(wall("z", 0.0, 1)))
    assert pores.vertex_sets == [frozenset({k, k + 1, -1}) for k in range(4)]
    np.testing.assert_allclose(geo.polygon_area, 2 * R * R, rtol=1e-13)
    np.testing.assert_allclose(geo.void_area, 2 * R**2 - np.pi * R**2 / 2, rtol=1e-13)
    on_wall = pores.he_wall >= 0
    assert np.array_equal(np.sort(pores.he_pore[on_wall]), np.arange(4))
    vertices, _ = ref.wall_vertices(pores, x, np.full(5, R))
    np.testing.assert_allclose(np.hypot(*(vertices[pores.he_b[on_wall]] - vertices[pores.he_a[on_wall]]).T),
                               2 * R, rtol=1e-13)
    to_wall = pores.links.max(axis=1) >= 5                   # disc-wall links: touching (eq 43b, gap 0)
    assert to_wall.sum() == 5 + 4 and geo.link_contact[to_wall & (pores.links.min(axis=1) < 5)].all()


def test_wall_pores_of_a_hexagonal_packing_above_a_wall():
    """A hexagonal packing (spacing a, radius r < a/2) whose bottom row stands a gap g < l_m above
    the wall: the wall pores are trapezoids (here rectangles a x (r + g)) minus two quarter discs,
    A = a (r + g) - pi r^2 / 2; the lattice triangles keep sqrt(3)/4 a^2 - pi r^2 / 2."""
    a, r, g = 1.0e-3, 0.42e-3, 0.05e-3
    x = hex_lattice(7, 4, a, origin=(0.0, r + g))
    pores, geo = pores_of(x, np.full(len(x), r), flat(wall("z", 0.0, 1)), l_m=0.25 * a)
    at_wall = np.array([-1 in vs for vs in pores.vertex_sets])
    assert at_wall.sum() == 6 and pores.n_pores == 6 + 3 * 12
    np.testing.assert_allclose(geo.void_area[at_wall], a * (r + g) - np.pi * r**2 / 2, rtol=1e-12)
    np.testing.assert_allclose(geo.void_area[~at_wall], np.sqrt(3) / 4 * a**2 - np.pi * r**2 / 2, rtol=1e-11)
    disc_wall = (pores.links[:, 0] < len(x)) & (pores.links[:, 1] >= len(x))
    assert disc_wall.sum() == 7 and not geo.link_contact[disc_wall].any()   # gap g > eps_m = 0: k1 (eq 43)


def test_two_walls_close_the_corner_pore():
    """2 x 2 touching discs in the corner of a left and a bottom wall: the corner pore (disc 0 and
    both walls) is the square R x R minus a quarter disc, A = R^2 (1 - pi/4); without the left wall
    the corner is open: no pore has the left of disc 0."""
    x = np.array([[R, R], [3 * R, R], [R, 3 * R], [3 * R, 3 * R]])
    r = np.full(4, R)
    both = flat(wall("x", 0.0, 1), wall("z", 0.0, 1))
    pores, geo = pores_of(x, r, both)
    area = dict(zip(pores.vertex_sets, geo.void_area))          # walls: left -1, bottom -2
    assert set(area) == {frozenset(s) for s in ({0, -1, -2}, {0, 1, -2}, {0, 2, -1}, {0, 1, 2, 3})}
    assert area[frozenset({0, -1, -2})] == pytest.approx(R**2 * (1 - np.pi / 4), rel=1e-12)
    assert area[frozenset({0, 1, -2})] == pytest.approx(R**2 * (2 - np.pi / 2), rel=1e-12)
    assert area[frozenset({0, 1, 2, 3})] == pytest.approx(R**2 * (4 - np.pi), rel=1e-12)
    bottom_only, _ = pores_of(x, r, flat(wall("z", 0.0, 1)))
    assert sorted(map(sorted, bottom_only.vertex_sets)) == [[-1, 0, 1], [0, 1, 2, 3]]


@pytest.mark.parametrize("seed", [1, 4])
def test_pores_tile_a_box_of_four_flat_walls(seed):
    """120 random discs (radii 0.1-1 mm) in a box of four flat walls 1 mm beyond the square they
    were dropped in, l_m = 1.5 mm (every disc near a wall is linked to it): the pore polygons tile
    the box, and the void areas are the box less the discs (every disc is wrapped by its sectors)."""
    x, r = non_overlapping_discs(seed)
    lo, hi = -1e-3, 1.2e-2 + 1e-3
    walls = flat(wall("x", lo, 1), wall("x", hi, -1), wall("z", lo, 1), wall("z", hi, -1))
    pores, geo = pores_of(x, r, walls, l_m=1.5e-3)
    box = (hi - lo) ** 2
    assert len(pores.corner_wall) == 4 and not pores.surface.any()
    assert np.sum(geo.polygon_area) == pytest.approx(box, rel=1e-12)
    assert np.sum(geo.void_area) == pytest.approx(box - np.pi * np.sum(r**2), rel=1e-12)


def test_uniform_pressure_in_a_closed_box():
    """A uniform U in every pore of the closed box: zero net force on every disc (eq 33 around it
    covers its whole circle), and each wall's reaction is U x its wetted length 6 R along the inward
    normal; the corner pores are R^2 (1 - pi/4), the wall pores R^2 (2 - pi/2), the inner ones
    R^2 (4 - pi)."""
    x, r, walls = square_box()
    pores, geo = pores_of(x, r, walls)
    assert pores.n_pores == 16 and not pores.surface.any()
    corners = [vs for vs in pores.vertex_sets if sum(v < 0 for v in vs) == 2]
    assert len(corners) == 4
    expected = np.sort(R**2 * np.array([1 - np.pi / 4] * 4 + [2 - np.pi / 2] * 8 + [4 - np.pi] * 4))
    np.testing.assert_allclose(np.sort(geo.void_area), expected, rtol=1e-12)
    U = np.full(pores.n_pores, 37.0)
    F = ref.pressure_forces(pores, x, r, U, geo.corner_angle)
    assert F.shape == x.shape and np.abs(F).max() < 1e-12 * 37.0 * R
    np.testing.assert_allclose(ref.wall_water_forces(pores, x, U), 37.0 * 6 * R, rtol=1e-13)


def test_wall_reactions_of_the_model_in_a_box_at_a_uniform_pressure():
    """ReferenceModel.wall_reactions on the closed box at U = 0.02 E_w everywhere (no gravity, the
    discs just touching: no contact force): normal = water = U x 6 R on each wall, and the discs stay."""
    x, r, _ = square_box()
    tables = box_tables(("undrained",) * 4, g=0.0)
    model = ref.ReferenceModel(tables, Packing(x, r, np.zeros(len(r), int), np.ones(len(r))))
    model.water.W = model.water.W / 0.98              # eq 32: U = 0.02 E_w
    model.step()
    normal, water = model.wall_reactions()
    U = 0.02 * model.water.E_w
    np.testing.assert_allclose(water, U * 6 * R, rtol=1e-12)
    np.testing.assert_allclose(normal, water, rtol=1e-9)        # contacts at zero overlap (to round-off)
    assert np.abs(model.F_pressure).max() < 1e-12 * U * R and np.abs(model.x - x).max() < 1e-15


def test_contact_reaction_of_a_disc_pressed_into_a_flat_wall():
    """A disc at rest pressed by delta into the wall z = 0 (spring a): the wall's normal reaction is
    kn delta along +z, equal to the contact force on the disc; no water."""
    delta = 1e-7
    s = make_scene(contact={"spring": "a", "eta_n": 0.0}).as_dict()
    s["walls"] = {"flat": [wall("z", 0.0, 1)]}
    model = ref.ReferenceModel(s, Packing(np.array([[0.0, R - delta]]), np.full(1, R), np.zeros(1, int), np.ones(1)))
    model.step()
    normal, water = model.wall_reactions()
    kn = s["contact"]["kn"]
    assert normal[0] == pytest.approx(kn * delta, rel=1e-9) and water[0] == 0
    assert model.v[0, 1] == pytest.approx(kn * delta / model.mass[0] * model.dt, rel=1e-9)


# -- boundary conditions ----------------------------------------------------------------------------
def box_tables(boundaries, g=0.0, **water):
    s = make_scene(material={"g": g}, water={"enabled": True, "E_w": 1000.0, "k1": 50.0, "k2": 0.5, "k3": 7.0,
                                             "q_w": 0.0, **water}).as_dict()
    side = 6 * R
    s["walls"] = {"flat": [wall("x", 0.0, 1, boundaries[0]), wall("x", side, -1, boundaries[1]),
                           wall("z", 0.0, 1, boundaries[2]), wall("z", side, -1, boundaries[3])]}
    return s


def water_in_box(boundaries, **water):
    x, r, walls = square_box(boundaries)
    pores, geo = pores_of(x, r, walls)
    s = ref.read_settings(box_tables(boundaries, **water))
    return pores, geo, ref.Water(pores, geo.void_area, s, np.float64)


def test_undrained_walls_pass_no_water():
    """All walls undrained, the box closed: water moves only between pores and its total is kept
    to round-off, though the corner pore loses water to its neighbours."""
    pores, geo, w = water_in_box(("undrained",) * 4, k2=50.0)   # every link touches: k2
    corner = pores.vertex_sets.index(frozenset({0, -1, -3}))
    w.W[corner] *= 1.05
    total = w.total()
    for _ in range(50):
        w.advance(1e-4, geo.void_area, geo.link_contact)
    assert w.W[corner] < 1.04 * geo.void_area[corner]
    assert abs(w.total() - total) <= 50 * 4e-16 * total
    assert w.inflow == w.side_out == w.surface_out == 0


def test_drained_wall_drains_with_k3_and_inflow_wall_receives_q_w():
    """One step h from W = A except in the bottom-left corner pore (U_c = E_w (W - A)/W): with the
    left wall drained the total falls by exactly h k3 W_c U_c / E_w (its pores other than the corner
    are at U = 0); with the top wall an inflow wall it rises by q_w h for each of its 4 pores
    (2 corners, 2 wall pores)."""
    h = 1e-4
    pores, geo, w = water_in_box(("drained", "undrained", "undrained", "undrained"))
    assert pores.wall_drained.sum() == 4 and not pores.wall_inflow.any()
    corner = pores.vertex_sets.index(frozenset({0, -1, -3}))
    w.W[corner] *= 1.05
    W_c, total = w.W[corner], w.total()
    U_c = ref.pore_pressure(W_c, geo.void_area[corner], w.E_w)
    w.advance(h, geo.void_area, geo.link_contact)
    assert total - w.total() == pytest.approx(h * w.k3 * W_c * U_c / w.E_w, rel=1e-9)
    assert w.side_out == pytest.approx(h * w.k3 * W_c * U_c / w.E_w, rel=1e-12)

    pores, geo, w = water_in_box(("undrained", "undrained", "undrained", "inflow"), q_w=3e-7)
    assert pores.wall_inflow.sum() == 4 and not pores.wall_drained.any()
    total = w.total()
    w.advance(h, geo.void_area, geo.link_contact)
    assert w.total() - total == pytest.approx(4 * 3e-7 * h, rel=1e-9)
    assert w.inflow == pytest.approx(4 * 3e-7 * h, rel=1e-14)


def test_water_budget_of_a_run_with_a_drained_and_an_inflow_flat_wall():
    """Jittered discs settling under gravity in a box of flat walls, left drained, bottom inflow,
    right undrained, open at the top, pores rebuilt twice: the total water equals initial + inflow -
    outflows (drained wall and surface) + re-meshing change to round-off."""
    rng = np.random.default_rng(3)
    x = hex_lattice(7, 6, 2 * R, origin=(R, R))
    r = R * (0.85 + 0.1 * rng.random(len(x)))
    s = make_scene(material={"g": 100.0}, water={"enabled": True, "q_w": 5e-4, "k3": 300.0},
                   contact={"separation_adjustment": True}, numerics={"dt": 1e-6, "rebuild_interval": 100}).as_dict()
    s["walls"] = {"flat": [wall("x", 0.0, 1, "drained"), wall("x", x[:, 0].max() + R, -1),
                           wall("z", 0.0, 1, "inflow")]}
    model = ref.ReferenceModel(s, Packing(x, r, np.zeros(len(r), int), np.ones(len(r))))
    assert model.pores.wall_drained.any() and model.pores.wall_inflow.any() and len(model.pores.corner_wall) == 2
    w = model.water
    w.W *= 1.001                                            # U ~ E_w / 1000: the drained wall drains at once
    w.initial = w.total()
    for _ in range(300):
        model.step()
    assert model.counts["rebuilds"] == 2 and np.abs(model.x - x).max() > 1e-3 * R
    assert w.inflow > 0 and w.side_out > 0
    assert abs(w.total() - w.initial) > 1e-4 * w.initial    # the budget terms are not negligible
    assert w.balance_error() < 1e-13


# -- re-meshing and contact -------------------------------------------------------------------------
def test_a_link_to_the_wall_lost_at_a_rebuild_merges_two_wall_pores_by_rule_b():
    """Disc 2 of a row on the wall rises beyond l_m: its two wall pores {1, 2, wall}, {2, 3, wall}
    become one pore {1, 2, 3, wall}, which contains both: rule (b), the mean of their U; the other
    wall pores keep theirs by rule (a)."""
    x = np.array([[2 * R * k, R] for k in range(5)])
    r = np.full(5, R)
    walls = flat(wall("z", 0.0, 1))
    old, _ = pores_of(x, r, walls)
    U_old = np.array([10.0, 20.0, 40.0, 80.0])
    lifted = x.copy()
    lifted[2, 1] += 0.2 * R                                  # gap 0.2 R > l_m = 0.1 R; still linked to 1 and 3
    new, _ = pores_of(lifted, r, walls)
    assert frozenset({1, 2, 3, -1}) in new.vertex_sets and new.n_pores == 3
    U, rule = ref.inherit_pressures(old, U_old, np.ones(4, bool), new)
    got = {vs: (u, k) for vs, u, k in zip(new.vertex_sets, U, rule)}
    assert got[frozenset({1, 2, 3, -1})] == (30.0, "b")
    assert got[frozenset({0, 1, -1})] == (10.0, "a") and got[frozenset({3, 4, -1})] == (80.0, "a")


def bounce(flat_wall, adjust, eta=2.0, v0=0.1):
    """A free disc moving at -v0 along x onto a flat wall x = 0 or onto a fixed wall disc whose face
    is at x = 0 (centre -R), starting 1e-9 m away; stepped until it has left it."""
    s = make_scene(contact={"spring": "a", "eta_n": eta, "separation_adjustment": adjust}).as_dict()
    if flat_wall:
        s["walls"] = {"flat": [wall("x", 0.0, 1)]}
        pk = Packing(np.array([[R + 1e-9, 0.0]]), np.full(1, R), np.zeros(1, int), np.ones(1))
    else:
        pk = Packing(np.array([[-R, 0.0], [R + 1e-9, 0.0]]), np.full(2, R), np.array([ref.LEFT, 0]), np.ones(2))
    model = ref.ReferenceModel(s, pk)
    model.v[-1, 0] = -v0
    touched = False
    for _ in range(100000):
        model.step()
        contacts = model.wall_contact.in_contact if flat_wall else model.contact.in_contact
        touched |= bool(contacts.any())
        if touched and not contacts.any():
            return model.v[-1], model.x[-1]
    raise AssertionError("no bounce")


@pytest.mark.parametrize("adjust", [False, True])
def test_a_flat_wall_is_a_fixed_wall_disc_of_infinite_radius(adjust):
    """The bounce on a flat wall equals the bounce on a fixed wall disc (the same law, eq 1-13, 18-24;
    the overlaps differ by round-off only); with the separation adjustment it leaves at e v0 (eq 19)."""
    v_flat, x_flat = bounce(True, adjust)
    v_disc, x_disc = bounce(False, adjust)
    np.testing.assert_allclose(v_flat, v_disc, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(x_flat, x_disc, rtol=1e-12, atol=1e-15)
    e = make_scene().contact.restitution
    assert v_flat[0] > 0 and (not adjust or v_flat[0] == pytest.approx(e * 0.1, rel=1e-9))


def test_flat_walls_refuse_what_they_are_not():
    with pytest.raises(ValueError, match="exactly the keys"):
        flat({**wall("z", 0.0, 1), "velocity": 0.1})
    with pytest.raises(ValueError, match="moves true"):
        flat({**wall("z", 0.0, 1), "moves": 1})
    with pytest.raises(ValueError, match="axis"):
        flat(wall("y", 0.0, 1))
    with pytest.raises(ValueError, match="same way"):
        flat(wall("z", 0.0, 1), wall("z", -1.0, 1))
    with pytest.raises(ValueError, match="beyond the face"):
        ref.build_pores(np.array([[0.0, -R], [2 * R, R], [4 * R, R]]), np.full(3, R), np.zeros(3, int), 0.0, 0.1 * R,
                        flat(wall("z", 0.0, 1)))


def test_a_disc_touching_a_flat_wall_is_not_free():
    """Disc 0 lies on the wall z = 0 (gap 0: touching); disc 1, just clear of the wall, hits it
    along x and rebounds. Disc 0 still touches the wall when they part, so it is not free: disc 1
    alone is adjusted, pattern (a) of eq 22-23, not the pair by pattern (d) (eq 24)."""
    s = make_scene(contact={"spring": "a", "separation_adjustment": True}).as_dict()
    s["walls"] = {"flat": [wall("z", 0.0, 1)]}
    model = ref.ReferenceModel(s, Packing(np.array([[0.0, R], [2 * R + 1e-9, R + 1e-8]]), np.full(2, R),
                                          np.zeros(2, int), np.ones(2)))
    model.v[1, 0] = -0.1
    touched = False
    while not (touched and not model.contact.in_contact.any()):
        model.step()
        touched |= bool(model.contact.in_contact.any())
    assert model.wall_contact.in_contact[0] and model.counts["separation"] == {"a": 1, "b": 0, "c": 0, "d": 0}
