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
    """

    kn: float = 1.0e8
    ks_ratio: float = 0.25
    phi_e_deg: float = 15.0
    rho: float = 2500.0
    damping_ratio: float = 1.0
    width_factor: float = 1.0

    def __post_init__(self):
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


def single_contact_dt_limit(r, c):
    """Largest stable dt [s] of the lightest pair alone (normal spring, leapfrog, ζ): a time step
    above it diverges for sure; a dense packing's modes are stiffer and diverge earlier.
    Leapfrog with the dashpot on the previous half-step velocity is stable for one spring while
    (ω dt)² + 4 ζ ω dt <= 4, i.e. ω dt <= 2 (√(1 + ζ²) − ζ): 0.83 at ζ = 1 (2 undamped)."""
    rmin = float(np.min(r))
    kn = pair_constants(rmin, rmin, c)[0]
    omega = math.sqrt(kn / series(disc_mass(rmin, c.rho), disc_mass(rmin, c.rho)))
    z = c.damping_ratio
    return 2 * (math.sqrt(1 + z * z) - z) / omega


PAPER_DT = 5e-5  # s, Table 2's constants (Fig. 6)


def stable_dt(r, c):
    """Time step [s] for seed 003's packings: the paper's 0.5e-4 s for its constants (Table 1–2),
    scaled as 1/ω for others, never above it. Measured on a 1000-disc packing at rest
    (yade_scripts/biaxial_stability.py): kn = 1e8, ks/kn = 0.25 rings at 7e-5 s, not at 5e-5 s;
    kn = 2e8 at 5e-5 s, not at 3.5e-5 s: the highest mode goes as √(kn f_w (1 + 4 ks/kn) / (ρ r_min)).
    Known defect: at ks/kn = 0.5 the 4.08e-5 s it gives still rings (docs/BIAXIAL.md)."""
    stiff = c.kn * c.width_factor * (1 + 4 * c.ks_ratio) / (c.rho * float(np.min(r)))
    paper = 1e8 * (1 + 4 * 0.25) / (2500.0 * 1.4e-3)
    return PAPER_DT * min(1.0, math.sqrt(paper / stiff))


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
    """Discs as YADE spheres in the x–z plane (blockedDOFs 'yXZ'), per-unit-thickness mass
    ρ π r² and inertia m r²/2, one ViscElMat per distinct radius. Returns the body ids."""
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
        b.state.blockedDOFs = "yXZ"
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
