"""pytest plugin of the mutation runs (tests/mutants.py loads it with -p): the tests a mutant reaches run
fastest first, by the durations mutmut recorded, so that the first failing test (mutmut stops there)
comes early; other runs are left as they are."""
import json
import os


def pytest_collection_modifyitems(items):
    if "__mutmut_" not in os.environ.get("MUTANT_UNDER_TEST", ""):
        return
    try:
        with open("mutmut-stats.json", encoding="utf-8") as f:   # mutmut runs the tests in its mutants/ copy
            seconds = json.load(f)["duration_by_test"]
    except OSError:
        return
    items.sort(key=lambda item: seconds.get(item.nodeid, 0.0))
