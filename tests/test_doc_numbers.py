"""Every measured number the docs quote is the number of a committed JSON: a marker right after
the number, ``<!--json:PATH#KEY/KEY/0-->`` (PATH from the project's root, the keys of nested objects
and the indices of lists separated by ``/``, ``FIELD=VALUE`` and ``len`` to count a list's items; ``*100`` after the keys for a percentage), names the
file and the value (keys may hold spaces, not ``*`` or ``>``), and the number as written must be that value rounded to the digits written.
Nothing is rerun: the JSON files are the measurements, the docs quote them."""
import glob
import json
import os
import re
import subprocess

import pytest

from engines import ROOT

PAGES = [os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(ROOT, "docs", "*.md")))
MARKER = re.compile(r"<!--json:(?P<path>[^#\s]+)#(?P<keys>[^*>]*?)(?:\*(?P<scale>[0-9.e+-]+))?-->")
NUMBER = re.compile(r"[-−]?\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?")


def quoted_numbers(text):
    """(number as written, json path, keys, scale, line number) of each marker: the number is the
    last one before the marker on its line, markdown emphasis and units between them allowed."""
    out = []
    for m in MARKER.finditer(text):
        line_start = text.rfind("\n", 0, m.start()) + 1
        before = MARKER.sub("", text[line_start:m.start()])
        numbers = NUMBER.findall(before)
        written = numbers[-1] if numbers else None
        out.append((written, m["path"], m["keys"], float(m["scale"] or 1), text.count("\n", 0, m.start()) + 1))
    return out


def value_at(doc, keys):
    """The value at ``keys``; on a list, ``FIELD=VALUE`` keeps the items whose FIELD is VALUE and
    ``len`` counts the items (a count the doc quotes: points, runs of an outcome)."""
    for key in keys.split("/") if keys else []:
        if not isinstance(doc, list):
            doc = doc[key]
        elif key == "len":
            doc = len(doc)
        elif "=" in key:
            field, value = key.split("=", 1)
            doc = [item for item in doc if str(item.get(field)) == value]
        else:
            doc = doc[int(key)]
    return doc


def agrees(written, value):
    """The number as written is ``value`` rounded to the written digits (half a unit of the last
    written digit, and a relative 1e-12 for the float's own round-off)."""
    text = written.replace(",", "").replace("−", "-")
    mantissa = text.split("e")[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    exponent = int(text.split("e")[1]) if "e" in text else 0
    unit = 10.0 ** (exponent - decimals)
    return abs(float(text) - value) <= 0.5 * unit * (1 + 1e-9) + 1e-12 * abs(value)


def test_the_marker_reading_finds_the_number_and_rounds_as_written():
    text = ("the run took **5.22 s**<!--json:a.json#x--> and 0.31 %<!--json:a.json#y/0*100--> "
            "of 180,000<!--json:b.json#n--> steps\n")
    assert quoted_numbers(text) == [("5.22", "a.json", "x", 1.0, 1), ("0.31", "a.json", "y/0", 100.0, 1),
                                    ("180,000", "b.json", "n", 1.0, 1)]
    assert value_at({"y": [0.5, 2]}, "y/0") == 0.5
    points = {"p": [{"o": "a"}, {"o": "b"}, {"o": "a"}]}
    assert value_at(points, "p/len") == 3 and value_at(points, "p/o=a/len") == 2 and value_at(points, "p/o=c/len") == 0
    assert agrees("5.22", 5.2211) and agrees("5.22", 5.2249) and not agrees("5.22", 5.226)
    assert agrees("180,000", 180000) and not agrees("180,000", 180001)
    assert agrees("6e-13", 6.4e-13) and not agrees("6e-13", 6.6e-13) and agrees("−0.5", -0.5)


def tracked():
    run = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    return set(run.stdout.split()) if run.returncode == 0 else None


QUOTES = [(os.path.relpath(page, ROOT), *q) for page in PAGES for q in quoted_numbers(open(page, encoding="utf-8").read())]


def test_the_docs_quote_measured_numbers():
    """The convention is in use where the measurements are reported (a page losing its markers fails)."""
    pages = {q[0] for q in QUOTES}
    assert {"README.md", "docs/PERFORMANCE.md", "docs/TRADEOFFS.md", "docs/LIQUEFACTION.md", "docs/CROSSCHECK.md"} <= pages, pages


@pytest.mark.parametrize("page", sorted({q[0] for q in QUOTES}))
def test_each_quoted_number_is_its_committed_jsons(page):
    """Each marked number of the page against its file; the message lists every disagreement."""
    files, wrong = tracked(), []
    for _, written, path, keys, scale, line in (q for q in QUOTES if q[0] == page):
        where = f"line {line}: {written!r} from {path}#{keys}"
        if written is None:
            wrong.append(f"{where}: no number before the marker")
        elif files is not None and path not in files:
            wrong.append(f"{where}: {path} is not committed")
        else:
            with open(os.path.join(ROOT, path)) as f:
                value = scale * value_at(json.load(f), keys)
            if not agrees(written, value):
                wrong.append(f"{where}: the JSON holds {value!r}")
    assert not wrong, f"{page}:\n" + "\n".join(wrong)


def test_each_quoted_json_is_named_on_its_page():
    """The page names each file it quotes (a link or a path a reader sees, not only the markers)."""
    for page in {q[0] for q in QUOTES}:
        text = MARKER.sub("", open(os.path.join(ROOT, page), encoding="utf-8").read())
        here = os.path.dirname(page)
        for path in {q[2] for q in QUOTES if q[0] == page}:
            assert path in text or os.path.relpath(path, here) in text, f"{page} quotes {path} without naming it"
