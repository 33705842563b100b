"""The demo's numbers in README.md and docs/OUTPUTS.md are those of the committed docs/demo/demo.json
(made by make demo-numbers); nothing is run here."""
import json

import pytest

from engines.run import demo_numbers


@pytest.fixture(scope="module")
def doc():
    with open(demo_numbers.JSON) as f:
        return json.load(f)


def test_the_record_says_when_where_and_from_how_many_starts(doc):
    assert doc["date"] and doc["commit"] and doc["version"] and doc["machine"]["cores"] >= 1
    assert doc["ensemble"]["starts"] == demo_numbers.STARTS == 8
    for key, value in doc["demo"]["results"].items():
        st = doc["ensemble"]["results"][key]
        if st["mean"] is None:  # no start has it (a band with no contacts at the start: no p'/p'_0)
            assert value is None and st["ci95_low"] is None is st["ci95_high"], key
            continue
        assert st["ci95_low"] <= st["mean"] <= st["ci95_high"], key
        assert value is None or isinstance(value, float), key


@pytest.mark.parametrize("path", demo_numbers.DOCS)
def test_the_documents_quote_the_record(doc, path):
    assert demo_numbers.quoted(path) == demo_numbers.text(doc), \
        f"{path}: its demo numbers are not docs/demo/demo.json's: run make demo-numbers (or yade_scripts/demo_numbers.py --docs-only)"


def test_a_changed_number_is_caught(doc, tmp_path):
    page = tmp_path / "page.md"
    page.write_text(f"a\n{demo_numbers.MARKS[0]}\nold\n{demo_numbers.MARKS[1]}\nb\n")
    demo_numbers.update(str(page), doc)
    assert demo_numbers.quoted(str(page)) == demo_numbers.text(doc) and page.read_text().startswith("a\n")
    changed = json.loads(json.dumps(doc))
    changed["demo"]["results"]["porosity_end"] += 0.01
    assert demo_numbers.text(changed) != demo_numbers.text(doc)
    with pytest.raises(ValueError, match="has no"):
        (tmp_path / "bare.md").write_text("nothing")
        demo_numbers.update(str(tmp_path / "bare.md"), doc)
