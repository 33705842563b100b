"""Seed 003's contact law (Murakami et al. §3, SPEC §4) on YADE's own linear law.

The paper's CEM contact: linear normal and shear springs kn, ks given "per unit contact area"
[Pa/m], Coulomb friction φe, no cohesion, and dashpots at the critical value (ζn = ζs = 1).
YADE has exactly this in ``ViscElMat`` + ``Law2_ScGeom_ViscElPhys_Basic``: F_n = kn δ + cn δ̇
(never attractive), an incremental shear spring ks capped at F_n tan φe (the dashpot cs acts only
while the contact sticks). It is chosen over FrictMat/CundallStrack because its dashpot is a
per-contact viscous one, as the paper's, where NewtonIntegrator's damping is a non-viscous global
damping of every body's acceleration; NewtonIntegrator's damping is therefore set to 0.

Per unit thickness (SPEC §1) a contact force is a line load [N/m], so a 2D spring is [N/m²]:
the paper's stiffness per unit area times the contact width w [m] that carries it,

    k_n = kn · w,    w = f_w · 2 r1 r2 / (r1 + r2),    k_s = (ks/kn) · k_n.

The paper does not give w. We take f_w = 1 (``CemContact.width_factor``), the harmonic mean of
the radii (the radius for equal discs): YADE's own mapping of a modulus to a sphere contact
(FrictMat: kn = E 2 R1 R2 / (R1 + R2)), so "kn" reads as YADE's ``young``. It reproduces the
paper's time-step finding (Fig. 6: Δt = 0.5e-4 s is stable, 1e-4 s diverges); with the diameter
(f_w = 2) a packing already rings at 0.5e-4 s (yade_scripts/biaxial_stability.py, docs/BIAXIAL.md).

YADE's Ip2_ViscElMat_ViscElMat_ViscElPhys combines the constants of the two materials in series,
k = k1 k2 / (k1 + k2). Each disc therefore gets a material of its own radius with
k_i = 2 kn f_w r_i (the series of two gives w above exactly) and
c_i = 2 ζ √(m_i k_i): the series of two is the critical dashpot 2 ζ √(m* k) of the pair
(m* = m1 m2 / (m1 + m2)) exactly for equal discs and within 1.5 % for Table 1's most different
pair (r = 1.4 and 3.2 mm).
"""
import math
from dataclasses import dataclass

import numpy as np


ROTATIONS = ("free", "locked")


@dataclass(frozen=True)
class CemContact:
    """Contact constants of seed 003 (Table 2 defaults).

    Attributes:
        kn: normal stiffness per unit contact area [Pa/m].
        ks_ratio: ks / kn [-].
        phi_e_deg: inter-element friction angle φe [deg], 0 < φe < 90.
        rho: disc density [kg/m³] (mass per unit thickness ρ π r²).
        damping_ratio: ζn = ζs, 1 = critical [-].
        width_factor: f_w, the contact width over the harmonic mean of the radii [-] (module doc).
        rotation: "free" (the discs turn under the shear forces' moments) or "locked" (they do
            not turn: CEM as the paper describes it never mentions moments).
    """

    kn: float = 1.0e8
    ks_ratio: float = 0.25
    phi_e_deg: float = 15.0
    rho: float = 2500.0
    damping_ratio: float = 1.0
    width_factor: float = 1.0
    rotation: str = "free"

    def __post_init__(self):
        if self.rotation not in ROTATIONS:
            raise ValueError(f"rotation must be one of {', '.join(ROTATIONS)}, got {self.rotation!r}")
        for name, ok, limit in [("kn", self.kn > 0, "> 0 Pa/m"), ("ks_ratio", self.ks_ratio >= 0, ">= 0"),
                                ("phi_e_deg", 0 < self.phi_e_deg < 90, "in (0, 90) degrees"),
                                ("rho", self.rho > 0, "> 0 kg/m^3"), ("damping_ratio", self.damping_ratio >= 0, ">= 0"),
                                ("width_factor", self.width_factor > 0, "> 0")]:
            if not (math.isfinite(getattr(self, name)) and ok):
                raise ValueError(f"{name} must be {limit}, got {getattr(self, name)}")


def disc_mass(r, rho):
    """Mass per unit thickness ρ π r² [kg/m] (SPEC §1)."""
    return rho * np.pi * np.asarray(r, float) ** 2


def disc_constants(r, c):
    """Per-disc constants (k_n, k_s, c_n, c_s) [N/m², N/m², N s/m²] whose series combination
    (YADE's Ip2_ViscElMat_ViscElMat_ViscElPhys) is the pair's contact (see module doc)."""
    r = np.asarray(r, float)
    kn_i = 2.0 * c.kn * c.width_factor * r
    ks_i = c.ks_ratio * kn_i
    m = disc_mass(r, c.rho)
    return kn_i, ks_i, 2 * c.damping_ratio * np.sqrt(m * kn_i), 2 * c.damping_ratio * np.sqrt(m * ks_i)


def series(a, b):
    """a b / (a + b), the series combination YADE applies to two materials' constants."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a * b / (a + b)


def pair_constants(r1, r2, c):
    """(k_n, k_s, c_n, c_s) of the contact between discs r1 and r2, as YADE will build it."""
    a, b = disc_constants(r1, c), disc_constants(r2, c)
    return tuple(series(x, y) for x, y in zip(a, b))


def leapfrog_dt(k, c, m):
    """Largest time step [s] at which one mode of stiffness k, dashpot c and mass m stays stable
    under YADE's leapfrog, whose dashpot acts on the previous half-step's velocity:
    x_{n+1} − 2 x_n + x_{n−1} = −(k/m) dt² x_n − (c/m) dt (x_n − x_{n−1}) is stable while
    dt² k/m + 2 dt c/m <= 4, i.e. dt = (√(c² + 4 m k) − c) / k (2 √(m/k) undamped, 2 m / c for a
    dashpot alone). For many degrees of freedom the same holds with 4 M − dt² K − 2 dt C >= 0."""
    return 2 * m / c if k == 0 else (math.sqrt(c * c + 4 * m * k) - c) / k


def single_contact_dt_limit(r, c):
    """Largest stable dt [s] of the lightest pair alone (normal spring and dashpot on the reduced
    mass): a time step above it diverges for sure; a packing's modes are stiffer and diverge
    earlier. 2 (√(1 + ζ²) − ζ)/ω: 0.83/ω at ζ = 1, 2/ω undamped."""
    rmin = float(np.min(r))
    kn, _, cn, _ = pair_constants(rmin, rmin, c)
    return leapfrog_dt(kn, cn, series(disc_mass(rmin, c.rho), disc_mass(rmin, c.rho)))


CONTACTS_PER_DISC = 4  # Z of stable_dt's disc: the coordination of the packings at rest is 3.3–4.1


def disc_dt_bound(r, c, contacts=CONTACTS_PER_DISC):
    """Leapfrog limit [s] of the fastest modes of an assembly of the lightest discs (r_min) with
    ``contacts`` = Z contacts each, springs and dashpots of the equal pair (k_n, k_s, c_n, c_s),
    mass m, moment of inertia m r²/2; the smaller of the two (``leapfrog_dt``):

    rotation: every disc turns by θ in the same sense; each shear spring is stretched by
    r θ + r θ = 2 r θ (two neighbours turning alike move their contact points oppositely), so in
    the coordinate r θ a disc has the stiffness (Z/2)(2²) k_s = 2 Z k_s and the mass I/r² = m/2:
    ω_rot² = 4 Z k_s / m, c_rot = 2 Z c_s. Against one fixed neighbour a disc has ω² = 3 k_s/m
    (translation and rotation coupled), between two fixed ones 4 k_s/m: √3 and √2 times the
    translation on the same shear springs (k_s/m, 2 k_s/m);

    translation: neighbours moving oppositely (the alternating mode, an upper bound of every
    translational mode by Gershgorin's splitting of each contact's energy, δ² <= 2 δ_i² + 2 δ_j²):
    ω_tr² = Z (k_n + k_s)/m, c_tr = Z (c_n + c_s) (an isotropic disc: Σ n nᵀ = Σ t tᵀ = Z/2 I).

    With critical dashpots the dashpot term 2 dt c/m dominates dt² k/m (ω dt ≈ 0.3 at the limit),
    and c_s = 2 √(m* k_s) is large next to c_n because of the rotation's small mass: the rotation
    decides for ks/kn above ≈ 1/9 (3 c_s > c_n), and its limit goes as 1/√(k_s), not as
    1/√(k_n + 4 k_s). Table 1–2's constants, Z = 4: 5.69e-5 s (rotation; translation 7.34e-5 s).
    With the rotation locked only the translation is left."""
    rmin = float(np.min(r))
    kn, ks, cn, cs = pair_constants(rmin, rmin, c)
    m = float(disc_mass(rmin, c.rho))
    z = contacts
    translation = leapfrog_dt(z * (kn + ks), z * (cn + cs), m)
    return translation if c.rotation == "locked" else min(leapfrog_dt(2 * z * ks, 2 * z * cs, m / 2), translation)


PAPER_DT = 5e-5  # s, Table 2's constants (Fig. 6)
TABLE2_DT = 4.5e-5  # s, stable_dt at Table 1–2's constants: below the network limits of the packings (stable_dt)
TABLE1_RMIN = 1.4e-3  # m, Table 1's smallest radius


def stable_dt(r, c):
    """Time step [s] for seed 003's packings: TABLE2_DT for the paper's constants (Table 1–2),
    scaled by disc_dt_bound(r, c) / disc_dt_bound(Table 1, Table 2), never above it.

    The scaling is the fastest mode's, the rotation of the lightest discs damped by the shear
    dashpots (disc_dt_bound), so it goes as √(ρ r_min / (kn f_w · ks/kn)) for ks/kn above ≈ 1/9.
    TABLE2_DT is set by the exact limit 4 M − dt² K − 2 dt C >= 0 of the contact networks of
    1000-disc packings at rest (stability.network_dt_limit): those of the packing protocol
    (friction nearly off while packing, Z ≈ 4.1 without rattlers) lie at 4.96–5.22e-5 s
    (12 packings, docs/BIAXIAL.md), so the paper's 0.5e-4 s is above the lowest, where a
    specimen did not come to rest; 4.5e-5 s is 9 % below it. The packings made at the test's
    friction (Z = 3.3–3.7) lie higher (5.15e-5 s measured). For other constants the network
    limits measured on such a packing (3.66e-5 s at ks/kn = 0.5, 2.59e-5 at ks/kn = 1, 3.64e-5
    at kn × 2 or f_w = 2, 7.2e-5 at ks/kn = 0.125) lie above the rule (3.19, 2.25, 3.19,
    4.5e-5 s) by 13 % or more; the former scaling 1/√(kn (1 + 4 ks/kn)) rang at ks/kn = 0.5."""
    return TABLE2_DT * min(1.0, disc_dt_bound(r, c) / disc_dt_bound(TABLE1_RMIN, CemContact()))


def check_dt(dt, r, c):
    """Refuse a time step above the single-contact limit (it cannot be stable)."""
    limit = single_contact_dt_limit(r, c)
    if not (math.isfinite(dt) and 0 < dt <= limit):
        raise ValueError(f"dt must be in (0, {limit:.3g}] s (stability of one contact of the lightest pair, "
                         f"kn = {c.kn:g} Pa/m), got {dt}")


# ---- YADE glue ------------------------------------------------------------------------------

def yade_engines(extra=()):
    """YADE's engine list for the law: collider, ScGeom, ViscEl physics and law, and a
    NewtonIntegrator without its numerical damping (the dashpots damp)."""
    from yade.wrapper import (
        Bo1_Sphere_Aabb,
        ForceResetter,
        Ig2_Sphere_Sphere_ScGeom,
        InsertionSortCollider,
        InteractionLoop,
        Ip2_ViscElMat_ViscElMat_ViscElPhys,
        Law2_ScGeom_ViscElPhys_Basic,
        NewtonIntegrator,
    )
    return [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
            InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_ViscElMat_ViscElMat_ViscElPhys()],
                            [Law2_ScGeom_ViscElPhys_Basic()]),
            NewtonIntegrator(damping=0.0, gravity=(0, 0, 0), label="newton"), *extra]


def add_discs(xz, r, c, y=0.0):
    """Discs as YADE spheres in the x–z plane (blockedDOFs 'yXZ', and 'Y' with c.rotation
    "locked"), per-unit-thickness mass ρ π r² and inertia m r²/2, one ViscElMat per distinct
    radius. Returns the body ids."""
    from yade import O, utils
    from yade.wrapper import ViscElMat

    xz, r = np.asarray(xz, float), np.asarray(r, float)
    materials = {}
    for radius in np.unique(r):
        kn_i, ks_i, cn_i, cs_i = (float(v) for v in disc_constants(radius, c))
        materials[radius] = O.materials.append(ViscElMat(kn=kn_i, ks=ks_i, cn=cn_i, cs=cs_i, density=c.rho,
                                                         frictionAngle=math.radians(c.phi_e_deg)))
    mass = disc_mass(r, c.rho)
    bodies = []
    for (x, z), ri, m in zip(xz, r, mass):
        b = utils.sphere((float(x), y, float(z)), float(ri), material=materials[ri])
        b.state.mass = float(m)
        inertia = 0.5 * float(m) * float(ri) ** 2
        b.state.inertia = (inertia, inertia, inertia)
        b.state.blockedDOFs = "yXYZ" if c.rotation == "locked" else "yXZ"
        bodies.append(b)
    return O.bodies.append(bodies)


_CALLBACKS = {}


def py_runner(callback, iter_period):
    """A YADE PyRunner that calls ``callback()`` every ``iter_period`` steps inside O.run (no
    per-call thread start as with repeated O.run(n, True); the callback may call O.pause())."""
    from yade.wrapper import PyRunner

    key = len(_CALLBACKS)
    _CALLBACKS[key] = callback
    return PyRunner(command=f"import engines.seeds.biaxial.cem_contact as _m; _m._CALLBACKS[{key}]()", iterPeriod=iter_period)
