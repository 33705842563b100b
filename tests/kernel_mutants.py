"""Mutation testing of the numba kernels (``make mutants-kernels``; not part of ``make test``).

    /usr/bin/python3 tests/kernel_mutants.py --n 200 --seed 1 --out out/mutants-kernels [--jobs 1]

mutmut (tests/mutants.py) does not mutate decorated functions, so the kernels are mutated here.
Every function of engines/compiled/ decorated with numba's jit or njit (found in the AST: the
decorator ``jit``/``njit``, ``nb.njit(...)``, or a module-level name bound to such a call, as
``jit = nb.njit(cache=True)``) is parsed, and its body yields the mutants (``enumerate_mutants``):

    binop   + <-> -, * <-> /            aug     += <-> -=, *= <-> /=
    cmp     < <-> <=, > <-> >=, == <-> !=   bool    and <-> or
    const   int 0 -> 1, 1 -> 0 and 2, c -> c + 1; float 0.0 -> 1.0, 1.0 -> 0.0 and 2.0, c -> 1.5 c
    unary   a unary minus dropped

each one token changed, with a stable id ``file:function:line:col:kind`` (line 1-based, col the
token's 0-based character column, e.g. ``engines/compiled/kernels/common.py:_beyond:19:15:cmp:Gt->GtE``).
The ids are sorted and shuffled with the seed; the first N are the sample (so a larger N with the
same seed extends a smaller one). Each mutant is applied to a copy of the project (OUT/work/slotK,
the one file patched, then restored with its timestamp) and no bytecode written (a same-size edit
within a second would otherwise run a stale .pyc). The killers, in order, each run only if the one
before did not kill:

  1. pytest -x -m "not check" on tests/compiled/ and every test file that names the mutated kernel
     or one of the functions of engines/compiled/ that call it (directly or not; a grep of tests/);
  2. the cross-check, ``yade -n -x yade_scripts/crosscheck.py --out OUT/xc/<hash>`` (--xc-only CASE...
     runs a subset).

The numba cache (NUMBA_CACHE_DIR = OUT/cache/<hash>; the project's engines/compiled/cache.py keys
its folder under it, and the key its parent marks in PORE_DEM_NUMBA_CACHE_DIR is dropped) starts
as the baseline's compiled kernels (OUT/cache/warm) without those a mutant can reach: every
function of the mutated module, and every function naming the mutated one directly or through
others (``callers``; numba's cache checks only the timestamp of a kernel's own file, and a caller's
machine code holds its callees). Compiling only those costs seconds where a fresh cache costs a
minute. Stale code could only make a mutant survive (the unmutated code would run), never kill it,
so every survivor not judged equivalent is run again with an empty cache (its row says
``"cache": "fresh"``) before it counts (``--retest`` first runs them again from the warm cache, after
tests were added); ``--fresh`` gives every mutant an empty cache.

A killer that fails, crashes (a numba typing error of the mutant counts: it cannot run) or passes
its timeout (a hang) kills the mutant; the row says which and why. Before the sample, the killers
run once on the unmutated sources ("baseline", all the test files the sample selects, compiling
OUT/cache/warm); a failing baseline stops the run. Each result is a line of OUT/results.jsonl (the
whole file rewritten atomically after each mutant; the last row of an id counts); a rerun skips the
ids done on the same sources (a hash of engines/compiled/) and ignores rows of other sources.
OUT/summary.json: the score killed / (total - equivalent), its 95 % Wilson interval, per module, the
CPU seconds of the children (user + sys, from os.wait4), the date and the commit;
OUT/survivors.txt: each survivor's diff. Mutants judged equivalent are listed in
tests/equivalent_kernel_mutants.txt as ``id  reason`` (one a line); a listed one that was killed is
reported stale.
"""
import argparse
import ast
import concurrent.futures
import datetime
import difflib
import hashlib
import io
import json
import math
import os
import queue
import random
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import tokenize
from dataclasses import dataclass

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

from engines import files  # noqa: E402
from engines.compiled.cache import cache_key  # noqa: E402
from tests.mutants import commit, read_equivalent  # noqa: E402

COMPILED = "engines/compiled"
EQUIVALENT = os.path.join(ROOT, "tests", "equivalent_kernel_mutants.txt")
SKIP_COPY = ("out", ".git", ".numba-cache", ".pytest_cache", "__pycache__", "*.pyc")
JIT = {"jit", "njit"}
NUMBA = {"numba"}
BINOP = {ast.Add: ("+", ast.Sub, "-"), ast.Sub: ("-", ast.Add, "+"),
         ast.Mult: ("*", ast.Div, "/"), ast.Div: ("/", ast.Mult, "*")}
CMP = {ast.Lt: ("<", ast.LtE, "<="), ast.LtE: ("<=", ast.Lt, "<"), ast.Gt: (">", ast.GtE, ">="),
       ast.GtE: (">=", ast.Gt, ">"), ast.Eq: ("==", ast.NotEq, "!="), ast.NotEq: ("!=", ast.Eq, "==")}
BOOL = {ast.And: ("and", ast.Or, "or"), ast.Or: ("or", ast.And, "and")}
AUG = {ast.Add: ("+=", ast.Sub, "-="), ast.Sub: ("-=", ast.Add, "+="),
       ast.Mult: ("*=", ast.Div, "/="), ast.Div: ("/=", ast.Mult, "*=")}
Z95 = 1.959963984540054  # the normal quantile of 0.975
KILLED = {"killed", "timeout"}
TIMEOUT_FACTOR, TIMEOUT_MIN, TIMEOUT_NO_BASELINE = 4, 600, 3600  # [-, s, s] a killer's timeout (Runner.timeouts)
TAIL = 400  # [characters] of a killer's output kept as the reason


@dataclass(frozen=True)
class Mutant:
    """One token of ``file`` (path from the project root) at ``line`` (1-based), ``col``..``end``
    (0-based characters, one line) reading ``old``, replaced by ``new``, inside ``function``."""
    file: str
    function: str
    line: int
    col: int
    end: int
    kind: str
    old: str
    new: str

    @property
    def id(self):
        return f"{self.file}:{self.function}:{self.line}:{self.col}:{self.kind}"


def _jit_names(tree, package="", exported=None):
    """(names that are numba's jit/njit or bound to one of their calls, {module alias: its jit names})
    in a module of ``package`` (dotted); ``exported``: {dotted module: the jit names it binds} of the
    other modules, so that ``from engines.compiled.x import kernel`` or ``x.kernel`` count too."""
    exported = exported or {}
    names, modules = set(JIT), {"numba": JIT}
    for node in tree.body:
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name == "numba" or a.name in exported:
                    modules[a.asname or a.name] = JIT if a.name == "numba" else exported[a.name]
        elif isinstance(node, ast.ImportFrom):
            module = ".".join(filter(None, [package] * (node.level == 1) + [node.module]))
            own = JIT if module == "numba" else exported.get(module, set())
            names |= {a.asname or a.name for a in node.names if a.name in own}
            modules.update({a.asname or a.name: exported[f"{module}.{a.name}"] for a in node.names
                            if f"{module}.{a.name}" in exported})
    for node in tree.body:
        if isinstance(node, ast.Assign) and _is_jit(node.value, names, modules):
            names |= {t.id for t in node.targets if isinstance(t, ast.Name)}
    return names, modules


def _is_jit(node, names, modules):
    """Is the decorator (or the expression) ``node`` numba's jit/njit, called or not?"""
    f = node.func if isinstance(node, ast.Call) else node
    if isinstance(f, ast.Name):
        return f.id in names
    return (isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name)
            and f.attr in modules.get(f.value.id, ()))


def exported_jit_names(trees):
    """{dotted module: the names it binds to a jit call} of ``trees`` ({dotted module: AST})."""
    return {m: _jit_names(t, m.rpartition(".")[0])[0] - JIT for m, t in trees.items()}


def jit_functions(tree, module="", exported=None):
    """The functions of a module's AST (``module``: its dotted name) decorated with numba's jit/njit,
    directly or by a name bound to it here or in ``exported``: [(qualified name, FunctionDef)]."""
    names, modules = _jit_names(tree, module.rpartition(".")[0], exported)
    out = []

    def visit(body, prefix):
        for node in body:
            if isinstance(node, ast.ClassDef):
                visit(node.body, f"{prefix}{node.name}.")
            elif isinstance(node, ast.FunctionDef) and any(_is_jit(d, names, modules) for d in node.decorator_list):
                out.append((prefix + node.name, node))
    visit(tree.body, "")
    return out


def _char_col(lines, line, byte_col):
    """The character column of the byte offset ``byte_col`` (the AST's unit) on 1-based ``line``."""
    return len(lines[line - 1].encode("utf-8")[:byte_col].decode("utf-8"))


def _start(lines, node):
    return node.lineno, _char_col(lines, node.lineno, node.col_offset)


def _end(lines, node):
    return node.end_lineno, _char_col(lines, node.end_lineno, node.end_col_offset)


def _token(tokens, lines, left, right, text):
    """The one token reading ``text`` between the AST nodes ``left`` and ``right`` (tokens: {line: [token]})."""
    a, b = _end(lines, left), _start(lines, right)
    found = [t for line in range(a[0], b[0] + 1) for t in tokens.get(line, ())
             if t.string == text and a <= t.start and t.end <= b]
    if len(found) != 1:
        raise ValueError(f"line {left.lineno}: {len(found)} tokens {text!r} between two operands")
    return found[0]


def _token_at(tokens, start):
    """The token starting at (line, col)."""
    return next(t for t in tokens[start[0]] if t.start == start)


def _constants(value):
    """The replacements of a number literal's value (module docstring)."""
    if isinstance(value, bool):
        return []
    if isinstance(value, int):
        return {0: [1], 1: [0, 2]}.get(value, [value + 1])
    if isinstance(value, float):
        return {0.0: [1.0], 1.0: [0.0, 2.0]}.get(value, [value * 1.5])
    return []


def _body_nodes(fn):
    """The AST nodes of a function's body, its docstring left out."""
    body = fn.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        body = body[1:]
    for stmt in body:
        yield from ast.walk(stmt)


def function_mutants(path, tokens, lines, name, fn):
    """The mutants of one jit function ``fn`` (named ``name``) of the file ``path`` (its ``lines``,
    its operator, name and number ``tokens`` by line)."""
    out = []

    def add(tok, kind, new):
        (line, col), (end_line, end) = tok.start, tok.end
        assert line == end_line, tok
        out.append(Mutant(path, name, line, col, end, kind, tok.string, new))

    for node in _body_nodes(fn):
        if isinstance(node, ast.BinOp) and type(node.op) in BINOP:
            sym, to, new = BINOP[type(node.op)]
            add(_token(tokens, lines, node.left, node.right, sym), f"binop:{type(node.op).__name__}->{to.__name__}", new)
        elif isinstance(node, ast.AugAssign) and type(node.op) in AUG:
            sym, to, new = AUG[type(node.op)]
            add(_token(tokens, lines, node.target, node.value, sym), f"aug:{type(node.op).__name__}->{to.__name__}", new)
        elif isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            for k, op in enumerate(node.ops):
                if type(op) in CMP:
                    sym, to, new = CMP[type(op)]
                    add(_token(tokens, lines, operands[k], operands[k + 1], sym), f"cmp:{type(op).__name__}->{to.__name__}", new)
        elif isinstance(node, ast.BoolOp):
            sym, to, new = BOOL[type(node.op)]
            for a, b in zip(node.values, node.values[1:]):
                add(_token(tokens, lines, a, b, sym), f"bool:{type(node.op).__name__}->{to.__name__}", new)
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            tok = _token_at(tokens, _start(lines, node))
            assert tok.string == "-", tok
            add(tok, "unary:drop-USub", "")
        elif isinstance(node, ast.Constant) and _constants(node.value):
            tok = _token_at(tokens, _start(lines, node))
            for value in _constants(node.value):
                add(tok, f"const:{tok.string}->{value!r}", repr(value))
    return out


def enumerate_mutants(root=ROOT, folder=COMPILED):
    """Every mutant of the jit functions of the .py files of ``folder`` (under ``root``), sorted by
    file, line, column and kind (each still parses: a swapped operator, a number for a number, a
    dropped minus)."""
    out, sources, trees = [], {}, {}
    for path in sorted(_py_files(root, folder)):
        with open(os.path.join(root, path), encoding="utf-8") as f:
            sources[path] = f.read()
        trees[path] = ast.parse(sources[path], path)
    exported = exported_jit_names({p[:-3].replace("/", "."): t for p, t in trees.items()})
    for path, tree in trees.items():
        source = sources[path]
        lines = source.split("\n")  # the AST's and the tokenizer's lines (str.splitlines also splits at \f, \u2028...)
        tokens = {}
        for t in tokenize.generate_tokens(io.StringIO(source).readline):
            if t.type in (tokenize.OP, tokenize.NAME, tokenize.NUMBER):
                tokens.setdefault(t.start[0], []).append(t)
        for name, fn in jit_functions(tree, path[:-3].replace("/", "."), exported):
            out += function_mutants(path, tokens, lines, name, fn)
    return sorted(out, key=lambda m: (m.file, m.line, m.col, m.kind))


def _py_files(root, folder):
    """The .py files under ``folder`` (paths from ``root``, with /)."""
    for d, dirs, names in os.walk(os.path.join(root, folder)):
        dirs[:] = [x for x in dirs if x != "__pycache__"]
        for n in names:
            if n.endswith(".py"):
                yield os.path.relpath(os.path.join(d, n), root).replace(os.sep, "/")


def apply(source, m):
    """``source`` (the text of m.file) with the mutant's token replaced; refuses a source where the
    token is not what the mutant was made from."""
    lines = source.split("\n")
    text = lines[m.line - 1] if m.line <= len(lines) else ""
    if text[m.col:m.end] != m.old:
        raise ValueError(f"{m.id}: expected {m.old!r} at {m.file}:{m.line}:{m.col}, found {text[m.col:m.end]!r}")
    lines[m.line - 1] = text[:m.col] + m.new + text[m.end:]
    return "\n".join(lines)


def diff(source, m):
    """The unified diff (one line of context) the mutant makes to ``source``."""
    return "".join(difflib.unified_diff(source.splitlines(keepends=True), apply(source, m).splitlines(keepends=True),
                                        f"a/{m.file}", f"b/{m.file}", n=1))


def sample(mutants, n, seed):
    """The first n of the mutants (sorted by id) shuffled with ``seed``: a larger n extends a smaller one."""
    order = sorted(mutants, key=lambda m: m.id)
    random.Random(seed).shuffle(order)
    return order[:n]


def sources_hash(root=ROOT, folder=COMPILED):
    """A hash of the .py files of ``folder`` (paths and contents): results are reused on the same sources only."""
    h = hashlib.sha256()
    for path in sorted(_py_files(root, folder)):
        with open(os.path.join(root, path), "rb") as f:
            data = f.read()
        h.update(f"{path} {len(data)}\n".encode())
        h.update(data)
    return h.hexdigest()[:16]


def wilson(k, n, z=Z95):
    """The Wilson score interval (low, high) of a proportion k / n; (None, None) for n = 0."""
    if n == 0:
        return None, None
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return centre - half, centre + half


# ---- which tests can kill a mutant ----------------------------------------------------------------

def call_graph(root=ROOT, folder=COMPILED):
    """{module-level function of ``folder``, or name bound to an expression (as BUILD = (kernels,
    ...)): the names it refers to}. Classes are left out: those of engines/compiled are named as
    the model's (PoreDEM, WaterModel...), so their names would select the NumPy model's tests, and
    tests/compiled runs them."""
    refs = {}
    for path in _py_files(root, folder):
        with open(os.path.join(root, path), encoding="utf-8") as f:
            tree = ast.parse(f.read(), path)
        for node in tree.body:
            if isinstance(node, ast.FunctionDef):
                targets, value = [node.name], node
            elif isinstance(node, ast.Assign):
                targets, value = [t.id for t in node.targets if isinstance(t, ast.Name)], node.value
            else:
                continue
            used = {n.id for n in ast.walk(value) if isinstance(n, ast.Name)} | \
                   {n.attr for n in ast.walk(value) if isinstance(n, ast.Attribute)}
            for t in targets:
                refs.setdefault(t, set()).update(used - {t})
    return refs


def callers(name, refs):
    """``name`` and every name of ``refs`` that refers to it, directly or through others."""
    found, todo = {name}, [name]
    while todo:
        n = todo.pop()
        for caller, used in refs.items():
            if n in used and caller not in found:
                found.add(caller)
                todo.append(caller)
    return found


def test_files(names, root=ROOT):
    """The test files of tests/ (outside tests/compiled/, which always runs) naming one of ``names``
    as a word, sorted; this tool's own files left out."""
    word = re.compile(r"\b(" + "|".join(re.escape(n) for n in sorted(names)) + r")\b")
    out = []
    for path in _py_files(root, "tests"):
        base = os.path.basename(path)
        if path.startswith("tests/compiled/") or not base.startswith("test_") or "kernel_mutants" in base:
            continue
        with open(os.path.join(root, path), encoding="utf-8") as f:
            if word.search(f.read()):
                out.append(path)
    return sorted(out)


# ---- the numba cache a mutant starts from --------------------------------------------------------

CACHE_FILE = re.compile(r"(?P<stem>[^.]+)\.(?P<qualname>.+)-\d+\.py\d+(\.\d+)?\.nb[ci]")  # numba's index and data files


def numba_folder(source_dir):
    """The subfolder of NUMBA_CACHE_DIR where numba caches the kernels of the .py files of ``source_dir``
    (numba.core.caching._CacheLocator.get_suitable_cache_subpath: the folder's name, the SHA-1 of its path)."""
    d = os.path.abspath(source_dir)
    return f"{os.path.basename(d)}_{hashlib.sha1(d.encode()).hexdigest()}"


def reach(m, refs, work):
    """Which cached kernels of the work copy ``work`` can hold the mutant's code: a predicate of (numba
    folder, cache file name), true for the files of the mutated module and of the functions naming the
    mutated one directly or through others (any module: a name shared by two modules selects both), and
    for a file not named as numba names them."""
    own = (numba_folder(os.path.dirname(os.path.join(work, m.file))), os.path.basename(m.file)[:-3])
    names = callers(m.function.split(".")[0], refs)

    def stale(folder, name):
        f = CACHE_FILE.fullmatch(name)
        return f is None or (folder, f["stem"]) == own or f["qualname"].split(".")[0] in names
    return stale


def seed_cache(warm, warm_work, work, dest, stale):
    """Copy the kernels numba compiled into ``warm`` (a keyed cache folder made in the work copy
    ``warm_work``) to ``dest``, each numba folder renamed for the same source folder of the work copy
    ``work``, the files ``stale(folder, file name)`` selects left out (folder: the new name). The
    number of files copied."""
    renamed = {}
    for d, dirs, _ in os.walk(work):
        dirs[:] = [x for x in dirs if x not in ("out", ".git", "__pycache__")]
        renamed[numba_folder(os.path.join(warm_work, os.path.relpath(d, work)))] = numba_folder(d)
    n = 0
    for folder in os.listdir(warm):
        new = renamed.get(folder, folder)
        for name in os.listdir(os.path.join(warm, folder)):
            if not stale(new, name):
                os.makedirs(os.path.join(dest, new), exist_ok=True)
                shutil.copy2(os.path.join(warm, folder, name), os.path.join(dest, new, name))
                n += 1
    return n


# ---- results -------------------------------------------------------------------------------------

def read_results(path, sources):
    """{id: row} of the rows of results.jsonl made on ``sources`` (a truncated last line is ignored),
    and the number of rows of other sources."""
    done, other = {}, 0
    if os.path.exists(path):
        for line in open(path, encoding="utf-8"):
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            if row.get("sources") == sources:
                done[row["id"]] = row
            else:
                other += 1
    return done, other


def append_result(path, row):
    """Add ``row`` as the last line of results.jsonl, the file rewritten whole (atomically)."""
    old = open(path, encoding="utf-8").read() if os.path.exists(path) else ""
    if old and not old.endswith("\n"):
        old = old[:old.rfind("\n") + 1]  # a line cut by a kill (write_text never leaves one; kept for safety)
    files.write_text(path, old + json.dumps(row) + "\n")


def summarise(rows, sample_ids, equivalent):
    """Counts, score and Wilson interval overall and per module of the rows of ``sample_ids``
    (rows: {id: row}; a row with status "error" is counted apart, not scored)."""
    per, stale, errors = {}, [], []
    for mid in sample_ids:
        row = rows.get(mid)
        if row is None:
            continue
        r = per.setdefault(mid.split(":")[0], {"total": 0, "killed": 0, "timeout": 0, "survived": 0, "equivalent": 0})
        if row["status"] == "error":
            errors.append(mid)
            continue
        r["total"] += 1
        if row["status"] in KILLED:
            r["killed"] += 1
            r["timeout"] += row["status"] == "timeout"
            if mid in equivalent:
                stale.append(mid)
        elif mid in equivalent:
            r["equivalent"] += 1
        else:
            r["survived"] += 1
    total = {k: sum(r[k] for r in per.values()) for k in ("total", "killed", "timeout", "survived", "equivalent")}
    for r in [*per.values(), total]:
        n = r["total"] - r["equivalent"]
        r["score"] = r["killed"] / n if n else None
        r["wilson95"] = list(wilson(r["killed"], n))
    return {**total, "modules": dict(sorted(per.items())), "stale_equivalent": sorted(stale), "errors": sorted(errors)}


# ---- running the killers -------------------------------------------------------------------------

def run(cmd, cwd, env, timeout, nice):
    """Run ``cmd`` niced in its own process group: (return code or "timeout", output tail, CPU
    seconds of the process and its waited-for children (os.wait4), wall seconds). A run past
    ``timeout`` [s] has its group killed."""
    t0 = time.time()
    p = subprocess.Popen(["nice", "-n", str(nice), *cmd], cwd=cwd, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, start_new_session=True)
    chunks = []
    reader = threading.Thread(target=lambda: chunks.extend(iter(lambda: p.stdout.read(65536), b"")), daemon=True)
    reader.start()
    timed_out = False
    while True:
        pid, status, usage = os.wait4(p.pid, os.WNOHANG)
        if pid:
            break
        if time.time() - t0 > timeout and not timed_out:
            timed_out = True
            os.killpg(p.pid, signal.SIGKILL)
        time.sleep(0.2)
    p.returncode = os.waitstatus_to_exitcode(status)
    reader.join(5)
    text = b"".join(chunks).decode("utf-8", "replace")
    return ("timeout" if timed_out else p.returncode), text, usage.ru_utime + usage.ru_stime, time.time() - t0


def reason_of(text):
    """The telling end of a killer's output: pytest's failure lines if any, else its last lines."""
    failed = [ln for ln in text.splitlines() if ln.startswith(("FAILED", "ERROR", "E ", "Traceback"))
              or "Error" in ln or "FAILED" in ln or "failed" in ln]
    tail = "\n".join((failed[-4:] if failed else text.splitlines()[-4:]))
    return tail[-TAIL:]


class Runner:
    """The killers of one run (module docstring), in the work copies OUT/work/slotK."""

    def __init__(self, out, refs, xc_only, nice, timeout=None):
        self.out, self.refs, self.xc_only, self.nice = out, refs, xc_only, nice
        self.warm = os.path.join(out, "cache", "warm")  # the baseline's numba cache (module docstring)
        self.warm_info = os.path.join(out, "cache", "warm.json")  # where and on which sources it was made
        self.timeout = {"tests": TIMEOUT_NO_BASELINE, "crosscheck": TIMEOUT_NO_BASELINE, **(timeout or {})}

    def timeouts(self, given, baseline):
        """Each killer's timeout [s]: as ``given`` ({killer: s or None}), else TIMEOUT_FACTOR x its wall
        time in the ``baseline`` row (at least TIMEOUT_MIN: a kernel looping for ever is common among
        the mutants, and each hang costs its timeout in CPU), else TIMEOUT_NO_BASELINE."""
        cost = (baseline or {}).get("cost", {})
        for k in self.timeout:
            self.timeout[k] = given.get(k) or (max(TIMEOUT_MIN, TIMEOUT_FACTOR * cost[k][1]) if k in cost else TIMEOUT_NO_BASELINE)
        return self.timeout

    def prepare(self, slot):
        """A fresh copy of the project in OUT/work/slot<slot> (whatever an interrupted run left is replaced)."""
        work = os.path.join(self.out, "work", f"slot{slot}")
        shutil.rmtree(work, ignore_errors=True)
        shutil.copytree(ROOT, work, ignore=shutil.ignore_patterns(*SKIP_COPY))
        return work

    def tests_for(self, m):
        return ["tests/compiled", *test_files(callers(m.function.split(".")[0], self.refs))]

    def warm_of(self, sources):
        """The record of the warm cache ({work, key, sources}) if there is one for ``sources``, else None."""
        try:
            with open(self.warm_info, encoding="utf-8") as f:
                info = json.load(f)
        except (OSError, ValueError):
            return None
        return info if info.get("sources") == sources and os.path.isdir(os.path.join(self.warm, info["key"])) else None

    def warm_start(self, work, m, sources):
        """A function filling a mutant's (empty) numba cache folder from the warm cache, or None
        when there is none for ``sources`` (the mutant then compiles everything)."""
        info = self.warm_of(sources)
        if info is None:
            return None
        key = cache_key(os.path.join(work, "engines"))  # the mutated sources' keyed folder
        stale = reach(m, self.refs, work)
        return lambda cache: seed_cache(os.path.join(self.warm, info["key"]), info["work"], work,
                                        os.path.join(cache, key), stale)

    def keep_warm(self, work, sources):
        """Record the baseline's cache (made in the work copy ``work``) as the warm one of ``sources``."""
        files.write_json(self.warm_info, {"work": work, "key": cache_key(os.path.join(work, "engines")),
                                          "sources": sources})

    def killers(self, work, tag, tests, start=None):
        """Run the tests, then the cross-check unless they killed: a row's fields (status, by, reason,
        cpu_s and wall_s, and cost: {killer: [CPU s, wall s]}). The numba cache is OUT/cache/<tag>,
        filled by ``start(folder)`` first if given and removed after; the baseline's is the warm one, kept."""
        cache = self.warm if tag == "baseline" else os.path.join(self.out, "cache", tag)
        xc = os.path.join(self.out, "xc", tag)
        for d in (cache, xc):
            shutil.rmtree(d, ignore_errors=True)
        os.makedirs(cache)
        if start:
            start(cache)
        env = {k: v for k, v in os.environ.items() if k != "PORE_DEM_NUMBA_CACHE_DIR"}
        env.update(PYTHONPATH=work, MPLBACKEND="Agg", NUMBA_CACHE_DIR=cache, PYTHONDONTWRITEBYTECODE="1",
                   OMP_NUM_THREADS="1")
        cost = {}

        def verdict(status, by, reason):
            return dict(status=status, by=by, reason=reason, cpu_s=sum(c for c, _ in cost.values()),
                        wall_s=sum(w for _, w in cost.values()), cost=cost)

        try:
            rc, text, *cost["tests"] = run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider",
                                            "-m", "not check", *tests], work, env, self.timeout["tests"], self.nice)
            if rc == "timeout":
                return verdict("timeout", "tests", f"no end within {self.timeout['tests']:.0f} s (a hang counts as killed)")
            if rc != 0:
                why = {1: "a test failed", 2: "the tests could not be collected or run"}.get(
                    rc, f"pytest ended by signal {-rc}" if rc < 0 else f"pytest exit {rc}")
                return verdict("killed" if rc in (1, 2) or rc < 0 else "error", "tests", f"{why}: {reason_of(text)}")
            cmd = ["yade", "-n", "-x", "yade_scripts/crosscheck.py", "--out", xc, *(["--only", *self.xc_only] if self.xc_only else [])]
            rc, text, *cost["crosscheck"] = run(cmd, work, env, self.timeout["crosscheck"], self.nice)
            if rc == "timeout":
                return verdict("timeout", "crosscheck", f"no end within {self.timeout['crosscheck']:.0f} s (a hang counts as killed)")
            if rc != 0:
                failed = _failed_cases(os.path.join(xc, "crosscheck.json"))
                return verdict("killed", "crosscheck", f"cases failed: {', '.join(failed)}" if failed
                               else f"crosscheck exit {rc}: {reason_of(text)}")
            return verdict("survived", None, "the tests and the cross-check passed")
        finally:
            for d in (cache, xc) if cache != self.warm else (xc,):
                shutil.rmtree(d, ignore_errors=True)

    def mutant(self, work, m, original, sources, fresh=False):
        """Apply ``m`` to the work copy, run the killers (from the warm cache unless ``fresh``), restore
        the file and its timestamp (numba's cache of the work copy checks it): the result row."""
        path = os.path.join(work, m.file)
        stamp = os.stat(path)
        files.write_text(path, apply(original, m))
        try:
            tests = self.tests_for(m)
            start = None if fresh else self.warm_start(work, m, sources)
            row = self.killers(work, hashlib.sha1(m.id.encode()).hexdigest()[:12], tests, start)
        finally:
            files.write_text(path, original)
            os.utime(path, ns=(stamp.st_atime_ns, stamp.st_mtime_ns))
        return {"id": m.id, **row, "tests": tests, "cache": "fresh" if start is None else "warm"}


def _failed_cases(path):
    """The names of the failed cases in a crosscheck.json (empty if it is missing or unreadable)."""
    try:
        with open(path, encoding="utf-8") as f:
            result = json.load(f)
    except (OSError, ValueError):
        return []
    return [c.get("name", "?") for group in ("cases", "feature_cases") for c in result.get(group, [])
            if isinstance(c, dict) and not c.get("passed", True)]


def write_summary(out, chosen, rows, equivalent, args, sources, other_rows, timeout):
    """OUT/summary.json and OUT/survivors.txt from the rows of the sample."""
    ids = [m.id for m in chosen]
    s = summarise(rows, ids, equivalent)
    done = [rows[i] for i in ids if i in rows]
    cpu = sum(r["cpu_s"] + r.get("earlier_cpu_s", 0.0) for r in done)
    per_killer = {k: [r["cost"][k][0] for r in done if k in r.get("cost", {})] for k in ("tests", "crosscheck")}
    s.update(date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), commit=commit(),
             sources=sources, seed=args.seed, n=args.n, done=len(done),
             cpu_seconds=cpu, cpu_seconds_per_mutant=cpu / len(done) if done else None,
             cpu_seconds_per_run={k: {"runs": len(v), "mean": sum(v) / len(v) if v else None}
                                  for k, v in per_killer.items()},
             wall_seconds=sum(r["wall_s"] for r in done),
             caches={c: sum(1 for r in done if r.get("cache", "fresh") == c) for c in ("warm", "fresh")},
             baseline=rows.get("baseline"), rows_of_other_sources=other_rows,
             equivalent_mutants={i: equivalent[i] for i in ids if i in equivalent},
             killed_by={k: sum(1 for r in done if r["status"] in KILLED and r["by"] == k) for k in ("tests", "crosscheck")},
             killers={"tests": "pytest -q -x -m 'not check' tests/compiled + the test files naming the kernel or its callers",
                      "crosscheck": "yade -n -x yade_scripts/crosscheck.py" + (f" --only {' '.join(args.xc_only)}" if args.xc_only else ""),
                      "timeout_s": timeout,
                      "cache": "the baseline's compiled kernels without the mutated module's and its callers'; "
                               "every survivor run again with an empty cache",
                      "timeout_note": "a killer past its timeout (a hang) counts as killing the mutant"})
    files.write_json(os.path.join(out, "summary.json"), s)
    by_id = {m.id: m for m in chosen}
    sources_text = {}
    parts = []
    for i in ids:
        r = rows.get(i)
        if r is None or r["status"] != "survived" or i in equivalent:
            continue
        m = by_id[i]
        if m.file not in sources_text:
            sources_text[m.file] = open(os.path.join(ROOT, m.file), encoding="utf-8").read()
        parts.append(f"## {i}: {r['reason']} (tests: {' '.join(r['tests'])})\n{diff(sources_text[m.file], m)}\n")
    files.write_text(os.path.join(out, "survivors.txt"), "".join(parts))
    return s


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=200, help="mutants in the sample")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "mutants-kernels"))
    ap.add_argument("--jobs", type=int, default=1, help="mutants run at once (each in its own work copy)")
    ap.add_argument("--nice", type=int, default=10, help="niceness of the killers")
    ap.add_argument("--timeout-tests", type=float, help=f"[s] the tests of one mutant (a hang: killed); default "
                    f"{TIMEOUT_FACTOR} x the baseline's, at least {TIMEOUT_MIN}")
    ap.add_argument("--timeout-xc", type=float, help="[s] the cross-check of one mutant, the same way")
    ap.add_argument("--xc-only", nargs="+", metavar="CASE", help="cross-check only these cases")
    ap.add_argument("--no-baseline", action="store_true", help="skip the killers' run on the unmutated sources "
                    "(and so the warm cache: every mutant compiles everything)")
    ap.add_argument("--fresh", action="store_true", help="every mutant with an empty numba cache (slower; the "
                    "default starts from the baseline's, module docstring)")
    ap.add_argument("--retest", nargs="*", metavar="ID", help="run the survivors not judged equivalent (or "
                    "those of these ids) again first, from the warm cache (after tests were added)")
    ap.add_argument("--list", action="store_true", help="print the sample's ids and stop")
    ap.add_argument("--report-only", action="store_true", help="write the summary from OUT/results.jsonl and stop")
    args = ap.parse_args(argv)
    if args.n < 1 or args.jobs < 1:
        ap.error(f"--n and --jobs must be >= 1, got {args.n} and {args.jobs}")
    out = os.path.abspath(args.out)
    if (out + os.sep).startswith(ROOT + os.sep) and not (out + os.sep).startswith(os.path.join(ROOT, "out") + os.sep):
        ap.error(f"--out {args.out} is inside the project, which is copied for each work folder; "
                 f"choose a folder under {os.path.join(ROOT, 'out')} or outside {ROOT}")
    os.makedirs(out, exist_ok=True)
    mutants = enumerate_mutants()
    chosen = sample(mutants, args.n, args.seed)
    if len(chosen) < args.n:
        ap.error(f"only {len(mutants)} mutants in {COMPILED}; ask for --n {len(mutants)} at most")
    if args.list:
        print("\n".join(m.id for m in chosen))
        return 0
    equivalent = read_equivalent(EQUIVALENT)
    sources = sources_hash()
    results = os.path.join(out, "results.jsonl")
    rows, other = read_results(results, sources)
    print(f"{len(mutants)} mutants in the jit functions of {COMPILED}; sample of {len(chosen)} (seed {args.seed}); "
          f"{sum(m.id in rows for m in chosen)} done before on these sources ({sources})", flush=True)
    runner = Runner(out, call_graph(), args.xc_only, args.nice)
    given = {"tests": args.timeout_tests, "crosscheck": args.timeout_xc}
    runner.timeouts(given, rows.get("baseline"))
    lock = threading.Lock()
    if not args.report_only:
        originals = {m.file: open(os.path.join(ROOT, m.file), encoding="utf-8").read() for m in chosen}
        survivor = lambda m: rows[m.id]["status"] == "survived" and m.id not in equivalent  # noqa: E731
        retest = lambda m: args.retest is not None and survivor(m) and (not args.retest or m.id in args.retest)  # noqa: E731
        todo = [m for m in chosen if m.id not in rows or retest(m)]
        slots = queue.Queue()
        for k in range(min(args.jobs, max(len(todo), 1))):
            slots.put((k, runner.prepare(k)))
        cold = "baseline" not in rows or not (args.fresh or runner.warm_of(sources))
        if not args.no_baseline and cold and todo:
            k, work = slots.get()
            tests = sorted({t for m in todo for t in runner.tests_for(m)})
            print(f"baseline: the killers on the unmutated sources ({len(tests)} test paths)", flush=True)
            row = {"id": "baseline", **runner.killers(work, "baseline", tests), "tests": tests, "sources": sources}
            slots.put((k, work))
            append_result(results, row)
            rows["baseline"] = row
            if row["status"] != "survived":
                sys.exit(f"the killers fail on the unmutated sources ({row['by']}: {row['reason']}); fix that first")
            runner.keep_warm(work, sources)
            runner.timeouts(given, row)
        print(f"timeouts: {runner.timeout} s", flush=True)

        def one(m, fresh):
            k, work = slots.get()
            try:
                row = {**runner.mutant(work, m, originals[m.file], sources, fresh), "sources": sources}
            finally:
                slots.put((k, work))
            if m.id in rows:  # a survivor run again with an empty cache: the CPU of both runs counts
                row["earlier_cpu_s"] = rows[m.id]["cpu_s"] + rows[m.id].get("earlier_cpu_s", 0.0)
            with lock:
                append_result(results, row)
                rows[m.id] = row
                print(f"[{len(rows) - ('baseline' in rows)}/{len(chosen)}] {m.id}: {row['status']}"
                      f"{' by ' + row['by'] if row['by'] else ''} ({row['cpu_s']:.0f} CPU s, {row['cache']} cache)",
                      flush=True)

        with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
            for f in [pool.submit(one, m, args.fresh) for m in todo]:
                f.result()
            again = [m for m in chosen if survivor(m) and rows[m.id].get("cache") != "fresh"]  # an equivalent one cannot be killed
            if again:
                print(f"{len(again)} survivors run again with an empty numba cache", flush=True)
            for f in [pool.submit(one, m, True) for m in again]:
                f.result()
    s = write_summary(out, chosen, rows, equivalent, args, sources, other, runner.timeout)
    lo, hi = s["wilson95"]
    print(f"score {s['score']} ({s['killed']} killed of {s['total'] - s['equivalent']}; 95 % interval "
          f"{lo}-{hi}); {s['survived']} survivors in {out}/survivors.txt; {s['cpu_seconds']:.0f} CPU s"
          + (f"; STALE equivalents: {s['stale_equivalent']}" if s["stale_equivalent"] else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
