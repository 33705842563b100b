"""Bad input refused in one line before anything is written (issue 37, items 2 and 6): names that
become paths, files that are not regular files or are too large or empty, the list fields of the
scene schema, the packing file's header and its lines as an editor counts them."""
import os
import subprocess

import numpy as np
import pytest

from engines import ROOT
from engines.files.inputs import check_input_file, check_name
from engines.model.ground_motion import read_record
from engines.run import scene as scenes
from engines.run.sweep import Job
from packing.packing import Packing

PRESET = os.path.join(scenes.SCENE_DIR, "quicksand_case1.toml")
PACKING = os.path.join(scenes.SCENE_DIR, "quicksand_packing.csv")


def scene_file(folder, body, name="mine.toml"):
    path = folder / name
    path.write_text(f'extends = "{os.path.relpath(PRESET, folder)}"\n' + body)
    return str(path)


def one_line(e):
    text = str(e.value)
    assert "\n" not in text and text, text
    return text


# -- names that become paths -----------------------------------------------------------------------
@pytest.mark.parametrize("name,why", [("..", "starts with a dot"), (".hidden", "starts with a dot"),
                                      ("a/b", "path separator"), ("../up", "path separator"),
                                      ("a\\b", "path separator"), ("x..y", "'..'"), ("", "expected a name"),
                                      ("a\nb", "control character")])
def test_check_name_refuses_what_leaves_the_folder(name, why):
    with pytest.raises(ValueError) as e:
        check_name(name, "[scene] name")
    assert one_line(e).startswith("[scene] name") and why in str(e.value)


@pytest.mark.parametrize("name", ["quicksand-case1", "case=2,k1=20", "a.b", "start_7"])
def test_check_name_accepts_plain_names(name):
    assert check_name(name, "x") == name


@pytest.mark.parametrize("name", ["../../evil", ".x", "sub/dir"])
def test_a_scene_name_that_is_a_path_is_refused(tmp_path, name):
    with pytest.raises(scenes.SceneError) as e:
        scenes.load(scene_file(tmp_path, f'[scene]\nname = "{name}"\n'))
    assert one_line(e).startswith("[scene] name = ")


@pytest.mark.parametrize("name", ["..", ".", ".hidden"])
def test_a_sweep_job_name_that_leaves_the_root_is_refused(name):
    with pytest.raises(ValueError, match="job name"):
        Job(name, ["true"])


def test_every_preset_name_is_a_plain_name():
    for name in os.listdir(scenes.SCENE_DIR):
        if name.endswith(".toml"):
            scenes.load(os.path.join(scenes.SCENE_DIR, name))  # [scene] name checked


# -- files where a file is expected ---------------------------------------------------------------
def test_check_input_file(tmp_path):
    (tmp_path / "f").write_text("x" * 10)
    assert check_input_file(str(tmp_path / "f"), "scene file", 10) == 10
    cases = [(str(tmp_path), "is a directory"), ("/dev/zero", "/dev/zero is not a regular file"),
             (str(tmp_path / "none"), "not found")]
    (tmp_path / "empty").write_text("")
    cases += [(str(tmp_path / "empty"), "is empty")]
    for path, why in cases:
        with pytest.raises(ValueError) as e:
            check_input_file(path, "scene file", 10)
        assert one_line(e).startswith(f"scene file {path}") and why in str(e.value)
    with pytest.raises(ValueError, match=r"is 11 bytes, above the limit of 10 bytes for a scene file"):
        (tmp_path / "f").write_text("x" * 11)
        check_input_file(str(tmp_path / "f"), "scene file", 10)


@pytest.mark.parametrize("target,why", [(None, "is a directory"), ("/dev/zero", "is not a regular file"),
                                        ("empty", "is empty"), ("big", "above the limit of 1 MB"),
                                        ("binary", "not a text file")])
def test_scene_files_and_extends_are_regular_small_text_files(tmp_path, target, why):
    path = {None: str(tmp_path), "/dev/zero": "/dev/zero"}.get(target, str(tmp_path / f"{target}.toml"))
    content = {"empty": b"", "big": b"#" * (2 << 20), "binary": b"\xff\xfe\x00"}.get(target)
    if content is not None:
        with open(path, "wb") as f:
            f.write(content)
    with pytest.raises(scenes.SceneError) as e:   # as --scene
        scenes.load(path)
    assert why in one_line(e)
    (tmp_path / "child").mkdir()
    child = tmp_path / "child" / "c.toml"
    child.write_text(f'extends = "{path}"\n')
    with pytest.raises(scenes.SceneError) as e:   # as the extends of another scene
        scenes.load(str(child))
    assert why in one_line(e) and (target == "binary" or str(child) in str(e.value))


def test_a_record_that_is_a_directory_or_a_device_is_refused(tmp_path):
    for path, why in ((str(tmp_path), "is a directory"), ("/dev/zero", "is not a regular file")):
        with pytest.raises(ValueError, match=f"record file {path} {why}"):
            read_record(path)


# -- the scene schema's list fields -----------------------------------------------------------------
BAD_ELEMENTS = ["nan", "inf", "-inf", '"a"', "true"]


def test_every_list_field_is_checked():
    assert set(scenes.LIST_FIELDS) == {("output", "snapshot_times"), ("output", "block_z"),
                                       ("output", "porosity_window")}


@pytest.mark.parametrize("value", [f"[{v}]" for v in BAD_ELEMENTS] + ["[0.01, nan]", "[-0.01]"])
def test_snapshot_times_are_finite_times(tmp_path, value):
    with pytest.raises(scenes.SceneError, match=r"^\[output\] snapshot_times\[\d\]: expected a finite time >= 0"):
        scenes.load(scene_file(tmp_path, f"[output]\nsnapshot_times = {value}\n"))


@pytest.mark.parametrize("value", ["[]", '[["a", "b"]]', "[[0.0, nan]]", "[[0.0, inf]]", "[[nan, 0.5]]", "[[0.5]]",
                                   "[0.1, 0.2]", "[[0.0, 0.5], []]"])
def test_block_z_is_a_list_of_finite_pairs(tmp_path, value):
    with pytest.raises(scenes.SceneError, match=r"^\[output\] block_z"):
        scenes.load(scene_file(tmp_path, f"[output]\nblock_z = {value}\n"))


@pytest.mark.parametrize("value", ["[]", "[0.0, inf]", "[nan, 0.5]", '["a", "b"]', "[0.0]", "[0.5, 0.1]"])
def test_the_porosity_window_is_a_finite_pair(tmp_path, value):
    with pytest.raises(scenes.SceneError, match=r"^\[output\] porosity_window"):
        scenes.load(scene_file(tmp_path, f"[output]\nporosity_window = {value}\n"))


def test_no_snapshots_is_allowed(tmp_path):
    assert scenes.load(scene_file(tmp_path, "[output]\nsnapshot_times = []\n")).output.snapshot_times == []


# -- packing files --------------------------------------------------------------------------------
def packing_lines():
    return open(PACKING).read().splitlines()


def write(folder, lines, name="p.csv"):
    path = folder / name
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_a_packing_without_its_header_is_refused_not_read_short(tmp_path):
    lines = packing_lines()
    path = write(tmp_path, lines[1:])
    with pytest.raises(ValueError) as e:
        Packing.load(path)
    assert one_line(e) == (f"packing file {path}, line 1: expected the header x_m,z_m,r_m,group,density_factor, "
                           f"got a row of numbers (a file without its header: add the header line)")
    assert len(Packing.load(write(tmp_path, ["x,z,r,group,density_factor"] + lines[1:], "q.csv")).r) == len(lines) - 1
    with pytest.raises(ValueError, match="line 1: expected the header .*, got 'a,b,c'"):
        Packing.load(write(tmp_path, ["a,b,c"] + lines[1:]))


@pytest.mark.parametrize("line,cell,why", [
    (10, "abc", "line 10: not a number: 'abc'"),
    (2, "", "line 2: not a number: ''"),
    (40, None, "line 40: expected 5 columns x_m,z_m,r_m,group,density_factor, got 4"),
])
def test_a_bad_packing_line_is_named_as_an_editor_counts_it(tmp_path, line, cell, why):
    lines = packing_lines()
    cells = lines[line - 1].split(",")
    if cell is None:
        cells = cells[:4]
    else:
        cells[1] = cell
    lines[line - 1] = ",".join(cells)
    path = write(tmp_path, lines)
    with pytest.raises(ValueError) as e:
        Packing.load(path)
    assert one_line(e).startswith(f"packing file {path}, {why}")


@pytest.mark.parametrize("kind,why", [("empty", "is empty"), ("header", "holds the header and no discs"),
                                      ("dir", "is a directory"), ("dev", "is not a regular file")])
def test_empty_and_special_packing_files_are_refused(tmp_path, kind, why):
    path = {"dir": str(tmp_path), "dev": "/dev/zero"}.get(kind) or write(tmp_path, [] if kind == "empty" else
                                                                          packing_lines()[:1])
    if kind == "empty":
        open(path, "w").close()
    with pytest.raises(ValueError) as e:
        Packing.load(path)
    assert one_line(e).startswith(f"packing file {path}") and why in str(e.value)


def test_a_packing_above_its_size_limit_is_refused_before_reading(tmp_path, monkeypatch):
    import packing.packing as module
    monkeypatch.setattr(module, "LIMIT", 1000)
    with pytest.raises(ValueError, match=r"^packing file .*quicksand_packing.csv is [\d.]+ kB, above the limit of 1000 bytes for a packing file$"):
        Packing.load(PACKING)


def test_a_packing_is_saved_whole_and_read_back(tmp_path):
    pk = Packing.load(PACKING)
    pk.save(str(tmp_path / "p.csv"))
    assert os.listdir(tmp_path) == ["p.csv"]
    back = Packing.load(str(tmp_path / "p.csv"))
    np.testing.assert_array_equal(back.group, pk.group)
    np.testing.assert_allclose(back.xz, pk.xz, rtol=1e-12)


# -- a script, end to end --------------------------------------------------------------------------
@pytest.mark.check
def test_deposit_does_not_follow_a_scene_name_out_of_its_folder(tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    victim = tmp_path / "victim.csv"
    victim.write_text("precious\n")
    scene = scene_file(work, '[scene]\nname = "../../victim"\n')
    run = subprocess.run(["yade", "-n", "-x", os.path.join(ROOT, "yade_scripts", "deposit.py"), "--scene", scene],
                         cwd=work, env=dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg"), capture_output=True,
                         text=True, timeout=300)
    errors = [line for line in run.stderr.splitlines() if "error" in line]
    assert run.returncode != 0 and len(errors) == 1 and "[scene] name = '../../victim'" in errors[0], run.stderr
    assert victim.read_text() == "precious\n" and os.listdir(work) == ["mine.toml"]


# -- the sweep runner's own arguments, an unreachable scheduler -------------------------------------
def closed_port():
    """A localhost port nothing listens on."""
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def sweep_refuses(tmp_path, capsys, args, why, code=1):
    from yade_scripts import sweep
    out = tmp_path / "sweep"
    with pytest.raises(SystemExit) as e:
        sweep.main(["--out", str(out), *args])
    message = e.value.code if isinstance(e.value.code, str) else capsys.readouterr().err
    assert (code == 1) == isinstance(e.value.code, str) and (code == 1 or e.value.code == code)
    assert why in message and len(message.strip().splitlines()) == 1, message
    assert not out.exists()


def test_the_sweep_runner_refuses_bad_arguments_in_one_line(tmp_path, capsys):
    jobs = tmp_path / "jobs.json"
    table = tmp_path / "t.table"
    table.write_text("description x\nA 1\n")
    cases = [
        (["--table", str(tmp_path), "--script", "s.py"], f"table {tmp_path} is a directory"),
        (["--table", "/dev/zero", "--script", "s.py"], "table /dev/zero is not a regular file"),
        (["--table", str(tmp_path / "none.table"), "--script", "s.py"], "none.table not found"),
        (["--table", str(table), "--script", str(tmp_path / "none.py")], "script"),
        (["--jobs", str(jobs)], "jobs file"),
    ]
    for args, why in cases:
        sweep_refuses(tmp_path, capsys, args, why)
    for text, why in [("[\n{\"name\": 1,\n", "line 3: not valid JSON"), ('{"name": "a"}', "expected a JSON list"),
                      ('[{"name": "a"}]', 'job 1: expected {"name", "argv"'),
                      ('[{"name": "..", "argv": ["true"]}]', "job 1: job name = '..' starts with a dot"),
                      ('[{"name": "a", "argv": "true"}]', '"argv" must be a list'),
                      ("[]", "holds no jobs"), ("", "is empty")]:
        jobs.write_text(text)
        sweep_refuses(tmp_path, capsys, ["--jobs", str(jobs)], why)
    jobs.write_text('[{"name": "a", "argv": ["true"]}]')
    for workers in ("0", "x", "1000"):
        sweep_refuses(tmp_path, capsys, ["--jobs", str(jobs), "--workers", workers], "--workers", code=2)
    port = closed_port()
    sweep_refuses(tmp_path, capsys, ["--jobs", str(jobs), "--scheduler", f"tcp://127.0.0.1:{port}"],
                  f"--scheduler tcp://127.0.0.1:{port}: no Dask scheduler answers there")
    sweep_refuses(tmp_path, capsys, ["--jobs", str(jobs), "--scheduler", "nonsense"], "expected tcp://HOST:PORT")


def test_an_ensemble_with_an_unreachable_scheduler_is_refused_before_its_folder(tmp_path):
    from tests.run.test_preflight import QUICKSAND, refused
    out = tmp_path / "ens"
    refused(QUICKSAND + ["--starts", "2", "--scheduler", f"tcp://127.0.0.1:{closed_port()}", "--out", str(out)], out,
            "no Dask scheduler answers there")


def test_a_cluster_lost_during_an_ensemble_marks_it_failed(tmp_path, monkeypatch, capsys):
    import argparse
    import json

    from engines.run import ensemble

    def lost(*args, **kw):
        raise OSError("Timed out trying to connect to tcp://127.0.0.1:1 after 30 s")

    monkeypatch.setattr(ensemble, "run_sweep", lost)
    plan = {"script": "s.py", "seeds": [0, 1], "starts": ["start_0", "start_1"]}
    args = argparse.Namespace(jobs=None, scheduler="tcp://127.0.0.1:1", scheduler_file=None)
    assert ensemble.run_starts([], str(tmp_path), plan, args) == 1
    doc = json.loads((tmp_path / "ensemble.json").read_text())
    assert doc["status"] == "failed" and "Timed out" in doc["error"]
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 and out[0].startswith("error: --scheduler tcp://127.0.0.1:1: ") and "--resume" in out[0]


@pytest.mark.check
def test_an_empty_table_is_refused(tmp_path):
    import sys
    table = tmp_path / "t.table"
    table.write_text("description x\n")
    run = subprocess.run([sys.executable, os.path.join(ROOT, "yade_scripts", "sweep.py"), "--out", str(tmp_path / "s"),
                          "--table", str(table), "--script", os.path.join(ROOT, "yade_scripts", "quicksand.py")],
                         cwd=tmp_path, env=dict(os.environ, PYTHONPATH=ROOT), capture_output=True, text=True, timeout=300)
    assert run.returncode == 1 and run.stderr.strip().splitlines() == [
        f"error: {table}: the table has column names (line 1) but no line of values"]
    assert not (tmp_path / "s").exists()


def test_blank_and_comment_lines_do_not_shift_the_line_named(tmp_path):
    lines = packing_lines()
    lines[5:5] = ["", "# a note"]
    cells = lines[11].split(",")
    cells[2] = "-1e-4"
    lines[11] = ",".join(cells)
    path = write(tmp_path, lines)
    with pytest.raises(ValueError, match=rf"^packing file {path}, line 12: r = -0.0001 m"):
        Packing.load(path)
    cells[2] = "x"
    lines[11] = ",".join(cells)
    with pytest.raises(ValueError, match=rf"^packing file {path}, line 12: not a number: 'x'"):
        Packing.load(write(tmp_path, lines))


def test_a_batch_description_or_an_ensembles_start_cannot_leave_the_folder(monkeypatch):
    from engines.run.command_line import batch_out
    from engines.run.ensemble import start_dir
    monkeypatch.delenv("SWEEP_JOB_DIR", raising=False)
    monkeypatch.setenv("YADE_BATCH", "t.table:2")
    assert batch_out("out/batch", "case=2/x") == os.path.join("out/batch", "case=2_x")
    for description in ("..", ".hidden", "a..b"):
        with pytest.raises(ValueError, match=r"^yade-batch table t.table:2: the job's description = "):
            batch_out("out/batch", description)
    assert start_dir("out", 3) == os.path.join("out", "start_3")
    for k in ("../../x", -1, True, 1.5):
        with pytest.raises(ValueError, match=r"out/ensemble.json: start .* is not a start number"):
            start_dir("out", k)


@pytest.mark.check
def test_a_table_line_described_as_dot_dot_is_refused_naming_the_line(tmp_path):
    from engines.run.sweep import jobs_from_table
    table = tmp_path / "t.table"
    table.write_text("description x\nok 1\n.. 2\n")
    with pytest.raises(ValueError, match=rf"^{table}, line 3: job name = '..' starts with a dot.*change the line's description"):
        jobs_from_table(str(table), "s.py")


@pytest.mark.parametrize("args,why", [
    (["--scene", "/dev/zero"], "scene file /dev/zero is not a regular file"),
    (["--scene", "DIR"], "is a directory"),
    (["--set", "output.snapshot_times=[nan]"], "[output] snapshot_times[0]: expected a finite time >= 0"),
    (["--set", "output.block_z=[]"], "[output] block_z: expected at least one block"),
    (["--set", 'output.block_z=[["a", "b"]]'], "[output] block_z[0]"),
    (["--duration", "1e6"], "of outputs is above 10 GB"),   # 1e12 steps
])
def test_a_scene_script_refuses_in_one_line_before_out_exists(tmp_path, args, why):
    from tests.run.test_preflight import QUICKSAND, refused
    out = tmp_path / "run"
    args = [str(tmp_path) if a == "DIR" else a for a in args]
    message = refused(QUICKSAND + args + ["--out", str(out)], out, why)
    assert "--duration" not in args or "--force" in message
