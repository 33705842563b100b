"""postproc.liquefaction_bands: the cases' band verdicts written as JSON, and the page's table whose
every number carries its marker and equals the JSON's (the rule of tests/test_doc_numbers.py)."""
import json
import re

import pytest

from postproc import liquefaction_bands as lb


def a_case(root, name, status, p_means, bed_top=0.01, d=0.001):
    case = root / name
    (case / "start_0").mkdir(parents=True)
    results = {}
    for k, m in enumerate(p_means, 1):
        results[f"bands.band{k}.p_ratio_min"] = {"n": 2, "mean": m, "ci95_low": m - 0.01, "ci95_high": m + 0.01,
                                                 "values": [m, m]}
        results[f"bands.band{k}.ru_max"] = {"n": 2, "mean": 1 - m, "ci95_low": 0.9 - m, "ci95_high": 1.1 - m,
                                            "values": [1 - m, 1 - m]}
        results[f"bands.band{k}.t_ru_0p9_s"] = {"n": 1, "mean": 0.01, "ci95_low": None, "ci95_high": None,
                                                "values": [0.01, None] if m < 0.1 else [None, None]}
    doc = {"status": status, "scene": name, "n_starts": 2}
    if status == "completed":
        doc["results"] = results
    (case / "ensemble.json").write_text(json.dumps(doc))
    n = len(p_means)
    bounds = [[bed_top * k / n, bed_top * (k + 1) / n] for k in range(n)]
    (case / "start_0" / "summary.json").write_text(json.dumps({
        "band_bounds_m": bounds, "parameters": {"packing": {"mean_diameter": d}},
        "provenance": {"git_commit": "0123456789abcdef"}}))
    (case / "start_0" / "history.csv").write_text(f"t,bed_top\n0,{bed_top}\n0.001,{bed_top}\n")


def test_the_table_names_the_lowest_band_and_the_verdict_and_each_number_is_the_jsons(tmp_path, capsys):
    a_case(tmp_path, "case1", "completed", [0.3, 0.02, 0.5, 0.0])  # band 4 lies within 2 diameters of the top
    a_case(tmp_path, "case2", "running", [0.3])
    out = tmp_path / "bands.json"
    lb.main([str(tmp_path), str(out)])
    doc = json.loads(out.read_text())
    assert list(doc["cases"]) == ["1"], "a running ensemble is left out"
    bands = doc["cases"]["1"]["bands"]
    assert [bands[b]["liquefied"] for b in ("band1", "band2", "band3", "band4")] == [False, True, False, None]
    text = capsys.readouterr().out
    row = [line for line in text.splitlines() if line.startswith("| 1 |")][0]
    assert "0.02" in row and "(band2)" in row and row.rstrip().endswith("| band2 |") and "1 of 2" in row
    for number, path, keys in re.findall(r"([-\d.]+)<!--json:([^#]+)#([^>]+)-->", row):
        value = doc
        for k in keys.split("/"):
            value = value[k]
        assert float(number) == pytest.approx(value, abs=0.006), keys


def test_no_completed_case_is_refused_in_one_line(tmp_path):
    a_case(tmp_path, "case1", "running", [0.3])
    with pytest.raises(SystemExit, match="no completed case"):
        lb.main([str(tmp_path), str(tmp_path / "bands.json")])
    assert not (tmp_path / "bands.json").exists()
