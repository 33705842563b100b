"""The pores and water of N discs stepped by compiled kernels: engines.model.water_model.WaterModel
with its pore builds and re-meshing by engines.compiled.pores (BUILD, REMESH) and its water steps by
kernels.water_step (the pore measure, the Darcy step, eq 32, 33 in one call), with flat walls too.
No YADE."""
import numpy as np

from engines.compiled import kernels
from engines.compiled import pores as cp
from engines.compiled.params import BALANCE, LAM, WATER_PRM, book_balance
from engines.model import limits, water_model
from engines.model import pores as pg
from engines.model.limits import DarcyStabilityError


class WaterModel(water_model.WaterModel):
    """engines.model.water_model.WaterModel by compiled kernels (tests/compiled/: the same results);
    the network's arrays are packed into the buffers of kernels.water_step at each build."""

    build_steps, remesh_steps = cp.BUILD, cp.REMESH
    CHECKPOINT_DERIVED = water_model.WaterModel.CHECKPOINT_DERIVED | {
        "wp": "the scene's [water] as the kernels' vector",
        **{name: "the kernels' buffers, packed from the network (checkpoint_restored)" for name in
           ("_ints", "_i_at", "_floats", "_f_at", "_q_prev", "_lam", "_balance", "_has_q_prev", "_args", "_args_key")}}

    def __init__(self, settings, r, walls, xz, eps_m, l_m, dt, schedule=None, log=print, flat_walls=()):
        super().__init__(settings, r, walls, xz, eps_m, l_m, dt, schedule, log, flat_walls)
        # the kernels' inflow q_in = inflow x bottom: rate and weights of PoreWater.inflow_weights
        self.wp = WATER_PRM.vector(settings, inflow=self.water.inflow[0])
        self._buffers()

    def _buffers(self):
        """The network's arrays for kernels.water_step, packed (allocated once per rebuild)."""
        net, n = self.water.net, len(self.r)
        n_p, n_l, n_t = net.n_pores, len(net.links), len(net.throat_conns)
        surface, drained, _ = self.water._boundary_masks()
        bottom = self.water.inflow[1]
        walls = net.flat_walls
        edge, edge_wall = pg.wall_edges(net)
        ints = {"links": net.links, "link_pores": net.link_pores, "throat_i": net.throat_conns[:, 0],
                "throat_j": net.throat_conns[:, 1], "throat_link": net.throat_link,
                "wall_axis": [w.axis for w in walls], "wall_edge": edge, "wall_edge_wall": edge_wall}
        floats = {"vec0": net.link_vec0, "turn_weight": net.link_turn_weight, "sector0": net.sector_area0,
                  "surface": surface, "drained": drained, "bottom": bottom, "wp": self.wp, "eps_m": self.eps_m,
                  "a_min": net.a_min,
                  "r": pg.vertex_radii(net, self.r), "vec": np.zeros((n_l, 2)), "right": np.zeros((n_p, 2)),
                  "Fj": np.zeros((n, 2)),
                  "balance": np.zeros(len(BALANCE.names)), "lam": np.zeros(len(LAM.names)), "has_q_prev": 0.0,
                  "check_areas": float(self.schedule.by_displacement),
                  "wall_position": self.wall_vertices.faces() if walls else [],
                  "vertices": pg.vertex_positions(net, self.xz_built) if walls else np.zeros((0, 2)),  # corners: move_walls
                  "F_walls": np.zeros(len(walls)), "A_watch": np.zeros(n_p), "watch": np.zeros(3)}
        # the rest: outputs and scratch of the kernels, by length
        for names, size in (("poly sect void", n_p), ("length contact", n_l), ("q g", n_t),
                            ("q_s q_d q_in g_b U acc_i acc_j rate out_i out_j", n_p)):
            floats.update((name, np.zeros(size)) for name in names.split())
        self._ints, self._i_at = kernels.WATER_INTS.pack(ints, np.int64)
        self._floats, self._f_at = kernels.WATER_FLOATS.pack(floats, float)
        self._q_prev = np.zeros(n_t)  # eq 46 running throat flows, while PoreWater.q_prev is None
        self._views()

    def _views(self):
        """Views of the float buffer read around each water step (F_walls among them); kernel_args
        built again."""
        self._lam, self._balance, self._has_q_prev, self.F_walls = (
            self._part(name) for name in ("lam", "balance", "has_q_prev", "F_walls"))
        self._args_key = None

    def checkpoint_restored(self):
        """After a checkpoint set the network and the water: the kernels' buffers packed again, with
        the walls' pushes and positions (F_walls is a view into them)."""
        super().checkpoint_restored()
        F_walls = self.F_walls.copy()
        self._buffers()
        self.F_walls[:] = F_walls
        if self.wall_vertices is not None:
            self.move_walls(self.wall_vertices.shift)

    def _part(self, name):
        """A view of the part ``name`` of the float buffer of kernels.water_step."""
        return kernels.WATER_FLOATS.part(self._floats, self._f_at, name)

    def max_sq_moved(self, xz):
        """max over the discs of |xz - xz_built|^2 [m^2] (kernels.max_sq_displacement)."""
        return kernels.max_sq_displacement(np.ascontiguousarray(xz, float), self.xz_built)

    def rebuild(self, xz, k=None):
        super().rebuild(xz, k)
        self._buffers()

    def move_walls(self, shift):
        """As engines.model.water_model.WaterModel.move_walls, into the kernels' buffers: the faces
        the feet are placed on, and the corners (kernels.place_wall_vertices leaves them)."""
        super().move_walls(shift)
        wv = self.wall_vertices
        self._part("wall_position")[:] = wv.faces()
        self._part("vertices").reshape(-1, 2)[wv.foot(len(wv.walls), 0):] = wv.corner_positions()

    def _void_area(self, net, xz):
        """Void areas (Np,) [m^2] of ``net`` at xz (eq 29) by kernels.measure."""
        return kernels.void_areas(pg.vertex_positions(net, xz), pg.vertex_radii(net, self.r), self.eps_m,
                                  *kernels.link_geometry(net))

    def advance(self, h, xz, k=None):
        """As engines.model.water_model.WaterModel.advance, by kernels.water_step."""
        n_sub = kernels.water_step(xz, *self.kernel_args(h))
        if n_sub == kernels.AREAS_OUT_OF_RANGE:
            self.rebuild(xz, k)
            n_sub = kernels.water_step(xz, *self.kernel_args(h))
        self.finish_kernel_step(h, n_sub)

    def kernel_args(self, h):
        """The arguments of kernels.water_step after xz (kernels.WATER), for a water step of h [s],
        with the buffer's eq 46 flag "has_q_prev" set from the water; the same tuple
        while h, the water's arrays and the eq 46 state stay (the tuple holds the arrays, so their
        ids are not reused while it is kept)."""
        w, s = self.water, self.settings
        self._has_q_prev[0] = w.q_prev is not None
        key = (h, id(w.W), id(w.A_prev), id(w.q_prev))
        if self._args_key != key:
            q_prev = self._q_prev if w.q_prev is None else w.q_prev
            self._args = kernels.WATER.values(h=h, W=w.W, A_prev=w.A_prev, q_prev=q_prev, smoothing=s.smoothing,
                                              substep=s.substep, F_water=self.F, ints=self._ints, i_at=self._i_at,
                                              floats=self._floats, f_at=self._f_at)
            self._args_key = key
        return self._args

    def finish_kernel_step(self, h, n_sub):
        """Book a water_step(xz, *kernel_args(h)) that returned n_sub: the Darcy limit, sub-steps,
        balance; raise DarcyStabilityError if it refused or a pore fell dry."""
        w = self.water
        self.after_kernel_steps()
        lam = self._lam
        if n_sub != 1:
            n = self._substeps(h)  # raises above the limit without settings.substep
            if n_sub < 0:
                raise DarcyStabilityError(f"water area of pore {-1 - n_sub} would fall to <= 0 in a step of "
                                          f"{h / n:.3e} s; {limits.DRY_HINT}")
            self.last_limit = limits.gershgorin_limit(lam[LAM.last])  # at the last sub-step, as PoreWater reports it
        book_balance(w.balance, self._balance, add=True)
        self.report_watch(h)

    def report_watch(self, h):
        """Hand the accuracy watch (``watch``, AccuracyWatch.seen) what the kernels' water steps of h
        [s] since the last report saw (kernels.watch_areas: each compared with the one before on the
        same pores), and start the next report."""
        w = self._part("watch")
        ratio, low = w[1], w[2]
        w[1] = w[2] = 0.0
        if self.watch is not None:
            self.watch.seen(ratio, low, h)

    def after_kernel_steps(self):
        """After water steps run by kernels with the arguments of ``kernel_args``: the eq 46 state
        they hold and the Darcy limit of the last one."""
        if self.settings.smoothing:
            self.water.q_prev = self._args[kernels.WATER.q_prev]
        self.last_limit = limits.gershgorin_limit(self._lam[LAM.first])

    def _substeps(self, h):
        """The sub-steps a water step of h [s] needs (engines.model.limits.substeps: refused without
        settings.substep); logged when sub-stepping starts and whenever the count doubles."""
        n = limits.substeps(h, self.last_limit, self.settings.substep, self.settings.E_w)
        if n == 1:
            return 1
        if n >= 2 * max(self.substeps_max, 1):
            self.log(f"water: step {h:.3e} s > Darcy limit {self.last_limit:.3e} s: {n} sub-steps per water step "
                     f"(each costs one flow and one update kernel pass, about {limits.SUBSTEP_COST:.0%} of a "
                     f"water step)")
        self.substeps_max = max(self.substeps_max, n)
        self.substeps_total += n
        return n
