"""Simple disc layouts for tests, benchmarks and demos: regular lattices and random packings."""
import numpy as np


def hex_lattice(nx, nz, spacing, origin=(0.0, 0.0)):
    """Centres (nx*nz, 2) [m] of a triangular (hexagonal) lattice, rows offset by half a spacing."""
    i, j = np.meshgrid(np.arange(nx), np.arange(nz))
    x = spacing * (i + 0.5 * (j % 2))
    z = spacing * np.sqrt(3) / 2 * j
    return np.column_stack([x.ravel(), z.ravel()]) + np.asarray(origin, float)


def random_discs(n, rng, r_mean=1.0, r_spread=0.3, aspect=1.0):
    """About n polydisperse discs, a jittered hexagonal packing with random gaps (no overlaps).

    Radii r_i = r_mean (1 - r_spread u), u ~ U(0, 1); each centre moves from its lattice site
    (spacing 2 r_mean) by at most r_mean - r_i, so no two discs overlap. ``aspect`` = width/height.
    Returns centres (m, 2) [m] and radii (m,) [m], m close to n.
    """
    nz = max(2, int(round(np.sqrt(n / aspect * np.sqrt(3) / 2))))
    nx = max(2, int(round(n / nz)))
    xz = hex_lattice(nx, nz, 2 * r_mean)
    m = len(xz)
    r = r_mean * (1 - r_spread * rng.random(m))
    ang = 2 * np.pi * rng.random(m)
    rad = (r_mean - r) * np.sqrt(rng.random(m))
    return xz + np.column_stack([rad * np.cos(ang), rad * np.sin(ang)]), r
