"""Saito & Fujiwara particle-potential model (seed 002): kernels, equilibrium, reactions, yield."""
import numpy as np
import pytest

from engines.seeds.particle_potential import specimen
from engines.seeds.particle_potential.model import (
    TONNE_FORCE,
    Kind,
    Model,
    Potential,
    SolverSettings,
    energy_gradient,
    find_pairs,
    free_dofs,
    pa_to_tf_m2,
    pair_energy,
    pair_force,
    pair_stiffness_at_well,
    reactions,
    tf_m2_to_pa,
    total_energy,
)

POT = Potential(A_m=TONNE_FORCE, alpha=1.0, C=2.0, DL=1.8)


def small_model(pot=POT):
    """3 × 4 lattice with every kind of particle, one column on a symmetry axis."""
    x, z = np.meshgrid(np.arange(3.0), np.arange(4.0))
    ref = np.column_stack([x.ravel(), z.ravel()])
    kinds = np.full(len(ref), Kind.FREE)
    kinds[[0, 1]] = Kind.FIXED
    kinds[2] = Kind.MOVING
    kinds[[5, 8, 11]] = Kind.Z_ONLY
    kinds[3] = Kind.X_ONLY
    return Model(ref, kinds, pot)


def test_pair_force_is_minus_derivative_of_energy():
    l = np.linspace(0.6, 1.79, 50)
    h = 1e-6
    fd = -(pair_energy(l + h, POT) - pair_energy(l - h, POT)) / (2 * h)
    assert np.allclose(pair_force(l, POT), fd, rtol=1e-6, atol=1e-6 * TONNE_FORCE)


@pytest.mark.parametrize("alpha", [1.0, 2.0])
def test_lattice_distances_are_well_bottoms(alpha):
    """With C = 2 and integer α, α l² is an integer at l = 1 and √2 (the neighbours inside
    DL = 1.8), so u = 0 and f = 0 there: the initial lattice is a stress-free global minimum
    (u >= 0 everywhere), as condition ③ of §2.3 asks. Non-integer α would prestress it."""
    pot = Potential(A_m=TONNE_FORCE, alpha=alpha, C=2.0, DL=1.8)
    l = np.array([1.0, np.sqrt(2.0)])
    assert np.allclose(pair_energy(l, pot), 0.0, atol=1e-12 * TONNE_FORCE)
    assert np.allclose(pair_force(l, pot), 0.0, atol=1e-12 * TONNE_FORCE)
    assert pair_force(1.05, pot) < 0 < pair_force(0.95, pot)  # restoring on both sides
    assert pair_energy(np.linspace(0.5, 1.79, 200), pot).min() >= 0
    assert np.isclose(pair_stiffness_at_well(1.0, pot), 16 * np.pi ** 2 * alpha ** 2 * TONNE_FORCE)


def test_initial_specimen_is_unloaded_equilibrium():
    spec = specimen.build_specimen(POT, moving_top=False)
    ref = spec.model.reference
    pairs = find_pairs(ref, spec.model)
    zero = np.zeros_like(ref)
    assert total_energy(ref, zero, spec.model.free, pairs, POT) == pytest.approx(0.0, abs=1e-9)
    assert np.abs(energy_gradient(ref, zero, pairs, POT)).max() < 1e-9
    assert np.abs(reactions(ref, spec.model.free, pairs, POT)).max() < 1e-9


def test_specimen_counts_match_paper_figure_5():
    kinds = specimen.build_specimen(POT, moving_top=False).model.kinds
    assert [np.sum(kinds == k) for k in (Kind.FREE, Kind.Z_ONLY, Kind.FIXED)] == [36, 12, 4]
    kinds = specimen.build_specimen(POT, moving_top=True).model.kinds
    assert np.sum(kinds == Kind.MOVING) == 4


def test_gradient_matches_central_differences():
    model = small_model()
    rng = np.random.default_rng(2)
    pos = model.reference + rng.normal(scale=0.08, size=model.reference.shape)
    forces = rng.normal(scale=0.3 * TONNE_FORCE, size=pos.shape)
    free = model.free
    pairs = find_pairs(pos, model)
    grad = energy_gradient(pos, forces, pairs, POT)
    h = 1e-6
    for i, d in zip(*np.nonzero(free)):
        plus, minus = pos.copy(), pos.copy()
        plus[i, d] += h
        minus[i, d] -= h
        fd = (total_energy(plus, forces, free, pairs, POT) - total_energy(minus, forces, free, pairs, POT)) / (2 * h)
        assert grad[i, d] == pytest.approx(fd, rel=1e-5, abs=1e-4)


def test_free_dofs_by_kind():
    mask = free_dofs([Kind.FREE, Kind.X_ONLY, Kind.Z_ONLY, Kind.MOVING, Kind.FIXED])
    assert mask.tolist() == [[True, True], [True, False], [False, True], [False, False], [False, False]]


def test_reactions_balance_applied_top_load():
    spec = specimen.build_specimen(POT, moving_top=False)
    path = specimen.load_path(spec, tf_m2_to_pa(specimen.ramp(10.0, 0.5)), SolverSettings())
    assert not path.yielded
    final = path.increments[-1]
    applied = -final.forces[:, 1].sum()
    assert applied == pytest.approx(tf_m2_to_pa(10.0) * 3.0)
    assert final.reactions[:, 1].sum() == pytest.approx(applied, rel=1e-6)
    assert final.reactions[spec.bottom, 1].sum() == pytest.approx(applied, rel=1e-6)


def test_apparent_modulus_scales_with_alpha_squared_and_lies_between_lattice_bounds():
    """k = u''(1) = 16 π² α² A_m; the lattice's continuum modulus is 1.5 k (free sides) to 2 k
    (no lateral strain); the clamped 12 m × 6 m specimen lies in between."""
    moduli = []
    for alpha in (1.0, 2.0):
        pot = Potential(A_m=TONNE_FORCE, alpha=alpha, C=2.0, DL=1.8)
        path = specimen.load_path(specimen.build_specimen(pot, moving_top=False), [tf_m2_to_pa(0.1)], SolverSettings())
        e = pa_to_tf_m2(path.stress[0] / path.strain[0])
        k = pa_to_tf_m2(pair_stiffness_at_well(1.0, pot))
        assert 1.5 * k < e < 2.0 * k
        moduli.append(e)
    assert moduli[1] / moduli[0] == pytest.approx(4.0, rel=1e-3)


def test_eq6_counts_every_pair_once_axis_pairs_included():
    """Eq 6 sums u over every pair j < k of the model: U of a deformed specimen equals that sum
    over all pairs closer than DL except boundary-boundary ones, computed here pair by pair."""
    spec = specimen.build_specimen(POT, moving_top=False)
    rng = np.random.default_rng(5)
    pos = spec.model.reference + rng.normal(scale=0.03, size=spec.model.reference.shape)
    pairs = find_pairs(pos, spec.model)
    boundary = spec.model.kinds >= Kind.MOVING
    expected = sum(pair_energy(np.linalg.norm(pos[b] - pos[a]), POT)
                   for a in range(len(pos)) for b in range(a + 1, len(pos))
                   if np.linalg.norm(pos[b] - pos[a]) < POT.DL and not (boundary[a] and boundary[b]))
    zero = np.zeros_like(pos)
    assert total_energy(pos, zero, spec.model.free, pairs, POT) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("alpha, paper_E", [(1.0, 300.0), (2.0, 1200.0)])
def test_apparent_modulus_against_the_paper(alpha, paper_E):
    """§4: "みかけのヤング率はほぼ 300t/m²" (α = 1) and "ほぼ 1200 t/m²" (α = 2): within 5 %."""
    pot = Potential(A_m=TONNE_FORCE, alpha=alpha, C=2.0, DL=1.8)
    path = specimen.load_path(specimen.build_specimen(pot, moving_top=False), [tf_m2_to_pa(0.25)], SolverSettings())
    E = pa_to_tf_m2(path.stress[0] / path.strain[0])
    assert E == pytest.approx(paper_E, rel=0.05)


def test_yield_against_the_paper_and_independent_of_increment_and_trust_box():
    """§4: "載荷応力 26t/m² (ヒズミにして8.5%) で降伏" (α = 1): the converged limit load within 15 % of
    26 t/m²; two searches with different first increments and trust boxes agree within the 2 % the
    search converges to."""
    spec = specimen.build_specimen(POT, moving_top=False)
    a = specimen.yield_search(spec, SolverSettings(max_step=0.05), tf_m2_to_pa(0.5), tf_m2_to_pa(60.0))
    b = specimen.yield_search(spec, SolverSettings(max_step=0.2), tf_m2_to_pa(0.25), tf_m2_to_pa(60.0))
    assert a.found and b.found
    assert pa_to_tf_m2(a.load) == pytest.approx(26.0, rel=0.15)
    assert a.load == pytest.approx(b.load, rel=0.02)
    assert a.refinements[-1][0] < 0.02 * a.load  # converged: the last increment is below 2 % of it
    assert np.all(np.diff(a.stress_path) > 0) and a.strain_path[-1] == pytest.approx(a.strain)


def test_alpha_2_does_not_yield_where_alpha_1_does():
    """§4: α = 2 "降伏点はみられない" (no yield point seen) over the range where α = 1 yields."""
    pot = Potential(A_m=TONNE_FORCE, alpha=2.0, C=2.0, DL=1.8)
    spec = specimen.build_specimen(pot, moving_top=False)
    lim = specimen.yield_search(spec, SolverSettings(), tf_m2_to_pa(1.0), tf_m2_to_pa(26.0 * 1.15))
    assert not lim.found


def test_slope_collapse_is_yield_even_when_converged():
    spec = specimen.build_specimen(POT, moving_top=True)
    path = specimen.displacement_path(spec, specimen.ramp(1.5, 0.05), SolverSettings(max_step=0.5))
    assert path.yielded
    assert path.increments[-1].yielded


@pytest.mark.parametrize("field, value", [("DL", 0.0), ("DL", -1.0), ("alpha", np.nan), ("A_m", 0.0), ("C", np.inf)])
def test_bad_potential_raises_naming_the_field(field, value):
    kwargs = dict(A_m=1.0, alpha=1.0, C=2.0, DL=1.8)
    kwargs[field] = value
    with pytest.raises(ValueError, match=field):
        Potential(**kwargs)


def test_bad_model_and_settings_raise():
    with pytest.raises(ValueError, match="spacing"):
        Model(np.zeros((2, 2)), np.zeros(2, int), POT)
    with pytest.raises(ValueError, match="reference"):
        Model(np.array([[0.0, np.nan], [1.0, 0.0]]), np.zeros(2, int), POT)
    with pytest.raises(ValueError, match="max_step"):
        SolverSettings(max_step=0.0)
