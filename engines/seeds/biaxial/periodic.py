"""Wall-less periodic packing of seed 003 (Murakami et al. §2(1), eq 1; SPEC §4).

Discs are placed at random in a rectangle, then the rectangle and every centre are scaled by
L′/L each step (eq 1) until the mean stresses σx and σz equal σ3 within 1 %. No walls: a disc
across an edge meets the discs near the opposite edge through its periodic image. The packed
block tiles the plane, so larger ground models are copies of it side by side (``tile``).

In YADE this is the periodic cell (``O.periodic``): the cell's velocity gradient ``velGrad``
with ``homoDeform`` scales the cell and carries every centre with the same affine field, which
is eq 1 in rate form, x′ = x (1 + ε̇ Δt); the collider finds the image contacts. Where it differs
from the paper: (1) the affine motion enters through the velocities, so the contact dashpots see
it as a relative velocity (in the paper it is an imposed displacement increment; at the rates
used the two are the same to first order in ε̇ Δt); (2) σx, σz are the Love averages over all
contacts of the cell instead of the forces across one section line (equal in static
equilibrium; the tests compare the two);
(3) the paper does not say how L′/L is chosen: each direction is servoed on its own stress
error with a rate (σ3 − σ)/(K τ), K the assembly's modulus estimated from its number of
contacts (a PeriTriaxController written for 2D): fast while the discs are apart, slow once they
carry load; it stops when both stresses are within the tolerance and the assembly is at rest.
The shear stress σxz is not controlled (in the paper neither); it is recorded in the block's info.
"""
import json
import math
import os
from dataclasses import asdict, dataclass

import numpy as np

from engines import files
from packing.packing import Packing

TABLE1_RADII = (1.4e-3, 2.8e-3, 3.2e-3)  # m
TABLE1_RATIO = (6.48, 2.30, 1.0)         # number ratio N1 : N2 : N3


def table1_radii(n, radii=TABLE1_RADII, ratio=TABLE1_RATIO):
    """n radii [m] in Table 1's number ratio (largest-remainder rounding), sorted large first."""
    if n < len(radii):
        raise ValueError(f"n_discs must be >= {len(radii)}, got {n}")
    share = n * np.asarray(ratio, float) / np.sum(ratio)
    counts = np.floor(share).astype(int)
    counts[np.argsort(share - counts)[::-1][: n - counts.sum()]] += 1
    return np.repeat(np.asarray(radii, float), counts)[::-1].copy()


def random_placement(r, cell, rng, max_tries=100000):
    """Centres (n, 2) [m] of discs r placed at random, without overlap, in the periodic cell
    (Lx, Lz), largest first (random sequential addition)."""
    r, cell = np.asarray(r, float), np.asarray(cell, float)
    xz = np.zeros((len(r), 2))
    done = []
    for i in np.argsort(-r, kind="stable"):
        for _ in range(max_tries):
            xz[i] = rng.random(2) * cell
            d = xz[done] - xz[i]
            d -= np.round(d / cell) * cell
            if np.all(np.hypot(d[:, 0], d[:, 1]) > r[done] + r[i]):
                done.append(i)
                break
        else:
            raise ValueError(f"random placement: no room for disc {i} after {max_tries} tries "
                             "(lower the initial solid fraction)")
    return xz


@dataclass
class PeriodicBlock:
    """A packed periodic block.

    Attributes:
        xz: centres (n, 2) [m], wrapped into the cell [0, Lx) × [0, Lz).
        r: radii (n,) [m].
        cell: (Lx, Lz) [m].
        sigma: (σx, σz) reached [Pa], compression positive.
        info: how it was made (target, contact constants, steps, seed, ...).
    """

    xz: np.ndarray
    r: np.ndarray
    cell: tuple
    sigma: tuple
    info: dict

    @property
    def solid_fraction(self):
        return float(np.sum(np.pi * self.r ** 2) / (self.cell[0] * self.cell[1]))

    def save(self, path):
        """CSV of x, z, r beside a JSON of cell, sigma and info (``path`` without extension)."""
        os.makedirs(os.path.dirname(os.path.abspath(path)) or ".", exist_ok=True)
        with files.saved(path + ".csv") as tmp:
            np.savetxt(tmp, np.column_stack([self.xz, self.r]), delimiter=",", header="x_m,z_m,r_m",
                       comments="", fmt="%.15e")
        files.write_json(path + ".json", {"cell_m": list(self.cell), "sigma_pa": list(self.sigma), "info": self.info})

    @classmethod
    def load(cls, path):
        d = np.loadtxt(path + ".csv", delimiter=",", skiprows=1, ndmin=2)
        with open(path + ".json") as f:
            meta = json.load(f)
        return cls(d[:, :2], d[:, 2], tuple(meta["cell_m"]), tuple(meta["sigma_pa"]), meta["info"])


def tile(block, nx, nz, origin=(0.0, 0.0)):
    """Ground model of nx × nz copies of a periodic block side by side (§2(1): the block as a
    unit). Discs crossing an inner seam overlap their neighbours in the next copy exactly as
    they overlapped the images in the cell, so the seams are invisible. Returns a Packing (all
    group 0, density factor 1) for a pore-water scene; its outer edges are the block's ragged
    periodic edges (a scene adds its own walls)."""
    if not (isinstance(nx, int) and isinstance(nz, int) and nx >= 1 and nz >= 1):
        raise ValueError(f"tile: nx and nz must be integers >= 1, got {nx}, {nz}")
    lx, lz = block.cell
    i, j = np.meshgrid(np.arange(nx), np.arange(nz), indexing="ij")
    shifts = np.column_stack([i.ravel() * lx, j.ravel() * lz])
    xz = (block.xz[None, :, :] + shifts[:, None, :]).reshape(-1, 2) + np.asarray(origin, float)
    r = np.tile(block.r, len(shifts))
    return Packing(xz, r, np.zeros(len(r), np.int64), np.ones(len(r)))


PACKING_PHI_E = 0.5  # deg: φe while packing (friction nearly off), the same for every test φe (docs/BIAXIAL.md)


# ---- YADE: the packing itself ---------------------------------------------------------------

@dataclass(frozen=True)
class PackingSettings:
    """How the cell is shrunk (all rates are true strain rates, shrinking > 0).

    Attributes:
        tolerance: relative stress tolerance (the paper: 1 %).
        initial_fraction: solid fraction of the random placement [-].
        aspect: Lz / Lx of the cell [-].
        dt: time step [s] (the paper: 0.5e-4).
        servo_time: time constant τ of the stress servo [s]: ε̇ = (σ3 − σ)/(K τ) in each
            direction, K the assembly's modulus estimated from its contacts (``affine_modulus``).
        max_rate: cap of |ε̇| [1/s] (the rate while the discs are still apart).
        unbalanced: the assembly is at rest when YADE's unbalanced force ratio is below this.
        check_every: steps between servo updates.
        max_time: simulated time limit [s]; reaching it is an error.
    """

    tolerance: float = 0.01
    initial_fraction: float = 0.5
    aspect: float = 1.0
    dt: float = 5e-5
    servo_time: float = 0.01
    max_rate: float = 1.0
    unbalanced: float = 0.01
    check_every: int = 10
    max_time: float = 10.0

    def __post_init__(self):
        if not 0 < self.tolerance < 1:
            raise ValueError(f"tolerance must be in (0, 1), got {self.tolerance}")
        if not 0 < self.initial_fraction < 0.7:
            raise ValueError(f"initial_fraction must be in (0, 0.7), got {self.initial_fraction}")
        if not self.aspect > 0:
            raise ValueError(f"aspect must be > 0, got {self.aspect}")


def cell_for(r, fraction, aspect):
    """(Lx, Lz) [m] of a cell holding discs r at a solid fraction, Lz = aspect Lx."""
    lx = math.sqrt(float(np.sum(np.pi * np.asarray(r) ** 2)) / fraction / aspect)
    return lx, aspect * lx


def affine_modulus(coordination, r, k_contact, area):
    """Modulus dσxx/dεxx [Pa] of an isotropic assembly strained affinely: (1/A) Σ k l² n_x⁴ over
    its Z N / 2 contacts, with ⟨n_x⁴⟩ = 3/8, l = 2 r̄ and k the typical contact stiffness [N/m²].
    An upper bound of the true modulus; small while the discs are apart, so the servo shrinks
    fast then and slows down as contacts form. Z floored at 0.1."""
    n_contacts = max(coordination, 0.1) * len(r) / 2
    return n_contacts * k_contact * (2 * float(np.mean(r))) ** 2 * 3 / 8 / area


def yade_cell_stress(depth, shear=False):
    """(σxx, σzz) [Pa] of the periodic cell, compression positive (and σxz if ``shear``): YADE's
    Love stress (over the 3D cell volume) times the cell's y depth (our forces are per unit
    thickness)."""
    from yade import utils
    s = utils.getStress()
    normal = (-float(s[0, 0]) * depth, -float(s[2, 2]) * depth)
    return (*normal, -0.5 * float(s[0, 2] + s[2, 0]) * depth) if shear else normal


def servo_rates(r, contact, settings):
    """The cell's stress servo (eq 1 in rate form, each direction on its own stress error):
    a function of (target [Pa], stresses (σ, ...) [Pa]) giving the shrinking rates [1/s]
    (σ3 − σ)/(K τ), K = affine_modulus of the current contacts, capped at settings.max_rate."""
    from yade import O, utils

    from engines.seeds.biaxial.cem_contact import pair_constants

    r = np.asarray(r, float)
    k_median = float(pair_constants(np.median(r), np.median(r), contact)[0])

    def rates(target, sigmas):
        h = O.cell.hSize
        modulus = affine_modulus(utils.avgNumInteractions(), r, k_median, float(h[0, 0] * h[2, 2]))
        return [float(np.clip((target - sig) / (modulus * settings.servo_time), -settings.max_rate, settings.max_rate))
                for sig in sigmas]
    return rates


def rest_servo(rates, depth, tolerance, unbalanced, state):
    """A PyRunner callback servoing both directions of the cell on state["target"] [Pa] with
    ``rates`` (servo_rates) until σx, σz are within ``tolerance`` of it and the unbalanced-force
    ratio is below ``unbalanced``: then the cell stops, state["done"] is set and YADE pauses.
    state["sigma"] holds the last (σx, σz)."""
    from yade import O, utils
    from yade.minieigenHP import Matrix3

    def servo():
        target = state["target"]
        sx, sz = state["sigma"] = yade_cell_stress(depth)
        r = rates(target, (sx, sz))
        if max(abs(sx - target), abs(sz - target)) < tolerance * target and utils.unbalancedForce() < unbalanced:
            state["done"] = True
            r = (0.0, 0.0)
            O.pause()
        O.cell.velGrad = Matrix3(-r[0], 0, 0, 0, 0, 0, 0, 0, -r[1])
    return servo


def run_to_rest(state, seconds, dt, what):
    """Run YADE up to ``seconds`` [s] of steps dt until the ``rest_servo`` of ``state`` is done;
    returns its (sigma_x, sigma_z) [Pa]. RuntimeError naming ``what``, the stresses, the
    unbalanced-force ratio and dt when it is not."""
    from yade import O, utils
    O.run(int(seconds / dt), True)
    sx, sz = state["sigma"]
    if not state["done"]:
        raise RuntimeError(f"{what}: not at rest within {seconds} s (dt = {dt:g} s): sigma_x = {sx:.2f}, "
                           f"sigma_z = {sz:.2f} Pa, unbalanced force ratio {utils.unbalancedForce():.3g}")
    return sx, sz


def pack_periodic(r, contact, sigma3, settings, rng, log=None):
    """Pack discs r (radii [m]) in a periodic cell with YADE (resets the YADE scene) to each
    confining stress of ``sigma3`` [Pa] in turn, lowest first: one random placement, shrunk to
    the first target, then servoed on to the next (the same initial arrangement for all, as the
    paper's §3(3)c asks). Returns the PeriodicBlocks in the order of ``sigma3``.

    ``contact``: engines.seeds.biaxial.cem_contact.CemContact; ``settings``: PackingSettings; ``rng``: numpy
    Generator for the placement. Raises RuntimeError if a target is not reached within
    ``settings.max_time`` (simulated seconds per target).
    """
    from yade import O

    from engines.seeds.biaxial.cem_contact import add_discs, check_dt, py_runner, yade_engines

    s = settings
    r = np.asarray(r, float)
    targets = [float(v) for v in np.atleast_1d(sigma3)]
    if not all(math.isfinite(v) and v > 0 for v in targets):
        raise ValueError(f"sigma3 must be > 0 Pa, got {targets}")
    check_dt(s.dt, r, contact)
    cell = cell_for(r, s.initial_fraction, s.aspect)
    xz = random_placement(r, cell, rng)
    depth = 10 * float(r.max())  # cell y size: no disc meets its own y-image (collider: bounds < depth / 2)
    O.reset()
    O.periodic = True
    O.cell.setBox(cell[0], depth, cell[1])
    add_discs(xz, r, contact, y=depth / 2)
    state = {"sigma": (0.0, 0.0), "target": None, "done": False}
    O.engines = yade_engines([py_runner(rest_servo(servo_rates(r, contact, s), depth, s.tolerance, s.unbalanced, state),
                                        s.check_every)])
    O.dt = s.dt
    blocks = {}
    for target in sorted(set(targets)):
        state.update(target=target, done=False)
        start = O.iter
        sx, sz = run_to_rest(state, s.max_time, s.dt, f"periodic packing at sigma3 = {target:g} Pa")
        h = O.cell.hSize
        lx, lz = float(h[0, 0]), float(h[2, 2])
        pos = np.mod([[b.state.pos[0], b.state.pos[2]] for b in O.bodies], [lx, lz])
        info = {"sigma3_pa": target, "sigma_xz_pa": yade_cell_stress(depth, shear=True)[2], "steps": O.iter - start,
                "time_s": O.time, "contact": asdict(contact), "settings": asdict(s), "depth_m": depth}
        blocks[target] = PeriodicBlock(pos, r.copy(), (lx, lz), (sx, sz), info)
        if log:
            log(f"packed {len(r)} discs to sigma3 = {target:g} Pa: sigma_x = {sx:.2f}, sigma_z = {sz:.2f} Pa "
                f"after {O.iter - start} steps, solid fraction {blocks[target].solid_fraction:.4f}")
    return [blocks[t] for t in targets]


# ---- YADE: the biaxial test on the cell itself ----------------------------------------------

TEST_SERVO_TIME = 1e-3  # s: τ of the σx servo in the test; the error it leaves is ≈ ε̇ K τ (K <= the
                        # affine modulus), 1 % of σ3 = 100 Pa at 100 %/min; the servo updates every
                        # 10 steps with a loop gain <= 10 dt / τ = 0.5 at dt = 5e-5 s


def run_periodic_biaxial(block, contact, settings, log=None):
    """The biaxial test on the periodic cell itself: no bands ②–⑤ and no side loads, σ3 is the
    cell's own stress. The block is rebuilt in its cell (contacts rebuilt, as for the specimen
    taken out of it), both directions are servoed on σ3 (``servo_rates``) until σx, σz are within
    settings.tolerance and the unbalanced-force ratio is below settings.unbalanced (the
    preliminary equilibrium), then z shrinks at the strain rate (reached linearly over
    settings.ramp_time) while x stays servoed on σ3 (τ = TEST_SERVO_TIME). Records: σ1 = σz, the axial strain
    1 − Lz/Lz0, sigma3_applied = σx, lateral strain −(Lx/Lx0 − 1). A specimen.BiaxialResult;
    RuntimeError if the equilibrium is not reached within settings.max_equilibrium_time."""
    import time

    from yade import O

    from engines.seeds.biaxial.specimen import BiaxialResult, Curve

    t0 = time.time()
    s = settings
    eq, pack = _periodic_rest(block, contact, s, log)
    a = _periodic_compression(block, contact, s, pack)
    curve = Curve(s.sigma3, a["strain"], a["sigma1"], a["sigma1"], a["sigma3_applied"], a["lateral_strain"])
    res = BiaxialResult(curve, s, eq, O.iter, time.time() - t0)
    if log:
        log(res.describe())
    return res


def _periodic_rest(block, contact, s, log):
    """The block rebuilt in its periodic cell and servoed on σ3 in both directions to rest
    (run_periodic_biaxial); returns (the equilibrium's record, the servo's PackingSettings)."""
    from yade import O, utils

    from engines.seeds.biaxial.cem_contact import add_discs, check_dt, py_runner, yade_engines

    check_dt(s.dt, block.r, contact)
    depth = block.info["depth_m"]
    O.reset()
    O.periodic = True
    O.cell.setBox(block.cell[0], depth, block.cell[1])
    add_discs(block.xz, block.r, contact, y=depth / 2)
    pack = PackingSettings(dt=s.dt)
    st = {"done": False, "sigma": (0.0, 0.0), "target": s.sigma3}
    O.engines = yade_engines([py_runner(rest_servo(servo_rates(block.r, contact, pack), depth, s.tolerance,
                                                   s.unbalanced, st), pack.check_every)])
    O.dt = s.dt
    sx, sz = run_to_rest(st, s.max_equilibrium_time, s.dt,
                         f"periodic equilibrium at sigma3 = {s.sigma3:g} Pa (at rest below {s.unbalanced})")
    eq = {"sigma1_pa": sz, "sigma1_bottom_pa": sz, "sigma3_applied_pa": sx, "unbalanced": utils.unbalancedForce(),
          "moves": 0, "steps": O.iter, "time_s": O.time}
    if log:
        log(f"  sigma3 = {s.sigma3:g} Pa: periodic equilibrium sigma_x = {sx:.2f}, sigma_z = {sz:.2f} Pa after {O.iter} steps")
    return eq, pack


def _periodic_compression(block, contact, s, pack):
    """The test from rest (run_periodic_biaxial): z shrinks at the strain rate (ramped), x servoed
    on σ3; returns the records {strain, sigma1, sigma3_applied, lateral_strain} as arrays."""
    from yade import O
    from yade.minieigenHP import Matrix3

    from engines.seeds.biaxial.cem_contact import py_runner, yade_engines

    depth = block.info["depth_m"]
    rec = {k: [] for k in ("strain", "sigma1", "sigma3_applied", "lateral_strain")}
    size = lambda: (float(O.cell.hSize[0, 0]), float(O.cell.hSize[2, 2]))  # noqa: E731
    lx0, lz0 = size()
    t_start = O.time

    fast = servo_rates(block.r, contact, PackingSettings(dt=s.dt, servo_time=TEST_SERVO_TIME))

    def control():
        sx, sz = yade_cell_stress(depth)
        rx = fast(s.sigma3, (sx,))[0]
        rz = s.strain_rate * min(1.0, (O.time - t_start) / s.ramp_time)
        O.cell.velGrad = Matrix3(-rx, 0, 0, 0, 0, 0, 0, 0, -rz)

    def record():
        lx, lz = size()
        sx, sz = yade_cell_stress(depth)
        for k, v in zip(rec, (1 - lz / lz0, sz, sx, -(lx / lx0 - 1))):
            rec[k].append(v)
        if rec["strain"][-1] >= s.max_strain:
            O.pause()

    every = max(1, int(round(s.record_strain / (s.strain_rate * s.dt))))
    record()
    O.engines = yade_engines([py_runner(control, pack.check_every), py_runner(record, every)])
    O.run(int(1.5 * s.max_strain / s.strain_rate / s.dt) + every + int(s.ramp_time / s.dt), True)
    O.cell.velGrad = Matrix3(0, 0, 0, 0, 0, 0, 0, 0, 0)
    return {k: np.array(v) for k, v in rec.items()}
