"""yade-batch tables read as data (engines.run.table): the project's tables read as YADE reads
them, an expression refused in one line naming table, line and column, a crafted value never run."""
import glob
import math
import os
import subprocess

import pytest

from engines import ROOT
from engines.run.command_line import job_argv
from engines.run.sweep import jobs_from_table
from engines.run.table import read_table

TABLES = sorted(glob.glob(os.path.join(ROOT, "yade_scripts", "*.table")))
FORMAT = ("# YADE's format: comments, blank lines, '!' columns, '=' and '*'\n"
          "\n"
          "a!   b        c!  !OMP_NUM_THREADS  d\n"
          "1    'x.toml' 2.5  1                [1,2]   # a comment\n"
          "\n"
          "=    =        -3e-4  =              (4,5)\n"
          "1    'x.toml' 2.5  2                *\n")


def _yades(path):
    """YADE's own reading: {line: {column: value}}, each value eval'ed as readParamsFromTable does."""
    from yade.utils import TableParamReader
    out = {}
    for line, row in TableParamReader(path).paramDict().items():
        out[line] = {k: v if k == "description" else eval(v, math.__dict__)
                     for k, v in row.items() if not k.startswith("!") and v != "*"}
    return out


@pytest.mark.parametrize("name", [os.path.basename(t) for t in TABLES] + ["format"])
def test_tables_read_as_yade_reads_them(tmp_path, name):
    pytest.importorskip("yade.utils")
    path = os.path.join(ROOT, "yade_scripts", name)
    if name == "format":
        path = str(tmp_path / "format.table")
        open(path, "w").write(FORMAT)
    ours = read_table(path)
    assert ours == _yades(path) and len(ours) >= 2
    if name == "format":
        assert ours[6] == {"a": 1, "b": "x.toml", "c": -3e-4, "d": (4, 5), "description": "a=1,c=-3e-4"}
        assert ours[7]["description"] == "a=1,c=2.5__line=7__" and "d" not in ours[7]  # '*': the default


@pytest.mark.parametrize("text, where", [
    ("a b\n1 pi/4\n", "line 2, column 'b': 'pi/4' is not a literal value"),
    ("a\n1\nfoo\n", "line 3, column 'a': 'foo' is not a literal value"),
    ("a b\n1 2 3\n", "line 2: 3 values for the 2 columns of line 1"),
    ("a\n=\n", "line 2, column 'a': '=' repeats the line above, but this is the first line of values"),
    ("a a!\n1 2\n", "line 1: column 'a' named twice"),
    ("# only a comment\n", "the table is empty"),
    ("a b\n", "no line of values"),
])
def test_bad_tables_are_refused_in_one_line(tmp_path, text, where):
    path = tmp_path / "t.table"
    path.write_text(text)
    with pytest.raises(ValueError) as e:
        read_table(str(path))
    assert str(e.value).startswith(str(path)) and where in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(ValueError, match="no such table file"):
        read_table(str(tmp_path / "missing.table"))
    with pytest.raises(ValueError, match="a directory"):
        read_table(str(tmp_path))


def _crafted(tmp_path):
    """A table whose value would create a file if it were evaluated."""
    witness = tmp_path / "evaluated"
    table = tmp_path / "crafted.table"
    table.write_text(f"duration\n0.001\n__import__('pathlib').Path({str(witness)!r}).touch()\n")
    return table, witness


def test_a_crafted_value_is_never_executed(tmp_path, monkeypatch, capsys):
    from tests.run.test_batch import quicksand
    table, witness = _crafted(tmp_path)
    with pytest.raises(ValueError, match="line 3, column 'duration'"):
        jobs_from_table(str(table), "script.py")
    monkeypatch.setenv("YADE_BATCH", f"{table}:3")
    with pytest.raises(SystemExit) as e:
        job_argv(quicksand().parser(), [])
    err = capsys.readouterr().err
    assert e.value.code == 2 and f"{table}, line 3, column 'duration'" in err and len(err.strip().splitlines()) == 1
    monkeypatch.setenv("YADE_BATCH", f"{table}:2")  # another line of the same table is refused too
    with pytest.raises(SystemExit):
        job_argv(quicksand().parser(), [])
    assert not witness.exists()


@pytest.mark.check
def test_a_scene_script_refuses_a_crafted_table_under_yade(tmp_path):
    table, witness = _crafted(tmp_path)
    env = dict(os.environ, YADE_BATCH=f"{table}:3", PYTHONPATH=ROOT, MPLBACKEND="Agg")
    run = subprocess.run(["yade", "-n", "-x", os.path.join(ROOT, "yade_scripts", "quicksand.py")], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 2 and f"{table}, line 3, column 'duration'" in run.stderr, run.stderr
    assert not witness.exists() and not (tmp_path / "out").exists()


def test_the_biaxial_table_gives_the_biaxial_options(monkeypatch):
    from engines.run.biaxial import parser, table_argv
    table = os.path.join(ROOT, "yade_scripts", "biaxial_sweep.table")
    line = sorted(read_table(table))[1]
    monkeypatch.setenv("YADE_BATCH", f"{table}:{line}")
    monkeypatch.delenv("SWEEP_JOB_DIR", raising=False)
    args = parser().parse_args(table_argv(parser()))
    assert (args.phi_e, args.sigma3, args.n_discs, args.max_strain, args.strain_rate) == (15, [100, 300], 250, 2, 200)
    assert args.out == os.path.join("out", "biaxial-batch", "phi15_small")
