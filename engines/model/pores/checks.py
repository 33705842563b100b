"""The checks of the pores' inputs: disc centres and radii, lengths (eq 28, 43b). No YADE."""
import numpy as np


def check_finite_array(name, a, shape=None):
    """Return ``a`` as float64, raising ValueError naming ``name`` on bad shape or NaN/inf."""
    a = np.asarray(a, dtype=float)
    if shape is not None and (a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape))):
        raise ValueError(f"{name}: expected shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.flatnonzero(~np.isfinite(a.ravel()))[0]
        raise ValueError(f"{name}: non-finite value {a.ravel()[bad]} at flat index {bad}")
    return a


def check_nonnegative(name, value):
    """Raise ValueError naming ``name`` unless ``value`` is a finite number >= 0."""
    if not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be finite and >= 0, got {value}")


LINK_RANGE = (0.01, 2.0)  # the accepted l_m, in median radii: below, a few pores; above, links across grains


def check_lengths(l_m, eps_m, r, names=("l_m", "eps_m")):
    """Refuse a link range l_m [m] outside LINK_RANGE x the median radius of r (N,) [m] (lengths
    typed in another unit: l_m = 2.3e-4 radii builds two pores), or a contact range eps_m [m]
    above l_m; ``names``: how the caller calls them."""
    r_med = float(np.median(r))
    lo, hi = LINK_RANGE
    if not lo * r_med <= l_m <= hi * r_med:
        raise ValueError(f"{names[0]} = {l_m:.3g} m is {l_m / r_med:.3g} x the median disc radius {r_med:.3g} m, "
                         f"outside {lo:g}-{hi:g} x it: the link range beyond touching (eq 28) is a fraction of a "
                         f"grain; check the units of the radii and of {names[0]} (both in m)")
    if eps_m > l_m:
        raise ValueError(f"{names[1]} = {eps_m:.3g} m exceeds {names[0]} = {l_m:.3g} m: the contact range (eq 43b) "
                         f"lies within the link range (eq 28); reduce {names[1]} or raise {names[0]}")


def check_discs(xz, r):
    """Validate disc centres (N, 2) [m] and radii (N,) [m] > 0; return float arrays."""
    xz = check_finite_array("xz", xz, (None, 2))
    r = check_finite_array("r", r, (xz.shape[0],))
    if np.any(r <= 0):
        i = int(np.flatnonzero(r <= 0)[0])
        raise ValueError(f"r must be > 0, got r[{i}] = {r[i]}")
    return xz, r


# PoreNetwork's arrays as a checkpoint holds them: (shape by size, lowest index, the size indices are
