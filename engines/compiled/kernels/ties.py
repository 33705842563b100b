"""The side-wall ties of the seismic box compiled (engines.model.side_walls.SideWallTies, Fig. 27):
f_u = -k'_s [(x_u - x_l) - rest] - eta'_s (v_u - v_l) on the upper disc, -f_u on the lower, and
the forces a step writes (the law's, the ties', the water's, plus held ones). No YADE."""
import numpy as np

from engines.compiled.kernels.common import jit
from engines.compiled.layout import Layout
from engines.compiled.params import TIE_PRM


@jit
def tie_forces(xz, du, dt, tie_pairs, tie_rest, tie_prm, T):
    """x-forces T[0] (N,) [N] of the side-wall ties (engines.model.side_walls) at centres xz (N, 2) with
    velocities du / dt: tie t pulls its upper disc tie_pairs[t, 1] by f = -k's [(x_u - x_l) - tie_rest[t]]
    - eta's (v_u - v_l) and its lower disc tie_pairs[t, 0] by -f; tie_prm: TIE_PRM (k's, eta's); T (2, N),
    T[1] is scratch."""
    ks, eta = tie_prm[TIE_PRM.ks_wall], tie_prm[TIE_PRM.eta_s_wall]
    T[:] = 0.0
    for t in range(len(tie_rest)):
        lo, up = tie_pairs[t, 0], tie_pairs[t, 1]
        f = -ks * ((xz[up, 0] - xz[lo, 0]) - tie_rest[t]) - eta * (du[up, 0] / dt - du[lo, 0] / dt)
        T[0, up] += f
        T[1, lo] += f
    for a in range(T.shape[1]):
        T[0, a] -= T[1, a]


TIES = Layout.of(tie_forces, 3)  # the arguments of tie_forces after (xz, du, dt)


@jit
def forces_to_write(xz, F_out, rows, held, du, dt, F, F_water, tie_pairs, tie_rest, tie_prm, T):
    """The forces of a step to write, F_out = (F + T + F_water)[rows] + held (n, 2) [N]: the law's
    F, the x-forces T of the side-wall ties (``tie_forces`` at xz, du / dt; none when tie_rest
    is empty) and the water's F_water (none when it is empty: a dry scene)."""
    tied = len(tie_rest) > 0
    if tied:
        tie_forces(xz, du, dt, tie_pairs, tie_rest, tie_prm, T)
    wet = len(F_water) > 0
    for k in range(len(rows)):
        a = rows[k]
        fx, fz = F[a, 0], F[a, 1]
        if tied:
            fx = fx + T[0, a]
        if wet:
            fx, fz = fx + F_water[a, 0], fz + F_water[a, 1]
        F_out[k, 0], F_out[k, 1] = fx + held[k, 0], fz + held[k, 1]


def no_tie_args():
    """The arguments of dem_drive_bulk_io from tie_pairs on (TIES) for a scene without side-wall ties."""
    return TIES.values(tie_pairs=np.zeros((0, 2), np.int64), tie_rest=np.zeros(0),
                       tie_prm=np.zeros(len(TIE_PRM.names)), T=np.zeros((2, 0)))


def tie_args(ties):
    """The arguments of tie_forces after (xz, du, dt) (TIES) of engines.model.side_walls.SideWallTies
    ``ties``: (lower, upper) pairs (M, 2), rest (M,), TIE_PRM and the (2, N) force buffer."""
    return TIES.values(tie_pairs=np.stack([ties.lower, ties.upper], axis=1), tie_rest=ties.rest,
                       tie_prm=TIE_PRM.vector(ks_wall=ties.ks, eta_s_wall=ties.eta), T=np.zeros((2, ties.n)))
