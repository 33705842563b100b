"""numba's cache folder keyed by the kernels' sources (engines.compiled.cache): an edit in a callee's
module or a layout runs fresh code where numba's own cache would run the old one."""
import os
import shutil
import subprocess
import sys

import pytest

from engines.compiled import cache

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

CALLEE = """import numba as nb
from engines.compiled.layout import Layout
L = Layout("L", ("a", "b"))
@nb.njit(cache=True)
def callee():
    return 1
"""
CALLER = """import numba as nb
import numpy as np
from engines.compiled.probe_callee import L, callee
@nb.njit(cache=True)
def caller(x):
    return 10 * callee() + x[L.b]
print(caller(np.arange(3)))
"""


def engines_copy(tmp_path):
    """engines/ (its __init__, model and compiled) copied under tmp_path; returns the copy's engines folder."""
    dst = tmp_path / "tree" / "engines"
    dst.mkdir(parents=True)
    shutil.copy(os.path.join(ROOT, "engines", "__init__.py"), dst)
    for package in cache.SOURCES:
        shutil.copytree(os.path.join(ROOT, "engines", package), dst / package,
                        ignore=shutil.ignore_patterns("__pycache__"))
    return dst


def test_the_key_is_that_of_the_sources_and_their_folder(tmp_path):
    eng = engines_copy(tmp_path)
    same = cache.cache_key(str(eng))
    assert same != cache.cache_key()  # another checkout: numba's subfolders are named by the sources' path
    assert cache.cache_key(str(eng)) == same
    callee = eng / "model" / "ground_motion.py"
    callee.write_text(callee.read_text().replace("self.vel += a_bar * dt", "self.vel += a_bar * dt * 1"))
    edited = cache.cache_key(str(eng))
    assert edited != same
    layout = eng / "compiled" / "kernels" / "base_motion.py"  # a module of a subfolder
    layout.write_text(layout.read_text().replace('"disp", "wall_velocity"))', '"disp", "wall_velocity", "spare"))'))
    assert cache.cache_key(str(eng)) not in (edited, same)
    shutil.copytree(eng.parent, tmp_path / "moved")
    moved = cache.cache_key(str(tmp_path / "moved" / "engines"))
    assert moved != cache.cache_key(str(eng))


def test_the_folder_is_keyed_under_the_users_numba_cache_dir_once(tmp_path):
    own = str(tmp_path / "mine")
    path = cache.cache_dir({"NUMBA_CACHE_DIR": own})
    assert path == os.path.join(own, cache.cache_key()) and os.path.isdir(path)
    child = {"NUMBA_CACHE_DIR": path, cache.KEYED: path}  # what use() leaves to a child process
    assert cache.cache_dir(child) == path
    assert cache.cache_dir({"XDG_CACHE_HOME": str(tmp_path)}).startswith(str(tmp_path / "pore-dem" / "numba"))


def test_only_the_most_recently_used_keyed_folders_are_kept(tmp_path):
    root = tmp_path / "mine"
    for n in range(cache.KEEP + 3):
        (root / f"{n:016x}").mkdir(parents=True)
        os.utime(root / f"{n:016x}", (n, n))
    (root / "not-a-key").mkdir()
    path = cache.cache_dir({"NUMBA_CACHE_DIR": str(root)})
    left = sorted(os.listdir(root))
    assert os.path.basename(path) in left and "not-a-key" in left
    assert left == sorted([f"{n:016x}" for n in range(4, cache.KEEP + 3)] + [os.path.basename(path), "not-a-key"])


def test_this_process_compiles_into_the_keyed_folder():
    import numba.core.config
    assert numba.core.config.CACHE_DIR == os.environ["NUMBA_CACHE_DIR"] == cache.cache_dir()


def run_probe(tree, env):
    out = subprocess.run([sys.executable, "-c", "import engines.compiled.probe_caller"], cwd=tree, env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return int(out.stdout.split()[-1])


@pytest.mark.check
def test_an_edited_callee_or_layout_in_another_module_runs_fresh(tmp_path):
    """A kernel (probe_caller) calling a kernel of another module (probe_callee) and reading its
    layout: numba's own cache would keep 10 callee() + x[L.b] = 11 after either edit (the caller's
    file is untouched); the keyed folder compiles afresh."""
    eng = engines_copy(tmp_path)
    callee, caller = eng / "compiled" / "probe_callee.py", eng / "compiled" / "probe_caller.py"
    callee.write_text(CALLEE)
    caller.write_text(CALLER)
    env = {**os.environ, "PYTHONPATH": str(eng.parent), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    env.pop(cache.KEYED, None)
    assert run_probe(eng.parent, env) == 11
    assert run_probe(eng.parent, env) == 11  # from the cache
    callee.write_text(CALLEE.replace("return 1", "return 2"))
    assert run_probe(eng.parent, env) == 21
    callee.write_text(CALLEE.replace('("a", "b")', '("z", "a", "b")').replace("return 1", "return 2"))
    assert run_probe(eng.parent, env) == 22
    keyed = sorted(os.listdir(tmp_path / "numba"))
    assert len(keyed) == 3


@pytest.mark.check
def test_numbas_own_cache_would_run_the_stale_callee(tmp_path):
    """The hazard the key removes, with numba's cache alone (the probe outside engines/compiled)."""
    tree = tmp_path / "plain"
    tree.mkdir()
    (tree / "probe_callee.py").write_text(CALLEE.replace("from engines.compiled.layout", "from layout"))
    shutil.copy(os.path.join(ROOT, "engines", "compiled", "layout.py"), tree / "layout.py")
    (tree / "probe_caller.py").write_text(CALLER.replace("engines.compiled.probe_callee", "probe_callee"))
    env = {**os.environ, "PYTHONPATH": str(tree), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def run():
        out = subprocess.run([sys.executable, "-c", "import probe_caller"], cwd=tree, env=env, capture_output=True,
                             text=True, timeout=600)
        assert out.returncode == 0, out.stderr
        return int(out.stdout.split()[-1])
    assert run() == 11
    (tree / "probe_callee.py").write_text(CALLEE.replace("from engines.compiled.layout", "from layout")
                                          .replace("return 1", "return 2"))
    assert run() == 11
