"""The paper's statement "full liquefaction (zero effective stress) was not reached in 2D" (SPEC
§2.5) measured on the seismic cases' ensembles, by band of the bed (engines.model.effective_stress;
the verdicts: engines.studies.liquefaction.band_verdicts). Reads ROOT/case<N>/ensemble.json and its
first start's summary.json and history.csv (the bands, the bed's top, the mean diameter), writes
OUT.json and prints docs/LIQUEFACTION.md's table, each number with its JSON marker
(tests/test_doc_numbers.py). ``make liquefaction-bands`` runs the ensembles and this:

    /usr/bin/python3 -m postproc.liquefaction_bands ROOT OUT.json
"""
import argparse
import json
import os
import re
import sys
import time

from engines import files
from engines.model.effective_stress import counted_bands
from engines.studies.liquefaction import P_RATIO_LIQUEFIED, RU_LIQUEFIED, band_verdicts
from postproc.run_files import read_history, read_summary


def case_bands(case_dir):
    """{"scene", "n_starts", "commit", "bands": band_verdicts} of one case's ensemble folder."""
    ens = json.load(open(os.path.join(case_dir, "ensemble.json"), encoding="utf-8"))
    start = os.path.join(case_dir, "start_0")
    summary = read_summary(start)
    bed_top = float(read_history(os.path.join(start, "history.csv"))["bed_top"][0])
    counted = counted_bands(summary["band_bounds_m"], bed_top, summary["parameters"]["packing"]["mean_diameter"])
    return {"scene": ens["scene"], "n_starts": ens["n_starts"], "commit": summary["provenance"]["git_commit"][:7],
            "bands": band_verdicts(ens["results"], counted)}


def completed(case_dir):
    """Has the ensemble of ``case_dir`` completed (every start, its statistics written)?"""
    return json.load(open(os.path.join(case_dir, "ensemble.json"), encoding="utf-8")).get("status") == "completed"


def table(doc, path):
    """docs/LIQUEFACTION.md's table of ``doc`` (written to ``path``): per case, the judged band of the
    lowest min p'/p'_0 and that of the highest max r_u, each with its 95 % interval."""
    def interval(case, band, q):
        key = f"cases/{case}/bands/{band}/{q}"
        st = doc["cases"][case]["bands"][band][q]
        return (f"{st['mean']:.2f}<!--json:{path}#{key}/mean--> [{st['ci95_low']:.2f}<!--json:{path}#{key}/ci95_low-->, "
                f"{st['ci95_high']:.2f}<!--json:{path}#{key}/ci95_high-->] ({band})")

    lines = ["| case | starts | bands judged | lowest min p'/p'_0 | highest max r_u | starts with r_u ≥ "
             f"{RU_LIQUEFIED:g} | zero effective stress (p'/p'_0 < {P_RATIO_LIQUEFIED:g}) |", "|---|---|---|---|---|---|---|"]
    for case, c in doc["cases"].items():
        judged = {b: v for b, v in c["bands"].items() if v["judged"]}
        low = min(judged, key=lambda b: judged[b]["p_ratio_min"]["mean"])
        wet = [b for b in judged if judged[b]["ru_max"] is not None]
        high = interval(case, max(wet, key=lambda b: judged[b]["ru_max"]["mean"]), "ru_max") if wet else "dry"
        reached = (f"{max(judged[b]['starts_ru_0p9'][0] for b in wet)} of {c['n_starts']}" if wet else "dry")
        verdict = ", ".join(b for b in judged if judged[b]["liquefied"]) or "no band"
        lines.append(f"| {case} | {c['n_starts']}<!--json:{path}#cases/{case}/n_starts--> | {len(judged)} of "
                     f"{len(c['bands'])} | {interval(case, low, 'p_ratio_min')} | {high} | {reached} | {verdict} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m postproc.liquefaction_bands", description=__doc__.split("\n\n")[0])
    ap.add_argument("root", help="the folder of the cases' ensembles (case1/ensemble.json, ...)")
    ap.add_argument("out", help="the JSON to write (e.g. docs/liquefaction/bands.json)")
    args = ap.parse_args(argv)
    found = sorted((d for d in os.listdir(args.root) if re.fullmatch(r"case\d+", d)
                    and os.path.exists(os.path.join(args.root, d, "ensemble.json"))), key=lambda d: int(d[4:]))
    cases = [d for d in found if completed(os.path.join(args.root, d))]
    if not cases:
        sys.exit(f"{args.root}: no completed case<N>/ensemble.json (run make liquefaction-bands first)")
    if len(cases) < len(found):
        print(f"left out (not completed): {', '.join(sorted(set(found) - set(cases)))}", file=sys.stderr)
    doc = {"what": __doc__.split("\n\n")[0], "date": time.strftime("%Y-%m-%d", time.gmtime()),
           "p_ratio_liquefied": P_RATIO_LIQUEFIED, "ru_liquefied": RU_LIQUEFIED,
           "cases": {d[4:]: case_bands(os.path.join(args.root, d)) for d in cases}}
    files.write_json(args.out, doc)
    print(table(doc, args.out))


if __name__ == "__main__":
    main()
