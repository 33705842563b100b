"""The checkpoint is data: every attribute of a run's objects is stored or listed as derived (with
its reason), and a file that is anything else than a checkpoint of this format is refused in one
line naming it, with nothing of it executed (a pickle, an object array, fields that are unknown,
missing or of another dtype or shape, a truncated file, a YADE scene with a PyRunner)."""
import io
import json
import os
import pickle
import shutil
import zipfile

import numpy as np
import pytest
from yade import O

from engines.model import state as named_state
from engines.run import runner
from engines.run import scene as scenes
from engines.run.runner import Run, resume_run, run_scene
from engines.yade import checkpoint
from engines.yade.deposition import scene_packing

STEPS = 300
SHORT = {"numerics": {"rebuild_interval": 100, "duration": STEPS * 1e-6},
         "output": {"snapshot_times": [STEPS * 1e-6], "history_interval": 100}}
# scenes whose objects between them have every class of a run's state and every optional attribute
SCENES = {
    "quick sand, paper law, VTK": ("quicksand_case1", {"output": {"vtk": True, "vtk_interval": 100}}),
    "moving box, smoothing": ("quicksand_case1", {"loading": {"type": "cosine", "moves": "box"},
                                                  "water": {"smoothing": True}}),
    "seismic, side-wall ties": ("liquefaction_case1", {}),
    "seismic record": ("liquefaction_case6", {}),
    "flat walls, paper law": ("quicksand_case1", {"walls": {"kind": "flat"}, "contact": {"spring": "b"}}),
    "yade law, moving base": ("quicksand_case1", {"contact": {"law": "yade", "spring": "a"},
                                                  "loading": {"type": "cosine", "moves": "bottom"}}),
    "flat walls, yade law": ("quicksand_case1", {"walls": {"kind": "flat"}, "contact": {"law": "yade", "spring": "b"}}),
}
# classes of the project whose instances a run holds without storing them: constant for a run
CONSTANT = {
    "Scene": "the scene: the recipe", "Packing": "the packing: the recipe",
    "FlatWall": "a frozen dataclass made from the scene and packing",
    "ContactSettings": "the scene's [contact]", "WaterSettings": "the scene's [water]",
    "Window": "the porosity window, from the scene and packing", "Bodies": "YADE body ids, from the build",
    "WaterBalance": "stored whole as a dict of its fields (PoreWater.balance)",
    "Settings": "the scene's tables (Scene.settings): the recipe",
    **{t: f"the scene's [{t.lower()}] (Scene.settings): the recipe"
       for t in ("Walls", "Material", "Contact", "Water", "Loading", "Numerics", "Output")},
    "Start": "the run's start (engines.model.start), made from the scene and packing",
}


def build(name, tmp_path, steps=STEPS):
    """A run of SCENES[name] in tmp_path/name after ``steps`` steps (its attributes made by stepping too)."""
    preset, over = SCENES[name]
    sc = scenes.preset(preset, scenes._merge(SHORT, over))
    out = str(tmp_path / name.replace(" ", "_").replace(",", ""))
    os.makedirs(out)
    run = Run(sc, scene_packing(sc), out, STEPS)
    run.rec.create()
    run.cp.run(steps)
    run.rec.close()
    return run


def parts(obj, path="run", seen=None):
    """(path, object) of ``obj`` and every object of the project reachable from its attributes."""
    seen = set() if seen is None else seen
    if id(obj) in seen:
        return
    seen.add(id(obj))
    yield path, obj
    for name, value in vars(obj).items():
        values = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, (list, tuple)) \
            else [(None, value)]
        for key, v in values:
            if type(v).__module__.split(".")[0] in ("engines", "postproc", "packing") and hasattr(v, "__dict__"):
                yield from parts(v, f"{path}.{name}" + ("" if key is None else f"[{key!r}]"), seen)


@pytest.mark.parametrize("name", SCENES)
def test_every_attribute_of_a_run_is_stored_or_derived(tmp_path, name):
    """An attribute an object of a run's state gains must be added to its class's CHECKPOINT_FIELDS
    (stored) or CHECKPOINT_DERIVED (with the reason it need not be): pickle's completeness, by list."""
    run = build(name, tmp_path)
    checked = set()
    for path, obj in parts(run):
        cls = type(obj)
        if not named_state.is_part(obj):
            assert cls.__name__ in CONSTANT, f"{path}: a {cls.__name__} of the run's state lists no CHECKPOINT_FIELDS"
            continue
        fields, derived = set(cls.CHECKPOINT_FIELDS), cls.CHECKPOINT_DERIVED
        assert not fields & set(derived), f"{cls.__name__}: both stored and derived: {fields & set(derived)}"
        assert all(isinstance(why, str) and why for why in derived.values()), cls.__name__
        unlisted = set(vars(obj)) - fields - set(derived)
        assert not unlisted, f"{path} ({cls.__name__}): attributes {sorted(unlisted)} are neither stored nor derived"
        checked.add(cls.__name__)
    assert {"Run", "Recorder", "YadeCoupling"} <= checked
    values = named_state.state_of(run)
    assert values["n_steps"] == STEPS and values["cp._hooked_at"] == STEPS  # the hooks ran at the last step


def test_the_lists_cover_every_class_of_a_run(tmp_path):
    """The scenes above reach every class that lists checkpoint fields (so each is checked)."""
    seen = set()
    for name in SCENES:
        seen |= {type(obj).__name__ for _, obj in parts(build(name, tmp_path, 3)) if named_state.is_part(obj)}
    assert seen >= {"Run", "Recorder", "VtkSeries", "YadeCoupling", "PaperLawEngine", "WaterEngine", "PoreDEM",
                    "PaperLaw", "ContactLaw", "WallVertices", "BaseMotion", "Cosine", "Sampled", "WaterModel",
                    "PoreWater", "PoreNetwork", "SideWallTies", "WallMotion"}


# -- refused, nothing executed --------------------------------------------------------------------
class Payload:
    """Unpickled, it would create the file ``marker``."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (open, (self.marker, "w"))


@pytest.fixture(scope="module")
def saved_run(tmp_path_factory):
    """A stopped run's folder (paper's law, water, VTK) with its checkpoint at step 150."""
    out = str(tmp_path_factory.mktemp("saved"))
    sc = scenes.preset("quicksand_case1", scenes._merge(SHORT, {"output": {"vtk": True, "vtk_interval": 50}}))
    run = Run(sc, scene_packing(sc), out, STEPS)
    run.rec.create()
    run.cp.run(150)
    run.rec.close()
    run.save_checkpoint()
    return out


def copy_run(src, dst):
    shutil.copytree(src, dst)
    return str(dst), os.path.join(dst, checkpoint.NAME)


def rewrite(path, edit_header=None, edit_arrays=None):
    """Write the checkpoint ``path`` again with its header (a dict) and arrays edited in place."""
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(arrays.pop("header").tobytes())
    if edit_header:
        edit_header(header)
    if edit_arrays:
        edit_arrays(arrays)
        header["arrays"] = sorted(arrays)
    np.savez(path, header=np.frombuffer(json.dumps(header).encode(), np.uint8), **arrays)


def refused(run_dir, match):
    """Resuming ``run_dir`` is refused with a one-line CheckpointError matching ``match``, naming the file."""
    O.reset()
    with pytest.raises(checkpoint.CheckpointError, match=match) as e:
        resume_run(run_dir, figures=False)
    msg = str(e.value)
    assert "\n" not in msg and (checkpoint.NAME in msg or "checkpoint.pkl" in msg), msg
    return msg


def test_the_saved_run_resumes(saved_run, tmp_path):
    """The control of the refusals below: the unedited copy resumes to its end."""
    run_dir, _ = copy_run(saved_run, tmp_path / "run")
    O.reset()
    assert resume_run(run_dir, figures=False)["status"] == "completed"


def test_a_pickle_is_refused_unread(saved_run, tmp_path):
    marker = tmp_path / "executed"
    run_dir, path = copy_run(saved_run, tmp_path / "run")
    with open(path, "wb") as f:
        pickle.dump({"format": checkpoint.FORMAT, "state": Payload(str(marker))}, f)
    assert "older format (a pickle)" in refused(run_dir, "older format")
    with pytest.raises(checkpoint.CheckpointError, match="older format"):
        checkpoint.read_info(path)
    os.rename(path, os.path.join(run_dir, "checkpoint.pkl"))  # a folder of a run of formats 1-3
    assert "checkpoint.pkl: a checkpoint of an older format" in refused(run_dir, "older format")
    assert not marker.exists()


def test_an_object_array_is_refused_unread(saved_run, tmp_path):
    marker = tmp_path / "executed"
    run_dir, path = copy_run(saved_run, tmp_path / "run")
    rewrite(path, edit_arrays=lambda a: a.update({"state:rec.rows": np.array([Payload(str(marker))], object)}))
    refused(run_dir, "not a readable checkpoint.*allow_pickle")
    assert not marker.exists()


@pytest.mark.parametrize("edit,match", [
    (lambda h: h["state"].update({"cp.core.hack": 1}), r"unknown field\(s\) \['cp.core.hack'\]"),
    (lambda h: h["state"].pop("rec.rows"), "field rec.rows is missing"),
    (lambda h: h["state"].update({"rec.rows": "2"}), "field rec.rows: expected a int, got a str"),
    (lambda h: h["state"].update({"checkpoint_step": [1]}), "checkpoint_step: expected an array"),
    (lambda h: h["state"]["segments"].append({"from_step": 0}), "segment 0: expected from_step, to_step"),
    (lambda h: h.update({"format": 3}), "not a checkpoint of format 4 .format 3."),
    (lambda h: h.update({"extra": 1}), "the header's fields"),
    (lambda h: h["recipe"].update({"start": "x"}), "recipe"),
    (lambda h: h["recipe"]["scene"]["tables"]["numerics"].update({"dt": -1}), "scene or packing is refused.*dt"),
    (lambda h: h["yade"].update({"iter": 3}), "YADE's iter"),
])
def test_a_header_with_other_fields_is_refused(saved_run, tmp_path, edit, match):
    run_dir, path = copy_run(saved_run, tmp_path / "run")
    rewrite(path, edit_header=edit)
    refused(run_dir, match)


@pytest.mark.parametrize("name,value,match", [
    ("state:cp.core.law.omega", lambda a: a.astype(np.int64), "omega: expected an array of float64, got int64"),
    ("state:cp.core.law.omega", lambda a: a[:-1], r"omega: expected shape \(76,\)"),
    ("state:cp.core.law.xz_prev", lambda a: a[:-1], r"xz_prev has shape \(75, 2\), expected \(76, 2\)"),
    ("state:cp.core.water_model.water.net.tri", lambda a: a[:, :2], r"tri has shape"),
    ("state:cp.core.law.contact.i", lambda a: a + 1000, "pair list: disc indices outside"),
    ("state:cp.core.water_model.water.net.links", lambda a: a + 10**6, "links holds indices outside"),
    ("state:cp.core.water_model.water.W", lambda a: a[:-1], "W, A_prev and rule must be one per pore"),
    ("yade:pos", lambda a: a[:, :2], r"YADE's pos must be \(76, 3\)"),
    ("packing:none", None, "not of a section"),
])
def test_arrays_of_another_dtype_or_shape_are_refused(saved_run, tmp_path, name, value, match):
    run_dir, path = copy_run(saved_run, tmp_path / "run")
    rewrite(path, edit_arrays=lambda a: a.update({name: value(a[name]) if value else np.zeros(1)}))
    refused(run_dir, match)


def test_a_truncated_or_foreign_file_is_refused(saved_run, tmp_path):
    run_dir, path = copy_run(saved_run, tmp_path / "run")
    data = open(path, "rb").read()
    for cut in (len(data) // 2, 100, 0):
        open(path, "wb").write(data[:cut])
        refused(run_dir, "not a (readable )?checkpoint")
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("notes.txt", "hello")
    open(path, "wb").write(buf.getvalue())
    refused(run_dir, "member 'notes.txt' is not a NumPy array")
    np.savez(path, a=np.zeros(3))
    refused(run_dir, "no header")


def test_a_yade_scene_with_a_pyrunner_is_refused_and_never_run(tmp_path):
    """law = 'yade' keeps YADE's own save: loaded, its engines are refused unless the scene makes them."""
    from yade.wrapper import PyRunner
    marker = tmp_path / "executed"
    sc = scenes.preset("quicksand_case1", scenes._merge(SHORT, {"contact": {"law": "yade", "spring": "a"}}))
    out = str(tmp_path / "run")
    os.makedirs(out)
    run = Run(sc, scene_packing(sc), out, STEPS)
    run.rec.create()
    run.cp.run(10)
    run.rec.close()
    O.engines = O.engines + [PyRunner(command=f"open({str(marker)!r}, 'w')", iterPeriod=1)]
    run.save_checkpoint()
    msg = refused(out, r"engines \['PyRunner'\] that the scene does not make")
    assert "PyRunner" in msg and not any(isinstance(e, PyRunner) for e in O.engines)
    O.step()
    assert not marker.exists()
    path = os.path.join(out, checkpoint.NAME)
    rewrite(path, edit_arrays=lambda a: a.update({"yade:scene": np.frombuffer(b"\x1f\x8b" + bytes(64), np.uint8)}))
    refused(out, "YADE's scene does not load")


@pytest.mark.parametrize("name", SCENES)
def test_the_state_set_from_a_checkpoint_is_the_state_stored(tmp_path, name):
    """Restoring sets every stored field: the state read back from the run built again equals the
    state stored."""
    run = build(name, tmp_path)
    run.save_checkpoint()
    ck = checkpoint.load(os.path.join(run.out, checkpoint.NAME))
    O.reset()
    again = named_state.state_of(Run.from_checkpoint(run.out))
    assert sorted(again) == sorted(ck.state)
    for k, v in ck.state.items():
        if isinstance(v, np.ndarray):
            assert again[k].dtype == v.dtype and np.array_equal(again[k], v), k
        else:
            assert json.loads(json.dumps(again[k])) == v, k
    assert runner.CHECKPOINT == checkpoint.NAME == "checkpoint.npz"


@pytest.mark.check
def test_the_script_refuses_a_crafted_checkpoint_in_one_line(saved_run, tmp_path):
    """Through ``yade ... --resume``: the refusal found while the run is built again is one line,
    exit status 1, and history.csv is left as it was."""
    import subprocess
    from engines import ROOT
    run_dir, path = copy_run(saved_run, tmp_path / "run")
    rewrite(path, edit_header=lambda h: h["state"].update({"cp.hack": 1}))
    history = open(os.path.join(run_dir, "history.csv"), "rb").read()
    run = subprocess.run(["yade", "-n", "-x", "yade_scripts/quicksand.py", "--resume", run_dir], cwd=ROOT,
                         env=dict(os.environ, PYTHONPATH=ROOT), capture_output=True, text=True, timeout=600)
    assert run.returncode == 1 and "Traceback" not in run.stderr, run.stderr
    assert run.stderr.strip().splitlines()[-1] == f"error: {path}: unknown field(s) ['cp.hack'] (the state of other code?)"
    assert open(os.path.join(run_dir, "history.csv"), "rb").read() == history
