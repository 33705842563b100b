"""Compiled (numba) per-step kernels: the paper's contact law, the pore measure, the Darcy step, the
eq 33 pressure forces, the ties, the separation adjustment, the base motion and the drives that
chain them. No YADE. One module a concept, each naming its equations:

  common        jit (cache=True, nogil, fastmath off), ``_at``, ``_beyond``
  law           contact_forces (eq 1-13, 26-27; ContactArgs), law_step (eq 17, 14c, 16c)
  pair_grid     near_pairs (the pair list) on a grid of cells (``_grid``, ``_groups``: engines.compiled.pores
                and engines.compiled.regular use them too)
  measure       measure (eq 29, 43b; LinkGeometry, Measures), turn, areas_in_range, place_wall_vertices
  darcy         permeability (eq 43), darcy_flows (eq 32, 38-43, boundaries, stability), darcy_update (eq 42),
                gershgorin_limit, substep_count
  water_step    water_step (measure, eq 45, flows, update, eq 46, sub-steps, eq 33), pressure_forces,
                flat_wall_forces; the network's buffers WATER_INTS, WATER_FLOATS read as a WaterNet
  ties          tie_forces (Fig. 27), forces_to_write
  separation    free_discs, separation_velocities (eq 18-24)
  base_motion   base_step, sampled_acceleration (MOTION)
  drives        dem_drive_bulk_io, water_drive_bulk_io, water_forces_step (BRIDGE: the bridge's C functions)

Each kernel repeats, loop by loop, the arithmetic of a readable NumPy function, which stays the
reference path and is tested against it (tests/compiled/test_kernels.py, 1e-12 relative):

  contact_forces    engines.model.contact.ContactLaw.forces          (eq 1-13, 26-27)
  measure           engines.model.pores.measure              (eq 29, 43b; ``turn`` below)
  darcy_flows       engines.model.pore_water.PoreWater.flows, _limit (eq 32, 38-43, boundaries, stability)
  darcy_update      engines.model.pore_water.PoreWater._step         (eq 42, the new U; eq 46 in water_step)
  pressure_forces   engines.model.pores.pressure_forces      (eq 33, telescoped over links)
  tie_forces        engines.model.side_walls.SideWallTies.forces    (Fig. 27, the side-wall springs)
  separation_velocities  engines.model.contact.separation_adjustment   (eq 18-24, bit for bit)
  near_pairs        engines.model.contact.ContactLaw._pairs_near    (the pair list, on a grid of cells)
  gershgorin_limit, substep_count   engines.model.limits (the Darcy check of a water step)

and per-step kernels chain them, so that a step costs one call from Python (each array passed to
a numba function costs ~0.1-0.3 us to unbox, each call ~0.5 us):

  law_step          engines.model.paper_law.PaperLaw.step    (eq 17, contact_forces, spin)
  water_step        engines.model.water_model.WaterModel.advance  (measure, flows, update, eq 32, 33)
  base_step         engines.model.ground_motion.BaseMotion.step (a Cosine, or a Sampled record by
                    ``sampled_acceleration``, np.interp's arithmetic)
  dem_drive_bulk_io engines.model.pore_dem.PoreDEM.step in YADE, its parts in its order (law_step,
                    water_step when due, forces_to_write with the side-wall ties, separation_velocities,
                    base_step), between the bridge's reads and writes: n steps, one step being n = 1
  water_forces_step engines.yade.water_engine.WaterEngine: water_step and the forces to write

Arguments by name (engines.compiled.layout): each kernel called from Python has the layout of its
parameters (``LAW = Layout.of(law_step, 1)``), and its callers build its arguments by name
(``LAW_OWN.values(xz_prev=..., ...) + (ContactArgs(...),)``); a kernel that spells out the
arguments of those it calls has its list checked to be theirs one after the other (DEM_DRIVE is
rows, held, LAW, WATER, TIES), and passes them on under their own names (tested). Arrays that
travel together are one tuple read by name (ContactArgs, LinkGeometry, Measures, the WaterNet).
The parameter vectors (prm, wp, tie_prm, balance, lam) are read by name through the layouts of
engines.compiled.params. The network's arrays of water_step are the parts of two buffers
(WATER_INTS, WATER_FLOATS), read by name as a WaterNet of views that hold no reference count
(``water_net``, ``_view``). numba's cache folder is keyed by the sources of engines/model and
engines/compiled (engines.compiled.cache), so that an edit in any of these modules, a layout or a
constant of engines.model compiles afresh.

The drives call the C functions of engines.yade.yadebulk, passed as addresses (BRIDGE; so that
this package stays cacheable and free of YADE): read, step, write and YADE's O.step() (the bridge's
steps()), many DEM steps in one call (``dem_drive_bulk_io``; ``water_drive_bulk_io`` with its water
steps between; one water step of the WaterEngine's PyRunner is a call of n = 1).

The pore measure takes each link's turn since the build with ``turn`` (a short series for the
small turns between rebuilds, else atan2) where engines.model.pores.measure calls arctan2: the same
angles to round-off, the measure 30 % cheaper. It sums each link's terms over the pores on its left
and on its right apart, as NumPy does. ``darcy_flows`` divides by E_w once per call and by
W once per pore where the NumPy flows divide each conductance, pressure and capacity: the same
values to round-off.

Sums over pairs are accumulated in the same order as np.bincount, into the same partial sums
(the i side and the j side apart), so most results are bit for bit those of NumPy. Outputs are
written into arrays the caller owns (allocated once per network or contact list). numba compiles on
first use and caches the machine code (``cache=True``); fastmath is off.
"""
from engines.compiled.kernels.law import (CONTACT, contact_forces, contact_params, ContactArgs, LAW, LAW_OWN,
    law_step, LIST_STALE, max_sq_displacement, spin_update, SPRING_CODE, stepped_state, with_pairs)
from engines.compiled.kernels.pair_grid import (_grid, _groups, _grown, near_pairs, _within)
from engines.compiled.kernels.measure import (areas_in_range, link_geometry, LinkGeometry, measure, Measures,
    new_measures, place_wall_vertices, SMALL_TURN, turn, void_areas)
from engines.compiled.kernels.darcy import (darcy_flows, darcy_update, gershgorin_limit, permeability, substep_count,
    throat_sums)
from engines.compiled.kernels.water_step import (AREAS_OUT_OF_RANGE, flat_wall_forces, _part, pressure_forces, WATER,
    WATER_FLOATS, WATER_INTS, watch_areas, water_net, water_step, WaterNet)
from engines.compiled.kernels.ties import (forces_to_write, no_tie_args, tie_args, tie_forces, TIES)
from engines.compiled.kernels.separation import free_discs, separation_velocities
from engines.compiled.kernels.base_motion import base_step, MOTION, sampled_acceleration
from engines.compiled.kernels.drives import (BRIDGE, _c_bulk_call, DEM_DRIVE, dem_drive_bulk_io, dry_water_args,
    read_bulk_io, _read_positions, water_drive_bulk_io, WATER_FORCES_STEP, water_forces_step, water_forces_step_args,
    _write_forces, write_rows_bulk_io)
