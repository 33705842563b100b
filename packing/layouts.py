"""Simple disc layouts for tests, benchmarks and demos: regular lattices and random packings."""
import numpy as np


def hex_lattice(nx, nz, spacing, origin=(0.0, 0.0)):
    """Centres (nx*nz, 2) [m] of a triangular (hexagonal) lattice, rows offset by half a spacing."""
    i, j = np.meshgrid(np.arange(nx), np.arange(nz))
    x = spacing * (i + 0.5 * (j % 2))
    z = spacing * np.sqrt(3) / 2 * j
    return np.column_stack([x.ravel(), z.ravel()]) + np.asarray(origin, float)


def square_lattice(nx, nz, spacing, origin=(0.0, 0.0)):
    """Centres (nx*nz, 2) [m] of a square lattice."""
    i, j = np.meshgrid(np.arange(nx), np.arange(nz))
    return spacing * np.column_stack([i.ravel(), j.ravel()]).astype(float) + np.asarray(origin, float)


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


def random_sequential(diameters, width, height, rng, tries=400):
    """Random sequential addition: discs (largest first) dropped at uniform random places in the
    rectangle [0, width] x [0, height] [m] where they overlap no disc placed before; a disc that
    finds no place in ``tries`` attempts is left out. Returns centres (m, 2) [m] and radii (m,) [m].
    A loose random packing with gaps of every size (unlike the jittered lattice of random_discs).
    """
    r_all = np.sort(np.asarray(diameters, float))[::-1] / 2
    xz, r = np.zeros((len(r_all), 2)), np.zeros(len(r_all))
    m = 0
    for ri in r_all:
        for _ in range(0, tries, 20):
            cand = rng.random((20, 2)) * [width, height]
            d2 = (cand[:, None, 0] - xz[None, :m, 0]) ** 2 + (cand[:, None, 1] - xz[None, :m, 1]) ** 2
            ok = np.flatnonzero(np.all(d2 >= (r[None, :m] + ri) ** 2, axis=1))
            if len(ok):
                xz[m], r[m] = cand[ok[0]], ri
                m += 1
                break
    return xz[:m], r[:m]
