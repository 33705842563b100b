"""YADE glue: discs as spheres in the x-z plane, a PyRunner that calls PoreDEM every step.

Engines: ForceResetter, PyRunner (reads centres in bulk with utils.coordsAndDisplacements, calls
PoreDEM.step, adds the forces), NewtonIntegrator (gravity along -z, no numerical damping unless
asked). No collider or interaction loop: the paper's contact law is not among YADE's laws (none
has the f_max plateau of springs c and d), so it runs vectorised in engines.contact. Particles
translate in x and z only (blockedDOFs 'yXYZ'); their spin about y is integrated by PoreDEM.
Masses and inertias are per unit thickness (SPEC §1), not YADE's 4/3 pi r^3 rho.
"""
import builtins

import numpy as np
from yade import O, utils
from yade.wrapper import ForceResetter, FrictMat, NewtonIntegrator, PyRunner

from engines.pore_dem import PoreDEM, disc_masses
from engines.trajectory import Trajectory

_REGISTRY = "_pore_dem_couplings"
SHORT_RUN = 2000  # steps below which O.step() beats O.run's wait


def build_bodies(scene, packing):
    """Reset YADE and create one sphere per disc; returns the body ids (same order as packing)."""
    O.reset()
    mat = O.materials.append(FrictMat(density=scene.material.rho, label="discs"))
    mass, inertia = disc_masses(scene, packing)
    bodies = []
    for (x, z), r, mob, m, I in zip(packing.xz, packing.r, packing.mobile, mass, inertia):
        b = utils.sphere((float(x), 0.0, float(z)), float(r), fixed=not mob, material=mat, color=(0.6, 0.6, 0.6))
        b.state.mass = float(m)
        b.state.inertia = (float(I),) * 3
        if mob:
            b.state.blockedDOFs = "yXYZ"
        bodies.append(b)
    ids = O.bodies.append(bodies)
    O.dt = scene.numerics.dt
    return np.asarray(ids)


class YadeCoupling:
    """The engine behind the PyRunner: one per scene. ``hooks`` are called after each step as
    hook(coupling, xz) (for histories and snapshots); they must be cheap or check the step."""

    def __init__(self, scene, packing, newton_damping=0.0):
        self.scene, self.packing = scene, packing
        self.ids = build_bodies(scene, packing)
        self.core = PoreDEM(scene, packing)
        self.mobile_ids = self.ids[packing.mobile].tolist()
        self.moving_ids = self.ids[self.core.moving].tolist()
        self.hooks = []
        g = scene.material.g
        if self.core.water is not None:  # buoyancy: the buoyant weight of eq 34b
            up = scene.material.rho_w * np.pi * packing.r**2 * g
            for i in self.mobile_ids:
                O.forces.setPermF(i, (0.0, 0.0, float(up[i])))
        slot = getattr(builtins, _REGISTRY, None)
        if slot is None:
            slot = []
            setattr(builtins, _REGISTRY, slot)
        slot.append(self)
        O.engines = [
            ForceResetter(),
            PyRunner(command=f"{_REGISTRY}[{len(slot) - 1}].step()", iterPeriod=1, initRun=True, label="poreDEM"),
            NewtonIntegrator(gravity=(0, 0, -g), damping=newton_damping),
        ]
        self.error = None

    def positions(self):
        """Disc centres (N, 2) [m], read in bulk."""
        return np.column_stack([utils.coordsAndDisplacements(0)[0], utils.coordsAndDisplacements(2)[0]])

    def step(self):
        try:
            xz = self.positions()
            F, fixes = self.core.step(xz)
            mob = self.mobile_ids
            for i, (fx, fz) in zip(mob, F[mob].tolist()):
                O.forces.addF(i, (fx, 0.0, fz))
            for i, (vx, vz) in fixes.items():
                O.bodies[int(i)].state.vel = (float(vx), 0.0, float(vz))
            if self.moving_ids:
                v = (float(self.core.wall_velocity), 0.0, 0.0)
                for i in self.moving_ids:
                    O.bodies[i].state.vel = v
            for hook in self.hooks:
                hook(self, xz)
        except Exception as e:  # stop YADE cleanly; the caller re-raises
            self.error = e
            O.pause()

    def run(self, n_steps):
        """Run n_steps DEM steps; re-raise an error raised inside the engine.

        Short runs go step by step: O.run(n, True) waits about 40 ms for YADE's thread."""
        if n_steps <= SHORT_RUN:
            for _ in range(int(n_steps)):
                O.step()
                if self.error is not None:
                    break
        else:
            O.run(int(n_steps), True)
        if self.error is not None:
            err, self.error = self.error, None
            raise err


def simulate(scene, packing, n_steps, record_every, hooks=()):
    """Run a scene in YADE and record a Trajectory after every ``record_every`` steps
    (at t = (k + 1) dt); the recording contract is shared with engines.reference.
    ``hooks``: extra per-step hooks hook(coupling, xz) (see YadeCoupling)."""
    cp = YadeCoupling(scene, packing)
    cp.hooks.extend(hooks)
    traj = Trajectory(info={"implementation": "yade"})

    steps_left = n_steps
    while steps_left > 0:
        chunk = min(record_every, steps_left)
        cp.run(chunk)
        steps_left -= chunk
        xz = cp.positions()
        w = cp.core.water
        traj.append(O.iter * scene.numerics.dt, xz, cp.core.block_pressures(xz),
                    w.total_water() if w else np.nan, w.balance_error() if w else np.nan)
    return traj
