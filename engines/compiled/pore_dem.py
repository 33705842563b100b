"""One DEM step of the seed-000 model by compiled kernels: engines.model.pore_dem.PoreDEM on the
compiled law (engines.compiled.paper_law) and water (engines.compiled.water_model), and the whole step
as one call of kernels.dem_step (law_step, tie_forces, water_step when due). No YADE."""
from engines.compiled import kernels
from engines.compiled.paper_law import PaperLaw
from engines.compiled.water_model import WaterModel
from engines.model import pore_dem


class PoreDEM(pore_dem.PoreDEM):
    """engines.model.pore_dem.PoreDEM by compiled kernels; ``kernel_step_args`` and
    ``finish_kernel_step`` wrap one kernels.dem_step call (what PaperLawEngine.drive runs)."""

    law_class, water_class = PaperLaw, WaterModel

    def __init__(self, scene, packing, flat_walls=()):
        super().__init__(scene, packing, flat_walls)
        self._tie_args = kernels.no_tie_args() if self.ties is None else kernels.TIES.values(**self.ties.kernel_args())

    def kernel_step_args(self, rows, held):
        """The arguments of kernels.dem_step after (xz, F_out) (kernels.DEM_STEP) for step k, the
        forces to write F[rows] + held, or None when this step needs the general ``step`` (the
        first step, a rebuild of the pores, every step with a rebuild_distance: the positions
        it checks are read inside the kernel call, and every step with flat walls)."""
        law, wm = self.law, self.water_model
        if law.xz_prev is None or law.walls is not None:
            return None
        if wm is None:
            return kernels.dem_step_args(rows, held, False, law.kernel_args(), kernels.dry_water_args(), self._tie_args)
        if wm.rebuild_distance > 0 or wm.rebuild_due(self.k):
            return None
        return kernels.dem_step_args(rows, held, self.k % wm.water_interval == 0, law.kernel_args(),
                                     wm.kernel_args(wm.water_interval * self.dt), self._tie_args)

    def finish_kernel_step(self, xz, n_lost, n_sub, args, vel=None):
        """The Python part of a dem_step at xz that returned (n_lost, n_sub) for ``args`` (from
        kernel_step_args): velocity fixes (eq 18-24, returned), the water's books, the walls."""
        fixes = self.law._fixes(self.law.finish_kernel_step(xz, n_lost), vel)
        if args[kernels.DEM_STEP.water_due]:
            self.water_model.finish_kernel_step(args[kernels.DEM_STEP.h], n_sub)
        self._move_walls()
        return fixes
