"""The compiled drives: many steps in one call between the bridge's reads and writes (the C
functions of engines.yade.yadebulk, passed as addresses: BRIDGE; this module stays free of YADE).
``dem_drive_bulk_io``: PoreDEM's step (engines.model.pore_dem.PoreDEM.step, its order a-f: law,
water, ties, writes, eq 18-24 adjustment, base motion, O.step()); ``water_drive_bulk_io``: the
WaterEngine's water steps; ``water_forces_step``: one water step and the forces to write. Their
argument lists are their parts' layouts, checked at import (DEM_DRIVE, WATER_FORCES_STEP)."""
import numba as nb
import numpy as np
from llvmlite import ir
from numba.extending import intrinsic

from engines.compiled.kernels.base_motion import base_step, MOTION
from engines.compiled.kernels.common import jit, jit_inline
from engines.compiled.kernels.law import (CONTACT, ContactArgs, law_step, LAW_OWN, LIST_STALE, max_sq_displacement,
                                          with_pairs)
from engines.compiled.kernels.pair_grid import near_pairs
from engines.compiled.kernels.separation import free_discs, separation_velocities
from engines.compiled.kernels.ties import forces_to_write, TIES
from engines.compiled.kernels.water_step import AREAS_OUT_OF_RANGE, _part, WATER, WATER_FLOATS, water_step
from engines.compiled.layout import Layout
from engines.compiled.params import CONTACT_PRM


@jit
def water_forces_step(xz, F_out, rows, held, water):
    """``water_step`` (``water``: the tuple of its arguments after xz, WATER), then F_out = held +
    F_water[rows] (n, 2) [N], the forces to write (WaterEngine). Returns (n, n) with water_step's
    answer n, or (-1, n) when it failed."""
    n_sub = water_step(xz, *water)
    F_water = water[WATER.F_water]
    for k in range(len(rows)):
        F_out[k, 0] = held[k, 0] + F_water[rows[k], 0]
        F_out[k, 1] = held[k, 1] + F_water[rows[k], 1]
    return (n_sub if n_sub > 0 else -1), n_sub


WATER_FORCES_STEP = Layout.of(water_forces_step, 2).check(("rows", "held", "water"))


def water_forces_step_args(rows, held, water):
    """The arguments of water_forces_step after (xz, F_out) (WATER_FORCES_STEP): the forces to
    write F_water[rows] + held, then the tuple WATER."""
    return WATER_FORCES_STEP.values(rows=rows, held=held, water=water)


# The addresses of the C functions of engines.yade.yadebulk a kernel calls: the position read, the
# force write (set_perm_force_xz, or add_force_unsynced_xz in a scene that resets the forces after
# NewtonIntegrator: engines.yade.yade_io.forces_reset_after_newton), the velocity write and YADE's
# steps (yadebulk.c_steps).
BRIDGE = Layout("BRIDGE", ("get_pos", "write_forces", "set_vel", "steps"))


@intrinsic
def _c_bulk_call(typingctx, address, ids, n, data):
    """(*address)(ids, n, data) for the C function int64 f(const int64 *ids, int64 n, double *data)
    at the integer ``address`` (engines.yade.yadebulk's bulk functions), ids and data addresses too."""
    def codegen(context, builder, signature, args):
        i64, ptr = ir.IntType(64), ir.IntType(8).as_pointer()
        fn = builder.inttoptr(args[0], ir.FunctionType(i64, [ptr, i64, ptr]).as_pointer())
        return builder.call(fn, [builder.inttoptr(args[1], ptr), args[2], builder.inttoptr(args[3], ptr)])
    return nb.types.int64(address, ids, n, data), codegen


@jit
def _read_positions(get_pos, ids, xz):
    return _c_bulk_call(get_pos, ids.ctypes.data, ids.size, xz.ctypes.data)


@jit
def _write_forces(status, write, ids, F):
    """write(ids <- F) when status >= 0; the bridge's error code (0 when nothing was written)."""
    return _c_bulk_call(write, ids.ctypes.data, ids.size, F.ctypes.data) if status >= 0 else 0


@jit
def water_drive_bulk_io(bridge, n, step_last, water_in, water_interval, totals, xz_built, moved2, ids_in, xz, ids_out,
                        F_out, rows, held, water):
    """WaterEngine's step without Python (engines.model.water_model.WaterModel.step in YADE): n DEM
    steps (one water step of the PyRunner is n = 1, water_in = 0, not ``step_last``), the water
    steps among them (step water_in of the call, then every water_interval:
    engines.model.schedule.Schedule) each get_pos(ids_in -> xz), ``water_forces_step`` (``water``:
    the tuple WATER) and write_forces(ids_out <- F_out), each step made by bridge's steps()
    (YADE's O.step()) but for the last when not ``step_last``. totals (3,) [m^2] gets the water
    balance (BALANCE) of every water step that needed no sub-steps. Stops before
    stepping after a water step that did not answer 1 (sub-steps or a failure: its bookkeeping is
    the caller's) or at an error code; with moved2 > 0 [m^2], also before a water step at which a
    disc is farther than sqrt(moved2) from its centre in xz_built (N, 2) [m] or a void area is out
    of range (water_step's AREAS_OUT_OF_RANGE): a rebuild is due, that water step is the
    caller's, nothing done of it. Returns (DEM steps done, water steps done, the last water step's
    answer or 1, the bridge's error code)."""
    balance = _part(water[WATER.floats], water[WATER.f_at], WATER_FLOATS.balance)
    n_water, next_water = 0, water_in
    for s in range(n):
        if s == next_water:  # the rebuild triggers, then the water and the forces to write
            next_water += water_interval
            rc = _read_positions(bridge[BRIDGE.get_pos], ids_in, xz)
            if rc != 0:
                return s, n_water, 1, rc
            if moved2 > 0.0 and max_sq_displacement(xz, xz_built) > moved2:
                return s, n_water, 1, 0  # a rebuild is due: that water step is the caller's
            status, n_sub = water_forces_step(xz, F_out, rows, held, water)
            if n_sub == AREAS_OUT_OF_RANGE:
                return s, n_water, 1, 0
            rc = _write_forces(status, bridge[BRIDGE.write_forces], ids_out, F_out)
            if rc != 0:
                return s, n_water, n_sub, rc
            n_water += 1
            if n_sub != 1:
                return s, n_water, n_sub, 0
            totals += balance
        if s == n - 1 and not step_last:
            return s, n_water, 1, 0
        rc = _c_bulk_call(bridge[BRIDGE.steps], 0, 1, 0)
        if rc != 0:
            return s, n_water, 1, rc
    return n, n_water, 1, 0


Layout.of(water_drive_bulk_io, 12).check(WATER_FORCES_STEP)


@jit
def _write_step_velocities(set_vel, ids, discs, V):
    """set_vel(ids[discs] <- V[discs]) for the discs where ``discs`` (N,) is true; the bridge's
    error code."""
    at = np.flatnonzero(discs)
    W = np.empty((len(at), 2))
    for m in range(len(at)):
        W[m, 0], W[m, 1] = V[at[m], 0], V[at[m], 1]
    chosen = ids[at]
    return _c_bulk_call(set_vel, chosen.ctypes.data, chosen.size, W.ctypes.data)


@jit
def dem_drive_bulk_io(bridge, n, k, step_last, water_in, water_interval, adjust, e, mass, skin, totals, motion, t_s,
                      a_s, wall_ids, wall_vel, ids_in, xz, ids_out, F_out, rows, held,
                      xz_prev, xz_list, half_skin2, omega, dpsi, du, inertia, mobile, dt,
                      r, pi, pj, state, prm, spring, F, M, acc_j, lost,
                      h, W, A_prev, q_prev, smoothing, substep, F_water, ints, i_at, floats, f_at,
                      tie_pairs, tie_rest, tie_prm, T):
    """PoreDEM's step (engines.model.pore_dem.PoreDEM.step, its order a-f) in YADE without Python,
    up to n steps from step index k (one step is n = 1), each: get_pos(ids_in -> xz); a law step
    (LAW_OWN, then CONTACT from r to lost: the ContactArgs ``contact``; a stale pair list rebuilt once by
    ``_law_step_listed``); ``water_step`` (WATER: from h to f_at) at step water_in of the call,
    then every water_interval (engines.model.schedule.Schedule), when the scene is wet;
    ``forces_to_write`` (the side-wall ties, TIES: from tie_pairs on); write_forces(ids_out <-
    F_out); with ``adjust`` the eq 18-24 velocity adjustment (``_adjust_separations``: restitution
    e, the discs' masses ``mass`` (N,) [kg/m]); the water's balance of the step added to totals
    (BALANCE) [m^2] (not that of a step that needed sub-steps: its books are the caller's); the
    base motion and the walls wall_ids (``_drive_walls``, when motion is not empty); then bridge's
    steps() (O.step()), but for the last step when not ``step_last``. The arguments are spelled
    out (a tuple costs ~3 us more to unbox from Python). It stops after a step whose water
    answered other than 1 (sub-steps or a failure) before its O.step(), at the start of a step
    whose list is still stale once rebuilt (skin 0: nothing done of it), or at an error code.
    Returns (steps made, of them stepped by O.step(), the list was stale, the last water step's
    answer or 1, the error code, the pair lists built, pi, pj, state, lost)."""
    contact = ContactArgs(r, pi, pj, state, prm, spring, F, M, acc_j, lost)
    wet = len(W) > 0
    V = np.empty_like(du) if adjust else du  # the adjusted velocities [m/s]
    balance = _part(floats, f_at, WATER_FLOATS.balance) if wet else totals  # a dry scene has no buffer: not read
    builds, next_water = 0, water_in
    for s in range(n):
        rc = _read_positions(bridge[BRIDGE.get_pos], ids_in, xz)
        if rc != 0:
            return s, s, False, 1, rc, builds, contact.pi, contact.pj, contact.state, contact.lost
        water_due, next_water = _water_due(wet, s, next_water, water_interval)
        n_lost, contact, built = _law_step_listed(xz, xz_prev, xz_list, half_skin2, omega, dpsi, du, inertia, mobile,
                                                  dt, contact, skin)
        builds += built
        if n_lost == LIST_STALE:
            return s, s, True, 1, 0, builds, contact.pi, contact.pj, contact.state, contact.lost
        n_sub = (water_step(xz, h, W, A_prev, q_prev, smoothing, substep, F_water, ints, i_at, floats, f_at)
                 if water_due else 1)
        forces_to_write(xz, F_out, rows, held, du, dt, contact.F, F_water, tie_pairs, tie_rest, tie_prm, T)
        rc = _write_forces(0, bridge[BRIDGE.write_forces], ids_out, F_out)
        if rc != 0:
            return s, s, False, n_sub, rc, builds, contact.pi, contact.pj, contact.state, contact.lost
        if adjust and n_lost > 0:
            rc = _adjust_separations(bridge[BRIDGE.set_vel], ids_in, contact, n_lost, xz, du, dt, mass, mobile, e, V)
            if rc != 0:
                return s, s, False, n_sub, rc, builds, contact.pi, contact.pj, contact.state, contact.lost
        if water_due and n_sub == 1:
            totals += balance
        if len(motion):
            rc = _drive_walls(bridge[BRIDGE.set_vel], motion, t_s, a_s, k + s, wall_ids, wall_vel)
            if rc != 0:
                return s + 1, s, False, n_sub, rc, builds, contact.pi, contact.pj, contact.state, contact.lost
        if n_sub != 1 or (s == n - 1 and not step_last):
            return s + 1, s, False, n_sub, 0, builds, contact.pi, contact.pj, contact.state, contact.lost
        rc = _c_bulk_call(bridge[BRIDGE.steps], 0, 1, 0)
        if rc != 0:
            return s + 1, s, False, 1, rc, builds, contact.pi, contact.pj, contact.state, contact.lost
    return n, n, False, 1, 0, builds, contact.pi, contact.pj, contact.state, contact.lost


DEM_DRIVE = Layout.of(dem_drive_bulk_io, 20).check(("rows", "held"), LAW_OWN, CONTACT, WATER, TIES)


@jit
def _water_due(wet, s, next_water, water_interval):
    """(Is step s of a drive's call a water step of a ``wet`` scene, the step of the water after
    it): the water at next_water, then every water_interval (engines.model.schedule.Schedule)."""
    due = s == next_water
    return wet and due, next_water + water_interval if due else next_water


@jit_inline
def _law_step_listed(xz, xz_prev, xz_list, half_skin2, omega, dpsi, du, inertia, mobile, dt, contact, skin):
    """``law_step`` (LAW), its pair list rebuilt once at xz when stale (``near_pairs`` with the
    list's skin [m]; xz_list overwritten). Returns (law_step's answer, the ContactArgs of the
    pair list, the lists built: 0 or 1)."""
    built = 0
    for attempt in range(2):  # a stale list rebuilt once
        n_lost = law_step(xz, xz_prev, xz_list, half_skin2, omega, dpsi, du, inertia, mobile, dt, contact)
        if n_lost != LIST_STALE or attempt == 1:
            break
        pi, pj, state = near_pairs(xz, contact.r, mobile, contact.prm[CONTACT_PRM.eps_m], skin, contact.pi,
                                   contact.pj, contact.state)
        contact = with_pairs(contact, pi, pj, state, np.zeros(len(pi), np.int64))
        xz_list[:] = xz
        built += 1
    return n_lost, contact, built


@jit_inline
def _adjust_separations(set_vel, ids, contact, n_lost, xz, du, dt, mass, mobile, e, V):
    """The eq 18-24 adjustment of a step whose pairs contact.lost[:n_lost] stopped touching: the
    discs set free (``free_discs``) get their ``separation_velocities`` (V (N, 2) [m/s]) by the
    bridge's set_vel (ids of the discs). Returns its error code (0: none, or nothing set)."""
    lost, pi, pj, state = contact.lost, contact.pi, contact.pj, contact.state
    free = free_discs(lost, n_lost, pi, pj, state, mobile)
    if not free.any():
        return 0
    separation_velocities(lost, n_lost, pi, pj, state, xz, du, dt, mass, free, e, V)
    return _write_step_velocities(set_vel, ids, free, V)


@jit
def _drive_walls(set_vel, motion, t_s, a_s, k, wall_ids, wall_vel):
    """The base motion advanced from step k (``base_step``: MOTION and the record t_s, a_s) and the
    walls wall_ids given its wall velocity (v, 0) by the bridge's set_vel (wall_vel (m, 2) is
    scratch). Returns its error code."""
    base_step(motion, t_s, a_s, k)
    for b in range(len(wall_ids)):
        wall_vel[b, 0], wall_vel[b, 1] = motion[MOTION.wall_velocity], 0.0
    return _c_bulk_call(set_vel, wall_ids.ctypes.data, wall_ids.size, wall_vel.ctypes.data)


@jit
def read_bulk_io(get_pos, ids, xz):
    """get_pos(ids -> xz): the bridge's position read; returns its error code."""
    return _read_positions(get_pos, ids, xz)


@jit
def write_rows_bulk_io(write, ids, F, rows, add, out):
    """out = F[rows] + add, then write(ids <- out): the bridge's force write (BRIDGE.write_forces)
    of some rows of F plus held forces; returns its error code."""
    for k in range(len(rows)):
        out[k, 0] = F[rows[k], 0] + add[k, 0]
        out[k, 1] = F[rows[k], 1] + add[k, 1]
    return _write_forces(0, write, ids, out)


def dry_water_args():
    """The arguments of dem_drive_bulk_io from h to f_at (WATER) for a scene without water."""
    no_i, no_f = np.zeros(0, np.int64), np.zeros(0)
    return WATER.values(h=0.0, W=no_f, A_prev=no_f, q_prev=no_f, smoothing=False, substep=False,
                        F_water=np.zeros((0, 2)), ints=no_i, i_at=np.zeros(1, np.int64), floats=no_f,
                        f_at=np.zeros(1, np.int64))
