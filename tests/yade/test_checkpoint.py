"""Stop and resume: a run stopped at any step (a signal, a crash) and resumed from its checkpoint
matches the run that was not stopped, row for row and disc for disc; SIGINT and SIGTERM stop a
run within a second. The checkpoint is data (engines.yade.checkpoint): every attribute of the run's
objects is either stored or listed as derived (test_every_attribute_of_a_run_is_stored_or_derived),
and a file that is anything else is refused in one line with nothing executed.
And the ParaView series a run writes holds the numbers of its history."""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from yade import O

from engines import ROOT
from engines.compiled.water_model import WaterModel
from engines.run import runner
from engines.run import scene as scenes
from engines.run.runner import resume_run, run_scene
from engines.yade import checkpoint
from engines.yade.deposition import scene_packing
from postproc.run_files import read_history, read_snapshot

ENV = dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg")
STEPS = 1500
END = "snapshot_001.50ms.npz"
# quick-sand case 1 for 1.5 ms, pores rebuilt every 500 steps, rows every 100, VTK every 500
BASE = {"numerics": {"rebuild_interval": 500, "duration": STEPS * 1e-6},
        "output": {"snapshot_times": [STEPS * 1e-6], "history_interval": 100, "vtk": True, "vtk_interval": 500}}
CLI_BASE = ["--duration", "0.0015", "--set", "numerics.rebuild_interval=500", "--set", "output.snapshot_times=[0.0015]",
            "--set", "output.history_interval=100", "--vtk", "--set", "output.vtk_interval=500"]


@pytest.fixture(scope="module")
def packing():
    return scene_packing(scenes.preset("quicksand_case1"))


@pytest.fixture(scope="module")
def full_run(packing, tmp_path_factory):
    """The run that is not stopped: its output directory."""
    out = str(tmp_path_factory.mktemp("full"))
    assert run_scene(scenes.preset("quicksand_case1", BASE), packing, out, figures=False)["status"] == "completed"
    return out


def stop_at(monkeypatch, k):
    """Make the run stop as after a signal once step k is done."""
    monkeypatch.setattr(runner.Interrupts, "requested", lambda self: bool(self.received) or O.iter >= k)


def assert_same_run(a, b, exact=True):
    """The history and the final snapshot of runs a and b agree (exactly, or to round-off)."""
    ha, hb = read_history(os.path.join(a, "history.csv")), read_history(os.path.join(b, "history.csv"))
    assert len(ha["t"]) == len(hb["t"]) >= 1
    sa, sb = read_snapshot(os.path.join(a, END)), read_snapshot(os.path.join(b, END))
    if exact:  # byte for byte: one line ending (\n) before and after a resume
        history = [open(os.path.join(d, "history.csv"), "rb").read() for d in (a, b)]
        assert history[0] == history[1] and b"\r" not in history[0]
        for c in ha:
            assert np.array_equal(ha[c], hb[c], equal_nan=True), c
        for k in sa:
            assert np.array_equal(sa[k], sb[k]), k
        return
    for c in ha:  # law = 'yade': YADE's interactions come back in another order, so forces sum in another order
        assert np.allclose(ha[c], hb[c], rtol=1e-9, atol=1e-15, equal_nan=True), c
    ka, kb = np.lexsort(sa["pairs"].T[::-1]), np.lexsort(sb["pairs"].T[::-1])
    assert np.array_equal(sa["pairs"][ka], sb["pairs"][kb])
    for k, order in (("f_n", (ka, kb)), ("f_s", (ka, kb)), ("xz", None), ("vel", None)):
        x, y = (sa[k][order[0]], sb[k][order[1]]) if order else (sa[k], sb[k])
        assert np.allclose(x, y, rtol=0, atol=1e-12 * max(np.abs(x).max(), 1e-300)), k


def vtk_frames(run_dir, series):
    import xml.etree.ElementTree as ET
    return [(float(d.get("timestep")), os.path.join(run_dir, "vtk", d.get("file")))
            for d in ET.parse(os.path.join(run_dir, "vtk", f"{series}.pvd")).getroot().iter("DataSet")]


@pytest.mark.parametrize("k", [1234, 1000])  # between the intervals; at a rebuild, a row and a VTK frame
def test_a_resumed_run_matches_the_uninterrupted_one(packing, full_run, tmp_path, monkeypatch, k):
    out = str(tmp_path / "part")
    with monkeypatch.context() as m:
        stop_at(m, k)
        part = run_scene(scenes.preset("quicksand_case1", BASE), packing, out, figures=False)
    j = part["steps"]  # the first stop at or after step k: compiled runs of steps ask between them
    assert part["status"] == "interrupted" and k <= j < STEPS and part["checkpoint"]["step"] == j
    O.reset()  # nothing of the first run is left in YADE
    done = resume_run(out, figures=False)
    assert done["status"] == "completed" and done["steps"] == STEPS
    assert [(s["from_step"], s["to_step"], s["status"]) for s in done["segments"]] == \
        [(0, j, "interrupted"), (j, STEPS, "completed")]
    assert_same_run(full_run, out)
    assert [t for t, _ in vtk_frames(out, "pores")] == [t for t, _ in vtk_frames(full_run, "pores")]


@pytest.mark.parametrize("name,over,k,exact", [
    ("moving box, smoothing", {"loading": {"type": "cosine", "moves": "box"}, "water": {"smoothing": True}}, 777, True),
    ("yade law, water every 3 steps", {"contact": {"law": "yade", "spring": "a"}, "numerics": {"water_interval": 3}},
     1001, False),
    ("yade law, dry, O.run chunks", {"contact": {"law": "yade", "spring": "a"}, "water": {"enabled": False},
                                     "output": {"history_interval": 1500, "vtk": False}}, 700, False),
    ("flat walls, paper law", {"walls": {"kind": "flat"}, "contact": {"spring": "b"}}, 777, True),
    ("flat walls, yade law", {"walls": {"kind": "flat"}, "contact": {"law": "yade", "spring": "b"}}, 777, False),
    ("moving flat walls, paper law", {"walls": {"kind": "flat"}, "contact": {"spring": "b"},
                                      "loading": {"type": "cosine", "moves": "box"}}, 777, True),
    ("moving flat walls, yade law", {"walls": {"kind": "flat"}, "contact": {"law": "yade", "spring": "b"},
                                     "loading": {"type": "cosine", "moves": "box"}}, 777, False),
])
def test_other_engines_resume_too(packing, tmp_path, monkeypatch, name, over, k, exact):  # noqa: ARG001
    sc = scenes.preset("quicksand_case1", scenes._merge(BASE, over))
    full, out = str(tmp_path / "full"), str(tmp_path / "part")
    run_scene(sc, packing, full, figures=False)
    with monkeypatch.context() as m:
        stop_at(m, k)
        part = run_scene(sc, packing, out, figures=False)
    assert part["status"] == "interrupted" and part["steps"] >= k  # O.run chunks poll every 20 ms
    O.reset()
    assert resume_run(out, figures=False)["status"] == "completed"
    assert_same_run(full, out, exact)


@pytest.mark.parametrize("preset", ["liquefaction_case1", "liquefaction_case6"])  # a cosine; a record (Sampled)
def test_the_seismic_case_resumes_exactly(tmp_path, monkeypatch, preset):
    """The moving base (its motion), the side-wall discs on springs and the hysteretic springs."""
    sc = scenes.preset(preset, BASE)
    pk = scene_packing(sc)
    full, out = str(tmp_path / "full"), str(tmp_path / "part")
    run_scene(sc, pk, full, figures=False)
    with monkeypatch.context() as m:
        stop_at(m, 777)
        assert run_scene(sc, pk, out, figures=False)["status"] == "interrupted"
    O.reset()
    assert resume_run(out, figures=False)["status"] == "completed"
    assert_same_run(full, out)
    h = read_history(os.path.join(out, "history.csv"))
    assert np.any(h["base_disp"] != 0) and np.any(np.isfinite(h["side_left_dx"]))  # the base moved, the ties are on


def test_a_crashed_run_resumes_from_its_checkpoint(packing, full_run, tmp_path, monkeypatch):
    out = str(tmp_path / "crash")
    def crash(self, xz, k=None):  # noqa: ARG001
        raise RuntimeError("simulated crash")
    with monkeypatch.context() as m:
        m.setattr(WaterModel, "rebuild", crash)  # the first rebuild, half way through step 500
        with pytest.raises(RuntimeError, match="simulated crash"):
            run_scene(scenes.preset("quicksand_case1", BASE), packing, out, figures=False)
    summary = json.load(open(os.path.join(out, "summary.json")))
    assert summary["status"].startswith("failed") and summary["checkpoint"]["step"] == 0
    assert int(np.load(os.path.join(out, "failure_state.npz"))["step"]) == 500
    assert len(read_history(os.path.join(out, "history.csv"))["t"]) == 6  # rows 0 ... 500 were written
    O.reset()
    assert resume_run(out, figures=False)["status"] == "completed"  # from step 0: the six rows are dropped and made again
    assert_same_run(full_run, out)


def test_a_complete_run_goes_on_to_a_later_end_and_checkpoints_periodically(packing, full_run, tmp_path, monkeypatch):
    out = str(tmp_path / "short")
    saves = []
    save = checkpoint.save
    monkeypatch.setattr(checkpoint, "save", lambda *a: saves.append(O.iter) or save(*a))
    sc = scenes.preset("quicksand_case1", scenes._merge(BASE, {"output": {"checkpoint_seconds": 1e-9}}))
    assert run_scene(sc, packing, out, duration=0.001, figures=False)["status"] == "completed"
    assert saves == list(range(0, 1001, 100)) + [1000]  # at every hook call (rows, VTK frames), and at the end
    with pytest.raises(ValueError, match="complete"):
        resume_run(out, figures=False)
    O.reset()
    sc2 = resume_run(out, duration=STEPS * 1e-6, figures=False)
    assert sc2["status"] == "completed" and sc2["parameters"]["numerics"]["duration"] == STEPS * 1e-6
    assert_same_run(full_run, out)


# -- signals, through the script ------------------------------------------------------------------
def interrupted_script_run(out, sig):
    """Start quicksand.py on the BASE scene, send ``sig`` once it has written three rows; returns
    (seconds from the signal to the summary saying 'interrupted', to the process's exit, exit code)."""
    cmd = ["yade", "-n", "-x", "yade_scripts/quicksand.py", "--out", out] + CLI_BASE
    proc = subprocess.Popen(cmd, cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    history, summary = os.path.join(out, "history.csv"), os.path.join(out, "summary.json")
    deadline = time.time() + 300
    while not (os.path.exists(history) and open(history).read().count("\n") >= 4):
        assert proc.poll() is None and time.time() < deadline, proc.communicate()[0]
        time.sleep(0.005)
    t0 = time.time()
    proc.send_signal(sig)
    t_summary = None
    while proc.poll() is None or t_summary is None:
        if t_summary is None and os.path.exists(summary) and '"interrupted"' in open(summary).read():
            t_summary = time.time() - t0
        time.sleep(0.002)
        assert time.time() - t0 < 30, "the run did not stop"
    t_exit = time.time() - t0
    log = proc.communicate()[0]
    assert "--resume" in log, log
    return t_summary, t_exit, proc.returncode


@pytest.mark.check
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_script_within_a_second_and_it_resumes_exactly(full_run, tmp_path, sig):
    out = str(tmp_path / "run")
    t_summary, t_exit, code = interrupted_script_run(out, sig)
    summary = json.load(open(os.path.join(out, "summary.json")))
    k = summary["steps"]
    assert code == 128 + sig and summary["status"] == "interrupted"
    assert summary["interrupt"]["signal"] == sig.name and summary["interrupt"]["step"] == k < STEPS
    assert summary["checkpoint"]["step"] == k
    assert t_summary < 1.0 and t_exit < 1.0, (t_summary, t_exit)
    print(f"{sig.name}: stopped at step {k}, summary after {t_summary:.3f} s, exit after {t_exit:.3f} s "
          f"(in the run: {summary['interrupt']['seconds_to_stop']:.3f} s)")
    if sig == signal.SIGINT:  # resumed by the script
        run = subprocess.run(["yade", "-n", "-x", "yade_scripts/quicksand.py", "--resume", out], cwd=ROOT, env=ENV,
                             capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stdout + run.stderr
    else:  # resumed from Python
        O.reset()
        assert resume_run(out, figures=False)["status"] == "completed"
    assert_same_run(full_run, out)


def test_resume_refusals_come_before_yade(full_run, tmp_path):
    def refused(args):
        run = subprocess.run([sys.executable, "yade_scripts/quicksand.py"] + args, cwd=ROOT, env=ENV,
                             capture_output=True, text=True, timeout=120)
        assert run.returncode != 0 and "Traceback" not in run.stderr, run.stderr
        return run.stderr.strip().splitlines()[-1]
    assert "complete" in refused(["--resume", full_run])
    assert "already at t = 0.0015 s" in refused(["--resume", full_run, "--duration", "0.001"])
    assert "does not exist" in refused(["--resume", str(tmp_path)])
    assert "--dt" in refused(["--resume", full_run, "--dt", "1e-6"])
    assert "the scene" in refused(["--resume", full_run, "--case", "2"])
    old, marker = tmp_path / "old", tmp_path / "executed"  # a run folder of an older version, its pickle crafted
    old.mkdir()
    (old / "checkpoint.pkl").write_bytes(b"\x80\x02cbuiltins\nopen\n(V" + str(marker).encode() + b"\nVw\ntR.")  # open(marker, "w")
    line = refused(["--resume", str(old)])
    assert "checkpoint.pkl: a checkpoint of an older format (a pickle), which is not read" in line and not marker.exists()


# -- ParaView from a run --------------------------------------------------------------------------
def test_the_vtk_series_of_a_run_holds_the_numbers_of_its_history(full_run):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

    def read(path):
        rd = vtkXMLPolyDataReader()
        rd.SetFileName(path)
        rd.Update()
        return rd.GetOutput()

    def xz_of(poly):
        return vtk_to_numpy(poly.GetPoints().GetData())[:, [0, 2]]

    def cells(cell_array):
        off, con = vtk_to_numpy(cell_array.GetOffsetsArray()), vtk_to_numpy(cell_array.GetConnectivityArray())
        return [con[off[k]:off[k + 1]] for k in range(len(off) - 1)]

    h = read_history(os.path.join(full_run, "history.csv"))
    bounds = json.load(open(os.path.join(full_run, "summary.json")))["block_bounds_m"]
    (z0, z1), _ = bounds
    series = {name: vtk_frames(full_run, name) for name in ("discs", "forces", "pores")}
    assert [t for t, _ in series["pores"]] == pytest.approx([0.0, 5e-4, 1e-3, 1.5e-3], abs=1e-15)
    checked_rows = 0
    for (t, f_discs), (_, f_forces), (_, f_pores) in zip(series["discs"], series["forces"], series["pores"]):
        di, fo, po = read(f_discs), read(f_forces), read(f_pores)
        xz = xz_of(di)
        assert np.array_equal(xz_of(fo), xz) and np.array_equal(xz_of(po), xz)
        r, group = vtk_to_numpy(di.GetPointData().GetArray("radius [m]")), vtk_to_numpy(di.GetPointData().GetArray("group"))
        pcd, fcd = po.GetCellData(), fo.GetCellData()
        pore, U, W = (vtk_to_numpy(pcd.GetArray(n)) for n in ("pore", "U [N/m]", "W [m^2]"))
        rule = vtk_to_numpy(pcd.GetArray("rule"))
        # the first rebuild is done in step 500, after the frame at t = 500 dt: rules a-d from then on
        assert set(rule) <= {0, 1, 2, 3, 4} and (t < 6e-4) == (set(rule) == {0})
        # per pore: the area-weighted centroid of its outline(s), as the history's block means use
        area, moment = {}, {}
        for p, poly in zip(pore, cells(po.GetPolys())):
            x, z = xz[poly].T
            cross = x * np.roll(z, -1) - np.roll(x, -1) * z
            area[p] = area.get(p, 0.0) + cross.sum() / 2
            moment[p] = moment.get(p, 0.0) + ((z + np.roll(z, -1)) * cross).sum() / 6
        ids = sorted(area)
        first = {p: k for k, p in reversed(list(enumerate(pore)))}
        zc = np.array([moment[p] / area[p] for p in ids])
        U_pore, W_pore = U[[first[p] for p in ids]], W[[first[p] for p in ids]]
        pairs = np.array(cells(fo.GetLines()))
        f_n = vtk_to_numpy(fcd.GetArray("normal_force [N/m]"))
        row = np.flatnonzero(np.isclose(h["t"], t, rtol=0, atol=1e-12))
        if not len(row):  # the last frame, at the end of the run: the end snapshot holds the same arrays
            snap = read_snapshot(os.path.join(full_run, END))
            assert np.array_equal(snap["xz"], xz) and np.array_equal(snap["pairs"], pairs)
            assert np.array_equal(snap["f_n"], f_n) and np.array_equal(snap["f_s"], vtk_to_numpy(fcd.GetArray("shear_force [N/m]")))
            assert np.array_equal(snap["U"][ids], U_pore) and np.array_equal(snap["W"][ids], W_pore)
            assert np.array_equal(snap["vel"][:, 1], vtk_to_numpy(di.GetPointData().GetArray("velocity [m/s]"))[:, 2])
            continue
        k = row[0]
        for b, (lo, hi) in enumerate(bounds):
            sel = (zc >= lo) & (zc < hi)
            assert U_pore[sel].mean() == pytest.approx(h[f"U_block{b + 1}"][k], rel=1e-8, abs=1e-9)
        assert len(ids) == h["n_pores"][k] and W_pore.sum() == pytest.approx(h["total_water"][k], rel=1e-8)
        mob = group == 0
        assert np.max(xz[mob, 1] + r[mob]) == pytest.approx(h["bed_top"][k], rel=1e-8)
        zmid = 0.5 * (xz[pairs[:, 0], 1] + xz[pairs[:, 1], 1])
        bottom = (zmid >= z0) & (zmid < z1)
        assert f_n[bottom].mean() == pytest.approx(h["fn_bottom_mean"][k], rel=1e-8)
        checked_rows += 1
    assert checked_rows == 4  # the frames at 0, 0.5, 1 ms and the end's


