"""YADE glue for scenes: discs as spheres in the x-z plane, the scene's contact law, the water engine.

[contact] law = "paper" (the presets): NewtonIntegrator, then ForceResetter; before each O.step()
``run`` drives the PaperLawEngine (engines.model.paper_law; it calls PoreDEM.step: the paper's law,
spin, the water in the paper's order), adds its forces plus buoyancy to the forces ForceResetter
reset at the end of the last step (no permanent forces: they cost YADE a sync pass over all bodies
every step; O.forces reads 0 between steps) and sets the velocity of the walls that follow the
input: no PyRunner (its dispatch costs ~50 us a call), and between pore rebuilds many steps in
one compiled call with the bridge (PaperLawEngine.drive). No collider: the law keeps its own
Verlet list.
Discs translate only (blockedDOFs 'yXYZ'); their spin about y is integrated by the law. Run these
scenes with ``YadeCoupling.run``, not O.run.

[contact] law = "yade" (springs a, b only): YADE's InsertionSortCollider and InteractionLoop with
ViscElMat / Law2_ScGeom_ViscElPhys_Basic, the wall motion, NewtonIntegrator; discs spin about y
in YADE (blockedDOFs 'yXZ'). The WaterEngine (engines.yade.water_engine; pressure forces and buoyancy
held as permanent forces) is called before O.step() every water_interval steps (WaterEngine.drive),
the work its PyRunner would do, without the PyRunner's dispatch. A dry scene runs no Python at all
(O.run, ``run_blocking``).
With [walls] kind = "flat" (law = "yade" only) the packing's wall discs are left out and fixed YADE
boxes of the discs' material stand at their inner faces (``wall_boxes``; Ig2_Box_Sphere_ScGeom):
the WaterEngine's flat walls (engines.model.pore_dem.scene_flat_walls), whose loads ``wall_loads`` reads.
The mapping to eq 1-13 and what differs: see ``yade_law_material``.
Each law's side of the coupling is one class with one interface (PaperLawDrive, YadeLawDrive; LAWS
by [contact] law), chosen once by YadeCoupling, which never asks the law's name.

Masses and inertias are per unit thickness (SPEC §1), not YADE's 4/3 pi r^3 rho. Runs go in chunks
of O.step() calls where Python works every step, or of blocking O.run calls of about CHUNK_SECONDS
without per-step Python; ``run(n, stop)`` asks ``stop()`` after every step (O.run: every chunk; the
paper's law's compiled runs of steps: after each) and returns early when it is true
(engines.run.runner: SIGINT, SIGTERM). A checkpoint (engines.yade.checkpoint) stores the fields
each class of the coupling lists (CHECKPOINT_FIELDS, engines.model.state) and YADE's bodies.
"""
import math
import time

import numpy as np
from yade import O, utils
from yade.wrapper import (
    Bo1_Box_Aabb,
    Bo1_Sphere_Aabb,
    ForceResetter,
    FrictMat,
    Ig2_Box_Sphere_ScGeom,
    Ig2_Sphere_Sphere_ScGeom,
    InsertionSortCollider,
    InteractionLoop,
    Ip2_ViscElMat_ViscElMat_ViscElPhys,
    Law2_ScGeom_ViscElPhys_Basic,
    NewtonIntegrator,
    TranslationEngine,
    ViscElMat,
)

from engines.model import effective_stress, ground_motion, limits, pore_dem
from engines.model import pores as pg
from engines.compiled import pore_dem as compiled_pore_dem
from engines.model.pore_dem import PoreDEM, disc_masses
from engines.model.pore_water import buoyancy
from engines.model.schedule import Schedule
from engines.model.start import Start
from engines.reference.trajectory import Trajectory
from engines.yade import yade_io
from engines.yade.paper_law_engine import PaperLawEngine
from engines.yade.walls import PLANE_AXES
from engines.yade.water_engine import WaterEngine

PER_STEP_CHUNK = 1000  # steps between the run loop's checks of a per-step run (errors, stop)
CHUNK_SECONDS = 0.2    # wall time of one blocking O.run (a stop's latency)
POLL_SECONDS = 1e-3    # run_blocking's poll of YADE's thread
X_ONLY = "yzXYZ"       # blockedDOFs of the side-wall discs on springs: they move in x only


def run_blocking(n):
    """O.run(n, True) without its wait's 40 ms poll (measured: a call returns 0-40 ms after YADE
    stops): poll O.running every POLL_SECONDS. An engine that fails stops YADE early, as with
    O.run (our callbacks keep their errors for yade_io.raise_pending)."""
    O.run(int(n))
    while O.running:
        time.sleep(POLL_SECONDS)
    O.wait()


def yade_law_material(scene):
    """ViscElMat whose pair constants are the paper's springs (a)/(b): YADE combines two materials
    in series (k = k1 k2 / (k1 + k2)), so each material gets twice the pair value.

    Law2_ScGeom_ViscElPhys_Basic against eq 1-13: the same linear spring kn and dashpot eta_n in
    normal, incremental ks with dashpot eta_s and the Coulomb cap mu e_n in shear. It differs in
    (1) tension: YADE clamps the total normal force kn u_n + eta_n v_n at zero, eq 6 keeps the
    dashpot's tension while e_n >= 0 (head-on collision: restitution 0.798 against 0.789 for eq 4-6,
    0.790 analytic), and YADE's Coulomb cap uses that total force, eq 11 uses e_n; (2) the rolling term:
    YADE's shear increment takes the relative velocity at the contact point with lever arms
    r - u_n/2 of the enlarged radii, eq 3b uses r_i dpsi_i + r_j dpsi_j; (3) no velocity
    adjustment at separation (eq 18-24); (4) eps_m (spring b) acts through radii enlarged by
    eps_m/2, so YADE's overlap is r_i + r_j + eps_m - R as in eq 26, while the pores use the true
    radii; (5) YADE rotates the shear force with the contact and integrates spin itself.
    """
    c = scene.contact
    return ViscElMat(kn=2 * c.kn, ks=2 * c.ks, cn=2 * c.eta_n, cs=2 * c.eta_s, frictionAngle=math.atan(c.mu),
                     density=scene.material.rho, label="discs")


def undamped(newton):
    """With NewtonIntegrator's damping 0 its damping of each body's accelerations multiplies them by
    exactly 1: switch it off on every body (State.isDamped; bit for bit the same run, ~25 % of
    YADE's step on the seismic discs)."""
    if newton.damping == 0:
        for b in O.bodies:
            b.state.isDamped = False


def build_bodies(scene, packing, material, radius_add=0.0, spin=False, x_only=None):
    """Reset YADE and create one sphere per disc (radius r + radius_add) with per-unit-thickness
    mass and inertia; returns the body ids (same order as packing). ``x_only`` (N,) bool: wall
    discs that are dynamic in x only (the side walls on springs, Fig. 27)."""
    O.reset()
    mat = O.materials.append(material)
    mass, inertia = disc_masses(scene.settings, packing)
    x_only = np.zeros(len(packing.r), bool) if x_only is None else x_only
    bodies = []
    for (x, z), r, mob, xo, m, I in zip(packing.xz, packing.r, packing.mobile, x_only, mass, inertia):
        b = utils.sphere((float(x), 0.0, float(z)), float(r + radius_add), fixed=not (mob or xo), material=mat,
                         color=(0.6, 0.6, 0.6))
        b.state.mass = float(m)
        b.state.inertia = (float(I),) * 3
        if mob:
            b.state.blockedDOFs = "yXZ" if spin else "yXYZ"
        elif xo:
            b.state.blockedDOFs = X_ONLY
        bodies.append(b)
    ids = O.bodies.append(bodies)
    O.dt = scene.numerics.dt
    return np.asarray(ids, np.int64)


def wall_boxes(walls, packing, material):
    """Fixed YADE boxes of ``material`` whose inner faces are the flat walls {wall code: FlatWall}
    around the discs of ``packing``; returns {wall code: body id}. Each is 2 max(r) thick along its
    normal, 4 max(r) along y and 4 x the packing's size along its face, centred on the packing: it
    reaches past the other walls and 1.5 x the packing's size above the packing's top."""
    h = 2 * float(packing.r.max())
    lo = (packing.xz - packing.r[:, None]).min(axis=0)
    hi = (packing.xz + packing.r[:, None]).max(axis=0)
    centre, size = 0.5 * (lo + hi), float((hi - lo).max())
    ids = {}
    for code, wall in walls.items():
        along = 1 - wall.axis  # the in-plane axis along the face
        pos, half = np.zeros(3), np.full(3, h)
        pos[PLANE_AXES[wall.axis]] = wall.position - wall.inward * 0.5 * h
        half[PLANE_AXES[wall.axis]] = 0.5 * h
        pos[PLANE_AXES[along]], half[PLANE_AXES[along]] = centre[along], 2 * size
        ids[code] = O.bodies.append(utils.box(tuple(pos), tuple(half), fixed=True, material=material,
                                              color=(0.4, 0.4, 0.6)))
    return ids


class PaperLawDrive:
    """[contact] law = 'paper': the core (PoreDEM, compiled or NumPy: the paper's law, spin, the
    water in the paper's order) driven by the PaperLawEngine before each O.step, between pore
    rebuilds in compiled runs of steps; NewtonIntegrator then ForceResetter, no collider. The
    coupling's side of one contact law (YadeLawDrive is the other): the bodies, YADE's engines,
    the wall motion, the run of n steps and what the law measures."""

    name = "paper"
    wall_engine = None  # the engine moves the walls itself (move_walls)
    CHECKPOINT_FIELDS = ()  # its parts are the coupling's fields (YadeCoupling.core, engine, base)
    CHECKPOINT_DERIVED = {
        **{name: "its owner's part (YadeCoupling), stored there" for name in ("core", "engine", "water_engine")},
        **{name: "the scene and the packing" for name in ("ids", "wall_ids")}}

    def __init__(self, scene, prepared, compiled):
        packing, flat_walls = prepared.packing, tuple(prepared.flat_walls.values())
        self.core = (compiled_pore_dem.PoreDEM if compiled else PoreDEM)(scene.settings, packing, flat_walls)
        self.water_engine = None
        self.wall_ids = {}  # the core's flat walls are no YADE bodies
        x_only = self.core.ties.moving if self.core.ties is not None else None
        self.ids = build_bodies(scene, packing, FrictMat(density=scene.material.rho, label="discs"), x_only=x_only)
        self.engine = PaperLawEngine(self.ids, core=self.core)
        for i in self.ids[x_only].tolist() if x_only is not None else ():
            O.bodies[i].state.blockedDOFs = X_ONLY  # the engine set 'yXYZ' on every dynamic body
        if scene.water.enabled:  # buoyancy: the buoyant weight of eq 34b, held with the law's forces (particles only)
            dyn = self.engine._dynamic
            self.engine.held[:, 1] = buoyancy(packing.r[dyn], scene.material.rho_w, scene.material.g) * packing.mobile[dyn]

    @property
    def schedule(self):
        return self.core.schedule

    @property
    def water_model(self):
        return self.core.water_model

    @property
    def ties(self):
        """The side-wall ties (engines.model.loading.SideWallTies) or None."""
        return self.core.ties

    def yade_engines(self, newton, walls):
        """O.engines: forces reset after the integration, the engine adds the next step's (no sync pass)."""
        newton.warnNoForceReset = False
        return [newton, ForceResetter()]

    def base_motion(self, scene):
        """The base motion of a scene with [loading]: the core's, which moves its own flat walls."""
        return self.core.base

    def move_walls(self, ids):
        """The bodies ``ids`` follow the base: the engine sets their velocities before each O.step
        (PaperLawEngine.drive_walls); no YADE engine."""
        self.engine.drive_walls(ids)
        return []

    def per_step(self, base):
        return True

    def advance(self, n, stop, base):
        self.engine.drive(n, stop)

    def restore_forces(self):
        """No permanent forces: the engine adds its forces before each O.step."""

    def spins(self, io):
        return self.core.omega

    def contact_pairs(self, xz, keep):
        return self.core.law.contact_pairs(xz, keep)

    def stress_contacts(self, xz, packing):
        """The paper's law's own contacts, its flat walls' feet included (PaperLaw.stress_contacts)."""
        return self.core.law.stress_contacts(xz)

    def wall_loads(self, flat_walls):
        """{wall name: (contact, water)}: the law's own contacts and water on its flat walls."""
        if not flat_walls:
            return {}
        wm = self.core.water_model
        water = wm.F_walls if wm is not None else np.zeros(len(flat_walls))
        return {pg.WALL_NAMES[code]: (float(c), float(u))
                for code, c, u in zip(flat_walls, self.core.law.wall_forces(), water)}


class YadeLawDrive:
    """[contact] law = 'yade' (springs a, b only): YADE's InsertionSortCollider and InteractionLoop
    with ViscElMat / Law2_ScGeom_ViscElPhys_Basic (``yade_law_material``), flat walls as fixed
    boxes (``wall_boxes``), the walls that follow the input on a TranslationEngine, the
    WaterEngine called before O.step on its steps (a dry scene without a moving base runs no
    Python: blocking O.run chunks). The interface of PaperLawDrive."""

    name = "yade"
    CHECKPOINT_FIELDS = ()  # its parts are the coupling's fields (YadeCoupling.water_engine, base)
    CHECKPOINT_DERIVED = {
        **{name: "its owner's part (YadeCoupling), stored there" for name in ("core", "engine", "water_engine", "base")},
        **{name: "the scene and the packing" for name in ("ids", "wall_ids")},
        "wall_engine": "YADE's TranslationEngine, built from the scene; its velocity is set before each step",
        "_chunk": "the steps of the next blocking O.run, adapted to the wall time: how steps are grouped, not what "
                  "they compute"}

    def __init__(self, scene, prepared, compiled):
        packing = prepared.packing
        limits.check_contact(scene.numerics.dt, scene.numerics.dt_safety, prepared.mass[packing.mobile], scene.contact.kn)
        material = yade_law_material(scene)
        self.ids = build_bodies(scene, packing, material, 0.5 * scene.contact.eps_m, spin=True)
        self.wall_ids = wall_boxes(prepared.flat_walls, packing, material)  # {wall code: YADE body id}
        self.core = self.engine = self.base = self.wall_engine = None
        self.water_engine = self._water_engine(scene, prepared, compiled) if scene.water.enabled else None
        self._chunk = PER_STEP_CHUNK  # steps of the next blocking O.run, adapted to CHUNK_SECONDS

    def _water_engine(self, scene, prepared, compiled):
        """The WaterEngine of the discs and the flat walls' boxes, called before O.step on its steps
        (see ``advance``), not as a PyRunner."""
        num, packing = scene.numerics, prepared.packing
        walls = {name: self.ids[packing.group == code].tolist() for code, name in pg.WALL_NAMES.items()}
        return WaterEngine(self.ids, walls, scene.water_settings(), scene.water.l_m, scene.contact.eps_m, packing.r,
                           num.rebuild_interval, num.water_interval, True, scene.material.rho_w, scene.material.g,
                           compiled, rebuild_distance=num.rebuild_distance,
                           flat_walls={i: prepared.flat_walls[code].boundary for code, i in self.wall_ids.items()})

    @property
    def schedule(self):
        """The water engine's model's; a dry scene's has output only."""
        return self.water_engine.model.schedule if self.water_engine is not None else Schedule(rebuild_interval=None)

    @property
    def water_model(self):
        return self.water_engine.model if self.water_engine else None

    ties = None  # the side-wall ties run in the paper's law engine only (engines.run.scene)

    def yade_engines(self, newton, walls):
        boxes = bool(self.wall_ids)
        loop = [InsertionSortCollider([Bo1_Sphere_Aabb()] + ([Bo1_Box_Aabb()] if boxes else [])),
                InteractionLoop([Ig2_Sphere_Sphere_ScGeom()] + ([Ig2_Box_Sphere_ScGeom()] if boxes else []),
                                [Ip2_ViscElMat_ViscElMat_ViscElPhys()], [Law2_ScGeom_ViscElPhys_Basic()])]
        return [ForceResetter()] + loop + walls + [newton]

    def base_motion(self, scene):
        """The base motion, its velocity set on the TranslationEngine before each O.step."""
        self.base = ground_motion.BaseMotion(ground_motion.input_acceleration(scene.settings), scene.numerics.dt)
        return self.base

    def move_walls(self, ids):
        """A TranslationEngine of the bodies ``ids``, its velocity set before each O.step."""
        self.wall_engine = TranslationEngine(ids=ids, translationAxis=(1, 0, 0), velocity=0.0)
        return [self.wall_engine]

    def per_step(self, base):
        """Does Python work every step (the water engine, the base velocity)?"""
        return self.water_engine is not None or base is not None

    def advance(self, n, stop, base):
        water, errors = self.water_engine, yade_io.ERRORS
        if not self.per_step(base) and n > PER_STEP_CHUNK:
            done = 0
            while done < n and not stop():  # blocking chunks: YADE is idle whenever Python looks
                m = min(int(n) - done, self._chunk)
                t0 = time.perf_counter()
                run_blocking(m)
                done += m
                if m == self._chunk:
                    self._chunk = int(min(max(m * CHUNK_SECONDS / max(time.perf_counter() - t0, 1e-6), PER_STEP_CHUNK), 1e6))
        elif base is None and water is not None:  # wet: water before O.step on its steps
            water.drive(n, None if stop is _never else stop)
        else:  # the base velocity of each step, the water engine on its steps
            for _ in range(int(n)):
                if water is not None and water.due(O.iter):
                    water()
                if base is not None:
                    self.wall_engine.velocity = base.step()
                O.step()
                if errors or stop():
                    break

    def restore_forces(self):
        """After a checkpoint's O.load: the water engine's permanent forces, which O.save does not keep."""
        if self.water_engine is not None:
            self.water_engine.write_forces()

    def spins(self, io):
        return io.spins()

    def contact_pairs(self, xz, keep):
        index = {i: k for k, i in enumerate(self.ids.tolist())}
        pairs, fn, fs = [], [], []
        for inter in O.interactions:
            if inter.isReal and inter.id1 in index and inter.id2 in index:
                i, j = index[inter.id1], index[inter.id2]
                pairs.append((i, j))
                fn.append(inter.phys.normalForce.norm())
                d = xz[j] - xz[i]
                t = np.array([-d[1], d[0]]) / np.hypot(*d)  # (-sin a, cos a)
                s = inter.phys.shearForce  # YADE's force on id2; eq 13 puts -f_s t on i, so +f_s t on j
                fs.append(s[0] * t[0] + s[2] * t[1])
        pairs, fn, fs = np.array(pairs, np.int64).reshape(-1, 2), np.array(fn), np.array(fs)
        if keep is None:
            return pairs, fn, fs
        sel = keep(pairs[:, 0], pairs[:, 1])
        return pairs[sel], fn[sel], fs[sel]

    def stress_contacts(self, xz, packing):
        """With YADE's law: the pairs of ``contact_pairs`` (wall discs counted for their particle) and
        the contacts with the flat walls' boxes at YADE's contact point, with the force YADE puts on
        the disc (normalForce + shearForce on id2)."""
        c = effective_stress.pair_contacts(xz, packing.r, *self.contact_pairs(xz, None), packing.mobile)
        index = {i: k for k, i in enumerate(self.ids.tolist())}
        disc, point, force = [], [], []
        for box in self.wall_ids.values():
            for inter in O.interactions.withBody(box):
                if inter.isReal:
                    other = inter.id2 if inter.id1 == box else inter.id1
                    f = (inter.phys.normalForce + inter.phys.shearForce) * (1.0 if inter.id2 == other else -1.0)
                    disc.append(index[other])
                    point.append((inter.geom.contactPoint[0], inter.geom.contactPoint[2]))
                    force.append((f[0], f[2]))
        if not disc:
            return c
        return c + effective_stress.Contacts(np.array(disc, np.int64), np.array(point, float), np.array(force, float))

    def wall_loads(self, flat_walls):
        """{wall name: (contact, water)}: YADE's contacts on each box and the water engine's push."""
        pushed = self.water_engine.wall_forces() if self.water_engine is not None else {}
        loads = {}
        for code, i in self.wall_ids.items():
            contact = sum(inter.phys.normalForce.norm() for inter in O.interactions.withBody(i) if inter.isReal)
            water = float(np.dot(pushed[i], -flat_walls[code].normal())) if i in pushed else 0.0
            loads[pg.WALL_NAMES[code]] = (float(contact), water)
        return loads


LAWS = {drive.name: drive for drive in (PaperLawDrive, YadeLawDrive)}  # [contact] law -> its drive


class YadeCoupling:
    """One scene in YADE. ``run(n)`` advances n steps; ``hooks`` are called as hook(coupling)
    between chunks of steps (see ``run``). ``compiled``: the core (engines.compiled.pore_dem.PoreDEM)
    or the water engine's model by compiled kernels, else their NumPy classes (engines.model).
    ``prepared``: the Start of scene on packing (engines.model.start: the walls, the discs to move,
    their masses; preflight's limits are those of its pores), made here if None. ``law``: the
    scene's contact law's drive (LAWS: PaperLawDrive or YadeLawDrive), chosen once here; the
    coupling asks it and never the law's name."""

    # what a checkpoint stores (engines.model.state); YADE's bodies: engines.yade.checkpoint
    CHECKPOINT_FIELDS = ("core", "water_engine", "engine", "base", "_hooked_at")
    CHECKPOINT_DERIVED = {
        **{name: "the scene and the packing" for name in ("scene", "flat_walls", "block_bounds", "window", "packing",
                                                          "wall_ids", "ids", "mass", "inertia", "io", "per_step",
                                                          "_undamped")},
        "law": "the scene's contact law's drive (LAWS), built from the scene; its parts are the fields above",
        "wall_engine": "YADE's TranslationEngine, built from the scene; its velocity is set before each step",
        "hooks": "set by the run (engines.run.runner.Run)",
        "schedule": "the core's (PoreDEM.schedule: its water model's, stored there) or the water engine's model's"}

    def __init__(self, scene, packing, newton_damping=0.0, compiled=True, prepared=None):
        self.scene = scene
        prepared = Start(scene.settings, packing) if prepared is None else prepared
        self._measures(prepared, packing)
        self.packing = prepared.packing
        self.mass, self.inertia = prepared.mass, prepared.inertia
        self.law = LAWS[scene.contact.law](scene, prepared, compiled)
        self.core, self.engine, self.water_engine = self.law.core, self.law.engine, self.law.water_engine
        self.ids, self.wall_ids = self.law.ids, self.law.wall_ids  # wall_ids: {wall code: YADE body id} of the flat walls
        self.io = yade_io.Bodies(self.ids)
        self._engines(newton_damping)
        self.hooks = []
        # what happens at step k (engines.model.schedule): the water's schedule, whose output
        # events (``set_output``) are when ``run`` calls the hooks; a dry scene's has output only
        self.schedule = self.law.schedule
        self._hooked_at = None
        if yade_io.BACKEND == "python":
            yade_io.freeze_gc()

    def _measures(self, prepared, packing):
        """The flat walls, and the blocks and the porosity window in the box of the flat walls, else
        of the wall discs' inner faces."""
        self.flat_walls = prepared.flat_walls  # {wall code: FlatWall}, {} with wall discs
        faces = prepared.faces
        self.block_bounds = packing.block_bounds(self.scene.output.block_z, faces.get(pg.WALL_BOTTOM))
        self.window = pore_dem.porosity_window(self.scene.settings, packing, faces)

    def _engines(self, newton_damping):
        """O.engines of the law, the wall motion and NewtonIntegrator (its damping pass off at 0)."""
        walls = self._wall_motion()
        self.per_step = self.law.per_step(self.base)
        newton = NewtonIntegrator(gravity=(0, 0, -self.scene.material.g), damping=newton_damping)
        undamped(newton)
        self._undamped = newton.damping == 0  # the bodies' damping pass is off (checked by run)
        O.engines = self.law.yade_engines(newton, walls)

    def _wall_motion(self):
        """The walls that follow the input ([loading] moves) move at the velocity of the base motion
        for each step (engines.model.ground_motion.BaseMotion, the one input path): with the paper's
        law the PaperLawEngine sets their velocities to the core's (PoreDEM) before each O.step
        (``drive_walls``; no engine), with law = 'yade' a TranslationEngine whose velocity is set
        before each O.step (the law's ``move_walls``). Returns the engines to add ([] or the
        TranslationEngine)."""
        self.wall_engine = self.base = None
        if self.scene.loading.type == "none":
            return []
        self.base = self.law.base_motion(self.scene)
        flat = pore_dem.moving_flat_walls(self.scene.settings, tuple(self.flat_walls.values()))
        ids = (self.ids[pore_dem.moving_walls(self.scene.settings, self.packing)].tolist()
               + [self.wall_ids[code] for code, m in zip(self.flat_walls, flat) if m and code in self.wall_ids])
        if not ids:
            return []
        walls = self.law.move_walls(ids)
        self.wall_engine = self.law.wall_engine
        return walls

    # -- running ------------------------------------------------------------------------------------
    def _advance(self, n, stop):
        self.law.advance(n, stop, self.base)
        yade_io.raise_pending()

    def run(self, n_steps, stop=None):
        """Run n_steps DEM steps; returns True when they all ran, False when ``stop()`` (a callable,
        asked after every step or compiled run of steps, see the module docstring) turned true
        first. The hooks are called as hook(self) at every output step of ``schedule``
        (Schedule.set_output; the start and the end included), once per step index, before the
        step. An error inside an engine stops YADE and is
        re-raised here."""
        if self._undamped and any(isinstance(e, NewtonIntegrator) and e.damping != 0 for e in O.engines):
            raise ValueError("NewtonIntegrator.damping was set after the scene was built with damping 0, whose bodies "
                             "have its damping pass off (coupling.undamped): pass newton_damping to YadeCoupling")
        stop = stop or _never
        end = O.iter + int(n_steps)
        sch = self.schedule
        while True:
            k = O.iter
            if sch.output_due(k) and k != self._hooked_at:
                self._hooked_at = k
                for hook in self.hooks:
                    hook(self)
            if k >= end:
                return True
            if stop():
                return False
            n = min(end - k, sch.steps_to_output(k))
            self._advance(min(n, PER_STEP_CHUNK) if self.per_step else n, stop)

    def restore_forces(self):
        """After a checkpoint's O.load: YADE's permanent forces, which O.save does not keep."""
        self.law.restore_forces()
        if yade_io.BACKEND == "python":
            yade_io.freeze_gc()

    # -- observations ------------------------------------------------------------------------------
    @property
    def step_index(self):
        return O.iter

    @property
    def water(self):
        """The PoreWater state, or None for a dry scene."""
        wm = self.law.water_model
        return wm.water if wm is not None else None

    @property
    def water_model(self):
        return self.law.water_model

    def positions(self):
        """Disc centres (N, 2) [m], read in bulk."""
        return self.io.positions()

    def velocities(self):
        return self.io.velocities()

    def block_pressures(self, xz):
        return pore_dem.block_pressures(self.water_model, xz, self.block_bounds)

    def porosity(self, xz):
        """Void fraction of the fixed porosity window moved with the base (engines.model.observe)."""
        return pore_dem.window_porosity(self.packing, self.window, xz, self.base.disp if self.base else 0.0)

    def flat_wall_faces(self):
        """The positions (W,) [m] of the flat walls' faces now: where they started, the x faces of
        those that follow the input ([loading] moves) carried by the base displacement."""
        walls = tuple(self.flat_walls.values())
        faces = np.array([w.position for w in walls])
        if self.base is not None and walls:
            carried = pore_dem.moving_flat_walls(self.scene.settings, walls) & np.array([w.axis == 0 for w in walls])
            faces = faces + self.base.disp * carried
        return faces

    def base_motion(self):
        """(acceleration [m/s^2], velocity [m/s], displacement [m]) of the driven base at O.iter dt."""
        b = self.base
        return (b.acc, b.vel, b.disp) if b is not None else (0.0, 0.0, 0.0)

    def side_wall_shift(self, xz):
        """Mean x displacement [m] of the left and the right side-wall column relative to the base
        (the discs on springs; nan when the side walls are fixed)."""
        ties = self.law.ties
        if ties is None:
            return np.nan, np.nan
        d = xz[:, 0] - self.packing.xz[:, 0] - self.base_motion()[2]
        return tuple(float(np.mean(d[ties.columns[c][1:]])) if c in ties.columns else np.nan for c in ("left", "right"))

    def kinetic_energy(self):
        """Translational + rotational kinetic energy of the particles [J per m]."""
        return pore_dem.kinetic_energy(self.mass, self.inertia, self.packing.mobile, self.velocities(),
                                       self.law.spins(self.io))

    def contact_pairs(self, xz, keep=None):
        """(pairs (K, 2) disc indices, normal force (K,), elastic shear force (K,) [N]) of the pairs
        touching at centres xz (the current ones); ``keep(i, j)``: a mask of the pairs (disc indices
        i, j) to report (default all). The shear force is signed along t of eq 3b (counter-clockwise
        about i), without its dashpot part, as YADE's phys.shearForce. The paper's law evaluates its
        pairs at xz without advancing its state (PaperLaw.contact_pairs)."""
        return self.law.contact_pairs(xz, keep)

    def stress_contacts(self, xz):
        """The particles' contacts at centres xz for the effective stress (Contacts of
        engines.model.effective_stress): the paper's law's own, its flat walls' feet included
        (PaperLaw.stress_contacts); with law = 'yade' the pairs of ``contact_pairs`` (wall discs
        counted for their particle) and the contacts with the flat walls' boxes at YADE's contact
        point, with the force YADE puts on the disc (normalForce + shearForce on id2)."""
        return self.law.stress_contacts(xz, self.packing)

    def wall_loads(self):
        """{wall name: (contact, water)} of the flat walls [N per m thickness]: the sum of the normal
        forces of YADE's contacts on each (as contact_pairs reads them; a box contact's normal is the
        face's) and the pore water's push on it (WaterEngine.wall_forces), both positive when they
        push the wall away from the discs; {} with wall discs."""
        return self.law.wall_loads(self.flat_walls)

    def bottom_normal_force(self, xz):
        """Mean normal force [N] of the touching pairs whose midpoint lies in the first block (0 if none)."""
        z0, z1 = self.block_bounds[0]

        def in_first_block(i, j):
            zmid = 0.5 * (xz[i, 1] + xz[j, 1])
            return (zmid >= z0) & (zmid < z1)

        _, fn, _ = self.contact_pairs(xz, in_first_block)
        return float(fn.mean()) if len(fn) else 0.0


def simulate(scene, packing, n_steps, record_every, hooks=()):
    """Run a scene in YADE and record a Trajectory after every ``record_every`` steps
    (at t = (k + 1) dt); the recording contract is shared with engines.reference.model.
    ``hooks``: called as hook(coupling) after each recorded chunk (the cross-check counts rules)."""
    cp = YadeCoupling(scene, packing)
    traj = Trajectory(info={"implementation": "yade", "law": scene.contact.law, "io": yade_io.BACKEND})
    steps_left = n_steps
    while steps_left > 0:
        chunk = min(record_every, steps_left)
        cp.run(chunk)
        steps_left -= chunk
        for hook in hooks:
            hook(cp)
        xz = cp.positions()
        w = cp.water
        traj.append(O.iter * scene.numerics.dt, xz, cp.block_pressures(xz),
                    w.total_water() if w else np.nan, w.balance_error() if w else np.nan)
    return traj


def _never():
    return False

