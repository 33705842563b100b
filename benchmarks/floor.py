"""YADE alone, dry: the floor our costs are measured against (DEVELOPERS.md)."""
import time

from yade import O, utils
from yade.wrapper import (
    Bo1_Sphere_Aabb,
    ForceResetter,
    Ig2_Sphere_Sphere_ScGeom,
    InsertionSortCollider,
    InteractionLoop,
    Ip2_ViscElMat_ViscElMat_ViscElPhys,
    Law2_ScGeom_ViscElPhys_Basic,
    NewtonIntegrator,
)

from engines.model.pore_dem import disc_masses
from engines.yade import coupling
from engines.yade.coupling import run_blocking, yade_law_material


def native_floor(scene, packing, undamped=True):
    """The same discs in plain YADE with its collider and its native linear spring-dashpot law
    (ViscElMat / Law2_ScGeom_ViscElPhys_Basic with the scene's kn, eta_n, ks, eta_s, mu: the same
    pair constants as [contact] law = "yade"), radii enlarged by eps_m/2 so the same pairs touch as
    with the paper's eps_m (eq 26). No Python engine. NewtonIntegrator as in our scenes: damping 0,
    its damping pass off on every body (engines.yade.coupling.undamped; ``undamped=False``:
    YADE's default, the pass on)."""
    O.reset()
    mat = O.materials.append(yade_law_material(scene))
    mass, inertia = disc_masses(scene.settings, packing)
    grow = 0.5 * scene.contact.eps_m
    for (x, z), r, mob, m, I in zip(packing.xz, packing.r, packing.mobile, mass, inertia):
        b = utils.sphere((float(x), 0.0, float(z)), float(r + grow), fixed=not mob, material=mat, color=(0.5, 0.5, 0.5))
        b.state.mass, b.state.inertia = float(m), (float(I),) * 3
        if mob:
            b.state.blockedDOFs = "yXZ"
        O.bodies.append(b)
    newton = NewtonIntegrator(gravity=(0, 0, -scene.material.g), damping=0.0)
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_ViscElMat_ViscElMat_ViscElPhys()],
                                 [Law2_ScGeom_ViscElPhys_Basic()]), newton]
    if undamped:
        coupling.undamped(newton)
    O.dt = scene.numerics.dt


def step_by_step(n):
    """Advance YADE n steps from Python, without starting YADE's thread (few steps)."""
    for _ in range(n):
        O.step()


def run_steps(n):
    """Advance YADE n steps the way YadeCoupling runs a scene without per-step Python."""
    if n > 1000:
        run_blocking(n)
    else:
        step_by_step(n)


def per_step(steps, run, warmup=200):
    """Microseconds per step of run(steps), after run(warmup)."""
    run(warmup)
    t0 = time.perf_counter()
    run(steps)
    return 1e6 * (time.perf_counter() - t0) / steps
