"""Run a scene in YADE with outputs: history.csv, snapshots, VTK, figures, summary.json, checkpoints.

``run_scene`` starts a run, ``resume_run`` continues one from its checkpoint, in place. history.csv
is appended and flushed row by row, so a stopped or crashed run keeps what it computed.

Stopping: SIGINT (Ctrl-C) or SIGTERM during a run stops it after the current step: the history is
flushed, a checkpoint written, summary.json says "interrupted" with the step, and the run returns
(the scripts then exit with 128 + the signal's number). A second signal stops at once.

Checkpoints (engines.yade.checkpoint, ``checkpoint.pkl``): at the start, every
``[output] checkpoint_seconds`` of wall time, at the end and on an interrupt; each holds YADE's
scene and the whole ``Run`` (coupling, recorder, bookkeeping), so that a resumed run continues
exactly as if it had not stopped. A crashed run keeps its last checkpoint (resumable: the history
rows written after it are dropped on resume) and writes the state at the failing step to
``failure_state.npz`` for a post-mortem.
"""
import csv
import json
import math
import os
import shutil
import signal
import threading
import time
from glob import glob

import numpy as np
from yade import O

from engines.model import pores as pg
from engines.model.pore_dem import pore_state
from engines.run.provenance import provenance
from engines.yade import checkpoint, yade_io
from engines.yade.coupling import YadeCoupling
from postproc import plots
from postproc.run_files import headline_results, read_history

CHECKPOINT = checkpoint.NAME
FAILURE_STATE = "failure_state.npz"


class Recorder:
    """Coupling hook: history rows every history_interval steps, snapshots at the scene's snapshot
    times and, with [output] vtk, ParaView frames (postproc.vtk) every vtk_interval steps or at the
    snapshot times; taken between steps at the positions after k steps (t = k dt). Each is taken
    once per step index, so a resumed run does not repeat one. Pickled with the run (the open
    history file is left out and opened again by ``reopen``)."""

    def __init__(self, cp, out_dir, n_steps):
        out = cp.scene.output
        self.dt = cp.scene.numerics.dt
        self.history_interval, self.vtk_interval = out.history_interval, out.vtk_interval
        self.snapshot_times = out.snapshot_times
        self.progress_seconds = out.progress_seconds
        self.n_blocks = len(cp.block_bounds)
        self.columns = (["t"] + [f"U_block{b + 1}" for b in range(self.n_blocks)] +
                        ["porosity", "kinetic_energy", "water_balance_error", "total_water", "n_pores",
                         "fn_bottom_mean", "bed_top", "base_acc", "base_vel", "base_disp", "side_left_dx",
                         "side_right_dx", "remesh_change"] +
                        [f"wall_{name}_{part}" for name in cp.wall_loads() for part in ("contact", "water")])
        self.rows, self.last_row, self.last_vtk = 0, -1, -1
        self.snapshot_steps = []  # steps whose snapshot file was written
        self.vtk = None
        if out.vtk:
            from postproc.vtk import VtkSeries
            self.vtk = VtkSeries(out_dir)
        self.schedule(n_steps)
        self.out = out_dir
        self._open("w")
        self.writer.writerow(self.columns)
        self.file.flush()

    def schedule(self, n_steps):
        """The run ends at step n_steps: snapshot steps within it."""
        self.n_steps = n_steps
        self.snap_steps = sorted({int(round(t / self.dt)) for t in self.snapshot_times if round(t / self.dt) <= n_steps})

    def _open(self, mode):
        self.file = open(os.path.join(self.out, "history.csv"), mode, newline="")
        self.writer = csv.writer(self.file, lineterminator="\n")
        self.t_wall0 = self.t_last = time.time()
        self.k_wall0 = O.iter

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in ("file", "writer")}

    def reopen(self, out_dir):
        """Continue in ``out_dir``: history.csv cut to the rows this recorder had written (a crashed
        run may have written more after its checkpoint), then appended to."""
        self.out = out_dir
        path = os.path.join(out_dir, "history.csv")
        with open(path) as f:
            lines = f.readlines()
        if len(lines) < 1 + self.rows:
            raise checkpoint.CheckpointError(f"{path} has {len(lines) - 1} rows, the checkpoint wrote {self.rows}")
        with open(path, "w") as f:
            f.writelines(lines[:1 + self.rows])
        if self.vtk is not None:
            self.vtk.dir = os.path.join(out_dir, "vtk")
        self._open("a")

    def __call__(self, cp):
        k = cp.step_index  # steps done: positions at t = k dt
        xz = cp.positions()
        if k % self.history_interval == 0 and self.last_row < k < self.n_steps:
            self.row(cp, xz, k)
        snap_due = k in self.snap_steps and k not in self.snapshot_steps
        vtk_due = self.vtk is not None and k > self.last_vtk and \
            (k % self.vtk_interval == 0 if self.vtk_interval else k in self.snap_steps)
        if snap_due or vtk_due:
            snap = snapshot_data(cp, xz, k)
            if snap_due:
                np.savez_compressed(os.path.join(self.out, f"snapshot_{k * self.dt * 1e3:06.2f}ms.npz"), **snap)
                self.snapshot_steps.append(k)
            if vtk_due:
                from postproc.vtk import snapshot_frame
                self.vtk.add(snap["t"], *snapshot_frame(snap))
                self.last_vtk = k
        now = time.time()
        if now - self.t_last >= self.progress_seconds:
            self.t_last = now
            eta = (now - self.t_wall0) / max(k - self.k_wall0, 1) * (self.n_steps - k)
            print(f"[{cp.scene.scene.name}] step {k}/{self.n_steps} t = {k * self.dt * 1e3:.2f} ms, "
                  f"wall {now - self.t_wall0:.0f} s, about {eta:.0f} s left", flush=True)

    def row(self, cp, xz, k):
        w = cp.water
        mob = cp.packing.mobile
        values = ([k * self.dt] + list(cp.block_pressures(xz)) +
                  [cp.porosity(xz), cp.kinetic_energy(), w.balance_error() if w else 0.0,
                   w.total_water() if w else 0.0, w.net.n_pores if w else 0,
                   cp.bottom_normal_force(xz), float(np.max(xz[mob, 1] + cp.packing.r[mob]))] +
                  list(cp.base_motion()) + list(cp.side_wall_shift(xz)) + [w.balance.remesh_change if w else 0.0] +
                  [f for load in cp.wall_loads().values() for f in load])
        self.writer.writerow([f"{v:.9g}" for v in values])
        self.file.flush()
        self.rows += 1
        self.last_row = k

    def close(self):
        self.file.close()


def snapshot_data(cp, xz, k):
    """The arrays of a snapshot at step k (positions xz): discs, touching pairs with their normal
    and elastic shear forces and, with water, the pores as triangles with U, W, A and rule (with
    flat walls, ``vertices``: the positions tri indexes, and ``flat_walls`` (W, 3): axis, position
    [m] now, inward of each)."""
    pairs, fn, fs = cp.contact_pairs(xz)
    pk = cp.packing
    snap = dict(t=k * cp.scene.numerics.dt, xz=xz.copy(), r=pk.r, group=pk.group, density_factor=pk.density_factor,
                vel=cp.velocities(), pairs=pairs, f_n=fn, f_s=fs)
    if cp.flat_walls:
        snap["flat_walls"] = np.array([[w.axis, face, w.inward] for w, face in zip(cp.flat_walls.values(),
                                                                                 cp.flat_wall_faces())])
    state = pore_state(cp.water_model, xz)
    if state is not None:
        net, A, U = state
        snap.update(tri=net.tri, tri_pore=net.tri_pore, U=U, W=cp.water.W.copy(), A=A, rule=cp.water.rule)
        if net.wall_vertices is not None:  # tri indexes the discs, then the flat walls' vertices
            snap["vertices"] = pg.vertex_positions(net, xz)
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
    np.savez_compressed(path, **data)


class Interrupts:
    """While active (``with``): the first SIGINT or SIGTERM is noted (``requested()`` turns true,
    the run stops after its current step), a second one raises KeyboardInterrupt at once.
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
        if self.received:
            raise KeyboardInterrupt(f"second signal ({signal.Signals(signum).name})")
        self.received.append((signum, time.time()))

    def requested(self):
        return bool(self.received)

    def __exit__(self, *exc):
        for s, handler in self._previous.items():
            signal.signal(s, handler)


class Run:
    """One run of a scene in ``out_dir``: the coupling, its recorder and the bookkeeping of the
    run's segments (a start and each resume). Pickled whole into the checkpoints; it is also the
    coupling's last hook, which writes the periodic checkpoints. ``start``: which start of an
    ensemble the packing is ({"seed", "perturbation_m"}; engines.run.ensemble), or None."""

    start = None

    def __init__(self, scene, packing, out_dir, n_steps, start=None):
        self.scene, self.out, self.n_steps, self.start = scene, out_dir, n_steps, start
        self.cp = YadeCoupling(scene, packing)
        self.rec = Recorder(self.cp, out_dir, n_steps)
        self.cp.hooks += [self.rec, self]
        self.segments = []
        self.checkpoint_step = None
        self._last_checkpoint = -math.inf  # the first hook call (step 0) writes one
        self._schedule()

    def _schedule(self):
        out = self.scene.output
        every = math.gcd(out.history_interval, out.vtk_interval) if out.vtk else out.history_interval
        self.cp.schedule.set_output(every, self.rec.snap_steps)

    def __call__(self, cp):  # noqa: ARG002  (the hook: periodic checkpoints)
        if time.time() - self._last_checkpoint >= self.scene.output.checkpoint_seconds:
            self.save_checkpoint()

    def save_checkpoint(self):
        self.checkpoint_step = O.iter
        checkpoint.save(os.path.join(self.out, CHECKPOINT), self,
                        {"n_steps": self.n_steps, "dt": self.scene.numerics.dt, "scene": self.scene.scene.name})
        self._last_checkpoint = time.time()

    def reopen(self, out_dir, duration=None):
        """After checkpoint.load: continue in ``out_dir`` (to ``duration`` [s] if given: a later end)."""
        self.out = out_dir
        self.cp.restore_forces()
        n = checkpoint.resume_end(O.iter, self.n_steps, self.scene.numerics.dt, duration)
        if duration is not None:
            self.scene = self.cp.scene = self.scene.with_overrides({"numerics": {"duration": duration}})
            self.n_steps = n
            self.rec.schedule(n)
            self._schedule()
            self.cp._hooked_at = None  # the hooks see this step again: the row at the old end is due now
        self.rec.reopen(out_dir)
        self._last_checkpoint = time.time()

    def go(self, overrides=None, figures=True):
        """Run to step n_steps (or until a signal or an error); write the checkpoint, summary and
        (when completed) the figures. Returns the summary; re-raises an error after writing what
        it can."""
        cp, sc = self.cp, self.scene
        k0, t0, c0, started = O.iter, time.time(), time.process_time(), time.strftime("%Y-%m-%dT%H:%M:%S")
        print(f"[{sc.scene.name}] {int(cp.packing.mobile.sum())} particles, {int((~cp.packing.mobile).sum())} wall discs, "
              f"{cp.water.net.n_pores if cp.water else 0} pores, law = {sc.contact.law}, I/O {yade_io.BACKEND}, "
              f"dt = {sc.numerics.dt:g} s, steps {k0} to {self.n_steps} -> {self.out}", flush=True)
        status = "completed"
        with Interrupts() as signals:
            try:
                if not cp.run(self.n_steps - k0, stop=signals.requested):
                    status = "interrupted"
            except BaseException as e:
                status = f"failed: {type(e).__name__}: {e}"
                write_failure_state(cp, os.path.join(self.out, FAILURE_STATE))
                raise
            finally:
                self.rec.close()
                self.segments.append({"from_step": k0, "to_step": int(O.iter), "status": status,
                                      "wall_seconds": time.time() - t0, "cpu_seconds": time.process_time() - c0, "started": started,
                                      "provenance": provenance(overrides=overrides)})
                if not status.startswith("failed"):
                    self.save_checkpoint()
                summary = self.summarise(status, signals.received)
                with open(os.path.join(self.out, "summary.json"), "w") as f:
                    json.dump(summary, f, indent=1)
                if status == "completed" and figures:
                    plots.figures_of_run(self.out)
        return summary

    def summarise(self, status, received):
        cp, sc = self.cp, self.scene
        w, wm = cp.water, cp.water_model
        wall = sum(s["wall_seconds"] for s in self.segments)
        steps_run = sum(s["to_step"] - s["from_step"] for s in self.segments)
        history_path = os.path.join(self.out, "history.csv")
        results = headline_results(read_history(history_path) if os.path.exists(history_path) else {},
                                   sc.output.heave_rise)
        if not status.startswith("failed"):
            results["porosity_end"] = cp.porosity(cp.positions())
        summary = {
            "scene": sc.scene.name, "status": status, "steps": int(O.iter), "steps_requested": self.n_steps,
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
            "start": self.start,
            "results": results,
            "checkpoint": {"file": CHECKPOINT, "step": self.checkpoint_step},
            "parameters": sc.as_dict(),
            "provenance": self.segments[0]["provenance"],
            "segments": self.segments,
        }
        if received:
            signum, t_signal = received[0]
            summary["interrupt"] = {"signal": signal.Signals(signum).name, "step": int(O.iter),
                                    "seconds_to_stop": time.time() - t_signal}
        return summary


def clear_outputs(out_dir):
    """Remove the files an earlier run left in ``out_dir`` that this one would not overwrite."""
    for path in glob(os.path.join(out_dir, "snapshot_*.npz")) + [os.path.join(out_dir, f) for f in (CHECKPOINT, FAILURE_STATE)]:
        if os.path.exists(path):
            os.remove(path)
    shutil.rmtree(os.path.join(out_dir, "vtk"), ignore_errors=True)


def run_scene(scene, packing, out_dir, duration=None, figures=True, start=None):
    """Run ``scene`` on ``packing`` for ``duration`` (default: the scene's) and write the outputs
    (``figures=False``: no PNGs; ``python3 -m postproc.plots DIR`` draws them later; ``start``:
    the ensemble's start the packing is, recorded in summary.json).
    Returns the summary ("status": completed or interrupted); re-raises an error after writing
    the history, summary and failure state. A dt = "auto" is chosen here (engines.model.time_step; printed)."""
    from engines.model.time_step import resolve_dt
    scene = resolve_dt(scene, packing)
    os.makedirs(out_dir, exist_ok=True)
    clear_outputs(out_dir)
    duration = scene.numerics.duration if duration is None else duration
    return Run(scene, packing, out_dir, int(round(duration / scene.numerics.dt)), start).go(scene.overrides, figures)


def resume_run(out_dir, duration=None, figures=True):
    """Continue the run in ``out_dir`` from its checkpoint, in place (history.csv appended), to its
    end or to ``duration`` [s]. Returns the summary like ``run_scene``."""
    run = checkpoint.load(os.path.join(out_dir, CHECKPOINT))
    run.reopen(out_dir, duration)
    return run.go({"numerics": {"duration": duration}} if duration is not None else None, figures)


def done_line(summary):
    """The one line a scene script prints at the end of a run."""
    return (f"done: {summary['steps']} steps in {summary['wall_seconds']:.1f} s ({summary['us_per_step']:.0f} us/step), "
            f"water balance error {summary['water_balance_error']:.2e}")
