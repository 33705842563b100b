"""Saito & Fujiwara's particle-potential soil model, solved by energy minimisation (seed 002).

The soil is a set of points in the (x, z) plane (the paper's y is our z). Every pair closer
than the influence radius DL stores the potential u(l) of eq 11; loads and weights do work on
the free coordinates; the equilibrium is a local minimum of the total energy U (eq 6), found
increment by increment with a quasi-Newton minimiser started from the previous solution.

Units: SI throughout, per unit depth of the 2D model. Positions in m, the potential and the
energy in J/m (= N), pair forces and loads in N/m, reactions in N/m, stresses in Pa. The
paper works in tonne-force and metres; convert only at the edges with `tf_m2_to_pa` and
`pa_to_tf_m2` (1 tf = 9806.65 N, so A_m = 1 tf·m/m = 9806.65 J/m).

Pairs: a neighbour list built with scipy.spatial.cKDTree from the configuration at the start of
each increment (pairs with l < DL) and held fixed during that increment's minimisation. A list
fixed during the minimisation keeps U smooth (the cut-off at DL makes u jump, which would break
the line searches); rebuilding it per increment still applies the paper's rule "u and f only
for l < DL", one small increment late for a pair crossing DL.
"""
from dataclasses import dataclass
from enum import IntEnum
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import cKDTree

from engines.model.fields import COUNT, POSITIVE, check_each

TONNE_FORCE = 9806.65  # N per tonne-force
L_REF = 1.0  # m; eq 11 is written with l in metres, so u uses l / L_REF


def tf_m2_to_pa(stress):
    """Convert t/m² (tonne-force per m²) to Pa."""
    return np.asarray(stress) * TONNE_FORCE


def pa_to_tf_m2(stress):
    """Convert Pa to t/m² (tonne-force per m²)."""
    return np.asarray(stress) / TONNE_FORCE


class Kind(IntEnum):
    """Particle kinds of §2.2 (the paper's LL, LX, LY, MM, NN)."""

    FREE = 0      # x and z unknown
    X_ONLY = 1    # x unknown, z prescribed
    Z_ONLY = 2    # z unknown, x prescribed (the paper's "y-only")
    MOVING = 3    # moving boundary point: x and z prescribed, changed between increments
    FIXED = 4     # fixed boundary point


_FREE_DOFS = {Kind.FREE: (True, True), Kind.X_ONLY: (True, False), Kind.Z_ONLY: (False, True),
              Kind.MOVING: (False, False), Kind.FIXED: (False, False)}


def free_dofs(kinds):
    """(N, 2) bool mask of unknown coordinates (the vector X of eq 4) for an (N,) kind array."""
    return np.array([_FREE_DOFS[Kind(k)] for k in kinds], dtype=bool).reshape(-1, 2)


def _check_finite(name, array):
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got non-finite values in {np.asarray(array)!r}")


@dataclass(frozen=True)
class Potential:
    """Parameters of the pair potential of eq 11 (the particle attributes C_i = C_j).

    Attributes:
        A_m: amplitude [J/m], energy per unit depth (the paper's A_m = 1 is 1 tf·m/m = 9806.65 J/m).
        alpha: number of potential wells per unit of (l / 1 m)^C [-].
        C: exponent [-].
        DL: influence radius [m]; pairs with l >= DL do not interact.
    """

    A_m: float
    alpha: float
    C: float
    DL: float

    def __post_init__(self):
        check_each(self, ("A_m", "alpha", "C", "DL"), POSITIVE)


def pair_energy(l, pot):
    """u(l) of eq 11 [J/m] for pair distances l [m]."""
    r = np.asarray(l) / L_REF
    s = pot.alpha * r ** pot.C
    # eq 11, with cos 2π(s + 0.5) + 1 = 2 sin² πs: the same value, without the round-off of
    # cos ≈ -1 at the well bottoms (it limits how far the minimiser can drive the gradient)
    return pot.A_m * 2 * np.sin(np.pi * s) ** 2 / r ** pot.C


def pair_force(l, pot):
    """f(l) = -du/dl of eq 12 [N/m]; positive pushes the pair apart."""
    r = np.asarray(l) / L_REF
    s = pot.alpha * r ** pot.C
    phase = 2 * np.pi * (s + 0.5)
    return (pot.C * pot.A_m * (2 * np.pi * s * np.sin(phase) + np.cos(phase) + 1)
            / (r ** (pot.C + 1) * L_REF))  # eq 12


def pair_stiffness_at_well(l, pot):
    """u''(l) [N/m per m] at a well bottom (alpha (l/1 m)^C an integer): A_m (2π α C r^(C-1))² / r^C."""
    r = np.asarray(l) / L_REF
    return pot.A_m * (2 * np.pi * pot.alpha * pot.C * r ** (pot.C - 1)) ** 2 / r ** pot.C / L_REF ** 2


@dataclass(frozen=True)
class Model:
    """Static description of a particle system.

    Attributes:
        reference: (N, 2) initial positions (x, z) [m].
        kinds: (N,) `Kind` of every particle.
        potential: the pair potential shared by all particles.

    Every pair counts once with full weight, as in eq 6 (the paper's half specimen of §4 is such a
    model: it sums eq 6 over its own particles, pairs on the symmetry axis included).
    """

    reference: np.ndarray
    kinds: np.ndarray
    potential: Potential

    def __post_init__(self):
        _check_finite("reference", self.reference)
        n = len(self.reference)
        if np.shape(self.reference) != (n, 2) or np.shape(self.kinds) != (n,):
            raise ValueError(f"reference must be (N, 2) and kinds (N,), got shapes "
                             f"{np.shape(self.reference)}, {np.shape(self.kinds)}")
        gap, _ = cKDTree(self.reference).query(self.reference, k=2)
        if n > 1 and np.min(gap[:, 1]) <= 0:
            raise ValueError(f"reference: particle spacing must be > 0, got {np.min(gap[:, 1])!r} "
                             f"(particle {int(np.argmin(gap[:, 1]))} coincides with another)")

    @property
    def free(self):
        """(N, 2) bool mask of the unknown coordinates."""
        return free_dofs(self.kinds)


@dataclass(frozen=True)
class Pairs:
    """Interacting pairs (i < j) of eq 6."""

    i: np.ndarray
    j: np.ndarray


def find_pairs(positions, model):
    """Pairs with l < DL at `positions`, except pairs of two boundary points (§2.2: boundary
    points exert no force on each other)."""
    ij = cKDTree(positions).query_pairs(model.potential.DL, output_type="ndarray")
    i, j = ij[:, 0], ij[:, 1]
    keep = np.linalg.norm(positions[j] - positions[i], axis=1) < model.potential.DL
    boundary = model.kinds >= Kind.MOVING
    keep &= ~(boundary[i] & boundary[j])
    return Pairs(i[keep], j[keep])


def _pair_terms(positions, pairs, pot):
    """Distance l [m] and f (x_j - x_i)/l [N/m] per pair: its share of ∂U/∂x_i (eq 8)."""
    d = positions[pairs.j] - positions[pairs.i]
    l = np.linalg.norm(d, axis=1)
    return l, (pair_force(l, pot) / l)[:, None] * d


def total_energy(positions, forces, free, pairs, pot, origin=0.0):
    """Total potential energy U of eq 6 [J/m].

    Args:
        positions: (N, 2) [m]; forces: (N, 2) loads plus weights M g [N/m], doing work only on the
        free coordinates; free: (N, 2) mask; pairs: `Pairs`; pot: `Potential`;
        origin: positions (N, 2) [m] from which the work of the forces is counted. It shifts U by
            a constant only; measuring from a nearby state avoids the round-off of F·x with large x.
    """
    l = np.linalg.norm(positions[pairs.j] - positions[pairs.i], axis=1)
    work = np.sum((forces * (positions - origin))[free])
    return np.sum(pair_energy(l, pot)) - work  # eq 6


def energy_gradient(positions, forces, pairs, pot):
    """∂U/∂x for every coordinate, (N, 2) [N/m] (eq 7–8); the gradient G(X) is its free part."""
    _, share = _pair_terms(positions, pairs, pot)
    grad = np.zeros_like(positions)
    np.add.at(grad, pairs.i, share)   # eq 8: sum_j f (x_j - x_i) / l_ij
    np.add.at(grad, pairs.j, -share)
    return grad - forces              # eq 8: - M g - F


def reactions(positions, free, pairs, pot):
    """Boundary reactions BF (eq 9–10), (N, 2) [N/m], zero on the free coordinates.

    BF is the force the support applies to a prescribed coordinate; only partners free in that
    direction contribute (eq 9 sums over j free in x, eq 10 over j free in z).
    """
    _, share = _pair_terms(positions, pairs, pot)
    bf = np.zeros_like(positions)
    np.add.at(bf, pairs.i, share * free[pairs.j])    # eq 9–10
    np.add.at(bf, pairs.j, -share * free[pairs.i])
    bf[free] = 0.0
    return bf


@dataclass(frozen=True)
class SolverSettings:
    """Settings of the incremental minimisation.

    Attributes:
        max_step: trust box [m]: no coordinate may move more than this in one increment. A
            solution on the box edge means the nearby minimum was lost: reported as yield.
            Choose increments whose elastic moves stay well below it (a third or less), or
            the box, not the model, decides the yield point.
        gtol: largest allowed |∂U/∂X| at a converged state, relative to A_m / 1 m [-]. The
            minimiser aims at gtol / 100; round-off in U may stop it anywhere below gtol.
        maxiter: iteration limit of the minimiser per increment.
        softening_ratio: yield when the tangent slope dσ/dε of an increment falls below this
            fraction of the first increment's slope (slope collapse or softening) [-].
    """

    max_step: float = 0.05
    gtol: float = 1e-5
    maxiter: int = 5000
    softening_ratio: float = 0.05

    def __post_init__(self):
        check_each(self, ("max_step", "gtol", "softening_ratio"), POSITIVE)
        check_each(self, ("maxiter",), COUNT)


@dataclass
class Increment:
    """Solution of one increment.

    Attributes:
        positions: (N, 2) positions at the end of the increment [m].
        reactions: (N, 2) boundary reactions BF (eq 9–10) [N/m].
        forces: (N, 2) applied loads and weights [N/m].
        energy: total energy U (eq 6) [J/m].
        max_gradient: largest |∂U/∂X| over the free coordinates [N/m].
        max_move: largest coordinate change of the free coordinates in this increment [m].
        n_pairs: number of interacting pairs used.
        converged: the minimiser met the gradient tolerance inside the trust box.
        yielded: this increment is reported as yield (see `reason`).
        reason: why it yielded ("" when it did not).
    """

    positions: np.ndarray
    reactions: np.ndarray
    forces: np.ndarray
    energy: float
    max_gradient: float
    max_move: float
    n_pairs: int
    converged: bool
    yielded: bool = False
    reason: str = ""


def solve_increment(model, start, forces, prescribed, settings):
    """Minimise U from `start` with loads `forces` [N/m] and prescribed coordinates taken from
    `prescribed` [m] (both (N, 2)), using L-BFGS-B inside a box of ±max_step around `start`."""
    _check_finite("forces", forces)
    _check_finite("prescribed", prescribed)
    pot, free = model.potential, model.free
    pairs = find_pairs(start, model)
    positions = np.where(free, start, prescribed)
    scale = pot.A_m / L_REF   # objective in units of A_m so that gtol is relative

    def objective(x):
        positions[free] = x
        energy = total_energy(positions, forces, free, pairs, pot, origin=start)
        return energy / pot.A_m, energy_gradient(positions, forces, pairs, pot)[free] / scale

    x0 = start[free]
    bounds = np.column_stack([x0 - settings.max_step, x0 + settings.max_step])
    res = minimize(objective, x0, jac=True, method="L-BFGS-B", bounds=bounds,
                   options=dict(gtol=settings.gtol / 100, ftol=0.0, maxiter=settings.maxiter, maxcor=30))
    positions[free] = res.x
    grad = energy_gradient(positions, forces, pairs, pot)[free]
    max_move = float(np.max(np.abs(res.x - x0), initial=0.0))
    max_gradient = float(np.max(np.abs(grad), initial=0.0))
    on_box = max_move >= settings.max_step * (1 - 1e-9)
    converged = max_gradient <= settings.gtol * scale and not on_box
    reason = ""
    if on_box:
        reason = f"no nearby minimum: a coordinate reached the trust box ({settings.max_step} m)"
    elif not converged:
        reason = f"minimiser did not converge (max |dU/dX| = {max_gradient:.3g} N/m)"
    return Increment(positions=positions.copy(), reactions=reactions(positions, free, pairs, pot),
                     forces=forces, energy=total_energy(positions, forces, free, pairs, pot),
                     max_gradient=max_gradient, max_move=max_move, n_pairs=len(pairs.i),
                     converged=converged, yielded=bool(reason), reason=reason)


@dataclass(frozen=True)
class Step:
    """Targets of one increment: loads and weights `forces` [N/m] and positions `prescribed` [m]
    of the prescribed coordinates, both (N, 2)."""

    forces: np.ndarray
    prescribed: np.ndarray


@dataclass
class Path:
    """An incremental loading path, stopped at the first increment reported as yield.

    Attributes:
        increments: the solved increments; the last one is the yield increment if `yielded`.
        strain, stress: response per increment from the caller's `measure` [-], [Pa].
        yielded: the path ended in yield.
        reason: the yield reason ("" when not yielded).
    """

    increments: List[Increment]
    strain: np.ndarray
    stress: np.ndarray
    yielded: bool
    reason: str

    def last_stable(self):
        """Index of the last increment that converged and is not yield (None if there is none)."""
        return next((k for k in reversed(range(len(self.increments)))
                     if self.increments[k].converged and not self.increments[k].yielded), None)

    def peak(self):
        """(strain, stress) of the converged increment with the largest |stress|; for a yielded
        path this is the yield point. None if no increment converged."""
        ok = [k for k, inc in enumerate(self.increments) if inc.converged]
        if not ok:
            return None
        k = max(ok, key=lambda m: abs(self.stress[m]))
        return float(self.strain[k]), float(self.stress[k])


def run_path(model, steps: Sequence[Step], settings,
             measure: Callable[[Increment], Tuple[float, float]]):
    """Solve `steps` in order, each from the previous solution, until the first yield.

    `measure` maps an increment to (strain [-], stress [Pa]) of the same sign; an increment whose
    tangent slope drops below `settings.softening_ratio` times the first slope is marked as yield.
    """
    start, increments, response = model.reference, [], [(0.0, 0.0)]
    first_slope: Optional[float] = None
    for step in steps:
        inc = solve_increment(model, start, step.forces, step.prescribed, settings)
        increments.append(inc)
        if inc.yielded:
            response.append((np.nan, np.nan))
            break
        response.append(measure(inc))
        (e0, s0), (e1, s1) = response[-2], response[-1]
        slope = (s1 - s0) / (e1 - e0) if e1 != e0 else np.inf
        first_slope = slope if first_slope is None else first_slope
        if slope < settings.softening_ratio * first_slope:
            inc.yielded = True
            inc.reason = f"slope collapse: dσ/dε = {slope:.4g} Pa < {settings.softening_ratio} × initial"
            break
        start = inc.positions
    strain, stress = np.array(response[1:]).T
    last = increments[-1]
    return Path(increments, strain, stress, last.yielded, last.reason)


@dataclass
class LimitLoad:
    """Yield under load control: the largest load [Pa] with an equilibrium on the branch followed
    continuously from the unloaded state (beyond it the particles snap: the nearby minimum of U
    disappears or jumps), converged in the load increment.

    Attributes:
        found: False when no yield was met up to the search's largest load.
        load: the last stable load [Pa] (signed like the loads searched).
        strain: the caller's strain at that load [-].
        increment: the `Increment` solved at that load.
        refinements: [(load increment [Pa], last stable load [Pa])], one per halving.
        strain_path, stress_path: the stable states met on the way, in load order.
        reason: why the next increment failed.
    """

    found: bool
    load: float
    strain: float
    increment: Increment
    refinements: list
    strain_path: np.ndarray
    stress_path: np.ndarray
    reason: str


JUMP_RATIO = 2.0   # an increment whose move per unit load exceeds this x the previous one's is a snap


def limit_load(model, step_at: Callable[[float], Step], measure, settings, h0, max_load,
               rel_tol=0.02, max_halvings=10):
    """March the load by h0 [Pa] from 0 until an increment fails, then halve the increment and march
    on from the last stable state, until the last stable load moves by less than ``rel_tol`` of
    itself (and the increment is below that too).

    An increment fails when the minimiser finds no minimum inside the trust box, or when its largest
    move per unit load exceeds JUMP_RATIO x that of the increment before: on the equilibrium branch
    moves shrink with the increment, across a snap-through they do not, so the limit found depends
    neither on h0 nor on the trust box. ``step_at(load)`` gives the `Step` of a load; ``measure``
    as in `run_path`.
    """
    visited = []

    def march(state, load, h, last, rate):
        while abs(load + h) <= abs(max_load) * (1 + 1e-12):
            step = step_at(load + h)
            inc = solve_increment(model, state, step.forces, step.prescribed, settings)
            new_rate = inc.max_move / abs(h)
            if not inc.yielded and rate is not None and new_rate > JUMP_RATIO * rate:
                inc.reason = (f"snap: the move per unit load jumped {new_rate / rate:.1f}x "
                              f"(largest move {inc.max_move:.3g} m)")
            if inc.yielded or inc.reason:
                return load, state, last, rate, inc.reason
            load, state, last, rate = load + h, inc.positions, inc, new_rate
            visited.append((load, measure(inc)))
        return load, state, last, rate, ""

    h = h0
    load, state, last, rate, reason = march(model.reference, 0.0, h, None, None)
    if last is None:
        raise ValueError(f"no equilibrium at the first load increment {h0} Pa: {reason}")
    refinements = [(h, load)]
    for _ in range(max_halvings if reason else 0):
        h /= 2
        new_load, state, last, rate, reason = march(state, load, h, last, rate)
        moved, load = abs(new_load - load), new_load
        refinements.append((h, load))
        if moved < rel_tol * abs(load) and abs(h) < rel_tol * abs(load):
            break
    visited.sort(key=lambda v: abs(v[0]))
    strain, _ = measure(last)
    path = np.array([m for _, m in visited])
    return LimitLoad(bool(reason), float(load), float(strain), last, refinements,
                     path[:, 0], path[:, 1], reason)
