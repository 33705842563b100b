"""One water step compiled (engines.model.water_model.WaterModel.advance): the network's arrays as
two buffers read by name (WATER_INTS, WATER_FLOATS, a WaterNet of views), the measure (eq 29), eq 45
smoothing of the areas, the Darcy flows and update (eq 32, 38-43, 42) with eq 46 smoothing of the
flows and sub-steps, and the pressure forces on the discs (eq 33, ``pressure_forces``) and on flat
walls (``flat_wall_forces``). No YADE."""
from collections import namedtuple

import numba as nb
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array

from engines.compiled.kernels.common import _at, jit
from engines.compiled.kernels.darcy import darcy_flows, darcy_update, gershgorin_limit, substep_count, throat_sums
from engines.compiled.kernels.measure import areas_in_range, LinkGeometry, measure, Measures, place_wall_vertices
from engines.compiled.layout import Layout
from engines.compiled.params import LAM, WATER_PRM


# The per-network arrays of water_step, in two buffers (one int64, one float64: a numba call
# unboxes each array argument, ~0.2 us each), each array a part by name (Layout.pack). A water step
# reads them as a WaterNet of views that take no reference count (``water_net``, ``_view``): a
# slice would cost an atomic add (~20 ns) for each of its ~40 parts at every step.
WATER_INTS = Layout("WATER_INTS", ("links", "link_pores", "throat_i", "throat_j", "throat_link", "wall_axis",
                                   "wall_edge", "wall_edge_wall"))


WATER_FLOATS = Layout("WATER_FLOATS", (
    "vec0", "turn_weight", "sector0", "surface", "drained", "bottom", "wp", "eps_m", "a_min", "r",  # inputs
    "poly", "sect", "void", "length", "contact", "vec", "right",                                # measure
    "q", "q_s", "q_d", "q_in", "g", "g_b", "U", "acc_i", "acc_j", "rate", "out_i", "out_j",     # flows
    "balance", "Fj", "lam", "has_q_prev", "check_areas",              # update, forces, eq 46, rebuild trigger
    "wall_position", "vertices", "F_walls",                                           # flat walls
    "A_watch", "watch"))                                                              # the accuracy watch


WaterNet = namedtuple("WaterNet", WATER_INTS.names + WATER_FLOATS.names)


@intrinsic
def _view(typingctx, buf, start, stop):
    """buf[start:stop] of a contiguous 1-d array without a reference to buf's memory: no reference
    count (an atomic add, ~20 ns, where buf[start:stop] makes one), so it is valid only while the
    call that made it holds buf, and must not leave compiled code."""
    def codegen(context, builder, signature, args):
        src = context.make_array(signature.args[0])(context, builder, args[0])
        out = context.make_array(signature.return_type)(context, builder)
        populate_array(out, data=builder.gep(src.data, [args[1]]), shape=[builder.sub(args[2], args[1])],
                       strides=[src.itemsize], itemsize=src.itemsize, meminfo=None)
        return out._getvalue()
    return buf.copy(layout="C")(buf, start, stop), codegen


@jit
def _part(buf, at, k):
    """Part k of a buffer made by Layout.pack, a ``_view`` (only while the call holds buf)."""
    return _view(buf, at[k], at[k + 1])


@intrinsic
def _view2(typingctx, buf, start, stop):
    """``_view`` of buf[start:stop] as an (n, 2) array (row after row)."""
    def codegen(context, builder, signature, args):
        src = context.make_array(signature.args[0])(context, builder, args[0])
        out = context.make_array(signature.return_type)(context, builder)
        two = context.get_constant(nb.types.intp, 2)
        populate_array(out, data=builder.gep(src.data, [args[1]]),
                       shape=[builder.sdiv(builder.sub(args[2], args[1]), two), two],
                       strides=[builder.mul(src.itemsize, two), src.itemsize], itemsize=src.itemsize, meminfo=None)
        return out._getvalue()
    return nb.types.Array(buf.dtype, 2, "C")(buf, start, stop), codegen


@jit
def _part2(buf, at, k):
    """Part k as an (n, 2) array (``_view2``, only while the call holds buf)."""
    return _view2(buf, at[k], at[k + 1])


AREAS_OUT_OF_RANGE = -(1 << 62)  # water_step's answer when a void area left its range (a rebuild is due)


@jit
def flat_wall_forces(wall_edge, wall_edge_wall, link_pores, U, length, F_walls):
    """Twin of engines.model.pores.flat_wall_forces: F_walls (W,) [N/m] = sum over each wall's edges
    (links wall_edge, of wall wall_edge_wall) of U x edge length, both sides' U (the outer one is 0)."""
    F_walls[:] = 0.0
    for e in range(len(wall_edge)):
        l = wall_edge[e]
        p0, p1 = link_pores[l, 0], link_pores[l, 1]
        F_walls[wall_edge_wall[e]] += ((U[p0] if p0 >= 0 else 0.0) + (U[p1] if p1 >= 0 else 0.0)) * length[l]


@jit
def water_net(ints, i_at, floats, f_at):
    """The parts WATER_INTS of (ints, i_at) and WATER_FLOATS of (floats, f_at) (Layout.pack) as a
    WaterNet, in the layouts' order (a call of more than a few keywords is not compiled): views,
    (n, 2) where the network's array is, and eps_m, a_min and check_areas as numbers (fixed for a
    network)."""
    return WaterNet(
        _part2(ints, i_at, WATER_INTS.links), _part2(ints, i_at, WATER_INTS.link_pores),
        _part(ints, i_at, WATER_INTS.throat_i), _part(ints, i_at, WATER_INTS.throat_j),
        _part(ints, i_at, WATER_INTS.throat_link), _part(ints, i_at, WATER_INTS.wall_axis),
        _part(ints, i_at, WATER_INTS.wall_edge), _part(ints, i_at, WATER_INTS.wall_edge_wall),
        _part2(floats, f_at, WATER_FLOATS.vec0), _part(floats, f_at, WATER_FLOATS.turn_weight),
        _part(floats, f_at, WATER_FLOATS.sector0), _part(floats, f_at, WATER_FLOATS.surface),
        _part(floats, f_at, WATER_FLOATS.drained), _part(floats, f_at, WATER_FLOATS.bottom),
        _part(floats, f_at, WATER_FLOATS.wp), floats[f_at[WATER_FLOATS.eps_m]], floats[f_at[WATER_FLOATS.a_min]],
        _part(floats, f_at, WATER_FLOATS.r),
        _part(floats, f_at, WATER_FLOATS.poly), _part(floats, f_at, WATER_FLOATS.sect),
        _part(floats, f_at, WATER_FLOATS.void), _part(floats, f_at, WATER_FLOATS.length),
        _part(floats, f_at, WATER_FLOATS.contact), _part2(floats, f_at, WATER_FLOATS.vec),
        _part2(floats, f_at, WATER_FLOATS.right),
        _part(floats, f_at, WATER_FLOATS.q), _part(floats, f_at, WATER_FLOATS.q_s),
        _part(floats, f_at, WATER_FLOATS.q_d), _part(floats, f_at, WATER_FLOATS.q_in),
        _part(floats, f_at, WATER_FLOATS.g), _part(floats, f_at, WATER_FLOATS.g_b),
        _part(floats, f_at, WATER_FLOATS.U), _part(floats, f_at, WATER_FLOATS.acc_i),
        _part(floats, f_at, WATER_FLOATS.acc_j), _part(floats, f_at, WATER_FLOATS.rate),
        _part(floats, f_at, WATER_FLOATS.out_i), _part(floats, f_at, WATER_FLOATS.out_j),
        _part(floats, f_at, WATER_FLOATS.balance), _part2(floats, f_at, WATER_FLOATS.Fj),
        _part(floats, f_at, WATER_FLOATS.lam), _part(floats, f_at, WATER_FLOATS.has_q_prev),
        floats[f_at[WATER_FLOATS.check_areas]],
        _part(floats, f_at, WATER_FLOATS.wall_position), _part2(floats, f_at, WATER_FLOATS.vertices),
        _part(floats, f_at, WATER_FLOATS.F_walls),
        _part(floats, f_at, WATER_FLOATS.A_watch), _part(floats, f_at, WATER_FLOATS.watch))


@jit
def water_step(xz, h, W, A_prev, q_prev, smoothing, substep, F_water, ints, i_at, floats, f_at):
    """Advance the water by h [s] at centres xz and recompute the pressure forces F_water (N, 2) [N]
    (WaterModel.advance): ``measure``, eq 45 smoothing of the areas into A_prev, ``darcy_flows``,
    n = 1 or ceil(h / Darcy limit) sub-steps of ``darcy_update`` by h / n (eq 46 smoothing of the
    throat flows into q_prev) with U at the areas used (eq 32, 45), ``pressure_forces``. The network's
    arrays are the parts WATER_INTS of (ints, i_at) and WATER_FLOATS of (floats, f_at)
    (Layout.pack), read as the WaterNet ``net`` (``water_net``). Flat walls (wall_axis not empty):
    the pores' vertices are the discs and the walls' (vertices, ``place_wall_vertices``; r holds 0
    for the wall vertices) and F_walls gets the water's force on each wall (``flat_wall_forces``).
    lam gets the Gershgorin bound of the first and of the last flows, balance the water of this
    step, has_q_prev is 1 once q_prev holds the flows of an earlier water step.
    Returns n >= 1; 0 when h exceeds the Darcy limit without ``substep`` (W unchanged); -1 - p
    when pore p would fall dry (W as after the previous sub-step); AREAS_OUT_OF_RANGE, nothing
    changed, when check_areas is 1 and a measured void area is out of range (``areas_in_range``)."""
    net = water_net(ints, i_at, floats, f_at)
    points = xz
    if len(net.wall_axis):
        place_wall_vertices(xz, net.vertices, net.wall_axis, net.wall_position)
        points = net.vertices
    measure(points, net.r, net.eps_m, LinkGeometry(net.links, net.link_pores, net.vec0, net.turn_weight, net.sector0),
            Measures(net.poly, net.sect, net.void, net.length, net.contact, net.vec, net.right))
    if net.check_areas != 0.0 and not areas_in_range(net.void, net.poly):
        return AREAS_OUT_OF_RANGE
    A = net.void
    if smoothing:  # eq 45
        for p in range(len(A_prev)):
            A_prev[p] = 0.5 * (A_prev[p] + net.void[p])
        A = A_prev
    lam = net.lam
    lam[LAM.first] = lam[LAM.last] = darcy_flows(W, A, net)
    n_sub = substep_count(h, gershgorin_limit(lam[LAM.first]))
    if n_sub > 1 and not substep:
        return 0
    q = net.q
    net.balance[:] = 0.0
    for sub in range(n_sub):
        if sub > 0:
            lam[LAM.last] = darcy_flows(W, A, net)
        if smoothing:  # eq 46: the flows' sums are those of the smoothed flows
            running = net.has_q_prev[0] != 0.0
            for t in range(len(q)):
                if running:
                    q[t] = 0.5 * (q_prev[t] + q[t])
                q_prev[t] = q[t]
            net.has_q_prev[0] = 1.0
            throat_sums(net.throat_i, net.throat_j, q, net.out_i, net.out_j)
        bad = darcy_update(W, h / n_sub, net.out_i, net.out_j, net.q_s, net.q_d, net.q_in, net.balance, A,
                           net.wp[WATER_PRM.E_w], net.U)  # U at the area used (eq 45)
        if bad >= 0:
            return -1 - bad
    pressure_forces(net.links, net.link_pores, net.r, net.U, net.length, net.vec, F_water, net.Fj)
    if len(net.wall_axis):
        flat_wall_forces(net.wall_edge, net.wall_edge_wall, net.link_pores, net.U, net.length, net.F_walls)
    watch_areas(net.void, net.U, net.a_min, net.wp[WATER_PRM.E_w], net.A_watch, net.watch)
    return n_sub


@jit
def watch_areas(void, U, a_min, E_w, A_watch, watch):
    """Twin of engines.model.limits.area_change and AccuracyWatch's lowest U / E_w, at each water
    step: watch = (1 once A_watch (Np,) [m^2] holds the void areas of the last water step on these
    pores, the largest max |dA| / A and the lowest U / E_w since the caller last reset them)."""
    ratio = 0.0
    if watch[0] != 0.0:
        for p in range(len(void)):
            if A_watch[p] > a_min and void[p] > a_min:
                ratio = max(ratio, abs(void[p] - A_watch[p]) / A_watch[p])
    for p in range(len(void)):
        A_watch[p] = void[p]
        watch[2] = min(watch[2], U[p] / E_w)
    watch[0] = 1.0
    watch[1] = max(watch[1], ratio)


WATER = Layout.of(water_step, 1)  # the arguments of water_step after xz


@jit
def pressure_forces(links, link_pores, r, U, length, vec, F, Fj):
    """Force of the pore pressures U on every disc, F (N, 2) [N] (eq 33); Fj (N, 2) is scratch.
    The outer face and closed faces (link_pores = -1) have U = 0. Vertices past the N discs (the
    flat walls', radius 0) take nothing. The links come sorted by i: disc i's sum is kept in
    registers while its links follow one another (the same sums in the same order)."""
    F[:] = 0.0
    Fj[:] = 0.0
    n = len(F)
    a_sum, fx, fz = _at(0), 0.0, 0.0  # the disc summed in (fx, fz), F[a_sum] not yet written
    for l in range(len(links)):
        p0, p1 = link_pores[l, 0], link_pores[l, 1]
        s = ((U[_at(p1)] if p1 >= 0 else 0.0) - (U[_at(p0)] if p0 >= 0 else 0.0)) / length[l]
        px, pz = -vec[l, 1] * s, vec[l, 0] * s
        i, j = links[l, 0], links[l, 1]
        if i < n:
            a = _at(i)
            if a != a_sum:
                F[a_sum, 0], F[a_sum, 1] = fx, fz
                a_sum, fx, fz = a, F[a, 0], F[a, 1]
            fx += r[a] * px
            fz += r[a] * pz
        if j < n:
            b = _at(j)
            Fj[b, 0] += r[b] * px
            Fj[b, 1] += r[b] * pz
    if n:
        F[a_sum, 0], F[a_sum, 1] = fx, fz
    for a in range(len(F)):
        F[a, 0] += Fj[a, 0]
        F[a, 1] += Fj[a, 1]
