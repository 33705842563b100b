"""Disc layouts that only the tests use (packing.layouts holds the ones the benchmarks share)."""
import numpy as np


def square_lattice(nx, nz, spacing, origin=(0.0, 0.0)):
    """Centres (nx*nz, 2) [m] of a square lattice."""
    i, j = np.meshgrid(np.arange(nx), np.arange(nz))
    return spacing * np.column_stack([i.ravel(), j.ravel()]).astype(float) + np.asarray(origin, float)


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
