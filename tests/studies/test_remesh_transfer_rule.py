"""The re-meshing transfer study's decision rule (benchmarks/remesh_transfer.py, docs/ENGINE.md)."""
from benchmarks.remesh_transfer import EXAMPLES, summary


def runs(values):
    """Runs of {(example, transfer): [remesh_over_inflow per start]}; no heave."""
    return [{"example": e, "transfer": t, "start": k, "remesh_over_inflow": v, "heave_time": None}
            for (e, t), vs in values.items() for k, v in enumerate(vs)]


def test_a_transfer_wins_an_example_only_with_apart_intervals_and_a_tie_goes_to_conserving():
    apart = {(EXAMPLES[0], "paper"): [0.10, 0.12, 0.11], (EXAMPLES[0], "conserving"): [1e-4, 2e-4, 1.5e-4]}
    table, decision = summary(runs(apart), 8)
    assert table[EXAMPLES[0]]["winner"] == "conserving" and decision["default"] == "conserving"
    paper_smaller = {(e, t): ([0.01, 0.011, 0.012] if t == "paper" else [0.1, 0.11, 0.12])
                     for e in EXAMPLES[:2] for t in ("paper", "conserving")}
    table, decision = summary(runs(paper_smaller), 8)
    assert decision["wins"] == {"paper": 2, "conserving": 0} and decision["default"] == "paper"
    overlap = {(EXAMPLES[1], "paper"): [0.01, 0.2], (EXAMPLES[1], "conserving"): [0.02, 0.1]}
    table, decision = summary(runs(overlap), 8)
    assert table[EXAMPLES[1]]["winner"] is None and decision["default"] == "conserving"
    assert summary(runs(apart), 2)[0][EXAMPLES[0]]["conserving"]["starts"] == 2  # starts >= 2 left out
