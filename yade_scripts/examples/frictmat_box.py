"""FrictMat and YADE's Cundall-Strack law at 0.5 PWaveTimeStep, a box of wall discs, the pore water.

    yade -n -x yade_scripts/examples/frictmat_box.py [--steps 5000]

Grains in hexagonal rows in a box of fixed wall spheres (a bottom row, a left and a right column)
settle dry under gravity; then the WaterEngine is added and water flows in at the bottom (q_w).
Ends with the checks: pores exist, every U <= E_w, the water balance, no grain left the box.
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__)))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
# isort: split
from yade import O, utils
from yade.wrapper import (Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
                          InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack,
                          NewtonIntegrator)

from engines.model.pore_water import WaterSettings
from engines.yade.contract import set_disc_mass
from engines.yade.water_engine import WaterEngine
from yade_scripts.examples import report

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--steps", type=int, default=5000, help="steps with the water (after 2000 dry ones)")
ap.add_argument("--transfer", choices=("paper", "conserving"), default="conserving",
                help="water at re-meshing (WaterSettings transfer; docs/ENGINE.md: what each changes)")
args = ap.parse_args()

R, RHO, N_WIDE, N_ROWS = 0.45e-3, 2700.0, 10, 8  # radius [m], density [kg/m^3], grains per row, rows
mat = O.materials.append(FrictMat(young=1e8, poisson=0.3, frictionAngle=math.radians(30), density=RHO))


def disc(x, z, fixed=False):
    b = utils.sphere((x, 0, z), R, fixed=fixed, material=mat)
    set_disc_mass(b, RHO)  # per metre of thickness, as the engine's forces are (not 4/3 pi r^3 rho)
    if not fixed:
        b.state.blockedDOFs = "yXZ"  # moves in the x-z plane, spins about y
    return O.bodies.append(b)


d = 2 * R
bottom = [disc(i * d, 0, fixed=True) for i in range(N_WIDE + 2)]
left = [disc(0, k * d, fixed=True) for k in range(1, 2 * N_ROWS)]  # walls above the bed: it heaves
right = [disc((N_WIDE + 1) * d, k * d, fixed=True) for k in range(1, 2 * N_ROWS)]
grains = [disc((i + 1 + 0.5 * (row % 2)) * d, d + row * math.sqrt(3) * R)
          for row in range(N_ROWS) for i in range(N_WIDE - row % 2)]

O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                             [Law2_ScGeom_FrictPhys_CundallStrack()]),
             NewtonIntegrator(damping=0.2, gravity=(0, 0, -9.81))]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(2000, True)  # dry settling

# the pore water, before NewtonIntegrator. The pores are rebuilt when a grain has moved l_m / 4
# since the last build (the engine's default rebuild_distance), at most 1000 steps apart
water = WaterEngine(bottom + left + right + grains, walls={"bottom": bottom, "left": left, "right": right},
                    settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=1e-4, transfer=args.transfer), l_m=1.3e-4, water_interval=5)
O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
O.run(args.steps, True)
print(f"dt {O.dt:.3g} s, {len(grains)} grains, {O.iter} steps ({O.time * 1e3:.2f} ms)")
report(water, grains, {"bottom": bottom, "left": left, "right": right})
