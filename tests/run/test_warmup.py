"""The warm-up of make deps: its runs exist as written, it is skipped once done, and after it a
demo-like run compiles nothing (numba's cache misses of every kernel: none)."""
import json
import os
import subprocess
import sys

import pytest

from engines import ROOT
from engines.compiled import cache
from engines.run import warmup

PROBE = """
import json, sys
sys.path.insert(0, {root!r})
import engines.yade  # noqa: F401
from engines.run import scene as scenes
from engines.run.runner import run_scene
from engines.yade.deposition import scene_packing
sc = scenes.preset("quicksand_case1", {{"output": {{"snapshot_times": [0.0]}}}})
run_scene(sc, scene_packing(sc), {out!r}, duration=0.0015, figures=False)
from numba.core.dispatcher import Dispatcher
misses, hits = {{}}, 0
for name, module in list(sys.modules.items()):
    if name.startswith("engines.compiled"):
        for key, obj in vars(module).items():
            if isinstance(obj, Dispatcher):
                misses.update({{f"{{name}}.{{key}}": sum(obj.stats.cache_misses.values())}})
                hits += sum(obj.stats.cache_hits.values())
print("PROBE " + json.dumps({{"misses": {{k: v for k, v in misses.items() if v}}, "hits": hits}}))
"""


def test_the_runs_name_scripts_and_scenes_that_exist(tmp_path):
    for what, script, args in warmup.RUNS:
        cmd = warmup.command(script, args, str(tmp_path))
        assert os.path.isfile(cmd[3]), what
        for a, b in zip(cmd, cmd[1:]):
            if a == "--scene":
                assert os.path.isfile(b), what
        assert ("--out" in cmd) == ("--case" in cmd or "--scene" in cmd), what


def test_a_warm_cache_is_not_warmed_again(tmp_path, monkeypatch):
    monkeypatch.setattr(cache, "use", lambda: str(tmp_path))
    (tmp_path / warmup.STAMP).write_text("done")
    said = []
    assert warmup.warm(runs=[("would fail", "no_such_script.py", [])], say=said.append) == 0
    assert said == [f"warm-up: the numba kernels of this version of the code are compiled already ({tmp_path})"]


def test_a_failing_run_ends_the_warm_up_with_its_last_lines(tmp_path, monkeypatch):
    monkeypatch.setattr(cache, "use", lambda: str(tmp_path))
    monkeypatch.setattr(warmup, "command", lambda script, args, out: [sys.executable, "-c",
                                                                       "import sys; print('the cause'); sys.exit(3)"])
    said = []
    assert warmup.warm(runs=[("a run", "x.py", [])], say=said.append) == 1
    assert said[-1] == "warm-up 1/1: a run: failed (exit status 3):\n    the cause"
    assert not (tmp_path / warmup.STAMP).exists()


def test_an_empty_cache_folder_is_announced_once(tmp_path, monkeypatch):
    monkeypatch.setattr(cache, "fresh", True)
    assert cache.compile_note() == (f"compiling the numba kernels (about {cache.COMPILE_SECONDS} s, once per version "
                                    "of the code)...")
    monkeypatch.setattr(cache, "fresh", False)
    assert cache.compile_note() is None
    (tmp_path / "a" / "b").mkdir(parents=True)
    assert cache.is_empty(str(tmp_path))
    (tmp_path / "a" / "b" / "k.nbi").write_text("")
    assert not cache.is_empty(str(tmp_path))


BANNER = ("Welcome to Yade", "Using python version", "TCP python prompt", "XMLRPC info provider", "Running script")


def script_lines(argv, env):
    """The stdout lines of ``yade -n -x`` argv without YADE's banner (its exit status checked)."""
    ran = subprocess.run(["yade", "-n", "-x"] + argv, env=env, capture_output=True, text=True, timeout=1800)
    assert ran.returncode == 0, ran.stdout + ran.stderr
    return [x for x in ran.stdout.splitlines() if not x.startswith(BANNER)]


@pytest.mark.check
def test_a_first_run_says_it_compiles_and_after_the_warm_up_a_demo_like_run_compiles_nothing(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), PYTHONPATH=ROOT, MPLBACKEND="Agg")
    env.pop(cache.KEYED, None)
    quicksand = [os.path.join(ROOT, "yade_scripts", "quicksand.py"), "--case", "1", "--duration", "0.0015",
                 "--set", "output.progress_seconds=0.001"]
    first = script_lines(quicksand + ["--out", str(tmp_path / "first")], env)  # an empty cache: it compiles
    assert sum("compiling the numba kernels" in x for x in first) == 1
    progress = [x for x in first if " step " in x and x.startswith("[quicksand-case1]")]
    assert "left" not in progress[0] and "s left" in progress[1]  # no estimate before steps were measured
    done = subprocess.run([sys.executable, os.path.join(ROOT, "yade_scripts", "warmup.py")], env=env,
                          capture_output=True, text=True, timeout=3600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.startswith("warm-up: the numba kernels in") and "warm-up 10/10" in done.stdout
    probe = tmp_path / "probe.py"
    probe.write_text(PROBE.format(root=ROOT, out=str(tmp_path / "run")))
    line = [x for x in script_lines([str(probe)], env) if x.startswith("PROBE ")]
    result = json.loads(line[0][6:])
    assert result["misses"] == {} and result["hits"] > 0
    quiet = script_lines(quicksand + ["--quiet", "--out", str(tmp_path / "quiet")], env)
    assert quiet[0].startswith("done: 1500 steps") and all(x.startswith("  ") for x in quiet[1:])
    assert any(x.startswith("  U_block1 peak ") and x.endswith(" ms") for x in quiet) and quiet[-1].startswith("  figure ")
