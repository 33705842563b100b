"""The user's guide points at things that exist: every relative link of README.md and docs/*.md
resolves to a file, every project path written in code exists, every `make TARGET` is a target of
the Makefile, and the Python snippets import what exists and call it with parameters it takes."""
import ast
import glob
import importlib
import inspect
import os
import re

import pytest

from engines import ROOT

PAGES = [os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(ROOT, "docs", "*.md")))
LINK = re.compile(r"\]\(([^)\s]+)\)")                       # [text](target)
CODE = re.compile(r"`([^`\n]+)`")
TOP = ("engines/", "packing/", "postproc/", "yade_scripts/", "benchmarks/", "tests/", "docs/")
PROJECT_PATH = re.compile(r"^(?:%s)[\w./*-]*$" % "|".join(re.escape(t) for t in TOP))
MAKE = re.compile(r"(?:^|\s)make ([a-z][\w-]*)")
FENCE = re.compile(r"^```[^\n]*\n(.*?)^```", re.M | re.S)
PYTHON = re.compile(r"^```python\n(.*?)^```", re.M | re.S)
TARGET = re.compile(r"^([a-z][\w-]*):", re.M)
README_LINES = 200  # the README is a user's guide; the details live in docs/


def page_id(path):
    return os.path.relpath(path, ROOT)


def relative_links(text):
    """Link targets that are neither URLs nor anchors, without their #fragment."""
    return [t.split("#")[0] for t in LINK.findall(text)
            if not re.match(r"^[a-z]+:", t) and not t.startswith("#")]


def code_spans(text):
    """The text inside backticks and the fenced code blocks."""
    return CODE.findall(FENCE.sub("", text)) + FENCE.findall(text)


def project_paths(text):
    """Paths in code that start with a top-level folder of the project (a test id's ::name and a
    trailing dot dropped; paths with placeholders such as <t> are skipped)."""
    out = []
    for code in code_spans(text):
        for word in code.split():
            word = word.split("::")[0].rstrip(".,;:)")
            if PROJECT_PATH.match(word):
                out.append(word)
    return out


def make_targets(text):
    """TARGET of each `make TARGET` in backticks or in a fenced code block (not in prose)."""
    return [t for c in code_spans(text) for t in MAKE.findall(c)]


def test_the_checks_find_what_they_look_for():
    text = ("see [a](docs/A.md#x), [b](https://x.org), [c](#top), `engines/run/scene.py::f`, `out/x.csv`,\n"
            "`make demo` to make an example\n```\nmake test   # yade_scripts/a.py\n```\n")
    assert relative_links(text) == ["docs/A.md"]
    assert project_paths(text) == ["engines/run/scene.py", "yade_scripts/a.py"]
    assert make_targets(text) == ["demo", "test"]


def read(page):
    return open(page, encoding="utf-8").read()


def test_relative_links_resolve():
    missing = {page_id(p): [t for t in relative_links(read(p)) if not os.path.exists(os.path.join(os.path.dirname(p), t))]
               for p in PAGES}
    assert not any(missing.values()), missing


def test_project_paths_exist():
    missing = {page_id(p): [q for q in project_paths(read(p)) if not glob.glob(os.path.join(ROOT, q))] for p in PAGES}
    assert not any(missing.values()), missing


def test_make_targets_exist():
    targets = set(TARGET.findall(read(os.path.join(ROOT, "Makefile"))))
    missing = {page_id(p): sorted(set(make_targets(read(p))) - targets) for p in PAGES}
    assert not any(missing.values()), missing


def test_the_readme_is_short():
    assert len(read(PAGES[0]).splitlines()) <= README_LINES


def snippet_calls(code):
    """(name as written, the object, positional count, keyword names) of each call in ``code`` to
    an object the snippet imported (``from M import X`` then ``X(...)``, or ``M.f(...)`` for an
    imported module M)."""
    tree = ast.parse(code)
    names = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            module = importlib.import_module(node.module)
            for a in node.names:
                if not hasattr(module, a.name):  # a submodule: from package import module
                    importlib.import_module(f"{node.module}.{a.name}")
                assert hasattr(module, a.name), f"{node.module} has no {a.name}"
                names[a.asname or a.name] = getattr(module, a.name)
    calls = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Name) and f.id in names:
                obj, name = names[f.id], f.id
            elif isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id in names \
                    and inspect.ismodule(names[f.value.id]):
                obj, name = getattr(names[f.value.id], f.attr), f"{f.value.id}.{f.attr}"
            else:
                continue
            calls.append((name, obj, len(node.args), [k.arg for k in node.keywords]))
    return calls


def snippet_errors(code):
    """What is wrong with a snippet: calls its callee's signature does not accept, and a
    WaterEngine run without raise_pending (an error inside the engine only pauses YADE)."""
    errors, called = [], set()
    for name, obj, n_args, keywords in snippet_calls(code):
        called.add(name)
        try:
            inspect.signature(obj).bind(*[None] * n_args, **dict.fromkeys(keywords))
        except TypeError as e:
            errors.append(f"{name}(...): {e}")
    if "WaterEngine" in called and "raise_pending" not in called:
        errors.append("WaterEngine without raise_pending() after the run")
    return errors


def test_snippet_errors_are_found():
    head = "from engines.model.pore_water import WaterSettings\n"
    assert snippet_errors(head + "s = WaterSettings(E_w=240.0, k1=1.0, k2=2.0)\n") == []
    assert snippet_errors(head + "s = WaterSettings(E_w=240.0, k1=1.0, k2=2.0, k4=1.0)\n")  # no such field
    assert snippet_errors(head + "s = WaterSettings(240.0, 1.0, 2.0, 0.0, 0.0, \"undrained\", False, True, \"paper\", 0.0, 1)\n")  # one too many


def test_python_snippets_match_the_code():
    pytest.importorskip("yade")  # the snippets import the YADE layer
    errors, engine_snippets = {}, 0
    for page in PAGES:
        for code in PYTHON.findall(read(page)):
            engine_snippets += "WaterEngine(" in code
            errors.setdefault(page_id(page), []).extend(snippet_errors(code))
    assert not any(errors.values()), errors
    assert engine_snippets >= 1
