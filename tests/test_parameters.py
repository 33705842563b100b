"""No function of engines/ takes more than MAX_PARAMETERS parameters (self and cls not counted)
but the Python-facing entry points that engines.ENTRY_POINTS lists (at most six), whose argument
lists are built from layouts and checked at import (engines.compiled.layout)."""
import ast
import glob
import os

import engines

MAX_PARAMETERS = 12


def parameter_counts(root=engines.ROOT):
    """{"engines/<path>.py:<function>": number of parameters} of every function of engines/ above
    MAX_PARAMETERS (methods by their own name)."""
    over = {}
    for path in sorted(glob.glob(os.path.join(root, "engines", "**", "*.py"), recursive=True)):
        tree = ast.parse(open(path).read(), path)
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                names = [p.arg for p in a.posonlyargs + a.args]
                n = len(names) + len(a.kwonlyargs) + (a.vararg is not None) + (a.kwarg is not None)
                n -= bool(names) and names[0] in ("self", "cls")
                if n > MAX_PARAMETERS:
                    over[f"{os.path.relpath(path, root)}:{node.name}"] = n
    return over


def test_no_function_above_twelve_parameters_but_the_entry_points():
    assert len(engines.ENTRY_POINTS) <= 6
    over = parameter_counts()
    assert sorted(set(over) - set(engines.ENTRY_POINTS)) == []
    assert sorted(set(engines.ENTRY_POINTS) - set(over)) == []  # an entry point of 12 or fewer: not listed


def test_counts_the_parameters(tmp_path):
    """The count takes positional, keyword-only, *args and **kwargs, not self."""
    (tmp_path / "engines").mkdir()
    (tmp_path / "engines" / "m.py").write_text(
        "def f(a, b, c, d, e, f, g, h, i, j, k, *l, m):\n    pass\n"
        "class C:\n    def g(self, a, b, c, d, e, f, g, h, i, j, k, l):\n        pass\n"
        "def h(a, b, c, d, e, f, g, h, i, j, k, l, **m):\n    pass\n")
    assert parameter_counts(str(tmp_path)) == {"engines/m.py:f": 13, "engines/m.py:h": 13}
