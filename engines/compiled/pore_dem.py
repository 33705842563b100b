"""One DEM step of the seed-000 model by compiled kernels: engines.model.pore_dem.PoreDEM on the
compiled law (engines.compiled.paper_law) and water (engines.compiled.water_model), and its steps
in YADE as calls of kernels.dem_drive_bulk_io (law_step, tie_forces, water_step when due, the
velocity adjustment, the base motion of every input: base_motion_args). No YADE."""
from collections import namedtuple

import numpy as np

from engines.compiled import kernels
from engines.compiled.paper_law import PaperLaw
from engines.compiled.params import BALANCE, balance_of, book_balance
from engines.compiled.water_model import WaterModel
from engines.model import pore_dem
from engines.model.ground_motion import Cosine, Sampled

NO_RECORD = np.zeros(0)  # the record of a Cosine input (kernels.base_step)
# what kernel_drive_args gives a kernels.dem_drive_bulk_io call (engines.yade.yade_io.drive_dem)
Drive = namedtuple("Drive", ("steps", "water_in", "water_interval", "adjust", "e", "mass", "skin", "totals", "motion",
                             "record", "args"))


class PoreDEM(pore_dem.PoreDEM):
    """engines.model.pore_dem.PoreDEM by compiled kernels; ``kernel_drive_args`` and
    ``finish_kernel_drive`` wrap a kernels.dem_drive_bulk_io call (what PaperLawEngine.drive runs:
    ``step``'s parts in its order, n steps in one call)."""

    law_class, water_class = PaperLaw, WaterModel
    CHECKPOINT_DERIVED = pore_dem.PoreDEM.CHECKPOINT_DERIVED | {"_tie_args": "the ties' kernel arguments and scratch"}

    def __init__(self, settings, packing, flat_walls=()):
        super().__init__(settings, packing, flat_walls)
        self._tie_args = kernels.no_tie_args() if self.ties is None else kernels.tie_args(self.ties)

    def pores_due(self):
        """Is step k one that ``kernel_drive_args`` leaves to the general path only for its pore
        rebuild on the interval (no rebuild_distance)? Then ``rebuild_pores`` makes it first."""
        sch = self.schedule
        return (self._law_compiled() and self.water_model is not None and not sch.by_displacement
                and sch.interval_due(self.k))

    def _law_compiled(self):
        """Can the law of step k run in kernels.law_step (after the first step, without flat walls)?"""
        return self.law.xz_prev is not None and self.law.walls is None

    def rebuild_pores(self, xz):
        """The pore rebuild of step k at its centres xz (N, 2) [m], before its law: ``step`` makes
        it after the law, which reads no pore, so the step is the same, and its law and water
        then run in one compiled call."""
        self.water_model.rebuild(xz, self.k)

    def kernel_drive_args(self, rows, held, n):
        """The Drive (steps, water_in, water_interval, adjust, e, mass, skin, totals, motion, record,
        args) of a kernels.dem_drive_bulk_io call: up to n steps from step k to the schedule's next event
        (Schedule.steps_to_event: none of them a pore rebuild), the water steps among them (the
        first water_in steps from k, then every water_interval; dry: none), whether
        the eq 18-24 adjustment is on, its restitution and the discs' masses, the skin of the pair
        lists it rebuilds [m], the water's balance so far (3,) [m^2], the base motion and its record
        (``base_motion_args``; an empty motion without one) and the arguments after F_out
        (DEM_DRIVE: the forces to write F[rows] + held, the law's, the water's, the ties'), or None
        when step k needs the general ``step``: the first step, a rebuild of the pores, every step
        with a rebuild_distance (the positions it checks are read inside the call) and every step
        with flat walls. ``finish_kernel_drive`` books what the call did."""
        law, wm = self.law, self.water_model
        if not self._law_compiled():
            return None
        sch = self.schedule
        if wm is not None and (sch.by_displacement or sch.interval_due(self.k)):
            return None
        water = kernels.dry_water_args() if wm is None else wm.kernel_args(sch.water_interval * self.dt)
        args = (rows, held) + law.kernel_args(flat=True) + water + self._tie_args  # DEM_DRIVE
        motion, *record = base_motion_args(self.base, self.wall_velocity)
        s, skin = law.settings, law.contact.skin  # no flat walls here: no pair filter
        steps = min(n, sch.steps_to_event(self.k))
        if wm is None:
            return Drive(steps, 0, 1, s.separation_adjustment, s.restitution, law.mass, skin,
                         np.zeros(len(BALANCE.names)), motion, record, args)
        b = wm.water.balance
        return Drive(steps, sch.steps_to_water(self.k), sch.water_interval, s.separation_adjustment, s.restitution,
                     law.mass, skin, balance_of(b), motion, record, args)

    def finish_kernel_drive(self, made, totals, motion):
        """Book the ``made`` steps a kernels.dem_drive_bulk_io call made with the totals and motion
        of ``kernel_drive_args``: the step index, the base motion, the water's books (but those of
        a last water step that needed sub-steps: ``finish_substeps``)."""
        k, self.k = self.k, self.k + made
        if len(motion):
            base, M = self.base, kernels.MOTION
            base.acc, base.vel, base.disp, self.wall_velocity = motion[[M.acc, M.vel, M.disp, M.wall_velocity]].tolist()
            base.k += made
        wm = self.water_model
        if wm is not None and self.schedule.water_among(k, self.k):
            book_balance(wm.water.balance, totals)
            wm.after_kernel_steps()

    def finish_substeps(self, n_sub):
        """The water's books of the last step a drive made, a water step that answered n_sub != 1
        (sub-steps; a failure raises DarcyStabilityError: engines.compiled.water_model)."""
        self.water_model.finish_kernel_step(self.schedule.water_interval * self.dt, n_sub)


def base_motion_args(base, wall_velocity):
    """(motion, t_s, a_s): the BaseMotion ``base`` as kernels.base_step advances it, with the
    wall velocity [m/s] of the last step: motion (kernels.MOTION) and the record (t_s [s], a_s
    [m/s^2]) of a Sampled input, empty for a Cosine; an empty motion for no base (None)."""
    if base is None:
        return NO_RECORD, NO_RECORD, NO_RECORD
    a = base.accel
    if isinstance(a, Cosine):
        amplitude, w, left, right, t_s, a_s = a.amplitude, a.w, 0.0, 0.0, NO_RECORD, NO_RECORD
    elif isinstance(a, Sampled):
        t_s, a_s = np.ascontiguousarray(a.t_s, float), np.ascontiguousarray(a.a_s, float)
        amplitude, w = 0.0, 0.0
        left = a_s[0] if a.left is None else a.left  # None: the end sample's value, as np.interp
        right = a_s[-1] if a.right is None else a.right
    else:
        raise TypeError(f"the input acceleration {type(a).__name__} has no compiled twin (kernels.base_step): "
                        f"give a Cosine or a Sampled record")
    motion = np.array(kernels.MOTION.values(amplitude=amplitude, w=w, left=left, right=right, dt=base.dt,
                                            acc=base.acc, vel=base.vel, disp=base.disp, wall_velocity=wall_velocity),
                      float)
    return motion, t_s, a_s
