"""Provenance of a run: the commit, dirtiness, command line and overrides it records."""
import subprocess

from engines.run.provenance import ROOT, provenance


def test_provenance_names_the_commit_the_command_and_the_overrides():
    p = provenance(["yade", "-x", "yade_scripts/quicksand.py", "--duration", "0.02"],
                   {"numerics": {"duration": 0.02}})
    head = subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    assert p["git_commit"] == head and len(head) == 40
    dirty = subprocess.run(["git", "-C", ROOT, "diff", "HEAD", "--quiet"]).returncode != 0
    assert p["git_dirty"] is dirty
    assert p["command_line"][-2:] == ["--duration", "0.02"]
    assert p["overrides"] == {"numerics": {"duration": 0.02}}
    assert p["yade_version"] and p["yade_version"].startswith("20")  # Debian's yade, e.g. 2023.02a-2


def test_outside_git_the_commit_is_none(tmp_path):
    from engines.run import provenance as prov
    assert prov.git_state(str(tmp_path)) == (None, None)


def test_one_version_read_by_pyproject_the_citation_and_every_summary():
    import os
    import re
    import tomllib

    from engines import __version__
    pyproject = tomllib.load(open(os.path.join(ROOT, "pyproject.toml"), "rb"))
    assert pyproject["project"]["dynamic"] == ["version"] and "version" not in pyproject["project"]
    assert pyproject["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "engines.__version__"}
    cff = open(os.path.join(ROOT, "CITATION.cff"), encoding="utf-8").read()
    assert re.search(r"^version: (\S+)$", cff, re.M).group(1) == __version__
    assert re.fullmatch(r"\d+\.\d+\.\d+(\.dev\d+)?", __version__)
    assert provenance([])["version"] == __version__
    assert open(os.path.join(ROOT, "LICENSE")).read().startswith("                    GNU GENERAL PUBLIC LICENSE\n                       Version 2")
