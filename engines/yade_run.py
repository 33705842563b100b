"""Run a scene in YADE with outputs: history.csv, snapshots, figures, summary.json, checkpoint.

history.csv is appended and flushed row by row, so a crashed or interrupted run keeps what it
computed; on failure a checkpoint.npz (positions, velocities, water) is written beside it.
"""
import csv
import json
import os
import time

import numpy as np
from yade import O

from engines import pore_geometry as pg
from engines import yade_io
from engines.pore_dem import pore_state
from engines.provenance import provenance
from engines.yade_coupling import YadeCoupling
from postproc import plots


class Recorder:
    """Coupling hook: history rows every history_interval steps and snapshots at given times,
    taken between chunks of steps at the positions after k steps (t = k dt)."""

    def __init__(self, cp, out_dir, progress_seconds, n_steps):
        self.cp, self.out, self.n_steps = cp, out_dir, n_steps
        self.dt = cp.scene.numerics.dt
        self.n_blocks = len(cp.block_bounds)
        self.columns = (["t"] + [f"U_block{b + 1}" for b in range(self.n_blocks)] +
                        ["porosity", "kinetic_energy", "water_balance_error", "total_water", "n_pores",
                         "fn_bottom_mean", "bed_top", "base_acc", "base_vel", "base_disp", "side_left_dx",
                         "side_right_dx", "remesh_change"])
        self.file = open(os.path.join(out_dir, "history.csv"), "w", newline="")
        self.writer = csv.writer(self.file)
        self.writer.writerow(self.columns)
        self.snap_steps = sorted({int(round(t / self.dt)) for t in cp.scene.output.snapshot_times
                                  if round(t / self.dt) <= n_steps})
        self.snapshots = []
        self.progress_seconds = progress_seconds
        self.t_wall0 = self.t_last = time.time()

    def __call__(self, cp):
        k = cp.step_index  # steps done: positions at t = k dt
        xz = cp.positions()
        if k % cp.scene.output.history_interval == 0 and k < self.n_steps:
            self.row(cp, xz, k)
        if k in self.snap_steps:
            self.snapshots.append(self.snapshot(cp, xz, k))
        now = time.time()
        if now - self.t_last >= self.progress_seconds:
            self.t_last = now
            eta = (now - self.t_wall0) / max(k, 1) * (self.n_steps - k)
            print(f"[{cp.scene.scene.name}] step {k}/{self.n_steps} t = {k * self.dt * 1e3:.2f} ms, "
                  f"wall {now - self.t_wall0:.0f} s, about {eta:.0f} s left", flush=True)

    def row(self, cp, xz, k):
        w = cp.water
        mob = cp.packing.mobile
        values = ([k * self.dt] + list(cp.block_pressures(xz)) +
                  [cp.porosity(xz), cp.kinetic_energy(), w.balance_error() if w else 0.0,
                   w.total_water() if w else 0.0, w.net.n_pores if w else 0,
                   cp.bottom_normal_force(xz), float(np.max(xz[mob, 1] + cp.packing.r[mob]))] +
                  list(cp.base_motion()) + list(cp.side_wall_shift(xz)) + [w.balance.remesh_change if w else 0.0])
        self.writer.writerow([f"{v:.9g}" for v in values])
        self.file.flush()

    def snapshot(self, cp, xz, k):
        pairs, fn = cp.contact_pairs(xz)
        pk = cp.packing
        snap = dict(t=k * self.dt, xz=xz.copy(), r=pk.r, group=pk.group, density_factor=pk.density_factor,
                    vel=cp.velocities(), pairs=pairs, f_n=fn)
        state = pore_state(cp.water, xz, pk.r)
        if state is not None:
            net, _, U = state
            snap.update(tri=net.tri, tri_pore=net.tri_pore, U=U)
        np.savez_compressed(os.path.join(self.out, f"snapshot_{k * self.dt * 1e3:06.2f}ms.npz"), **snap)
        return snap

    def close(self):
        self.file.close()


def write_checkpoint(cp, path):
    """Positions, velocities, spin and water of the current state (for a post-mortem or restart)."""
    xz = cp.positions()
    data = dict(step=cp.step_index, t=cp.step_index * cp.scene.numerics.dt, xz=xz, vel=cp.velocities(),
                r=cp.packing.r, group=cp.packing.group)
    if cp.core is not None:
        data.update(du=cp.core.du, omega=cp.core.omega, contact_pairs=np.column_stack([cp.core.contact.i, cp.core.contact.j]),
                    contact_state=cp.core.contact.state)
    if cp.water is not None:
        data.update(W=cp.water.W, U=cp.water.pressure(pg.measure(cp.water.net, xz, cp.packing.r).void_area))
    np.savez_compressed(path, **data)


def run_scene(scene, packing, out_dir, duration=None):
    """Run ``scene`` on ``packing`` for ``duration`` (default: the scene's) and write the outputs.
    Returns the summary dict; re-raises after writing the checkpoint if the run fails."""
    os.makedirs(out_dir, exist_ok=True)
    duration = scene.numerics.duration if duration is None else duration
    n_steps = int(round(duration / scene.numerics.dt))
    cp = YadeCoupling(scene, packing)
    rec = Recorder(cp, out_dir, scene.output.progress_seconds, n_steps)
    cp.hooks.append(rec)
    cp.run_every, cp.stops = scene.output.history_interval, set(rec.snap_steps)
    print(f"[{scene.scene.name}] {int(packing.mobile.sum())} particles, {int((~packing.mobile).sum())} wall discs, "
          f"{cp.water.net.n_pores if cp.water else 0} pores, law = {scene.contact.law}, I/O {yade_io.BACKEND}, "
          f"dt = {scene.numerics.dt:g} s, {n_steps} steps -> {out_dir}", flush=True)
    t0, c0 = time.time(), time.process_time()
    status = "completed"
    try:
        cp.run(n_steps)
    except BaseException as e:
        status = f"failed: {type(e).__name__}: {e}"
        write_checkpoint(cp, os.path.join(out_dir, "checkpoint.npz"))
        raise
    finally:
        wall, cpu = time.time() - t0, time.process_time() - c0
        rec.close()
        summary = summarise(scene, packing, cp, n_steps, wall, status)
        summary["cpu_seconds"] = cpu
        with open(os.path.join(out_dir, "summary.json"), "w") as f:
            json.dump(summary, f, indent=1)
        make_figures(scene, out_dir, rec.snapshots)
    return summary


def done_line(summary):
    """The one line a scene script prints at the end of a run."""
    return (f"done: {summary['steps']} steps in {summary['wall_seconds']:.1f} s ({summary['us_per_step']:.0f} us/step), "
            f"water balance error {summary['water_balance_error']:.2e}")


def summarise(scene, packing, cp, n_steps, wall, status):
    w, wm = cp.water, cp.water_model
    return {
        "scene": scene.scene.name, "status": status, "steps": int(O.iter), "steps_requested": n_steps,
        "wall_seconds": wall, "us_per_step": 1e6 * wall / max(O.iter, 1),
        "n_particles": int(packing.mobile.sum()), "n_walls": int((~packing.mobile).sum()),
        "n_pores": int(w.net.n_pores) if w else 0, "n_rebuilds": wm.n_rebuilds if wm else 0,
        "water_substeps_max": wm.substeps_max if wm else 0, "law": scene.contact.law, "io_backend": yade_io.BACKEND,
        "dt": scene.numerics.dt, "t_end": O.iter * scene.numerics.dt,
        "water_balance_error": w.balance_error() if w else 0.0,
        "water_balance": vars(w.balance) if w else None,
        "remesh_rules_last": w.remesh_counts if w else None,
        "contact_list_builds": cp.core.contact.list_builds if cp.core is not None else None,
        "block_bounds_m": cp.block_bounds,
        "parameters": scene.as_dict(),
        "provenance": provenance(overrides=scene.overrides),
    }


def make_figures(scene, out_dir, snapshots):
    hist_path = os.path.join(out_dir, "history.csv")
    history = plots.read_history(hist_path) if os.path.exists(hist_path) else {}
    if len(history.get("t", [])) < 2:
        return
    title = scene.scene.name
    if scene.water.enabled:
        plots.plot_block_pressures(history, scene.water.E_w, os.path.join(out_dir, "pressure_blocks.png"),
                                   f"{title}: block-mean excess pore pressure")
    plots.plot_history_panels(history, os.path.join(out_dir, "history_panels.png"), title)
    if snapshots:
        plots.plot_snapshots(snapshots, os.path.join(out_dir, "snapshots.png"), title)
