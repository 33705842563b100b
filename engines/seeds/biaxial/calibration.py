"""Seed 003 §3(3)b–c: the model ground's strength and stiffness as functions of the contact
constants, and their inversion (eq 2–6).

    φ* = f1(φe)                                    eq 2 (kn, ks/kn fixed)
    E50/σ3 = A(φe) (σ3/kn)^m(φe)                   eq 4
    φe = f1⁻¹(φ*)                                  eq 5
    kn = A^(1/m) E50^(−1/m) σ3^(1 + 1/m)           eq 6

Erratum: the paper prints σ3^(−1 + 1/m) in eq 6. Solving eq 4 for kn gives
kn = σ3 (A σ3 / E50)^(1/m), i.e. σ3^(1 + 1/m); only this makes kn a stiffness per unit area
[Pa/m] (A carries m^(−m)) and gives back E50 when put into eq 4 (tests/seeds/test_calibration.py).

f1, A and m are known at the φe of the study only; between them they are interpolated
linearly (A in log), and a target outside the studied range is refused, not extrapolated.
"""
import json
import math
from dataclasses import asdict, dataclass

import numpy as np

from engines import files


def fit_eq4(sigma3, kn, e50):
    """(A, m) of eq 4 by least squares of log(E50/σ3) on log(σ3/kn). Arrays [Pa], [Pa/m], [Pa]."""
    x = np.log(np.asarray(sigma3, float) / np.asarray(kn, float))
    y = np.log(np.asarray(e50, float) / np.asarray(sigma3, float))
    if len(x) < 2 or np.ptp(x) <= 0:
        raise ValueError("eq 4 fit: need E50 at two or more different sigma3/kn")
    m, log_a = np.polyfit(x, y, 1)
    return float(math.exp(log_a)), float(m)


def eq4_e50(sigma3, kn, A, m):
    """E50 [Pa] of eq 4 at σ3 [Pa], kn [Pa/m]."""
    return np.asarray(sigma3, float) * A * (np.asarray(sigma3, float) / kn) ** m


def eq6_kn(e50, sigma3, A, m):
    """kn [Pa/m] giving E50 at σ3 (eq 6, exponent corrected: module doc)."""
    return sigma3 * (A * sigma3 / e50) ** (1.0 / m)


@dataclass
class Calibration:
    """The study's curves: at each φe [deg] the strength φ* [deg] (eq 2) and A, m (eq 4), for
    the contact constants kn [Pa/m] (at which f1 was measured) and ks/kn; optionally, at each φe,
    the scatter between packings: the standard deviation of ln E50 at one σ3 and of φ* [deg],
    and the number of packings."""

    phi_e: list
    phi_star: list
    A: list
    m: list
    kn: float
    ks_ratio: float
    e50_log_sd: list = None
    phi_star_sd: list = None
    packings: list = None

    def __post_init__(self):
        n = len(self.phi_e)
        if n < 2 or any(len(v) != n for v in (self.phi_star, self.A, self.m)):
            raise ValueError("calibration: need phi_e, phi_star, A, m of equal length >= 2")
        if np.any(np.diff(self.phi_e) <= 0):
            raise ValueError("calibration: phi_e must increase")

    def phi_e_for(self, phi_star):
        """eq 5: φe [deg] giving φ* [deg]; f1 must increase over the studied range."""
        f = np.asarray(self.phi_star, float)
        if np.any(np.diff(f) <= 0):
            raise ValueError(f"eq 5: phi* does not increase with phi_e in the study ({f.round(2).tolist()}): "
                             "f1 cannot be inverted")
        if not f[0] <= phi_star <= f[-1]:
            raise ValueError(f"--phi-star must be within the studied range [{f[0]:.2f}, {f[-1]:.2f}] deg, got {phi_star}")
        return float(np.interp(phi_star, f, self.phi_e))

    def eq4_at(self, phi_e):
        """(A, m) at φe: log A and m interpolated linearly between the studied φe."""
        return (float(np.exp(np.interp(phi_e, self.phi_e, np.log(self.A)))),
                float(np.interp(phi_e, self.phi_e, self.m)))

    def invert(self, phi_star, e50, sigma3):
        """(φe [deg], kn [Pa/m]) for a target φ* [deg] and E50 [Pa] at σ3 [Pa] (eq 5, eq 6)."""
        for name, v in (("--e50", e50), ("--sigma3", sigma3)):
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be > 0 Pa, got {v}")
        phi_e = self.phi_e_for(phi_star)
        A, m = self.eq4_at(phi_e)
        return phi_e, float(eq6_kn(e50, sigma3, A, m))

    def save(self, path):
        files.write_json(path, asdict(self))

    @classmethod
    def load(cls, path):
        with open(path) as f:
            return cls(**json.load(f))
