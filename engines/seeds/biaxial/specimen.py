"""The biaxial compression test of seed 003 (Murakami et al. §2(2)–(3), SPEC §4).

A packed periodic block is taken out of its cell (no periodic images any more) and its discs
grouped by centre (Fig. 2): ④ top and ⑤ bottom bands across the width, ② left and ③ right
bands between them, ① the interior; every band is ``band`` wide (the paper: d = the largest
diameter). ⑤ is fixed, ④ moves as one rigid body (vertically only), ② and ③ are pushed inwards
by σ3 times a projected length. First a preliminary equilibrium: ④ is moved up or down until
σ1 = σ3 within 1 % (and the discs are at rest); then ④ is lowered at a constant axial strain
rate. σ1 is the vertical contact force the other discs exert on ④ over the specimen width.

The side load. The paper: "σ3 × the element area projected in the direction of σ3". Applied to
every disc of a band (``side_load = "diameter"``: 2 r σ3 each) the band, which is more than one
disc thick, carries more than σ3 × its height. By default (``"exposed"``) a disc carries σ3
times the part of its vertical extent [z − r, z + r] not hidden behind a disc lying further out,
so the loads add up to σ3 × the covered height, as a membrane would give; ``Curve.sigma3_applied``
records what was applied.

Results (§2(3)): the deviator q = σ1 − σ3 against the axial strain, its peak q_f, E50 the secant
modulus to q_f / 2, and from several σ3 the Mohr–Coulomb envelope φ*, c*.
"""
import math
from dataclasses import dataclass, field

import numpy as np

INTERIOR, LEFT, RIGHT, TOP, BOTTOM = 1, 2, 3, 4, 5  # the paper's ① – ⑤


def assign_groups(xz, cell, band):
    """Group of each disc by its centre (Fig. 2): 4 top, 5 bottom (full width), 2 left,
    3 right (between them), 1 interior. xz: (n, 2) in [0, Lx) × [0, Lz) [m]; band [m]."""
    x, z = np.asarray(xz, float).T
    lx, lz = cell
    if not 0 < band < min(lx, lz) / 3:
        raise ValueError(f"band must be in (0, {min(lx, lz) / 3:.4g}) m for a {lx:.4g} x {lz:.4g} m specimen, got {band}")
    g = np.full(len(x), INTERIOR)
    g[x < band] = LEFT
    g[x >= lx - band] = RIGHT
    g[z < band] = BOTTOM
    g[z >= lz - band] = TOP
    return g


def _segments(lo, hi):
    """Breakpoints of the intervals [lo, hi]: segment lengths (m,) and which intervals cover
    each segment (n, m)."""
    edges = np.unique(np.concatenate([lo, hi]))
    mid = 0.5 * (edges[:-1] + edges[1:])
    return np.diff(edges), (lo[:, None] < mid[None, :]) & (mid[None, :] < hi[:, None])


def exposed_lengths(lo, hi, depth):
    """Length of each interval [lo, hi] not covered by intervals of discs lying further out
    (larger ``depth`` = further out, e.g. the distance of the outer edge from the specimen)."""
    lo, hi, depth = (np.asarray(v, float) for v in (lo, hi, depth))
    length, cover = _segments(lo, hi)
    seen = cover.any(axis=0)
    front = np.argmax(np.where(cover, depth[:, None], -np.inf), axis=0)  # outermost disc per segment
    return np.bincount(front[seen], weights=length[seen], minlength=len(lo))


def side_forces(xz, r, groups, sigma3, mode):
    """Horizontal forces [N/m] on the side discs (② pushed +x, ③ pushed −x), zero elsewhere."""
    xz, r = np.asarray(xz, float), np.asarray(r, float)
    f = np.zeros(len(r))
    for group, sign in ((LEFT, 1.0), (RIGHT, -1.0)):
        m = groups == group
        if mode == "diameter":
            length = 2 * r[m]
        elif mode == "exposed":
            outward = -sign * xz[m, 0] + r[m]  # the outer edge's distance outwards
            length = exposed_lengths(xz[m, 1] - r[m], xz[m, 1] + r[m], outward)
        else:
            raise ValueError(f"side_load must be 'exposed' or 'diameter', got {mode!r}")
        f[m] = sign * sigma3 * length
    return f


def covered_height(z, r):
    """Length of the union of the intervals [z − r, z + r] [m]."""
    length, cover = _segments(np.asarray(z) - r, np.asarray(z) + r)
    return float(length[cover.any(axis=0)].sum())


def e50(strain, deviator):
    """E50 [Pa] (§2(3)): slope of the line from the origin to the point of the curve at half the
    peak deviator, its first crossing on the loading branch (linear interpolation between
    records; a later dip of a stick-slip plateau below q_f / 2 is not the loading branch)."""
    strain, q = np.asarray(strain, float), np.asarray(deviator, float)
    half = 0.5 * q.max()
    k = int(np.argmax(q >= half))
    if k == 0:
        return math.nan
    e = strain[k - 1] + (half - q[k - 1]) * (strain[k] - strain[k - 1]) / (q[k] - q[k - 1])
    return float(half / e)


def mohr_coulomb_fit(sigma3, sigma1):
    """(φ* [deg], c* [Pa]) of the straight line closest to tangent to the Mohr circles at failure
    (Fig. 4(B)): least squares of the radius t = c cos φ + s sin φ over the centres s, with
    s = (σ1 + σ3)/2 and t = (σ1 − σ3)/2. Needs two or more circles."""
    s3, s1 = np.asarray(sigma3, float), np.asarray(sigma1, float)
    if len(s3) < 2 or np.ptp(s3) <= 0:
        raise ValueError("Mohr-Coulomb fit: need circles at two or more different sigma3")
    s, t = 0.5 * (s1 + s3), 0.5 * (s1 - s3)
    slope, intercept = np.polyfit(s, t, 1)
    if not -1 < slope < 1:
        raise ValueError(f"Mohr-Coulomb fit: circles give sin(phi) = {slope:.3f}, outside (-1, 1)")
    phi = math.asin(slope)
    return math.degrees(phi), float(intercept / math.cos(phi))


@dataclass
class Curve:
    """One test's records (compression positive).

    Attributes:
        sigma3: nominal confining stress [Pa].
        strain: axial strain, ④'s descent over the initial height [-].
        sigma1: σ1 from the contact forces on ④ over the width [Pa].
        sigma1_bottom: the same from ⑤'s reactions [Pa].
        sigma3_applied: side loads of ② over the height they cover [Pa].
        lateral_strain: −(change of the distance between ② and ③ mean centres) / initial [-].
        volumetric_strain: strain + lateral_strain [-] (contraction > 0).
    """

    sigma3: float
    strain: np.ndarray
    sigma1: np.ndarray
    sigma1_bottom: np.ndarray
    sigma3_applied: np.ndarray
    lateral_strain: np.ndarray

    @property
    def deviator(self):
        return self.sigma1 - self.sigma3

    @property
    def volumetric_strain(self):
        return self.strain + self.lateral_strain

    def peak(self):
        """(strain, deviator) at the peak deviator (σ1 − σ3)_f."""
        k = int(np.argmax(self.deviator))
        return float(self.strain[k]), float(self.deviator[k])

    def e50(self):
        return e50(self.strain, self.deviator)


# ---- YADE ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class BiaxialSettings:
    """The test's controls.

    Attributes:
        sigma3: confining stress [Pa].
        strain_rate: axial strain rate [1/s] (the paper: 100 %/min = 1/60).
        dt: time step [s] (the paper: 0.5e-4).
        max_strain: the compression stops at this axial strain [-].
        band: width of groups ②–⑤ [m]; None = the largest diameter (the paper's d).
        side_load: "exposed" or "diameter" (module doc).
        tolerance: |σ1 − σ3| / σ3 of the preliminary equilibrium (the paper: 1 %).
        unbalanced: the specimen is at rest when YADE's unbalanced force ratio is below this.
        record_strain: axial strain between records [-].
        ramp_time: ④ reaches the strain rate's velocity linearly over this time [s]; a sudden
            start would add the dashpots' resistance of the discs under ④ to σ1 for a few steps
            (at 100 %/min, 1000 discs: about 60 Pa), more than half the peak at low σ3 and φe.
        side_update: steps between updates of the exposed side loads.
        max_equilibrium_time: simulated time allowed for the preliminary equilibrium [s].
    """

    sigma3: float = 200.0
    strain_rate: float = 1.0 / 60.0
    dt: float = 5e-5
    max_strain: float = 0.06
    band: float = None
    side_load: str = "exposed"
    tolerance: float = 0.01
    unbalanced: float = 0.002
    record_strain: float = 2e-4
    ramp_time: float = 0.03
    side_update: int = 50
    max_equilibrium_time: float = 2.0

    def __post_init__(self):
        for name, ok, limit in [("sigma3", self.sigma3 > 0, "> 0 Pa"), ("strain_rate", self.strain_rate > 0, "> 0 1/s"),
                                ("max_strain", 0 < self.max_strain < 0.5, "in (0, 0.5)"),
                                ("tolerance", 0 < self.tolerance < 1, "in (0, 1)"),
                                ("record_strain", 0 < self.record_strain < self.max_strain, "in (0, max_strain)")]:
            if not (math.isfinite(getattr(self, name)) and ok):
                raise ValueError(f"{name} must be {limit}, got {getattr(self, name)}")
        if self.side_load not in ("exposed", "diameter"):
            raise ValueError(f"side_load must be 'exposed' or 'diameter', got {self.side_load!r}")


@dataclass
class BiaxialResult:
    """A test: its curve, the preliminary equilibrium reached and the cost."""

    curve: Curve
    settings: BiaxialSettings
    equilibrium: dict = field(default_factory=dict)
    steps: int = 0
    wall_s: float = 0.0

    def describe(self):
        """The log line of a finished test."""
        eps_f, q_f = self.curve.peak()
        return (f"  sigma3 = {self.settings.sigma3:g} Pa: peak deviator {q_f:.1f} Pa at strain {100 * eps_f:.2f} %, "
                f"E50 {self.curve.e50():.4g} Pa; {self.steps} steps in {self.wall_s:.1f} s")

    def summary(self):
        eps_f, q_f = self.curve.peak()
        return {"sigma3_pa": self.settings.sigma3, "peak_deviator_pa": q_f, "peak_strain": eps_f,
                "peak_at_end": bool(eps_f >= self.curve.strain[-1] - 2 * self.settings.record_strain),
                "sigma1_at_peak_pa": q_f + self.settings.sigma3, "e50_pa": self.curve.e50(),
                "equilibrium": self.equilibrium, "steps": self.steps, "wall_s": self.wall_s}


class BiaxialSpecimen:
    """The YADE scene of one test, built from a PeriodicBlock (resets the YADE scene)."""

    def __init__(self, block, contact, settings):
        from yade import O

        from engines.seeds.biaxial.cem_contact import add_discs, check_dt, pair_constants, yade_engines

        self.s = settings
        check_dt(settings.dt, block.r, contact)
        self.width, self.height = block.cell
        band = settings.band if settings.band is not None else 2 * float(block.r.max())
        self.groups = assign_groups(block.xz, block.cell, band)
        self.r = block.r
        O.reset()
        self.ids = np.asarray(add_discs(block.xz, block.r, contact))
        for g in (TOP, BOTTOM):
            for i in self.ids[self.groups == g]:
                O.bodies[int(i)].state.blockedDOFs = "xyzXYZ"
        self.top = [int(i) for i in self.ids[self.groups == TOP]]
        self.bottom = [int(i) for i in self.ids[self.groups == BOTTOM]]
        self.sides = [int(i) for i in self.ids[(self.groups == LEFT) | (self.groups == RIGHT)]]
        self.stiffness = float(pair_constants(np.median(block.r), np.median(block.r), contact)[0])
        self.sigma3_applied = settings.sigma3
        self.engines = yade_engines()
        O.engines = self.engines
        O.dt = settings.dt
        self.update_side_loads()
        self.z_top0 = self.top_z()
        self.width0 = self.side_distance()

    def positions(self, ids):
        from yade import O
        return np.array([(p[0], p[2]) for p in (O.bodies[i].state.pos for i in ids)])

    def update_side_loads(self):
        """Set the permanent side forces from the current positions of ② and ③."""
        from yade import O
        from yade.minieigenHP import Vector3

        ids = self.sides
        xz, r = self.positions(ids), self.r[ids]
        g = self.groups[ids]
        f = side_forces(xz, r, g, self.s.sigma3, self.s.side_load)
        for i, fx in zip(ids, f):
            O.forces.setPermF(i, Vector3(fx, 0, 0))
        left = g == LEFT
        self.sigma3_applied = float(np.sum(f[left]) / covered_height(xz[left, 1], r[left]))

    def sigma1(self, ids=None):
        """Vertical contact force on ④ (or on ⑤, sign turned) over the width [Pa]."""
        from yade import O
        if ids is None:
            return sum(O.forces.f(i)[2] for i in self.top) / self.width
        return -sum(O.forces.f(i)[2] for i in ids) / self.width

    def top_z(self):
        from yade import O
        return float(np.mean([O.bodies[i].state.pos[2] for i in self.top]))

    def side_distance(self):
        xz = self.positions(self.sides)
        left = self.groups[self.sides] == LEFT
        return float(xz[~left, 0].mean() - xz[left, 0].mean())

    def set_top_velocity(self, v):
        from yade import O
        for i in self.top:
            O.bodies[i].state.vel = (0, 0, v)

    def run(self, callback, every, max_steps, extra=()):
        """Run until ``callback`` returns True (checked every ``every`` steps) or max_steps;
        side loads are refreshed every ``side_update`` steps; ``extra``: more PyRunners.
        Returns True if stopped by the callback."""
        from yade import O

        from engines.seeds.biaxial.cem_contact import py_runner

        state = {"done": False}

        def check():
            if callback():
                state["done"] = True
                O.pause()

        def sides():
            self.update_side_loads()

        O.engines = self.engines + [py_runner(sides, self.s.side_update), *extra, py_runner(check, every)]
        O.run(max_steps, True)
        return state["done"]

    def equilibrate(self):
        """Preliminary equilibrium (§2(2)): let the specimen come to rest, read σ1; while it is
        not σ3 within the tolerance, move ④ (rigidly, at the test's strain rate) by the
        displacement a secant estimate of the specimen's modulus asks for, and again. Returns a
        dict of what was reached; raises RuntimeError if it is not reached in time."""
        from yade import O, utils

        s = self.s
        every = 10
        v_max = s.strain_rate * self.height
        k = self.stiffness  # the specimen's modulus lies well below the contacts' k_n (Pa)
        st = {"until": None, "modulus": 0.3 * k, "last": None, "moves": 0}

        def step():
            if st["until"] is not None:  # ④ moving
                if O.iter < st["until"]:
                    return False
                st["until"] = None
                self.set_top_velocity(0.0)
            if utils.unbalancedForce() > s.unbalanced:
                return False
            s1, strain = self.sigma1(), -self.top_z() / self.height
            if abs(s1 - s.sigma3) < s.tolerance * s.sigma3:
                return True
            if st["last"] is not None:  # secant modulus of the last move, within sane bounds
                ds, de = s1 - st["last"][0], strain - st["last"][1]
                if de != 0 and ds / de > 0:
                    st["modulus"] = float(np.clip(ds / de, 0.01 * k, k))
            st["last"] = (s1, strain)
            dz = (s1 - s.sigma3) / st["modulus"] * self.height  # up when σ1 > σ3
            n = every * max(1, math.ceil(abs(dz) / (v_max * s.dt * every)))  # whole checks, at most v_max
            self.set_top_velocity(dz / (n * s.dt))
            st["until"] = O.iter + n
            st["moves"] += 1
            return False

        ok = self.run(step, every, int(s.max_equilibrium_time / s.dt))
        self.set_top_velocity(0.0)
        if not ok:
            raise RuntimeError(f"preliminary equilibrium not reached in {s.max_equilibrium_time} s (dt = {s.dt:g} s): "
                               f"sigma1 = {self.sigma1():.2f} Pa for sigma3 = {s.sigma3:g} Pa, unbalanced force "
                               f"ratio {utils.unbalancedForce():.3g} (at rest below {s.unbalanced}), {st['moves']} moves")
        self.z_top0 = self.top_z()
        self.width0 = self.side_distance()
        return {"sigma1_pa": self.sigma1(), "sigma1_bottom_pa": self.sigma1(self.bottom),
                "sigma3_applied_pa": self.sigma3_applied, "unbalanced": utils.unbalancedForce(),
                "moves": st["moves"], "steps": O.iter, "time_s": O.time}

    def compress(self, log=None):
        """Lower ④ at the constant strain rate to max_strain, recording every record_strain
        (a progress line to ``log`` every 1 % of strain)."""
        from yade import O

        from engines.seeds.biaxial.cem_contact import py_runner

        s = self.s
        v = s.strain_rate * self.height
        start, ramp_steps = O.iter, max(1, int(round(s.ramp_time / s.dt)))

        def ramp():
            k = O.iter - start
            self.set_top_velocity(-v * min(k, ramp_steps) / ramp_steps)
            if k >= ramp_steps:  # at full speed: a runner every step costs ~10 % of a 1000-disc step
                ramp_runner.dead = True

        every = max(1, int(round(s.record_strain / (s.strain_rate * s.dt))))
        rec = {k: [] for k in ("strain", "sigma1", "sigma1_bottom", "sigma3_applied", "lateral_strain")}

        def record():
            strain = (self.z_top0 - self.top_z()) / self.height
            rec["strain"].append(strain)
            rec["sigma1"].append(self.sigma1())
            rec["sigma1_bottom"].append(self.sigma1(self.bottom))
            rec["sigma3_applied"].append(self.sigma3_applied)
            rec["lateral_strain"].append(-(self.side_distance() - self.width0) / self.width0)
            if log and int(100 * strain) > int(100 * rec["strain"][-2 if len(rec["strain"]) > 1 else -1]):
                log(f"    strain {100 * strain:.1f} %: deviator {rec['sigma1'][-1] - s.sigma3:.1f} Pa")
            return strain >= s.max_strain

        record()
        ramp_runner = py_runner(ramp, 1)
        self.run(record, every, int(1.5 * s.max_strain / s.strain_rate / s.dt) + every + ramp_steps,
                 extra=[ramp_runner])
        self.set_top_velocity(0.0)
        return Curve(s.sigma3, *(np.array(rec[k]) for k in ("strain", "sigma1", "sigma1_bottom", "sigma3_applied",
                                                             "lateral_strain")))


def run_biaxial(block, contact, settings, log=None):
    """Preliminary equilibrium then compression of one packed block; a BiaxialResult."""
    import time

    from yade import O

    t0 = time.time()
    sp = BiaxialSpecimen(block, contact, settings)
    eq = sp.equilibrate()
    if log:
        log(f"  sigma3 = {settings.sigma3:g} Pa: equilibrium sigma1 = {eq['sigma1_pa']:.2f} Pa "
            f"(bottom {eq['sigma1_bottom_pa']:.2f}, sides {eq['sigma3_applied_pa']:.2f}) after {eq['steps']} steps")
    curve = sp.compress(log)
    res = BiaxialResult(curve, settings, eq, O.iter, time.time() - t0)
    if log:
        log(res.describe())
    return res

