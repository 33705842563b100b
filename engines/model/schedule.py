"""What happens at DEM step k: the one owner of the water, pore-rebuild and output schedule.

Every stepper asks a ``Schedule``: the NumPy step (engines.model.pore_dem, engines.model.water_model),
the compiled drives (engines.compiled.kernels: given ``steps_to_event`` and the water steps in the
named form ``steps_to_water`` / ``water_interval``), the YADE engines (WaterEngine, PaperLawEngine)
and the run's hooks (engines.yade.coupling). No YADE.

One convention: steps are counted from the schedule's start k0, the step at which its model was
made (0 for a scene's run; O.iter at a WaterEngine's creation).

- Water (seed 000 §3.4(1)): due at k0 + j water_interval (j >= 0); each water step advances the
  water by water_interval dt. A new water_interval (``set_water_interval``, a WaterEngine's
  settable ``water_interval``) takes effect at the next water step n of the old one: the water
  then steps at n + j water_interval (``k_water`` = n), so each water step still covers the
  water_interval dt that follow it.
- Pore rebuild (§3.4(2), SPEC §2.6): by interval, at the first step asked at or after each
  k0 + n rebuild_interval (n >= 1) since the last build (asked at every step, the paper's law: exactly
  there; asked at water steps only, the YADE law's engine: at the first water step at or after it);
  with rebuild_distance d > 0 also by displacement (a disc more than d from its centre at the last
  build; YADE's collider keeps its Verlet lists so) and by areas (a measured void area out of its
  range, ``areas_in_range``: eq 32 would put U above E_w); the interval is then an upper bound.
- Output: due at the multiples of ``output_interval`` of the run's step index and at
  ``output_steps`` (history rows, snapshots, VTK frames, checkpoints: engines.run.runner).
"""
import math

import numpy as np


def rebuild_due(k, k_built, k0, interval):
    """Is a pore rebuild due at step k by interval, the pores last built at step k_built: has a
    multiple of ``interval`` steps counted from the start k0 been reached since?"""
    return (k - k0) // interval > (k_built - k0) // interval


def steps_to_rebuild(k, k_built, k0, interval, call_interval):
    """Steps from step k to the first step, among those k0 + j call_interval, at which
    ``rebuild_due`` holds."""
    due = k0 + ((k_built - k0) // interval + 1) * interval  # the next multiple after the last build
    t = max(k, due)
    return t + (k0 - t) % call_interval - k


def areas_in_range(void, poly):
    """Are the void areas A (Np,) [m^2] in their range 0 <= A <= polygon area poly (Np,)? Below 0
    the discs cover more than their pore's polygon, above it a sector is negative (a disc has
    crossed a link): the pores no longer describe the discs. Every pore has A > a_min > 0 at its
    build (engines.model.pores), so a rebuild brings the areas back into range."""
    return bool(np.all((void >= 0) & (void <= poly)))


class Schedule:
    """The events of one model from its start step k0 (module docstring): water_interval [steps],
    rebuild_interval [steps] (None: no pores, a dry scene's schedule), rebuild_distance [m] (> 0:
    also by displacement and areas; 0: off).
    ``k_built`` is the step of the last pore build (``built``), ``k_water`` a water step from which
    the water steps are counted (k0 until ``set_water_interval``); the output events are set by
    ``set_output`` (none until then)."""

    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("k0", "k_built", "k_water")
    CHECKPOINT_DERIVED = {
        **{name: "the scene's [numerics] (a WaterEngine's arguments)" for name in
           ("water_interval", "rebuild_interval", "rebuild_distance")},
        **{name: "set by the run (engines.run.runner.Run._schedule)" for name in ("output_interval", "output_steps")}}

    def __init__(self, water_interval=1, rebuild_interval=1000, rebuild_distance=0.0, k0=0):
        self.water_interval = int(water_interval)
        self.rebuild_interval = None if rebuild_interval is None else int(rebuild_interval)
        if (self.rebuild_interval is not None and self.rebuild_interval < 1) or self.water_interval < 1:
            raise ValueError(f"rebuild_interval and water_interval must be >= 1, got "
                             f"{rebuild_interval}, {water_interval}")
        self.rebuild_distance = float(rebuild_distance)
        if not self.rebuild_distance >= 0:
            raise ValueError(f"rebuild_distance must be >= 0 [m], got {rebuild_distance}")
        self.k0 = self.k_built = self.k_water = int(k0)
        self.output_interval, self.output_steps = 0, frozenset()

    # -- water ------------------------------------------------------------------------------------
    def water_due(self, k):
        """Does step k advance the water?"""
        return self.steps_to_water(k) == 0

    def _phase(self, k):
        """Steps from the last water step at or before step k to k (0: k is a water step)."""
        return (k - self.k_water) % self.water_interval

    def steps_to_water(self, k):
        """Steps from step k to the first water step at or after it."""
        p = self._phase(k)
        return 0 if p == 0 else self.water_interval - p

    def last_water(self, k):
        """The last water step at or before step k (k >= k0)."""
        return k - self._phase(k)

    def set_water_interval(self, water_interval, k):
        """Water every ``water_interval`` steps from the first water step at or after step k (that
        of the old interval, whose water step before it covers the steps up to it); returns that step."""
        water_interval = int(water_interval)
        if water_interval < 1:
            raise ValueError(f"water_interval must be >= 1, got {water_interval}")
        self.k_water = int(k) + self.steps_to_water(k)
        self.water_interval = water_interval
        return self.k_water

    def water_among(self, k, end):
        """Is one of the steps k, ..., end - 1 a water step?"""
        return k + self.steps_to_water(k) < end

    # -- pore rebuilds ----------------------------------------------------------------------------
    @property
    def by_displacement(self):
        """Are the pores also rebuilt by displacement and areas (rebuild_distance > 0)?"""
        return self.rebuild_distance > 0

    @property
    def moved2(self):
        """The squared rebuild distance [m^2] the compiled drive compares displacements with (0: off)."""
        return self.rebuild_distance * self.rebuild_distance

    def interval_due(self, k):
        """Is a rebuild due at step k by interval (``rebuild_due``)?"""
        return self.rebuild_interval is not None and rebuild_due(k, self.k_built, self.k0, self.rebuild_interval)

    def rebuild_due(self, k, max_sq_moved=None):
        """Is a pore rebuild due at step k: by interval, or, with rebuild_distance > 0 and the
        largest squared displacement max_sq_moved [m^2] since the last build given, by displacement?"""
        return self.interval_due(k) or (max_sq_moved is not None and self.moved_too_far(max_sq_moved))

    def moved_too_far(self, max_sq_moved):
        """Is a rebuild due by displacement: rebuild_distance > 0 and the largest squared
        displacement max_sq_moved [m^2] since the last build above its square?"""
        return self.by_displacement and max_sq_moved > self.moved2

    def areas_due(self, void, poly):
        """Is a rebuild due by areas: rebuild_distance > 0 and a void area (Np,) [m^2] out of its
        range 0 <= void <= poly (``areas_in_range``)?"""
        return self.by_displacement and not areas_in_range(void, poly)

    def built(self, k):
        """The pores were built at step k."""
        self.k_built = int(k)

    def steps_to_rebuild(self, k, water_steps_only=False):
        """Steps from step k to the first step at which a rebuild is due by interval, asked at
        every step or, with ``water_steps_only``, at the water steps only (inf: no pores)."""
        if self.rebuild_interval is None:
            return math.inf
        due = k + steps_to_rebuild(k, self.k_built, self.k0, self.rebuild_interval, 1)
        return due - k + (self.steps_to_water(due) if water_steps_only else 0)

    # -- output -----------------------------------------------------------------------------------
    def set_output(self, interval, steps=()):
        """Output due at the multiples of interval [steps] (0: none) and at the steps ``steps``."""
        self.output_interval, self.output_steps = int(interval), frozenset(int(s) for s in steps)

    def output_due(self, k):
        """Is step k an output step?"""
        return (self.output_interval > 0 and k % self.output_interval == 0) or k in self.output_steps

    def steps_to_output(self, k):
        """Steps from step k to the next output step after it (inf: none)."""
        after = [s for s in self.output_steps if s > k]
        if self.output_interval > 0:
            after.append((k // self.output_interval + 1) * self.output_interval)
        return min(after) - k if after else math.inf

    # -- the next event ---------------------------------------------------------------------------
    def steps_to_event(self, k, water_steps_only=False):
        """Steps from step k that can run without an event Python makes: up to the next rebuild by
        interval (asked at every step, or at the water steps only) or the next output step. The
        water steps and the rebuilds by displacement and areas are checked inside a compiled drive."""
        return min(self.steps_to_rebuild(k, water_steps_only), self.steps_to_output(k))
