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
from engines.provenance import provenance
from engines.yade_coupling import YadeCoupling
from postproc import plots


class Recorder:
    """PyRunner hook: history rows every history_interval steps and snapshots at given times."""

    def __init__(self, cp, out_dir, progress_seconds, n_steps):
        self.cp, self.out, self.n_steps = cp, out_dir, n_steps
        core = cp.core
        self.n_blocks = len(core.block_bounds)
        self.columns = (["t"] + [f"U_block{b + 1}" for b in range(self.n_blocks)] +
                        ["porosity", "kinetic_energy", "water_balance_error", "total_water", "n_pores",
                         "fn_bottom_mean", "bed_top"])
        self.file = open(os.path.join(out_dir, "history.csv"), "w", newline="")
        self.writer = csv.writer(self.file)
        self.writer.writerow(self.columns)
        # a snapshot at the end time is taken at the last step
        self.snap_steps = sorted({min(int(round(t / core.dt)), n_steps - 1)
                                  for t in cp.scene.output.snapshot_times if round(t / core.dt) <= n_steps})
        self.snapshots = []
        self.progress_seconds = progress_seconds
        self.t_wall0 = self.t_last = time.time()

    def __call__(self, cp, xz):
        core = cp.core
        k = core.k - 1  # the step just computed, at t = k dt (positions xz)
        if k % cp.scene.output.history_interval == 0:
            self.row(core, xz, k)
        if k in self.snap_steps:
            self.snapshots.append(self.snapshot(core, xz, k))
        now = time.time()
        if now - self.t_last >= self.progress_seconds:
            self.t_last = now
            done = k + 1
            eta = (now - self.t_wall0) / done * (self.n_steps - done)
            print(f"[{cp.scene.scene.name}] step {done}/{self.n_steps} t = {done * core.dt * 1e3:.2f} ms, "
                  f"wall {now - self.t_wall0:.0f} s, about {eta:.0f} s left", flush=True)

    def row(self, core, xz, k):
        w = core.water
        mob = core.mobile
        values = ([k * core.dt] + list(core.block_pressures(xz)) +
                  [core.porosity(xz), core.kinetic_energy(), w.balance_error() if w else 0.0,
                   w.total_water() if w else 0.0, w.net.n_pores if w else 0,
                   core.bottom_normal_force(xz), float(np.max(xz[mob, 1] + core.r[mob]))])
        self.writer.writerow([f"{v:.9g}" for v in values])
        self.file.flush()

    def snapshot(self, core, xz, k):
        pairs, fn = core.contact.contact_pairs()
        snap = dict(t=k * core.dt, xz=xz.copy(), r=core.r, group=core.packing.group,
                    density_factor=core.packing.density_factor, vel=core.du / core.dt, pairs=pairs, f_n=fn)
        state = core.pore_state(xz)
        if state is not None:
            net, _, U = state
            snap.update(tri=net.tri, tri_pore=net.tri_pore, U=U)
        np.savez_compressed(os.path.join(self.out, f"snapshot_{k * core.dt * 1e3:06.2f}ms.npz"), **snap)
        return snap

    def close(self):
        self.file.close()


def write_checkpoint(cp, path):
    """Positions, velocities, spin and water of the current state (for a post-mortem or restart)."""
    core = cp.core
    xz = cp.positions()
    data = dict(step=core.k, t=core.k * core.dt, xz=xz, du=core.du, omega=core.omega, r=core.r,
                group=core.packing.group)
    if core.water is not None:
        data.update(W=core.water.W, U=core.water.pressure(pg.measure(core.water.net, xz, core.r).void_area))
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
    print(f"[{scene.scene.name}] {int(packing.mobile.sum())} particles, {int((~packing.mobile).sum())} wall discs, "
          f"{cp.core.water.net.n_pores if cp.core.water else 0} pores, dt = {scene.numerics.dt:g} s, "
          f"{n_steps} steps -> {out_dir}", flush=True)
    t0 = time.time()
    status = "completed"
    try:
        cp.run(n_steps)
    except BaseException as e:
        status = f"failed: {type(e).__name__}: {e}"
        write_checkpoint(cp, os.path.join(out_dir, "checkpoint.npz"))
        raise
    finally:
        wall = time.time() - t0
        rec.close()
        summary = summarise(scene, packing, cp, n_steps, wall, status)
        with open(os.path.join(out_dir, "summary.json"), "w") as f:
            json.dump(summary, f, indent=1)
        make_figures(scene, out_dir, rec.snapshots)
    return summary


def summarise(scene, packing, cp, n_steps, wall, status):
    core = cp.core
    w = core.water
    return {
        "scene": scene.scene.name, "status": status, "steps": int(O.iter), "steps_requested": n_steps,
        "wall_seconds": wall, "us_per_step": 1e6 * wall / max(O.iter, 1),
        "n_particles": int(packing.mobile.sum()), "n_walls": int((~packing.mobile).sum()),
        "n_pores": int(w.net.n_pores) if w else 0, "n_rebuilds": core.n_rebuilds,
        "dt": scene.numerics.dt, "t_end": O.iter * scene.numerics.dt,
        "water_balance_error": w.balance_error() if w else 0.0,
        "water_balance": vars(w.balance) if w else None,
        "remesh_rules_last": w.remesh_counts if w else None,
        "contact_list_builds": core.contact.list_builds,
        "block_bounds_m": core.block_bounds,
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
