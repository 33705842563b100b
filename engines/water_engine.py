"""The pore water as an engine: pores between discs, Darcy exchange, pressure forces (seed 000 §3).

``WaterEngine`` is the public YADE object: a YADE script with its own spheres (kept in the x-z
plane), its own collider and contact law adds the water in a few lines::

    from engines.water_engine import WaterEngine
    from engines.pore_water import WaterSettings
    water = WaterEngine(disc_ids, walls={"bottom": bottom_ids, "left": left_ids, "right": right_ids},
                        settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4), l_m=1.3e-4)
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]   # before NewtonIntegrator

Every ``water_interval`` steps its PyRunner reads the centres in bulk (engines.yade_io), rebuilds
the pores when ``rebuild_interval`` steps have passed, measures the void areas (eq 29), advances
the water by water_interval x O.dt (eq 32-43, 45-46) and writes the pressure forces (eq 33) plus
buoyancy (eq 34b) as permanent forces: between water steps no Python runs.

``WaterModel`` is the same work without YADE (engines.pore_dem uses it for the paper's step order;
the tests use it directly): the compiled kernels of engines.kernels (and of engines.kernels_pores
for the pore rebuild), or with ``compiled=False`` the readable NumPy functions of
engines.pore_geometry and engines.pore_water.

Stability: the explicit update is refused above its Darcy limit 2/lambda (engines.pore_water),
checked at every water step: the bound is one more pass over throats and pores inside the flow
kernel (measured at a few per cent of a water step), about what testing whether the areas changed
enough to need a new check would cost, so the check is exact at every step instead. With ``settings.substep`` a water
step above the limit is split into n = ceil(dt_w / limit) sub-steps; the engine prints the count
when it first sub-steps and whenever the count doubles, and keeps ``substeps_max``/``substeps_total``.
"""
import math
import time

import numpy as np

from engines import kernels
from engines import pore_geometry as pg
from engines.pore_water import DarcyStabilityError, PoreWater

CHUNK_SECONDS = 0.1  # wall time of one compiled call of WaterEngine.drive (signals wait that long)

WALL_CODES = {"bottom": pg.WALL_BOTTOM, "left": pg.WALL_LEFT, "right": pg.WALL_RIGHT}


class WaterModel:
    """Pores and water of N discs (no YADE). Units: SI per unit thickness (engines.pore_water).

    r (N,) radii [m] (the true ones: pores use them even where a contact law enlarges them by
    eps_m/2); walls (N,) wall codes of engines.pore_geometry; xz (N, 2) initial centres [m].
    ``F`` (N, 2) [N] holds the pressure forces of the last water step.
    """

    def __init__(self, settings, r, walls, xz, eps_m, l_m, dt, rebuild_interval=1000, water_interval=1,
                 compiled=True, log=print):
        self.settings, self.eps_m, self.l_m = settings, float(eps_m), float(l_m)
        self.r = np.ascontiguousarray(r, float)
        self.walls = np.asarray(walls, np.int64)
        self.dt, self.rebuild_interval, self.water_interval = float(dt), int(rebuild_interval), int(water_interval)
        if self.rebuild_interval < 1 or self.water_interval < 1:
            raise ValueError(f"rebuild_interval and water_interval must be >= 1, got "
                             f"{rebuild_interval}, {water_interval}")
        self.compiled, self.log = compiled, log
        self.wp = np.array([settings.E_w, settings.k1, settings.k2, settings.k3, settings.q_w])
        self.F = np.zeros((len(self.r), 2))
        self.n_rebuilds = 0
        self.substeps_max = self.substeps_total = 0
        self.last_limit = np.inf  # Darcy limit of the last water step [s]
        net = self._build(xz)
        self.water = PoreWater(net, pg.measure(net, xz, self.r).void_area, settings)
        self._buffers()

    def _build(self, xz):
        return pg.build_pores(xz, self.r, eps_m=self.eps_m, l_m=self.l_m, walls=self.walls, compiled=self.compiled)

    def _buffers(self):
        """The network's arrays for kernels.water_step, packed (allocated once per rebuild)."""
        net, n = self.water.net, len(self.r)
        n_p, n_l, n_t, n_k = net.n_pores, len(net.links), len(net.throat_conns), len(net.corner_pore)
        surface, drained, bottom = self.water._boundary_masks()
        ints = {"links": net.links, "link_pores": net.link_pores, "corner_pore": net.corner_pore,
                "corner_link": net.corner_link, "corner_next_link": net.corner_next_link,
                "throat_i": net.throat_conns[:, 0], "throat_j": net.throat_conns[:, 1], "throat_link": net.throat_link}
        floats = {"corner_sign": net.corner_sign, "vec0": net.link_vec0, "corner_theta0": net.corner_theta0,
                  "corner_r2": net.corner_r2, "rattler_area": net.rattler_area, "surface": surface,
                  "drained": drained, "bottom": bottom, "wp": self.wp, "eps_m_a_min": [self.eps_m, net.a_min],
                  "r": self.r, "vec": np.zeros((n_l, 2)), "Fj": np.zeros((n, 2)), "balance": np.zeros(3),
                  "lam": np.zeros(2)}  # the rest: outputs and scratch of the kernels, by length
        for names, size in (("poly sect void", n_p), ("length contact rot cross", n_l), ("theta", n_k),
                            ("q g", n_t), ("q_s q_d q_in g_b U acc_i acc_j", n_p)):
            floats.update((name, np.zeros(size)) for name in names.split())
        self._ints, self._i_at = kernels.pack([np.asarray(ints[k], np.int64) for k in kernels.WATER_INTS])
        self._floats, self._f_at = kernels.pack([np.asarray(floats[k], float) for k in kernels.WATER_FLOATS])
        self._q_prev = np.zeros(n_t)  # eq 46 running throat flows, while PoreWater.q_prev is None
        self._views()

    def _views(self):
        """Views of the float buffer read after each water step; kernel_args built again."""
        self._lam, self._balance = self._part("lam"), self._part("balance")
        self._args_key = None

    def __getstate__(self):  # a pickle copies views: leave them out, make them again on loading
        state = dict(self.__dict__)
        for name in ("_lam", "_balance", "_args", "_args_key"):
            state.pop(name, None)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._views()

    def _part(self, name):
        """A view of the part ``name`` of the float buffer of kernels.water_step."""
        k = kernels.WATER_FLOATS.index(name)
        return self._floats[self._f_at[k]:self._f_at[k + 1]]

    # -- per step ---------------------------------------------------------------------------------
    def step(self, k, xz):
        """Step k of the DEM at centres xz (N, 2) [m]: rebuild when k > 0 and k % rebuild_interval
        == 0, advance when k % water_interval == 0. Returns True when ``F`` was recomputed."""
        if k > 0 and k % self.rebuild_interval == 0:
            self.rebuild(xz)
        if k % self.water_interval != 0:
            return False
        self.advance(self.water_interval * self.dt, xz)
        return True

    def rebuild(self, xz):
        """Rebuild the pores at xz and move the water onto them (§3.4(2))."""
        old, new = self.water.net, self._build(xz)
        self.water.remesh(new, self._void_area(new, xz), self._void_area(old, xz), xz=xz, compiled=self.compiled)
        self.n_rebuilds += 1
        self._buffers()

    def _void_area(self, net, xz):
        """Void areas (Np,) [m^2] of ``net`` at xz (eq 29): pg.measure, or kernels.measure (compiled)."""
        if not self.compiled:
            return pg.measure(net, xz, self.r).void_area
        n_p, n_l, n_k = net.n_pores, len(net.links), len(net.corner_pore)
        void = np.empty(n_p)
        kernels.measure(xz, self.r, net.links, net.link_vec0, net.corner_pore, net.corner_sign, net.corner_link,
                        net.corner_next_link, net.corner_theta0, net.corner_r2, net.rattler_area, self.eps_m,
                        np.empty(n_p), np.empty(n_p), void, np.empty(n_l), np.empty(n_l, bool), np.empty(n_k),
                        np.empty((n_l, 2)), np.empty(n_l), np.empty(n_l))
        return void

    def advance(self, h, xz):
        """Advance the water by h [s] at centres xz and recompute the pressure forces ``F``."""
        if not self.compiled:
            m = pg.measure(self.water.net, xz, self.r)
            self.last_limit = self.water._limit(self.water.advance(h, m.void_area, m.link_contact))
            A = self.water.A_prev if self.settings.smoothing else m.void_area  # eq 45: the area used
            self.F = pg.pressure_forces(self.water.net, self.r, self.water.pressure(A), m)
            return
        args = self.kernel_args(h)
        self.finish_kernel_step(h, kernels.water_step(xz, *args), args)

    def kernel_args(self, h):
        """The arguments of kernels.water_step after xz, for a water step of h [s] (compiled); the
        same tuple while h, the water's arrays and the eq 46 state stay (the tuple holds the arrays,
        so their ids are not reused while it is kept)."""
        w, s = self.water, self.settings
        key = (h, id(w.W), id(w.A_prev), id(w.q_prev))
        if self._args_key != key:
            q_prev = self._q_prev if w.q_prev is None else w.q_prev
            self._args = (h, w.W, w.A_prev, q_prev, s.smoothing, s.substep, w.q_prev is not None, self.F,
                          self._ints, self._i_at, self._floats, self._f_at)
            self._args_key = key
        return self._args

    def finish_kernel_step(self, h, n_sub, args):
        """Book a water_step(xz, *args) that returned n_sub: the Darcy limit, sub-steps, balance;
        raise DarcyStabilityError if it refused or a pore fell dry."""
        w = self.water
        self.after_kernel_steps(args)
        lam = self._lam
        if n_sub != 1:
            n = self._substeps(h)  # raises above the limit without settings.substep
            if n_sub < 0:
                raise DarcyStabilityError(f"water area of pore {-1 - n_sub} would fall to <= 0 in a step of {h / n:.3e} s")
            self.last_limit = 2.0 / lam[1] if lam[1] > 0 else np.inf  # at the last sub-step, as PoreWater reports it
        inflow, surface, side = self._balance.tolist()
        b = w.balance
        b.inflow += inflow
        b.surface_outflow += surface
        b.side_outflow += side

    def after_kernel_steps(self, args):
        """After water steps run by kernels with ``args``: the eq 46 state they hold and the Darcy
        limit of the last one."""
        if self.settings.smoothing:
            self.water.q_prev = args[3]
        lam = self._lam
        self.last_limit = 2.0 / lam[0] if lam[0] > 0 else np.inf

    def _substeps(self, h):
        """1, or the sub-steps a water step of h [s] needs (settings.substep); else refuse."""
        if h <= self.last_limit:
            return 1
        if not self.settings.substep:
            raise DarcyStabilityError(
                f"water step dt = {h:.3e} s exceeds the explicit Darcy limit {self.last_limit:.3e} s "
                f"(2/lambda_max of eq 38-43 at E_w = {self.settings.E_w}); reduce dt or water_interval, "
                f"or set [water] substep = true")
        n = int(math.ceil(h / self.last_limit))
        if n >= 2 * max(self.substeps_max, 1):
            self.log(f"water: step {h:.3e} s > Darcy limit {self.last_limit:.3e} s: {n} sub-steps per water step "
                     f"(each costs one flow and one update kernel pass, about a quarter of a water step)")
        self.substeps_max = max(self.substeps_max, n)
        self.substeps_total += n
        return n

    # -- observations ------------------------------------------------------------------------------
    def measures(self, xz):
        return pg.measure(self.water.net, xz, self.r)

    def pressures(self, xz):
        """U (Np,) [N/m] at centres xz (eq 32)."""
        return self.water.pressure(self.measures(xz).void_area)


class WaterEngine:
    """The pore water of a YADE scene as a PyRunner (see the module docstring for the usage).

    disc_ids: the spheres that bound the pores (particles and wall discs), kept in the x-z plane.
    walls: {"bottom"|"left"|"right": ids} among disc_ids (inflow enters bottom pores; drained
    sides drain through left/right). radii: the true disc radii [m] (default: read from the
    bodies; give them when the contact law enlarges the spheres by eps_m/2). eps_m: contact range
    of the links (eq 43b); l_m: link range (eq 28). buoyancy: add rho_w pi r^2 g upwards to the
    dynamic discs (eq 34b), rho_w from ``rho_w``. Pressure forces act on dynamic bodies only.
    """

    def __init__(self, disc_ids, walls, settings, l_m, eps_m=0.0, radii=None, rebuild_interval=1000,
                 water_interval=1, buoyancy=True, rho_w=1000.0, gravity=9.81, compiled=True):
        from yade import O  # YADE only here and below
        from engines import yade_io

        self.io = yade_io.Bodies(disc_ids)
        ids = self.io.ids
        if radii is None:
            radii = [O.bodies[i].shape.radius for i in ids.tolist()]
        code = np.zeros(len(ids), np.int64)
        pos = {i: k for k, i in enumerate(ids.tolist())}
        for name, group in (walls or {}).items():
            if name not in WALL_CODES:
                raise ValueError(f"walls: unknown group {name!r}; known: {sorted(WALL_CODES)}")
            missing = [i for i in group if i not in pos]
            if missing:
                raise ValueError(f"walls[{name!r}]: ids {missing[:5]} are not among disc_ids")
            code[[pos[i] for i in group]] = WALL_CODES[name]
        if not O.dt > 0:
            raise ValueError("set O.dt before creating the WaterEngine (the water step is water_interval x O.dt)")
        self.model = WaterModel(settings, radii, code, self.io.positions(), eps_m, l_m, O.dt,
                                rebuild_interval, water_interval, compiled)
        dynamic = np.array([O.bodies[i].dynamic for i in ids.tolist()])
        self.forced = yade_io.Bodies(ids[dynamic])
        self._dynamic = np.flatnonzero(dynamic)
        self.F_const = np.zeros((len(self._dynamic), 2))
        if buoyancy:
            self.F_const[:, 1] = rho_w * np.pi * np.asarray(radii, float)[self._dynamic] ** 2 * gravity
        self.forced.set_permanent_forces(self.F_const)
        self._xz, self._F_out = np.zeros((len(ids), 2)), np.zeros((len(self._dynamic), 2))  # buffers of __call__
        self._run_kernel = yade_io.run_kernel
        self.k = self.k_built = self.k0 = O.iter  # DEM step of the last call, of the last build, of creation
        self._chunk = 100  # steps of drive's next compiled call, adapted to CHUNK_SECONDS

    def due(self, k):
        """True when step k is a water step (every water_interval steps from the engine's creation)."""
        return (k - self.k0) % self.model.water_interval == 0

    def runner(self, label="water"):
        """The PyRunner to put after the InteractionLoop and before NewtonIntegrator. YADE's
        PyRunner costs about 50 us a call (measured at 240 bodies; ``drive`` does not pay it)."""
        from engines import yade_io
        return yade_io.py_runner(self.__call__, self.model.water_interval, label)

    def drive(self, n, stop=None):
        """Instead of the runner and O.run(n): n O.step() calls, this engine's work before each of
        them that is a water step (the same work: nothing moves the bodies between NewtonIntegrator
        and the next step's PyRunner). ``stop()`` true, or an error kept by an engine callback
        (yade_io.ERRORS), ends early. Without ``stop`` and without a PyRunner among O.engines, with
        the bulk bridge, the steps between two rebuilds run in compiled calls of about CHUNK_SECONDS
        (``_drive_compiled``): the same run without Python per step."""
        from yade import O
        from yade.wrapper import PyRunner

        from engines import yade_io
        n, done = int(n), 0
        fast = (stop is None and self.model.compiled and yade_io.BACKEND == "yadebulk"
                and not any(isinstance(e, PyRunner) for e in O.engines))
        due, errors = self.due, yade_io.ERRORS
        while done < n:
            m = min(n - done, self._steps_before_rebuild(O.iter), self._chunk) if fast else 0
            if m > 0:
                t0 = time.perf_counter()
                done += self._drive_compiled(m)
                if m == self._chunk:
                    self._chunk = int(min(max(m * CHUNK_SECONDS / max(time.perf_counter() - t0, 1e-6), 10), 1e6))
                continue
            if due(O.iter):
                self()
            O.step()
            done += 1
            if errors or (stop is not None and stop()):
                break

    def _steps_before_rebuild(self, k):
        """Steps from step k to the first water step whose call rebuilds the pores."""
        wi = self.model.water_interval
        t = max(k, self.k_built + self.model.rebuild_interval)
        return t + (self.k0 - t) % wi - k

    def _drive_compiled(self, n):
        """Up to n steps by kernels.water_drive_bulk_io, no rebuild among them; returns the steps
        done (fewer after a water step that needed sub-steps: its bookkeeping and its step follow
        here; an error is raised)."""
        from yade import O

        from engines import yade_io
        m = self.model
        h = m.water_interval * O.dt
        args = m.kernel_args(h)
        b = m.water.balance
        totals = np.array([b.inflow, b.surface_outflow, b.side_outflow])
        k = O.iter
        done, n_water, n_sub, rc = yade_io.drive_water(n, k, self.k0, m.water_interval, totals, self.io, self._xz,
                                                       self.forced, self._F_out, self._dynamic, self.F_const, args)
        b.inflow, b.surface_outflow, b.side_outflow = totals.tolist()
        if n_water:
            last = k + done - (1 if n_sub == 1 else 0)  # the last water step
            self.k = last - (last - self.k0) % m.water_interval
            m.after_kernel_steps(args)
        yade_io.check(rc)
        if n_sub != 1:  # that water step's sub-steps or failure, then its DEM step
            m.finish_kernel_step(h, n_sub, args)
            O.step()
            done += 1
        return done

    def __call__(self):
        """One water step: rebuild at the first call at least rebuild_interval steps after the last
        build, advance by water_interval x O.dt, write the forces."""
        from yade import O
        m = self.model
        self.k = O.iter
        h = m.water_interval * O.dt
        if m.compiled and self.k - self.k_built < m.rebuild_interval:  # read, water, write: one compiled call
            args = m.kernel_args(h)
            _, n_sub = self._run_kernel(kernels.water_forces_step, self.io, self._xz, self.forced, self._F_out,
                                        self._dynamic, self.F_const, *args)
            m.finish_kernel_step(h, n_sub, args)
            return
        xz = self.io.positions()
        if self.k - self.k_built >= m.rebuild_interval:
            m.rebuild(xz)
            self.k_built = self.k
        m.advance(h, xz)
        self.write_forces()

    def write_forces(self):
        """The permanent forces: the last water step's pressure forces plus buoyancy."""
        self.forced.set_permanent_forces(self.model.F, self._dynamic, self.F_const)

    def pressures(self):
        """U (Np,) [N/m] of the pores at the current positions."""
        return self.model.pressures(self.io.positions())
