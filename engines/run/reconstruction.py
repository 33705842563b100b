"""The reconstruction study run (yade_scripts/liquefaction_reconstruction.py; the variants:
engines.studies.reconstruction): a deposit per packing variant, then each variant's cases as
ensembles of perturbed starts (yade_scripts/liquefaction.py --starts), through the sweep runner
(resumable: a re-run skips the finished jobs and continues a case's ensemble from its finished
starts), then postproc.liquefaction.reconstruction.

    OUT/runs/<variant>_packing/packing.csv          a packing variant's deposit
    OUT/runs/<variant>_case<N>/ensemble/            its case N: start_<k>/, ensemble.json
"""
import json
import os

from engines import ROOT
from engines.run import scene as scenes
from engines.studies.reconstruction import ENSEMBLE, STARTS, VARIANTS, case_job, ensemble_path, packing_job, packing_path

SCRIPTS = os.path.join(ROOT, "yade_scripts")
DEPOSITED = "liquefaction_case1"  # the preset whose deposition the packing variants change


def case_scene(case):
    """The scene option of a case: its fast preset where the validation passed for it (as make
    liquefaction runs it), else the case."""
    fast = os.path.join(scenes.SCENE_DIR, f"liquefaction_case{case}_fast.toml")
    return ["--scene", fast] if os.path.exists(fast) else ["--case", str(case)]


def _sets(table, fields):
    return [w for f, v in fields.items() for w in ("--set", f"{table}.{f}={json.dumps(v)}")]


def case_settings(variant, case, packing_file=None):
    """The --set options of ``variant`` on ``case``: its scaled fields (times the preset's own
    values) and, for a packing variant, its deposit's file."""
    preset = scenes.preset(f"liquefaction_case{case}")
    out = []
    for table, factors in variant.scale.items():
        out += _sets(table, {f: getattr(getattr(preset, table), f) * k for f, k in factors.items()})
    if packing_file:
        out += _sets("packing", {"source": "file", "file": packing_file})
    return out


def _ensemble_status(ensemble):
    """The status in an ensemble's plan ("completed", or its job was stopped), None before it began."""
    try:
        with open(os.path.join(ensemble, "ensemble.json")) as f:
            return json.load(f).get("status")
    except FileNotFoundError:
        return None


def study_jobs(root, variants=None, starts=STARTS, yade=("yade", "-n")):
    """(deposit jobs, case jobs) for engines.run.sweep of the variants (all, or the names
    ``variants``); ``root``: the sweep's folder (OUT/runs). A case whose ensemble has completed
    has no job; one stopped during its starts resumes them."""
    from engines.run.sweep import Job
    deposits, cases = [], []
    for name, v in VARIANTS.items():
        if variants and name not in variants:
            continue
        pk = None
        if v.deposit:
            pk = packing_path(root, name)
            deposits.append(Job(packing_job(name), [*yade, "-x", os.path.join(SCRIPTS, "deposit.py"), "--scene",
                                                    DEPOSITED, *_sets("packing", v.deposit), "--out", "{out}/packing.csv"],
                                {"PYTHONPATH": ROOT}))
        for case in v.cases:
            script = [*yade, "-x", os.path.join(SCRIPTS, "liquefaction.py")]
            status = _ensemble_status(ensemble_path(root, name, case))
            if status == "completed":
                continue
            if status is not None:  # stopped during its starts: continue it
                argv = [*script, "--resume", ensemble_path(root, name, case), "--jobs", "1"]
            else:
                argv = [*script, *case_scene(case), *case_settings(v, case, pk), "--starts", str(starts), "--jobs", "1",
                        "--out", f"{{out}}/{ENSEMBLE}"]
            cases.append(Job(case_job(name, case), argv, {"PYTHONPATH": ROOT}))
    return deposits, cases


def run_study(out, baseline, workers=1, scheduler=None, variants=None, analyse_only=False):
    """The deposits, then the cases, through the sweep runner (none with ``analyse_only``), then
    the table against the study's ensembles in ``baseline`` (its summary.json); returns its dict."""
    root = os.path.join(out, "runs")
    deposits, cases = study_jobs(root, variants)
    if not analyse_only:
        from engines.run.sweep import run_sweep
        for jobs in (deposits, cases):
            if jobs:
                run_sweep(jobs, root, workers=workers, scheduler=scheduler)
    from postproc.liquefaction import reconstruction
    return reconstruction(out, baseline, packing_facts(root))


def packing_facts(root):
    """{variant: {dense_top_support, bed_top_mm}} of the packing variants deposited in ``root``
    (engines.model.pore_dem.weight_carried: ~1 when the packing starts at rest)."""
    from engines.model.pore_dem import weight_carried
    from packing.packing import Packing
    sc = scenes.preset(DEPOSITED)
    out = {}
    for name, v in VARIANTS.items():
        if v.deposit and os.path.exists(packing_path(root, name)):
            pk = Packing.load(packing_path(root, name))
            m = pk.mobile
            out[name] = {"dense_top_support": weight_carried(sc.settings, pk, pk.mobile & (pk.density_factor > 1)),
                         "bed_top_mm": float(1e3 * (pk.xz[m, 1] + pk.r[m]).max())}
    return out
