"""A packing from YADE's pack.SpherePack().makeCloud turned into discs, the pore water added.

    yade -n -x yade_scripts/examples/makecloud_discs.py [--steps 5000]

makeCloud with a box of zero thickness along y gives a 2D cloud of spheres in the x-z plane;
they become discs (per-thickness masses, kept in the plane) in a box of fixed wall discs,
fall and settle dry with FrictMat and the Cundall-Strack law, then water flows in at the bottom.
Ends with the checks: pores exist, every U <= E_w, the water balance, no grain left the box.
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__)))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
# isort: split
from yade import O, pack, utils
from yade.wrapper import (Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
                          InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack,
                          NewtonIntegrator)

from engines.model.pore_water import WaterSettings
from engines.yade.contract import set_disc_mass
from engines.yade.water_engine import WaterEngine
from yade_scripts.examples import report

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--steps", type=int, default=5000, help="steps with the water (after 6000 dry ones)")
args = ap.parse_args()

R, RHO, W, H = 0.45e-3, 2700.0, 10e-3, 12e-3  # mean radius [m], density [kg/m^3], box width and height [m]
mat = O.materials.append(FrictMat(young=1e8, poisson=0.3, frictionAngle=math.radians(30), density=RHO))


def disc(x, z, r, fixed=False):
    b = utils.sphere((x, 0, z), r, fixed=fixed, material=mat)
    set_disc_mass(b, RHO)  # per metre of thickness, as the engine's forces are (not 4/3 pi r^3 rho)
    if not fixed:
        b.state.blockedDOFs = "yXZ"  # moves in the x-z plane, spins about y
    return O.bodies.append(b)


n = int(W / (2 * R))  # wall discs of radius R touching each other, the grains' box inside them
bottom = [disc(i * 2 * R, 0, R, fixed=True) for i in range(n + 2)]
left = [disc(0, k * 2 * R, R, fixed=True) for k in range(1, int(H / (2 * R)))]
right = [disc((n + 1) * 2 * R, k * 2 * R, R, fixed=True) for k in range(1, int(H / (2 * R)))]
cloud = pack.SpherePack()
cloud.makeCloud((2 * R, 0, 2 * R), (n * 2 * R, 0, H), rMean=R, rRelFuzz=0.2, seed=1)  # y extent 0: a 2D cloud
grains = [disc(c[0], c[2], r) for c, r in cloud]

O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                             [Law2_ScGeom_FrictPhys_CundallStrack()]),
             NewtonIntegrator(damping=0.2, gravity=(0, 0, -9.81))]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(6000, True)  # the cloud falls and settles dry

# the pore water, before NewtonIntegrator. In this loose packing the water sets grains moving up
# to 0.15 m/s (dt 4.3e-5 s): rebuilt every 10 steps they moved up to 0.54 l_m on one mesh, so the
# water steps and rebuilds are every step (at most 6.4e-6 m = 0.05 l_m between two, measured
# over the default run)
water = WaterEngine(bottom + left + right + grains, walls={"bottom": bottom, "left": left, "right": right},
                    settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=1e-4, transfer="conserving"), l_m=1.3e-4,
                    rebuild_interval=1, water_interval=1)
O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
O.run(args.steps, True)
print(f"dt {O.dt:.3g} s, {len(grains)} grains from makeCloud, {O.iter} steps ({O.time * 1e3:.2f} ms)")
report(water, grains, {"bottom": bottom, "left": left, "right": right})
