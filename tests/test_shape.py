"""The shape of the code: no function of LIMIT lines or more (from its def line to its last) in the
library and the scripts; a long function is split into named parts."""
import ast
import os

from engines import ROOT

LIMIT = 60
TOPS = ("engines", "packing", "postproc", "yade_scripts")
# being split now by other helpers (the pores' and kernels' module split, the contact-law classes,
# the coupling); the developer empties this list at merge
BEING_SPLIT = set()


def functions(tree, prefix=""):
    """(qualified name, number of lines) of every function in ``tree``, nested ones and methods too."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield prefix + node.name, node.end_lineno - node.lineno + 1
            yield from functions(node, prefix + node.name + ".")
        elif isinstance(node, ast.ClassDef):
            yield from functions(node, prefix + node.name + ".")
        else:
            yield from functions(node, prefix)


def long_functions(root=ROOT, tops=TOPS, limit=LIMIT):
    """{(path relative to ``root``, qualified name): lines} of the functions of ``limit`` lines or more."""
    out = {}
    for top in tops:
        for d, _, names in os.walk(os.path.join(root, top)):
            for f in sorted(names):
                if f.endswith(".py"):
                    path = os.path.join(d, f)
                    rel = os.path.relpath(path, root).replace(os.sep, "/")
                    tree = ast.parse(open(path, encoding="utf-8").read())
                    out.update({(rel, name): n for name, n in functions(tree) if n >= limit})
    return out


def test_long_functions_are_found_with_their_class(tmp_path):
    body = "\n".join(f"    x{k} = {k}" for k in range(LIMIT - 1))
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text(f"class A:\n    def f(self):\n    {body.replace(chr(10), chr(10) + '    ')}\n\n\n"
                                           f"def g():\n{body}\n\n\ndef h():\n    return 1\n")
    assert long_functions(str(tmp_path), ("pkg",)) == {("pkg/m.py", "A.f"): LIMIT, ("pkg/m.py", "g"): LIMIT}


def test_no_function_of_sixty_lines_or_more():
    found = long_functions()
    new = sorted(f"{path} {name} ({n} lines)" for (path, name), n in found.items() if (path, name) not in BEING_SPLIT)
    assert new == [], f"functions of {LIMIT} lines or more (split them into named parts): " + "; ".join(new)
    done = sorted(f"{path} {name}" for path, name in BEING_SPLIT if (path, name) not in found)
    assert done == [], "split now: remove from BEING_SPLIT: " + "; ".join(done)
