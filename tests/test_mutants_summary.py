"""The mutation-testing summary (tests/mutants.py, `make mutants`): counts, scores, stale equivalents."""
import importlib.util
import os

import pytest

_spec = importlib.util.spec_from_file_location("mutants", os.path.join(os.path.dirname(__file__), "mutants.py"))
mutants = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mutants)


def test_summary_counts_and_scores_per_module_and_over_the_judged_ones():
    status = {"engines.a.f__mutmut_1": "killed", "engines.a.f__mutmut_2": "survived", "engines.a.f__mutmut_3": "timeout",
              "engines.a.g__mutmut_1": "survived", "engines.a.g__mutmut_2": "not checked",
              "engines.b.h__mutmut_1": "killed", "engines.b.h__mutmut_2": "no tests",
              "engines.x.k__mutmut_1": "survived"}
    equivalent = {"engines.a.g__mutmut_1": "why", "engines.b.h__mutmut_1": "stale"}
    s = mutants.summarise(status, ["engines/a.py", "engines/b.py", "engines/x.py"], equivalent,
                          judged=["engines/a.py", "engines/b.py"])
    a, b, x = (s["modules"][m] for m in ("engines/a.py", "engines/b.py", "engines/x.py"))
    assert a == {"total": 4, "killed": 2, "survived": 1, "equivalent": 1, "not_checked": 1, "score": pytest.approx(2 / 3)}
    assert (b["total"], b["killed"], b["survived"], b["equivalent"], b["score"]) == (2, 1, 1, 0, 0.5)
    assert x["score"] == 0.0
    assert s["score"] == pytest.approx(3 / 5)             # over a and b only: (2 + 1) / (6 - 1)
    assert s["stale_equivalent"] == ["engines.b.h__mutmut_1"]
    with pytest.raises(ValueError, match="none of"):
        mutants.summarise({"engines.c.f__mutmut_1": "killed"}, ["engines/a.py"], {})


def test_equivalent_list_needs_a_reason(tmp_path):
    f = tmp_path / "eq.txt"
    f.write_text("# comment\n\nengines.a.f__mutmut_1  a reason\n")
    assert mutants.read_equivalent(str(f)) == {"engines.a.f__mutmut_1": "a reason"}
    f.write_text("engines.a.f__mutmut_1\n")
    with pytest.raises(ValueError, match="no reason"):
        mutants.read_equivalent(str(f))
