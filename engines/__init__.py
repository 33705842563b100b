"""The pore-water DEM of Tarumi & Hakuno (seed 000) for YADE, and the three companion models.

The packages, each importing only those before it (tests/test_layers.py checks it):

  files/      writing a file whole or not at all (temporary file, fsync, rename); one line on failure
  model/      the seed-000 physics, NumPy only, no YADE
  compiled/   its numba twins (the same arithmetic, tested equal to round-off): the kernels, and the
              model's classes by the same names (contact, paper_law, water_model, pore_dem), which
              the YADE layer and the runs use
  reference/  the independent reference, written from the paper; imports nothing of the above
  yade/       everything that talks to YADE: bulk I/O, the two engines, the water engine's contract
              (checks of the bodies it is given), the coupling, checkpoints
  seeds/      the companion models: particle_potential (seed 002), biaxial (003), sand_layer (004)
  studies/    the speed-accuracy and stability studies (their points and analysis, no YADE); the
              perturbed starts of an ensemble and its statistics (ensemble.py); seed 003's judged
              points and their intervals (biaxial_judged.py); every study's verdicts
              (tradeoffs_judged.py, liquefaction.py: the paper's trends, reconstruction.py); never
              imports yade/
  run/        a run as a user starts it: scene files, preflight, command line, runner, provenance,
              sweeps, ensembles (--starts); the cross-check's cases; the studies' runs

Outside engines/: packing/ (the Packing file format, size distributions, lattices; after
reference/), postproc/ (reads run files, draws figures; after studies/, never imports yade/ or
run/), yade_scripts/ (thin command-line scripts, scenes/ presets), tests/ (mirrors this tree).

One step k of the model (model/pore_dem.py, PoreDEM.step, the readable NumPy one; in YADE the one
compiled step, compiled/kernels/drives.py dem_drive_bulk_io, calls the same parts in the same order, n
steps a call, the bridge and the base motion of every input as its arguments (compiled/pore_dem.py
kernel_drive_args); the engines choose their path in one place, yade/paper_law_engine.py
step_path and yade/water_engine.py water_path; the YADE law skips a-c and e):
  a. displacement increments du = x_t - x_{t-dt}      model/paper_law.py        eq 1
  b. contact forces, springs a-d, eps_m               model/contact.py          eq 1-13, 25-27
  c. velocity adjustment at separation                model/contact.py          eq 18-24
  d. pores: build, measure, re-mesh rules a-d         model/pores/ (build, links, faces, measure, overlaps),
                                                      model/pore_water.py  eq 28-31
     the regular triangulation without Qhull          compiled/regular.py
     flat walls as pore boundaries (SPEC §2.6)        model/flat_walls.py
     water: pressure, Darcy flows, update, forces    model/pore_water.py, model/water_model.py
                                                                                eq 32-46
  e. spin                                             model/paper_law.py        eq 14c, 16c
  f. moving walls, side-wall ties                     model/ground_motion.py, model/side_walls.py
     its twin for every input (cosine, sampled record) compiled/kernels/base_motion.py
What happens at step k (water due, pore rebuild due by interval, displacement or areas, output due,
steps to the next event, counted from the model's start k0): model/schedule.py (Schedule), asked
by the NumPy step, the compiled drives (given its steps to the water and to the next event),
WaterEngine, PaperLawEngine and the coupling's hooks. numba's cache folder is keyed by the
sources of model/ and compiled/ (compiled/cache.py).
Stability limits (eq 52, ties, water stiffness, Darcy bound, sub-steps): model/limits.py. The start
of a run, computed once (model/start.py, Start): the walls, the discs that move and their masses, the
pores at the start as the water model builds them (flat walls included), their limits and dt = "auto";
run/preflight.py checks it and announces dt = "auto", run/runner.py and yade/coupling.py run on it;
where dt_auto_factor was validated: studies/tradeoffs.py (VALIDATED_ON).
Observables: the window porosity and block means (model/observe.py); block pressures from one
measure of the positions by the water model (WaterModel.void_area); the contact forces a step gives
without taking it (ContactLaw.touching_at: the bottom wall's normal force); the pores as a network
in OpenPNM's vocabulary, for users, snapshots and VTK: model/network_view.py. The effective stress
of the contacts (Love-Weber) by band of the bed, per disc, and the pore-pressure ratio r_u (SPEC
§2.8): model/effective_stress.py, from the contacts the step gives (PaperLaw.stress_contacts,
YadeCoupling.stress_contacts).
Kernel arguments and buffers by name: compiled/layout.py (the lists themselves in the modules of
compiled/kernels/, one concept each: law, pair_grid, measure, darcy, water_step, ties, separation,
base_motion, drives).
Parameter vectors by name (contact, water, ties, balance, Gershgorin bound): compiled/params.py,
Layouts of the settings' field lists less the fields no kernel reads. No function takes more than
12 parameters but the entry points of ENTRY_POINTS (tests/test_parameters.py): the two compiled
drives, whose argument lists are their parts' layouts checked at import (DEM_DRIVE,
WATER_FORCES_STEP), and WaterEngine.__init__, whose keywords are public (README, docs/ENGINE.md).
What a checkpoint stores of each object (its CHECKPOINT_FIELDS, and CHECKPOINT_DERIVED with reasons):
model/state.py; the file (data only, no pickle): yade/checkpoint.py; a WaterEngine's state in
YADE's own O.save/O.load (O.tags, the same format): yade/scene_save.py.

Where to add ...
  a permeability law (eq 43: k1 across a gap, k2 across a contact; k1 at the free surface, k3
    through drained walls): 3 places, the function ``permeability`` of each implementation
    (model/pore_water.py, compiled/kernels/darcy.py, reference/model.py; tests/model/test_permeability.py
    puts a toy law in the NumPy one's place). A new constant adds 4: WATER_FIELDS
    (model/pore_water.py: WaterSettings, the scene's [water] table and the kernels' WATER_PRM are
    made from it) and, in reference/model.py, its Settings field, read_settings and Water.__init__.
  a wall type (a boundary kind): one row of BOUNDARY_KINDS in model/groups.py (name; a disc group
    code, which packing files store, or a flat-wall word; what it does to a pore's water: surface,
    drained, inflow, undrained; a disc group's face). The pores' wall codes, the water's masks
    (pore_water.boundary_masks) and inflow lengths, the compiled twins (they take those masks), the
    scene's flat walls and [water] sides, packing faces, WaterEngine's ``walls``/``flat_walls`` and
    its contract read it: 1 place (tests/compiled/test_boundary_kinds.py adds a toy word and a toy
    group there and nowhere else). Besides: the independent reference (reference/model.py, its own
    codes and words: 1 file, 3-4 places) for the cross-check; a disc group the deposition should
    build, yade/deposition.py (1 place). A new action on the water (e.g. a fixed pressure) is a
    physics change: WATER and the table, PoreWater.flows, its twins (compiled/kernels/darcy.py
    darcy_flows and compiled/water_model.py) and the balance, and the reference: 5 files.
  an output column: history_columns and Recorder.row in run/runner.py (only for the scenes that
    produce it), from what the coupling (yade/coupling.py) measured at the step; its unit in
    run/history.py (UNITS) and docs/OUTPUTS.md.
  an attribute to a class of a run's state: its CHECKPOINT_FIELDS (stored) or CHECKPOINT_DERIVED
    (why not), else tests/yade/test_checkpoint_format.py fails; raise FORMAT in yade/checkpoint.py
    when the stored fields change.
  a scene option: a constant of the contact law or of the water goes into CONTACT_FIELDS
    (model/contact.py) or WATER_FIELDS (model/pore_water.py), which make both the settings class
    and the scene's table; another option the model reads into its table's field list in
    model/settings.py (walls, material, contact, water, loading, numerics, output: one typed
    dataclass each, made by model/fields.py, which checks each value once as the table is made);
    one only the run layer reads ([scene], [packing]) into SCHEMA in run/scene.py. The model is
    given the typed Settings (a validated scene's ``settings``), never the scene itself; a stability
    limit goes into model/limits.py; run/preflight.py if it needs a check before the run.
"""
import os

__version__ = "0.2.0.dev0"  # the one version: pyproject.toml reads it, every summary.json records it
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the project's folder
# the functions of more than 12 parameters (tests/test_parameters.py), "path:function"
ENTRY_POINTS = ("engines/compiled/kernels/drives.py:dem_drive_bulk_io",
                "engines/compiled/kernels/drives.py:water_drive_bulk_io",
                "engines/yade/water_engine.py:__init__")
