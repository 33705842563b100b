"""Run a scene in YADE with outputs: history.csv, snapshots, VTK, figures, summary.json, checkpoints.

``run_scene`` starts a run, ``resume_run`` continues one from its checkpoint, in place. history.csv
is appended and flushed row by row, so a stopped or crashed run keeps what it computed.

Stopping: SIGINT (Ctrl-C) or SIGTERM during a run stops it after the current step: the history is
flushed, a checkpoint written, summary.json says "interrupted" with the step, and the run returns
(the scripts then exit with 128 + the signal's number). A second signal ends the process at once,
with one line and the same status; the run resumes from its last checkpoint. Before the run loop
(compilation, preflight, loading a checkpoint) the scripts' engines.run.guard.catch_signals ends
the process with one line and nothing changed.

One run per folder: ``run_scene`` and ``resume_run`` hold the folder's lock (engines.run.guard)
while they write; at their start they remove the temporary files a killed run left there. A run
has an id (``run_id``, in every checkpoint and in summary.json). summary.json (written atomically,
engines.files) says "running" from the start and is written again at every checkpoint, so that a
killed segment stays listed (a resume marks it "killed" with its last known step); its provenance
is the first segment's. A write that fails (a full disk) ends the run "failed: cannot write PATH:
CAUSE" (``WriteError``, one line), after writing what it still can.

Checkpoints (engines.yade.checkpoint, ``checkpoint.npz``, data only, written whole or not at all):
at the start, every ``[output] checkpoint_seconds`` of wall time, at the end and on an interrupt;
each holds the run's scene and packing (``Run.recipe``), YADE's bodies, the run's ``info`` (its id,
history.csv's rows, last t and checksum) and the named state of the ``Run`` and its parts
(coupling, recorder, bookkeeping: each class's CHECKPOINT_FIELDS). A resume builds the run again
from the scene and packing and sets that state (``Run.from_checkpoint``), so that it continues
exactly as if it had not stopped. A crashed run keeps its last checkpoint (resumable: the history
rows written after it are dropped on resume: engines.run.history checks the rows it keeps) and
writes the state at the failing step to ``failure_state.npz`` for a post-mortem.
"""
import contextlib
import csv
import hashlib
import io
import json
import math
import os
import signal
import socket
import threading
import time
import uuid
from glob import escape as glob_escape
from glob import glob

import numpy as np
from yade import O

from engines import files
from engines.model import effective_stress as es
from engines.model import pores as pg
from engines.model.network_view import pore_network
from engines.model.pore_dem import pore_state
from engines.model.start import Start
from engines.run import guard, history, manifest
from engines.run.preflight import announce_dt, timed
from engines.run import scene as scenes
from engines.run.provenance import provenance
from engines.run.talk import result_lines, say
from engines.yade import checkpoint, yade_io
from engines.yade.coupling import YadeCoupling
from packing.packing import Packing
from postproc import plots
from postproc.run_files import headline_results, read_history

CHECKPOINT = checkpoint.NAME
RECIPE = ("scene", "start", "packing.xz", "packing.r", "packing.group", "packing.density_factor")  # Run.recipe
FAILURE_STATE = "failure_state.npz"
SUMMARY = "summary.json"


class Recorder:
    """Coupling hook: history rows every history_interval steps and at the end, snapshots at the
    scene's snapshot times and at the end and, with [output] vtk, ParaView frames (postproc.vtk) every vtk_interval steps or at the
    snapshot times; taken between steps at the positions after k steps (t = k dt). Each is taken
    once per step index, so a resumed run does not repeat one. ``create`` starts history.csv (and
    the VTK folder; Run.go calls it for a new run); a resumed run's ``reopen`` checks the file
    against the checkpoint and continues it."""

    file = None  # history.csv, open for appending

    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("rows", "last_row", "last_t", "last_vtk", "snapshot_steps", "vtk")
    CHECKPOINT_DERIVED = {
        "bands": "the packing and the walls (effective_stress.bed_bands)", "band_areas": "with the bands",
        "sigma_v0": "history.csv's first row whose sv_band columns carry a load, read again by reopen",
        **{name: "the scene's [output] and the coupling's blocks and walls" for name in
           ("dt", "history_interval", "vtk_interval", "snapshot_times", "progress_seconds", "n_blocks", "columns")},
        "n_steps": "schedule(Run.n_steps)", "snap_steps": "schedule(Run.n_steps)", "out": "the folder resumed in",
        "file": "history.csv, opened by reopen", "path": "history.csv in the folder resumed in",
        "sha": "the checksum of history.csv's rows, read again by reopen (engines.run.history.kept)",
        **{name: "progress lines: the wall clock of this segment" for name in ("t_wall0", "t_last", "k_wall0", "t_ref",
                                                                               "k_ref")}}

    def __init__(self, cp, out_dir, n_steps):
        out = cp.scene.output
        self.dt = cp.scene.numerics.dt
        self.history_interval, self.vtk_interval = out.history_interval, out.vtk_interval
        self.snapshot_times = out.snapshot_times
        self.progress_seconds = out.progress_seconds
        self.n_blocks = len(cp.block_bounds)
        self.bands, self.band_areas = es.bed_bands(cp.packing, box_faces(cp), out.n_bands)
        self.sigma_v0 = None  # sigma'_v of each band at the first loaded row [Pa]: r_u's reference (stress_row)
        self.columns = history_columns(cp)
        self.rows, self.last_row, self.last_vtk = 0, -1, -1
        self.last_t = None  # the last row's t [s] as written
        self.snapshot_steps = []  # steps whose snapshot file was written
        self.vtk = None
        if out.vtk:  # its folder is made at the first frame
            from postproc.vtk import VtkSeries
            self.vtk = VtkSeries(out_dir)
        self.schedule(n_steps)
        self.out = out_dir

    def create(self):
        """Start history.csv (its header)."""
        header = io.StringIO()
        csv.writer(header, lineterminator="\n").writerow(self.columns)
        self.sha = hashlib.sha256()
        self._open("w")
        self._write(header.getvalue())

    def schedule(self, n_steps):
        """The run ends at step n_steps: the snapshot steps within it, and the end (its last row too)."""
        self.n_steps = n_steps
        self.snap_steps = sorted({int(round(t / self.dt)) for t in self.snapshot_times
                                  if round(t / self.dt) <= n_steps} | {n_steps})

    def _open(self, mode):
        self.path = os.path.join(self.out, history.NAME)
        try:
            self.file = open(self.path, mode, newline="")
        except OSError as e:
            raise files.WriteError(f"cannot write {self.path}: {files.reason(e)}") from None
        self.t_wall0 = self.t_last = time.time()
        self.k_wall0 = O.iter
        self.t_ref = self.k_ref = None  # the wall clock and step the speed of the ETA is measured from

    def _write(self, line):
        """Append ``line`` (text ending in a newline) to history.csv, flushed; the checksum follows
        only what was written whole."""
        try:
            self.file.write(line)
            self.file.flush()
        except OSError as e:
            raise files.WriteError(f"cannot write {self.path}: {files.reason(e)}") from None
        self.sha.update(line.encode())

    def history_info(self):
        """What the checkpoint records of history.csv (engines.run.history.info)."""
        return history.info(self.rows, self.last_t, self.sha.hexdigest())

    def reopen(self, out_dir, info):
        """Continue in ``out_dir`` from the checkpoint whose ``info`` (checkpoint.read_info) recorded
        the history: history.csv checked against it (engines.run.history; HistoryMismatch), then
        appended to when it holds exactly those rows, else first rebuilt from them in a temporary
        file renamed over it (a run stopped or crashed after its checkpoint wrote more rows)."""
        self.out = out_dir
        path = os.path.join(out_dir, history.NAME)
        size, whole, self.sha = history.kept(out_dir, info, self.rows)
        if not whole:
            with files.saved(path) as tmp, open(path, "rb") as old, open(tmp, "wb") as new:
                while new.tell() < size:
                    new.write(old.read(min(history.CHUNK, size - new.tell())))
        if self.vtk is not None:
            self.vtk.dir = os.path.join(out_dir, "vtk")
        bands = [f"sv_band{k + 1}" for k in range(len(self.bands))]
        first = history.first_loaded_row(out_dir, bands)
        if first is not None:
            self.sigma_v0 = np.array([first[c] for c in bands])
        self._open("a")

    def __call__(self, cp):
        k = cp.step_index  # steps done: positions at t = k dt
        xz = cp.positions()
        if (k % self.history_interval == 0 or k == self.n_steps) and self.last_row < k <= self.n_steps:
            self.row(cp, xz, k)
        snap_due = k in self.snap_steps and k not in self.snapshot_steps
        vtk_due = self.vtk is not None and k > self.last_vtk and \
            (k % self.vtk_interval == 0 if self.vtk_interval else k in self.snap_steps)
        if snap_due or vtk_due:
            snap = snapshot_data(cp, xz, k)
            if snap_due:
                files.savez(os.path.join(self.out, snapshot_name(k, self.dt)), **snap)
                self.snapshot_steps.append(k)
            if vtk_due:
                from postproc.vtk import snapshot_frame, snapshot_throats
                self.vtk.add(snap["t"], *snapshot_frame(snap), throats=snapshot_throats(snap))
                self.last_vtk = k
        now = time.time()
        if now - self.t_last >= self.progress_seconds:
            self.t_last = now
            say(f"[{cp.scene.scene.name}] step {k}/{self.n_steps} t = {k * self.dt * 1e3:.2f} ms, "
                f"wall {now - self.t_wall0:.0f} s{self.eta(now, k)}")

    def eta(self, now, k):
        """The progress line's estimate of the wall time left at step k (wall clock ``now`` [s]): the
        speed is measured from the first progress line on (the compile and the first steps before
        it are not counted), so that line has none."""
        if self.k_ref is None or k <= self.k_ref:
            self.t_ref, self.k_ref = now, k
            return ""
        return f", about {(now - self.t_ref) / (k - self.k_ref) * (self.n_steps - k):.0f} s left"

    def row(self, cp, xz, k):
        """Append the row of step k (positions xz): the values of ``self.columns``."""
        mob = cp.packing.mobile
        v = {"t": k * self.dt, "porosity": cp.porosity(xz), "kinetic_energy": cp.kinetic_energy(),
             "fn_bottom_mean": cp.bottom_normal_force(xz), "bed_top": float(np.max(xz[mob, 1] + cp.packing.r[mob]))}
        w = cp.water
        if w is not None:
            v.update({f"U_block{b + 1}": u for b, u in enumerate(cp.block_pressures(xz))},
                     water_balance_error=w.balance_error(), total_water=w.total_water(), n_pores=w.net.n_pores,
                     remesh_change=w.balance.remesh_change)
        if "base_acc" in self.columns:
            v.update(zip(("base_acc", "base_vel", "base_disp"), cp.base_motion()))
        if "side_left_dx" in self.columns:
            v.update(zip(("side_left_dx", "side_right_dx"), cp.side_wall_shift(xz)))
        v.update({f"wall_{name}_{part}": f for name, load in cp.wall_loads().items()
                  for part, f in zip(("contact", "water"), load)})
        v.update(self.stress_row(cp, xz))
        texts = [f"{v[c]:.9g}" for c in self.columns]
        self._write(",".join(texts) + "\n")
        self.rows += 1
        self.last_row, self.last_t = k, float(texts[0])

    def stress_row(self, cp, xz):
        """{column: value} of the bands' effective stress at centres xz (engines.model.effective_stress:
        sigma'_v, p', q and the shear stress sigma'_xz [Pa] from the contacts, eq L1-L2) and, with
        water, their r_u (L3) against sigma'_v at the first row whose contacts carry a load (the first;
        with law = "yade" the second, as YADE finds its contacts in the first step; nan before it)."""
        s = es.region_stress(xz, cp.stress_contacts(xz), -np.inf, np.inf, self.bands, self.band_areas)
        sv, _, p, q = es.invariants(s)
        if self.sigma_v0 is None and sv.sum() > 0:  # YADE's law finds its contacts at the first step
            self.sigma_v0 = np.array([float(f"{x:.9g}") for x in sv])  # as history.csv holds it: reopen reads it
        v = {}
        for name, values in (("sv", sv), ("p", p), ("q", q), ("sxz", s[:, 2])):
            v.update({f"{name}_band{k + 1}": x for k, x in enumerate(values)})
        state = pore_state(cp.water_model, xz)
        if state is not None:
            net, A, U = state
            u = es.region_pressure(pg.pore_centroids(net, xz)[:, 1], A, U, self.bands)
            ru = es.pore_pressure_ratio(u, self.sigma_v0) if self.sigma_v0 is not None else np.full(len(u), np.nan)
            v.update({f"ru_band{k + 1}": x for k, x in enumerate(ru)})
        return v

    def close(self):
        """Close history.csv (every row was flushed when written)."""
        if self.file is not None:
            with contextlib.suppress(OSError):
                self.file.close()


def history_columns(cp):
    """The columns of history.csv for the coupling ``cp``: only those its scene produces (the
    water's with water, the base motion's with a driven base, the side-wall shifts with side
    walls on springs, each flat wall's loads, the bands' effective stress and, with water, their
    r_u; units: engines.run.history.UNITS)."""
    water = cp.water is not None
    ties = cp.core is not None and cp.core.ties is not None
    bands = range(1, cp.scene.output.n_bands + 1)
    return (["t"] + ([f"U_block{b + 1}" for b in range(len(cp.block_bounds))] if water else []) +
            ["porosity", "kinetic_energy"] + (["water_balance_error", "total_water", "n_pores"] if water else []) +
            ["fn_bottom_mean", "bed_top"] + (["base_acc", "base_vel", "base_disp"] if cp.base is not None else []) +
            (["side_left_dx", "side_right_dx"] if ties else []) + (["remesh_change"] if water else []) +
            [f"wall_{name}_{part}" for name in cp.wall_loads() for part in ("contact", "water")] +
            [f"{name}_band{k}" for name in ("sv", "p", "q", "sxz") + (("ru",) if water else ()) for k in bands])


def box_faces(cp):
    """{wall code: position [m]} of the box of the coupling ``cp`` at the start: its flat walls',
    else its wall discs' inner faces (engines.model.start.Start.faces)."""
    return {code: w.position for code, w in cp.flat_walls.items()} or cp.packing.inner_faces()


def snapshot_data(cp, xz, k):
    """The arrays of a snapshot at step k (positions xz): discs, touching pairs with their normal
    and elastic shear forces, each disc's effective stress ``stress`` (N, 3): xx, zz, xz [Pa] over
    pi r^2 / (1 - n), n the window porosity (engines.model.effective_stress.disc_stress; zeros for
    the wall discs, nan without a porosity window) and, with water, the pores as triangles with U, W, A and rule (with
    flat walls, ``vertices``: the positions tri indexes, and ``flat_walls`` (W, 3): axis, position
    [m] now, inward of each), and the network under OpenPNM's names (engines.model.network_view:
    pore.*, throat.*, polygon.*, balance.*)."""
    pairs, fn, fs = cp.contact_pairs(xz)
    pk = cp.packing
    snap = dict(t=k * cp.scene.numerics.dt, xz=xz.copy(), r=pk.r, group=pk.group, density_factor=pk.density_factor,
                vel=cp.velocities(), pairs=pairs, f_n=fn, f_s=fs,
                stress=es.disc_stress(xz, pk.r, cp.stress_contacts(xz), cp.porosity(xz)))
    if cp.flat_walls:
        snap["flat_walls"] = np.array([[w.axis, face, w.inward] for w, face in zip(cp.flat_walls.values(),
                                                                                 cp.flat_wall_faces())])
    state = pore_state(cp.water_model, xz)
    if state is not None:
        net, A, U = state
        snap.update(tri=net.tri, tri_pore=net.tri_pore, U=U, W=cp.water.W.copy(), A=A, rule=cp.water.rule)
        if net.wall_vertices is not None:  # tri indexes the discs, then the flat walls' vertices
            snap["vertices"] = pg.vertex_positions(net, xz)
        snap.update(pore_network(cp.water_model, xz))  # the same pores under OpenPNM's names
    return snap


def write_failure_state(cp, path):
    """Positions, velocities, spin and water at the failing step (a post-mortem; resume from the
    checkpoint)."""
    xz = cp.positions()
    data = dict(step=cp.step_index, t=cp.step_index * cp.scene.numerics.dt, xz=xz, vel=cp.velocities(),
                r=cp.packing.r, group=cp.packing.group)
    if cp.core is not None:
        data.update(du=cp.core.du, omega=cp.core.omega, contact_pairs=np.column_stack([cp.core.contact.i, cp.core.contact.j]),
                    contact_state=cp.core.contact.state)
    state = pore_state(cp.water_model, xz)
    if state is not None:
        data.update(W=cp.water.W, U=state[2])
    files.savez(path, **data)


class Interrupts:
    """While active (``with``): the first SIGINT or SIGTERM is noted (``requested()`` turns true,
    the run stops after its current step), a second one ends the process at once with one line
    and 128 + its number (engines.run.guard.exit_now; the run resumes from its last checkpoint).
    Signal handlers can only be set in the main thread; elsewhere nothing is caught."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __enter__(self):
        self.received = []  # (signal number, time.time() when it arrived)
        self._previous = {}
        if threading.current_thread() is threading.main_thread():
            for s in self.SIGNALS:
                self._previous[s] = signal.signal(s, self._handle)
        return self

    def _handle(self, signum, frame):  # noqa: ARG002
        if self.received:  # the status of the first signal: a second Ctrl-C or a Ctrl-C then a kill, the same
            guard.exit_now(self.received[0][0], f"stopped at once by a second {signal.Signals(signum).name} at step "
                                                f"{O.iter}: continue from the last checkpoint with --resume")
        self.received.append((signum, time.time()))

    def requested(self):
        return bool(self.received)

    def __exit__(self, *exc):
        for s, handler in self._previous.items():
            signal.signal(s, handler)


class Run:
    """One run of a scene in ``out_dir``: the coupling, its recorder and the bookkeeping of the
    run's segments (a start and each resume). Its checkpoints hold its ``recipe``, its ``info`` and
    its named state (CHECKPOINT_FIELDS, engines.model.state); it is also the coupling's last hook,
    which writes the periodic checkpoints (and summary.json with them). ``start``: which start of an
    ensemble the packing is ({"seed", "perturbation_m"}; engines.run.ensemble), or None;
    ``prepared``: the Start of scene on packing (engines.model.start) the coupling runs on, or None.
    ``run_id``: made here, kept by every segment (a run built from its checkpoint takes the stored one)."""

    # what a checkpoint stores (engines.model.state)
    CHECKPOINT_FIELDS = ("n_steps", "segments", "checkpoint_step", "run_id", "cp", "rec")
    CHECKPOINT_DERIVED = {"scene": "the recipe", "packing": "the recipe", "start": "the recipe",
                          "out": "the folder resumed in", "_last_checkpoint": "the wall clock of this segment",
                          "_clock": "the wall and CPU clocks of this segment (set by go)",
                          "_overburden": "band_overburden's value, computed from the recipe at its first call"}

    def __init__(self, scene, packing, out_dir, n_steps, start=None, prepared=None):
        self.scene, self.packing, self.out, self.n_steps, self.start = scene, packing, out_dir, n_steps, start
        self.run_id = uuid.uuid4().hex
        self._overburden = None
        self.cp = YadeCoupling(scene, packing, prepared=prepared)
        self.rec = Recorder(self.cp, out_dir, n_steps)
        self.cp.hooks += [self.rec, self]
        self.segments = []
        self.checkpoint_step = None
        self._last_checkpoint = -math.inf  # the first hook call (step 0) writes one
        self._schedule()

    def checkpoint_restored(self):
        """Refuse stored segments that summarise cannot read."""
        for k, s in enumerate(self.segments):
            if not (isinstance(s, dict) and all(type(s.get(key)) is int for key in ("from_step", "to_step"))
                    and type(s.get("wall_seconds")) in (int, float) and type(s.get("cpu_seconds", 0.0)) in (int, float)
                    and "provenance" in s):
                raise ValueError(f"segment {k}: expected from_step, to_step, wall_seconds, cpu_seconds and provenance")

    def _schedule(self):
        out = self.scene.output
        every = math.gcd(out.history_interval, out.vtk_interval) if out.vtk else out.history_interval
        self.cp.schedule.set_output(every, self.rec.snap_steps)

    def __call__(self, cp):  # noqa: ARG002  (the hook: periodic checkpoints)
        if time.time() - self._last_checkpoint >= self.scene.output.checkpoint_seconds:
            self.save_checkpoint()
            self.write_summary("running", [])

    def info(self):
        """The checkpoint's ``info``: plain values readable without YADE (checkpoint.read_info)."""
        return {"n_steps": self.n_steps, "dt": self.scene.numerics.dt, "scene": self.scene.scene.name,
                "run_id": self.run_id, **self.rec.history_info()}

    def save_checkpoint(self):
        """The checkpoint at this step (fsync'd, renamed into place; WriteError names the path)."""
        self._segment_to_now()
        self.checkpoint_step = O.iter
        checkpoint.save(os.path.join(self.out, CHECKPOINT), self, self.info(), self.recipe())  # whole or not at all
        self._last_checkpoint = time.time()

    def write_summary(self, status, received):
        """summary.json (``summarise``), atomically; returns the summary."""
        summary = self.summarise(status, received)
        files.write_json(os.path.join(self.out, SUMMARY), summary)
        return summary

    def recipe(self):
        """What builds this run again (``from_checkpoint``): the scene (its tables, file and
        overrides), the ensemble's start and the packing's arrays."""
        sc, pk = self.scene, self.packing
        return dict(zip(RECIPE, ({"tables": sc.as_dict(), "path": sc.path, "overrides": sc.overrides}, self.start,
                                 pk.xz, pk.r, pk.group, pk.density_factor)))

    @classmethod
    def from_checkpoint(cls, out_dir):
        """The run of ``out_dir`` built again from its checkpoint's recipe as a new run is built,
        then set to its stored state (engines.yade.checkpoint.restore); CheckpointError in one line."""
        path = os.path.join(out_dir, CHECKPOINT)
        ck = checkpoint.load(path)
        r, start, n_steps = ck.recipe, ck.recipe.get("start"), ck.state.get("n_steps")
        if set(r) != set(RECIPE) or not (start is None or isinstance(start, dict)) or type(n_steps) is not int \
                or not isinstance(r["scene"], dict) or set(r["scene"]) != {"tables", "path", "overrides"} \
                or not (isinstance(r["scene"]["tables"], dict) and isinstance(r["scene"]["path"], str)
                        and isinstance(r["scene"]["overrides"], dict)):
            raise checkpoint.CheckpointError(f"{path}: its recipe is not {', '.join(RECIPE)} of their types, or "
                                             "n_steps is missing")
        try:
            scene = scenes.validate(r["scene"]["tables"], r["scene"]["path"])
            scene.overrides = r["scene"]["overrides"]
            packing = Packing(r["packing.xz"], r["packing.r"], r["packing.group"], r["packing.density_factor"])
        except ValueError as e:
            raise checkpoint.CheckpointError(f"{path}: its scene or packing is refused: {e}") from None
        run = cls(scene, packing, out_dir, n_steps, start)
        checkpoint.restore(ck, run)
        return run

    def reopen(self, out_dir, info, duration=None):
        """After ``from_checkpoint``: continue in ``out_dir`` (to ``duration`` [s] if given: a later end);
        ``info``: the checkpoint's (history.csv is checked against it). The segments are those of
        summary.json when it is this run's and knows as much or more (a segment that failed or
        was killed after the checkpoint ran on), those of the checkpoint otherwise; a segment left
        "running" is marked "killed"."""
        self.out = out_dir
        self.cp.restore_forces()
        n = checkpoint.resume_end(O.iter, self.n_steps, self.scene.numerics.dt, duration)
        self.rec.reopen(out_dir, info)
        if duration is not None:
            self.scene = self.cp.scene = self.scene.with_overrides({"numerics": {"duration": duration}})
            self.n_steps = n
            self.rec.schedule(n)
            self._schedule()
            self.cp._hooked_at = None  # the hooks see this step again: the row at the old end is due now
        try:
            with open(os.path.join(out_dir, SUMMARY)) as f:
                before = json.load(f)
        except (OSError, ValueError):
            before = {}
        theirs = before.get("segments") if isinstance(before, dict) and before.get("run_id") == self.run_id else None
        if isinstance(theirs, list) and theirs and all(isinstance(x, dict) for x in theirs) and \
                (len(theirs), theirs[-1].get("to_step", -1)) >= (len(self.segments), self.segments[-1]["to_step"]
                                                                 if self.segments else -1):
            self.segments = theirs
        for seg in self.segments:
            if seg.get("status") == "running":
                seg["status"] = "killed"
        self._last_checkpoint = time.time()

    def _segment_to_now(self, status=None):
        """The current segment's last step, times and (if given) status."""
        if not self.segments or self.segments[-1]["status"] != "running":
            return
        seg = self.segments[-1]
        seg.update(to_step=int(O.iter), wall_seconds=time.time() - self._clock[0],
                   cpu_seconds=time.process_time() - self._clock[1])
        if status is not None:
            seg["status"] = status

    def go(self, overrides=None, figures=True, signals=None):
        """Run to step n_steps (or until a signal or an error); write the checkpoint, summary and
        (when completed) the figures. Returns the summary; re-raises an error after writing what
        it can (a failed write: WriteError, one line naming the path); a completed run's drawn PNGs are
        its "figures" (not in summary.json). ``signals``: the active
        Interrupts (default: its own)."""
        cp, sc = self.cp, self.scene
        k0 = O.iter
        self._clock = (time.time(), time.process_time())
        self.segments.append({"from_step": k0, "to_step": k0, "status": "running", "wall_seconds": 0.0,
                              "cpu_seconds": 0.0, "started": time.strftime("%Y-%m-%dT%H:%M:%S"),
                              "host": socket.gethostname(), "pid": os.getpid(),
                              "provenance": provenance(overrides=overrides)})
        say(f"[{sc.scene.name}] {int(cp.packing.mobile.sum())} particles, {int((~cp.packing.mobile).sum())} wall discs, "
            f"{cp.water.net.n_pores if cp.water else 0} pores, law = {sc.contact.law}, I/O {yade_io.BACKEND}, "
            f"dt = {sc.numerics.dt:g} s, steps {k0} to {self.n_steps} -> {self.out}")
        status, error = "completed", None
        with contextlib.ExitStack() as stack:
            if signals is None:
                signals = stack.enter_context(Interrupts())
            try:
                if self.rec.file is None:  # a fresh run: its history starts here
                    self.rec.create()
                self.write_summary("running", [])
                if not cp.run(self.n_steps - k0, stop=signals.requested):
                    status = "interrupted"
            except BaseException as e:
                error = e
                status = f"failed: {e}" if isinstance(e, files.WriteError) else f"failed: {type(e).__name__}: {e}"
                with contextlib.suppress(OSError):  # a full disk: the error above is the one to report
                    write_failure_state(cp, os.path.join(self.out, FAILURE_STATE))
            self.rec.close()
            self._segment_to_now(status)
            try:
                if error is None:
                    self.save_checkpoint()
                summary = self.write_summary(status, signals.received)
            except OSError as e:
                if error is None:  # the checkpoint or summary could not be written: the run failed
                    error, status = e, f"failed: {e}"
                    self.segments[-1]["status"] = status
                    with contextlib.suppress(OSError):
                        self.write_summary(status, signals.received)
        if error is not None:
            raise error
        if status == "completed" and figures:
            guard.stage("while drawing the figures (the run's files are complete; python3 -m postproc.plots "
                        f"{self.out} draws them)")
            summary["figures"] = plots.figures_of_run(self.out)
        return summary

    def band_overburden(self):
        """The buoyant overburden [Pa] of each band at the start (effective_stress.overburden: the
        particles' unit weight rho f g, less rho_w g with water), beside sigma'_v0 from the contacts;
        computed once (each summary writes it)."""
        if self._overburden is not None:
            return self._overburden
        pk, m = self.packing, self.packing.mobile
        mat = self.scene.material
        unit = (mat.rho * pk.density_factor[m] - (mat.rho_w if self.scene.water.enabled else 0.0)) * mat.g
        b = self.rec.bands
        width = self.rec.band_areas[0] / (b[0][1] - b[0][0])
        self._overburden = es.overburden(pk.xz[m], pk.r[m], unit, 0.0, width, b)
        return self._overburden

    def summarise(self, status, received):
        cp, sc = self.cp, self.scene
        w, wm = cp.water, cp.water_model
        wall = sum(s["wall_seconds"] for s in self.segments)
        steps_run = sum(s["to_step"] - s["from_step"] for s in self.segments)
        history_path = os.path.join(self.out, history.NAME)
        results = headline_results(read_history(history_path) if os.path.exists(history_path) else {},
                                   sc.output.heave_rise)
        if not status.startswith("failed"):
            results["porosity_end"] = cp.porosity(cp.positions())
        summary = {
            "scene": sc.scene.name, "run_id": self.run_id, "status": status, "steps": int(O.iter),
            "steps_requested": self.n_steps,
            "wall_seconds": wall, "us_per_step": 1e6 * wall / max(steps_run, 1),
            "cpu_seconds": sum(s.get("cpu_seconds", 0.0) for s in self.segments),
            "n_particles": int(cp.packing.mobile.sum()), "n_walls": int((~cp.packing.mobile).sum()),
            "n_pores": int(w.net.n_pores) if w else 0, "n_rebuilds": wm.n_rebuilds if wm else 0,
            "water_substeps_max": wm.substeps_max if wm else 0, "law": sc.contact.law, "io_backend": yade_io.BACKEND,
            "dt": sc.numerics.dt, "t_end": O.iter * sc.numerics.dt,
            "water_balance_error": w.balance_error() if w else 0.0,
            "water_balance": vars(w.balance) if w else None,
            "remesh_rules_last": w.remesh_counts if w else None,
            "contact_list_builds": cp.core.contact.list_builds if cp.core is not None else None,
            "block_bounds_m": cp.block_bounds,
            "band_bounds_m": self.rec.bands,
            "band_sigma_v0_Pa": None if self.rec.sigma_v0 is None else self.rec.sigma_v0.tolist(),
            "band_overburden_Pa": self.band_overburden().tolist(),
            "history_units": history.units(self.rec.columns),
            "start": self.start,
            "results": results,
            "checkpoint": {"file": CHECKPOINT, "step": self.checkpoint_step},
            "parameters": sc.as_dict(),
            "provenance": self.segments[0]["provenance"] if self.segments else None,
            "segments": self.segments,
        }
        if received:
            signum, t_signal = received[0]
            summary["interrupt"] = {"signal": signal.Signals(signum).name, "step": int(O.iter),
                                    "seconds_to_stop": time.time() - t_signal}
        return summary


def snapshot_name(k, dt):
    """The file of the snapshot at step k (time k dt [s], in ms in the name)."""
    return f"snapshot_{k * dt * 1e3:06.2f}ms.npz"


def claim_outputs(out_dir, scene, snap_steps=()):
    """Record in the manifest of ``out_dir`` the files a run of ``scene`` may write (its snapshots
    at ``snap_steps``), before it writes them (engines.run.manifest)."""
    manifest.claim(out_dir, [n for n in manifest.RUN_FILES if n != manifest.NAME] +
                   ([manifest.VTK] if scene.output.vtk else []) +
                   [snapshot_name(k, scene.numerics.dt) for k in snap_steps])


def remove_stale_temporaries(out_dir):
    """Remove what a killed run left in ``out_dir`` (its lock held): engines.files' temporaries
    there and in vtk/, and the checkpoint's (``.checkpoint-*``)."""
    for folder in (out_dir, os.path.join(out_dir, "vtk")):
        if os.path.isdir(folder):
            files.remove_stale_temporaries(folder)
    for path in glob(os.path.join(glob_escape(out_dir), ".checkpoint-*")):
        with contextlib.suppress(OSError):
            os.remove(path)


def run_scene(scene, packing, out_dir, duration=None, figures=True, start=None, prepared=None):
    """Run ``scene`` on ``packing`` for ``duration`` (default: the scene's) and write the outputs
    (``figures=False``: no PNGs; ``python3 -m postproc.plots DIR`` draws them later; ``start``:
    the ensemble's start the packing is, recorded in summary.json).
    Returns the summary ("status": completed or interrupted); re-raises an error after writing
    the history, summary and failure state. ``prepared``: the Start of scene on packing
    (engines.model.start) preflight checked, made here if None; it holds the time step of dt =
    "auto", whose choice is printed here (engines.run.preflight.announce_dt). The coupling is built
    before anything is written; then the folder's lock is taken (engines.run.guard.FolderLocked if
    another run holds it) and a signal stops the run after its first checkpoint."""
    prepared = Start(scene.settings, packing) if prepared is None else prepared
    announce_dt(prepared, say)
    scene = timed(scene, prepared)
    duration = scene.numerics.duration if duration is None else duration
    run = Run(scene, packing, out_dir, int(round(duration / scene.numerics.dt)), start, prepared)
    with guard.hold(out_dir), Interrupts() as signals:
        remove_stale_temporaries(out_dir)
        manifest.clear(out_dir)  # an earlier run's files (--overwrite, a sweep's re-run job); others kept
        claim_outputs(out_dir, scene, run.rec.snap_steps)
        return run.go(scene.overrides, figures, signals)


def resume_run(out_dir, duration=None, figures=True):
    """Continue the run in ``out_dir`` from its checkpoint, in place (history.csv appended), to its
    end or to ``duration`` [s]. Returns the summary like ``run_scene``. Holds the folder's lock;
    the run is built again from the checkpoint (Run.from_checkpoint; CheckpointError) and history.csv
    checked against it before anything is written (Run.reopen; engines.run.history.HistoryMismatch)."""
    path = os.path.join(out_dir, CHECKPOINT)
    with guard.hold(out_dir):
        remove_stale_temporaries(out_dir)
        info = checkpoint.read_info(path)
        run = Run.from_checkpoint(out_dir)
        run.reopen(out_dir, info, duration)
        claim_outputs(out_dir, run.scene, run.rec.snap_steps)
        with Interrupts() as signals:
            return run.go({"numerics": {"duration": duration}} if duration is not None else None, figures, signals)


def done_line(summary, figures=()):
    """What a scene script prints at the end of a run (its only lines with --quiet): the steps, the
    cost, the water balance, then its results with units (engines.run.talk.result_lines) and the
    paths of its ``figures``."""
    return "\n".join([f"done: {summary['steps']} steps in {summary['wall_seconds']:.1f} s "
                      f"({summary['us_per_step']:.0f} us/step), water balance error {summary['water_balance_error']:.2e}"]
                     + ["  " + line for line in result_lines(summary.get("results", {}))]
                     + [f"  figure {path}" for path in figures])
