"""The kernels' mutation driver (tests/kernel_mutants.py, make mutants-kernels): which functions and
tokens it mutates, the patch, the seeded sample, resuming, the score's interval. No numba compile."""
import ast
import io
import json
import os
import sys
import tokenize

import pytest

from tests import kernel_mutants as km

SOURCE = '''"""A module of kernels."""
import numba as nb
from numba import njit as fast
from numba.extending import intrinsic

jit = nb.njit(cache=True)


@jit
def f(a, b):
    """1 + 2 < 3 in a docstring: not mutated."""
    c = len("\u00e9\u00e9") + a * 2
    if a < b and b != 0:
        c -= -a
    return c / 1.5


def plain(a):
    return a + 1 < 2


@fast
def g(x):
    return x >= 0.0 or x == 1


@nb.njit
def h(x):
    x *= 3
    return x > 2.0


@intrinsic
def i(typingctx, x):
    return x + 1
'''
F = {"binop:Add->Sub", "binop:Mult->Div", "const:2->3", "cmp:Lt->LtE", "bool:And->Or", "cmp:NotEq->Eq",
     "const:0->1", "aug:Sub->Add", "unary:drop-USub", "binop:Div->Mult", "const:1.5->2.25"}
G = {"cmp:GtE->Gt", "const:0.0->1.0", "bool:Or->And", "cmp:Eq->NotEq", "const:1->0", "const:1->2"}
H = {"aug:Mult->Div", "const:3->4", "cmp:Gt->GtE", "const:2.0->3.0"}


@pytest.fixture
def module(tmp_path):
    folder = tmp_path / "engines" / "compiled"
    folder.mkdir(parents=True)
    (folder / "k.py").write_text(SOURCE, encoding="utf-8")
    (folder / "empty.py").write_text("def f(a):\n    return a + 1\n")
    (folder / "shared.py").write_text("import numba\nkernel = numba.njit(cache=True)\nother = print\n")
    (folder / "k2.py").write_text("from engines.compiled import shared\nfrom .shared import kernel as kern\n\n\n"
                                  "@kern\ndef p(a):\n    return a + 1\n\n\n@shared.kernel\ndef q(a):\n    return a - 1\n\n\n"
                                  "@shared.other\ndef r(a):\n    return a - 1\n")
    return tmp_path


def _tokens(source):
    return [(t.type, t.string) for t in tokenize.generate_tokens(io.StringIO(source).readline)]


def test_only_the_jit_functions_are_mutated_each_token_once_with_unique_ids(module):
    ms = km.enumerate_mutants(str(module))
    assert {m.file for m in ms} == {"engines/compiled/k.py", "engines/compiled/k2.py"}
    kinds = {}
    for m in ms:
        kinds.setdefault(m.function, set()).add(m.kind)
    one = {"const:1->0", "const:1->2"}
    assert kinds == {"f": F, "g": G, "h": H, "p": {"binop:Add->Sub", *one}, "q": {"binop:Sub->Add", *one}}
    assert len({m.id for m in ms}) == len(ms) == len(F) + len(G) + len(H) + 6
    plus = next(m for m in ms if m.kind == "binop:Add->Sub")
    assert plus.id == "engines/compiled/k.py:f:12:18:binop:Add->Sub"   # the character column, after two 2-byte letters
    assert ms == sorted(ms, key=lambda m: (m.file, m.line, m.col, m.kind))


def test_a_mutant_changes_exactly_its_token(module):
    source = SOURCE
    before = _tokens(source)
    for m in km.enumerate_mutants(str(module)):
        if m.file != "engines/compiled/k.py":
            continue
        after = _tokens(km.apply(source, m))
        ast.parse(km.apply(source, m))
        changed = [k for k, (a, b) in enumerate(zip(before, after)) if a != b]
        if m.new:                                    # a token swapped for another, nothing else moved
            assert len(after) == len(before) and len(changed) == 1, m.id
            assert before[changed[0]][1] == m.old and after[changed[0]][1] == m.new, m.id
        else:                                        # the unary minus dropped: one token fewer
            k = changed[0]
            assert before[k][1] == "-" and before[:k] + before[k + 1:] == after, m.id
        line = source.split("\n")[m.line - 1]
        assert line[m.col:m.end] == m.old
    diff = km.diff(source, next(m for m in km.enumerate_mutants(str(module)) if m.kind == "cmp:Lt->LtE"))
    assert "-    if a < b and b != 0:\n+    if a <= b and b != 0:\n" in diff
    m = km.enumerate_mutants(str(module))[0]
    with pytest.raises(ValueError, match="expected"):
        km.apply(source.replace("\n", "\n\n", 1), m)   # the sources moved under the mutant: refused


def test_the_real_kernels_enumerate_and_patch_to_code_that_parses():
    ms = km.enumerate_mutants()
    assert len(ms) > 1000 and all(m.file.startswith("engines/compiled/") for m in ms)
    assert {m.kind.split(":")[0] for m in ms} == {"binop", "cmp", "bool", "const", "unary", "aug"}
    sources = {}
    for m in km.sample(ms, 25, 3):
        source = sources.setdefault(m.file, open(os.path.join(km.ROOT, m.file), encoding="utf-8").read())
        ast.parse(km.apply(source, m))


def test_the_sample_is_fixed_by_the_seed_and_a_larger_one_extends_it():
    ms = km.enumerate_mutants()
    a = km.sample(ms, 20, 5)
    assert a == km.sample(list(reversed(ms)), 20, 5)
    assert km.sample(ms, 8, 5) == a[:8]
    assert km.sample(ms, 20, 6) != a


def test_wilson_interval_on_a_known_case():
    lo, hi = km.wilson(8, 10)
    assert (round(lo, 4), round(hi, 4)) == (0.4902, 0.9433)   # Wilson (1927) for 8 of 10, z = 1.96
    scipy_stats = pytest.importorskip("scipy.stats")
    ci = scipy_stats.binomtest(190, 200).proportion_ci(0.95, method="wilson")
    assert km.wilson(190, 200) == pytest.approx((ci.low, ci.high), rel=1e-9)
    assert km.wilson(0, 5)[0] == pytest.approx(0.0, abs=1e-15)
    assert km.wilson(0, 0) == (None, None)


def test_summary_counts_scores_stale_equivalents_and_errors():
    rows = {"a.py:f:1:0:x": {"status": "killed"}, "a.py:f:2:0:x": {"status": "timeout"},
            "a.py:f:3:0:x": {"status": "survived"}, "a.py:f:4:0:x": {"status": "survived"},
            "b.py:g:1:0:x": {"status": "killed"}, "b.py:g:2:0:x": {"status": "error"}}
    equivalent = {"a.py:f:4:0:x": "why", "b.py:g:1:0:x": "stale"}
    s = km.summarise(rows, [*rows, "b.py:g:9:0:x"], equivalent)
    assert (s["total"], s["killed"], s["timeout"], s["survived"], s["equivalent"]) == (5, 3, 1, 1, 1)
    assert s["score"] == pytest.approx(3 / 4) and s["wilson95"] == list(km.wilson(3, 4))
    assert s["modules"]["a.py"]["score"] == pytest.approx(2 / 3) and s["modules"]["b.py"]["score"] == 1.0
    assert s["stale_equivalent"] == ["b.py:g:1:0:x"] and s["errors"] == ["b.py:g:2:0:x"]


def test_a_rerun_skips_the_mutants_done_on_the_same_sources(tmp_path, monkeypatch):
    ran = []

    def mutant(self, work, m, original, sources, fresh=False):
        assert km.apply(original, m) != original
        ran.append((m.id, fresh))
        survived = fresh or len(ran) % 2 == 0   # every other mutant survives its warm run, and its fresh one
        return {"id": m.id, "status": "survived" if survived else "killed", "by": "tests", "reason": "r",
                "cpu_s": 2.0, "wall_s": 3.0, "tests": ["tests/compiled"], "cache": "fresh" if fresh else "warm"}

    monkeypatch.setattr(km.Runner, "prepare", lambda self, slot: str(tmp_path / "work"))
    monkeypatch.setattr(km.Runner, "mutant", mutant)
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.jsonl").write_text(json.dumps({"id": "x", "sources": "older", "status": "killed"}) + "\n")
    args = ["--n", "3", "--seed", "4", "--out", str(out), "--no-baseline"]
    assert km.main(args) == 0
    first = [m.id for m in km.sample(km.enumerate_mutants(), 3, 4)]
    assert ran == [(i, False) for i in first] + [(first[1], True)]   # the survivor again, with an empty cache
    assert km.main(args) == 0 and len(ran) == 4                # all done: nothing run again
    assert km.main(args[:1] + ["5"] + args[2:]) == 0
    five = [m.id for m in km.sample(km.enumerate_mutants(), 5, 4)]
    assert ran[4:] == [(five[3], False), (five[4], False), (five[4], True)]   # only the two new ones
    lines = (out / "results.jsonl").read_text().splitlines()
    assert len(lines) == 8 and all(json.loads(ln)["sources"] == km.sources_hash() for ln in lines[1:])
    s = json.loads((out / "summary.json").read_text())
    assert (s["done"], s["killed"], s["survived"], s["rows_of_other_sources"]) == (5, 3, 2, 1)
    assert s["cpu_seconds"] == 14.0 and s["caches"] == {"warm": 3, "fresh": 2} and s["commit"] and s["date"]
    assert (out / "survivors.txt").read_text().count("## ") == 2
    before = len(ran)
    assert km.main(args[:1] + ["5"] + args[2:] + ["--retest"]) == 0   # the two survivors again, warm first
    assert sorted(ran[before:before + 2]) == sorted([(first[1], False), (five[4], False)])


def test_a_killer_past_its_timeout_is_killed_and_its_cpu_time_counted(tmp_path):
    env = dict(os.environ)
    rc, text, cpu, wall = km.run([sys.executable, "-c", "import time\nprint('hangs', flush=True)\ntime.sleep(120)"],
                                 str(tmp_path), env, timeout=3, nice=0)
    assert rc == "timeout" and "hangs" in text and wall < 60
    rc, text, cpu, wall = km.run([sys.executable, "-c", "import time\nt = time.process_time()\n"
                                  "while time.process_time() - t < 0.3: pass\nraise SystemExit(3)"], str(tmp_path), env, 60, 0)
    assert rc == 3 and cpu >= 0.25


def test_the_killers_in_order_with_a_fresh_numba_cache(tmp_path, monkeypatch):
    """A toy project: its test fails when the file ``fail_tests`` exists; a stand-in ``yade`` on PATH
    fails the cross-check (a case named) when ``fail_xc`` exists."""
    work, bin_ = tmp_path / "work", tmp_path / "bin"
    (work / "tests").mkdir(parents=True)
    bin_.mkdir()
    (work / "tests" / "test_toy.py").write_text(
        "import os\n\ndef test_toy():\n"
        "    open('env.txt', 'w').write(os.environ['NUMBA_CACHE_DIR'] + ' ' + os.environ.get('PORE_DEM_NUMBA_CACHE_DIR', '-'))\n"
        "    assert not os.path.exists('fail_tests'), 'toy failure'\n")
    yade = bin_ / "yade"
    yade.write_text("#!/bin/sh\nmkdir -p \"$5\"\nif [ -e fail_xc ]; then echo '{\"cases\": [], \"feature_cases\": "
                    "[{\"name\": \"toy_case\", \"passed\": false}]}' > \"$5/crosscheck.json\"; exit 1; fi\n")
    yade.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("PORE_DEM_NUMBA_CACHE_DIR", "/a/parent/key")
    runner = km.Runner(str(tmp_path / "out"), {}, None, 0, {"tests": 120, "crosscheck": 120})
    row = runner.killers(str(work), "t1", ["tests"])
    assert (row["status"], row["by"], set(row["cost"])) == ("survived", None, {"tests", "crosscheck"})
    cache, parent = (work / "env.txt").read_text().split()
    assert cache == str(tmp_path / "out" / "cache" / "t1") and parent == "-"
    assert not os.path.exists(cache)                     # removed after the mutant
    (work / "fail_xc").touch()
    row = runner.killers(str(work), "t2", ["tests"])
    assert (row["status"], row["by"], row["reason"]) == ("killed", "crosscheck", "cases failed: toy_case")
    (work / "fail_tests").touch()
    row = runner.killers(str(work), "t3", ["tests"])
    assert (row["status"], row["by"], set(row["cost"])) == ("killed", "tests", {"tests"})
    assert "a test failed" in row["reason"] and "toy failure" in row["reason"]


def test_timeouts_are_given_or_a_multiple_of_the_baselines_wall_time():
    runner = km.Runner("out", {}, None, 0)
    none = {"tests": None, "crosscheck": None}
    assert runner.timeouts(none, None) == {"tests": km.TIMEOUT_NO_BASELINE, "crosscheck": km.TIMEOUT_NO_BASELINE}
    baseline = {"cost": {"tests": [100.0, 400.0], "crosscheck": [50.0, 100.0]}}
    assert runner.timeouts(none, baseline) == {"tests": km.TIMEOUT_FACTOR * 400.0, "crosscheck": km.TIMEOUT_MIN}
    assert runner.timeouts({"tests": 50.0, "crosscheck": None}, baseline)["tests"] == 50.0


def test_the_cache_folders_are_named_as_numbas():
    from numba.core.caching import _CacheLocator
    for d in ("/tmp/a/engines/compiled/kernels", "/work/x y/engines"):
        assert km.numba_folder(d) == _CacheLocator.get_suitable_cache_subpath(os.path.join(d, "m.py"))


def test_a_mutant_starts_from_the_warm_cache_without_the_kernels_that_can_hold_it(tmp_path):
    """The toy: c is mutated in engines/compiled/k.py; b calls c and a calls b (in other modules); d calls none."""
    refs = {"a": {"b", "np"}, "b": {"c"}, "c": set(), "d": {"np"}}
    old, new = tmp_path / "slot0", tmp_path / "slot1"
    for w in (old, new):
        (w / "engines" / "compiled" / "kernels").mkdir(parents=True)
    m = km.Mutant("engines/compiled/k.py", "c", 3, 4, 5, "binop:Add->Sub", "+", "-")
    warm = tmp_path / "warm"
    top, sub = km.numba_folder(old / "engines" / "compiled"), km.numba_folder(old / "engines" / "compiled" / "kernels")
    names = {top: ["k.c-3.py311.nbi", "k.c-3.py311.1.nbc", "k.e-9.py311.nbi", "x.b-1.py311.nbi", "x.d-4.py311.nbi"],
             sub: ["y.a-2.py311.1.nbc", "y.Cls.d-7.py311.nbi", "stray.txt"], "elsewhere_0123": ["z.d-1.py311.nbi"]}
    for folder, files in names.items():
        (warm / folder).mkdir(parents=True)
        for f in files:
            (warm / folder / f).write_text(f)
    dest = tmp_path / "cache" / "key"
    n = km.seed_cache(str(warm), str(old), str(new), str(dest), km.reach(m, refs, str(new)))
    kept = {str(p.relative_to(dest)) for p in dest.rglob("*") if p.is_file()}
    top, sub = km.numba_folder(new / "engines" / "compiled"), km.numba_folder(new / "engines" / "compiled" / "kernels")
    assert kept == {f"{top}/x.d-4.py311.nbi", f"{sub}/y.Cls.d-7.py311.nbi", "elsewhere_0123/z.d-1.py311.nbi"} and n == 3


def test_a_mutant_restores_its_file_and_timestamp_and_says_which_cache(tmp_path, monkeypatch):
    work = tmp_path / "work"
    (work / "engines" / "compiled").mkdir(parents=True)
    path = work / "engines" / "compiled" / "k.py"
    path.write_text(SOURCE, encoding="utf-8")
    os.utime(path, ns=(1_000_000_000, 2_000_000_000))
    m = next(x for x in km.enumerate_mutants(str(work)) if x.function == "f")
    seen = []
    monkeypatch.setattr(km.Runner, "killers", lambda self, w, tag, tests, start=None: seen.append(
        (path.read_text(encoding="utf-8"), start)) or {"status": "killed"})
    runner = km.Runner(str(tmp_path / "out"), {}, None, 0)
    monkeypatch.setattr(runner, "tests_for", lambda m: [])
    assert runner.mutant(str(work), m, SOURCE, "s")["cache"] == "fresh"        # no warm cache yet
    monkeypatch.setattr(runner, "warm_of", lambda sources: {"work": str(work), "key": "k0", "sources": sources})
    assert runner.mutant(str(work), m, SOURCE, "s")["cache"] == "warm"
    assert runner.mutant(str(work), m, SOURCE, "s", fresh=True)["cache"] == "fresh"
    assert [t == km.apply(SOURCE, m) for t, _ in seen] == [True] * 3 and [s is None for _, s in seen] == [True, False, True]
    assert path.read_text(encoding="utf-8") == SOURCE and os.stat(path).st_mtime_ns == 2_000_000_000
