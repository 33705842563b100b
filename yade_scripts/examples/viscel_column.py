"""A plain YADE script (spheres, YADE's collider and contact law, O.run) with the pore water added.

    yade -n -x yade_scripts/examples/viscel_column.py [--steps 20000] [--water-interval 10]

A small saturated column in the x-z plane: a box of fixed wall spheres, grains stacked in it,
ViscElMat / Law2_ScGeom_ViscElPhys_Basic. Water flows in at the bottom (q_w, as in the quick
sand); the WaterEngine builds the pores, exchanges the water and pushes the grains every
``water_interval`` steps. Prints the mean pore pressure of the bottom and surface pores, then the
checks: pores exist, every U <= E_w, the water balance, no grain left the box.
"""
import argparse
import math
import os
import sys

# the project's folder first: `yade -x` puts only YADE's folders on sys.path
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0] if __name__ == "__main__" else __file__)))))

import engines.yade  # noqa: F401  (first: closes the console and XML-RPC server YADE opened, engines/yade/listeners.py)
# isort: split
import numpy as np
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
    ViscElMat,
)

from engines.model.pore_water import WaterSettings
from engines.yade.contract import set_disc_mass
from engines.yade.water_engine import WaterEngine
from engines.yade.yade_io import freeze_gc, raise_pending
from yade_scripts.examples import report

R, RHO = 0.45e-3, 2700.0  # grain radius [m], density [kg/m^3]


def disc(x, z, material, fixed=False):
    """A sphere kept in the x-z plane, with per-unit-thickness mass and inertia (SPEC §1)."""
    b = utils.sphere((x, 0.0, z), R, fixed=fixed, material=material)
    set_disc_mass(b, RHO)
    if not fixed:
        b.state.blockedDOFs = "yXZ"
    return O.bodies.append(b)


def build_column(n_wide=10, n_rows=8):
    """Wall spheres (bottom row, left and right columns) and grains in hexagonal rows; returns the
    id lists (bottom, left, right, grains)."""
    O.reset()
    # pair stiffness kn = 1.4e5 N/m: YADE puts two ViscElMat in series, so each gets twice that
    mat = O.materials.append(ViscElMat(kn=2.8e5, ks=7e4, cn=5.2, cs=1.2, frictionAngle=math.atan(1.0), density=RHO))
    d = 2 * R
    bottom = [disc(i * d, 0.0, mat, fixed=True) for i in range(n_wide + 2)]
    left = [disc(0.0, k * d, mat, fixed=True) for k in range(1, n_rows + 2)]
    right = [disc((n_wide + 1) * d, k * d, mat, fixed=True) for k in range(1, n_rows + 2)]
    grains = []
    for row in range(n_rows):
        odd = row % 2
        for i in range(n_wide - odd):
            grains.append(disc((i + 1 + 0.5 * odd) * d, d + row * math.sqrt(3) * R, mat))
    return bottom, left, right, grains


def engines():
    """YADE's own engine list: its collider, the ViscEl law, gravity."""
    return [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
            InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_ViscElMat_ViscElMat_ViscElPhys()],
                            [Law2_ScGeom_ViscElPhys_Basic()]),
            NewtonIntegrator(gravity=(0, 0, -9.81))]


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--water-interval", type=int, default=10)
    args = ap.parse_args(argv)

    bottom, left, right, grains = build_column()
    O.engines = engines()
    O.dt = 1e-6

    # the pore water, in a few lines: disc ids, wall groups, water constants; the runner goes
    # after the InteractionLoop and before NewtonIntegrator. The pores are rebuilt when a grain
    # has moved l_m / 4 since the last build (the default rebuild_distance)
    water = WaterEngine(bottom + left + right + grains, walls={"bottom": bottom, "left": left, "right": right},
                        settings=WaterSettings(E_w=240.0, k1=200.0, k2=2.0, q_w=5e-4, transfer="conserving"), l_m=1.3e-4,
                        water_interval=args.water_interval)
    O.engines = O.engines[:-1] + [water.runner(), O.engines[-1]]
    freeze_gc()  # optional: keeps Python's garbage collector off the scene's objects (faster writes)

    O.run(args.steps, True)  # or, with no runner added, water.drive(args.steps): no PyRunner dispatch
    raise_pending()  # optional: raise an error of the water engine here (else the script exits with status 1)
    net, U = water.model.water.net, water.pressures()
    print(f"{len(grains)} grains, {net.n_pores} pores after {O.iter} steps ({O.time * 1e3:.1f} ms): "
          f"mean U bottom pores {np.mean(U[net.pore_touches['bottom']]):.1f} N/m, "
          f"surface pores {np.mean(U[net.pore_surface]):.1f} N/m")
    report(water, grains, {"bottom": bottom, "left": left, "right": right})
    return water


if __name__ == "__main__":
    main(sys.argv[1:])
