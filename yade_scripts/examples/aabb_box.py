"""The classic YADE box of utils.aabbWalls as the pores' flat walls: FrictMat, the Cundall-Strack law,
inflow through the bottom wall.

    yade -n -x yade_scripts/examples/aabb_box.py [--steps 5000] [--q-w 1e-5]

Grains in hexagonal rows in the four in-plane boxes of aabbWalls (its front and back boxes, facing
along y, are left out of the water) settle dry under gravity; then the WaterEngine is added with the
bottom box as the inflow wall (flat_walls) and water flows in. Ends with the checks (pores, every
U <= E_w, the water balance, no grain out of the box) and the walls' vertical reactions (YADE's
contact forces on the boxes plus the water's push, WaterEngine.wall_forces) against the bed's
buoyant weight.
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__)))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
# isort: split
from yade import O, utils
from yade.wrapper import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                          Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)

from engines.model.pore_water import WaterSettings
from engines.yade.contract import set_disc_mass
from engines.yade.water_engine import WaterEngine
from yade_scripts.examples import report, wall_balance

R, RHO, N_WIDE, N_ROWS = 0.45e-3, 2700.0, 10, 8  # radius [m], density [kg/m^3], grains per row, rows


def build_box():
    """A fresh scene: the six boxes of aabbWalls, the grains in hexagonal rows on the bottom one,
    the engines and O.dt = 0.5 PWaveTimeStep; (bottom, left, right, grains) ids."""
    O.reset()
    mat = O.materials.append(FrictMat(young=1e8, poisson=0.3, frictionAngle=math.radians(30), density=RHO))
    d = 2 * R
    walls = utils.aabbWalls([(0, -2 * R, 0), (N_WIDE * d, 2 * R, 2 * N_ROWS * d)], thickness=d, material=mat)
    left, right, front, back, bottom, top = (O.bodies.append(w) for w in walls)  # front, back: clear of the discs

    def disc(x, z):
        b = utils.sphere((x, 0, z), R, material=mat)
        set_disc_mass(b, RHO)  # per metre of thickness, as the engine's forces are (not 4/3 pi r^3 rho)
        b.state.blockedDOFs = "yXZ"  # moves in the x-z plane, spins about y
        return O.bodies.append(b)

    grains = [disc((i + 0.5 + 0.5 * (row % 2)) * d, R * 1.01 + row * math.sqrt(3) * R)
              for row in range(N_ROWS) for i in range(N_WIDE - row % 2)]
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                                 [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
                 NewtonIntegrator(damping=0.2, gravity=(0, 0, -9.81))]
    O.dt = 0.5 * utils.PWaveTimeStep()
    return bottom, left, right, grains


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=5000, help="steps with the water (after 3000 dry ones)")
    ap.add_argument("--q-w", type=float, default=1e-5, help="inflow into each pore on the bottom wall [m^2/s]")
    args = ap.parse_args()
    bottom, left, right, grains = build_box()
    O.run(3000, True)  # dry settling
    # the pore water, before NewtonIntegrator: the bottom box lets the water in, the sides are closed
    water = WaterEngine(grains, walls={}, flat_walls={bottom: "inflow", left: "undrained", right: "undrained"},
                        settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=args.q_w, transfer="conserving"),
                        l_m=1.3e-4, water_interval=5)
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
    O.run(args.steps, True)
    print(f"dt {O.dt:.3g} s, {len(grains)} grains, {O.iter} steps ({O.time * 1e3:.2f} ms)")
    report(water, grains)
    wall_balance(water, grains, [bottom, left, right])


if __name__ == "__main__":
    main()
