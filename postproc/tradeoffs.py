"""The speed/accuracy study's tables and figures (engines.run.tradeoffs runs it; docs/TRADEOFFS.md).

``analyse(out, jobs, meta)`` reads OUT/runs/<job>/result.json, has each setting's errors, speed-up
and judgement computed (engines.studies.tradeoffs_judged.assess), and writes OUT/tradeoffs.json,
OUT/table.md and OUT/tradeoffs_<case>.png (error against cost, log axes, the Pareto front marked).
Cost is CPU seconds per start (the machine is shared, so CPU time is steadier than wall time; both
are kept).

Each row carries the raw metrics (``error``) and the noise-corrected estimate of the systematic
error (``systematic``: per metric the measured value, its floor between the run's and the
reference's ensembles, the estimate sqrt(max(0, measured^2 - floor^2)) and its bootstrap sigma;
engines.studies.tradeoffs.systematic), and the judgement against the 5 % target
(engines.studies.tradeoffs_judged.judge).

``validate(out, jobs, meta)`` writes the validation of the runs (engines.studies.tradeoffs_judged.validation:
per scene every metric and the verdict of the fast setting and of the candidate settings tried)
-> OUT/validation.json and validation.md.
"""
import json
import os

import numpy as np

from engines import files
from engines.studies import tradeoffs as tr
from engines.studies.tradeoffs_judged import METRICS, TARGET, assess, load, validation

LABELS = {"pressure_rms": "block pressure RMS", "porosity_change": "porosity change", "settlement": "settlement"}
DIAGNOSTIC = "pressure_rms_below_surface"


def analyse(out, jobs, meta, log=print):
    """The table and the figures of the study in ``out`` (module docstring). ``meta``: job name ->
    (case, knob, value). Returns the tradeoffs.json dict."""
    log = log or (lambda *a: None)
    results = {j.name: load(os.path.join(out, "runs", j.name, "result.json")) for j in jobs}
    doc = assess(results, meta, log)
    speed = os.path.join(out, "speed", "speed.json")  # engines.run.tradeoffs.measure_speed: interleaved in one process
    if os.path.exists(speed):
        with open(speed) as f:
            doc["speed_interleaved"] = json.load(f)
        if doc["defaults"] is not None:
            doc["defaults"]["speedup_interleaved"] = doc["speed_interleaved"]["speedup"].get("defaults=fast")
    files.write_json(os.path.join(out, "tradeoffs.json"), doc, indent=1, default=float)
    files.write_text(os.path.join(out, "table.md"), table(doc))
    for case in doc["reference"]:
        log("figure:", figure(doc, case, os.path.join(out, f"tradeoffs_{case}.png")))
        shown = [n for n, (c, k, v) in meta.items() if c == case and k in ("reference", "perturbation")
                 and (results[n] or {}).get("data") is not None]
        if len(shown) > 1:  # the ensemble means against the size of the perturbation of the starts
            series = [(_label(meta[n], results[n]), results[n]["data"]) for n in shown]
            log("figure:", histories_figure(series, os.path.join(out, f"perturbation_{case}.png"), case))
    return doc


def _label(point, res):
    _, knob, value = point
    return f"{knob} {_value({'value': value})}: dt {res['dt']:g} s, starts perturbed by {res.get('perturbation', 1e-9):g} m"


def histories_figure(series, path, title, n_blocks=4):
    """The ensemble-mean block pressure histories [N/m] of ``series`` [(label, data of ``load``)],
    one panel for each of the first ``n_blocks`` blocks, each mean with a band of ± its standard
    error over the starts."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    blocks = range(min(n_blocks, series[0][1]["U"].shape[2]))
    fig, axes = plt.subplots(1, len(blocks), figsize=(4 * len(blocks), 4), sharex=True)
    for label, data in series:
        t, U = 1e3 * data["t"], data["U"]
        mean, se = np.nanmean(U, axis=0), np.nanstd(U, axis=0, ddof=1) / np.sqrt(len(U))
        for ax, b in zip(axes, blocks):
            line, = ax.plot(t, mean[:, b], lw=1.2, label=label)
            ax.fill_between(t, mean[:, b] - se[:, b], mean[:, b] + se[:, b], color=line.get_color(), alpha=0.25, lw=0)
    for ax, b in zip(axes, blocks):
        ax.axhline(0, color="0.5", lw=0.6)
        ax.set_title(f"block {b + 1} (from the bottom)", fontsize=10)
        ax.set_xlabel("t [ms]")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("ensemble-mean excess pore pressure U [N/m]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=8)
    fig.suptitle(f"{title}: mean over the starts ± its standard error (band)", fontsize=10)
    fig.tight_layout(rect=(0, 0.14, 1, 0.95))
    files.save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def worst(err):
    return max(err[m] for m in METRICS) if err else np.nan


def estimate(row, metric):
    """(noise-corrected estimate, sigma) of a row's metric; "worst": that of the metric whose
    estimate is largest."""
    sys_ = row["systematic"]
    if metric == "worst":
        metric = max(METRICS, key=lambda m: sys_[m]["systematic"])
    return sys_[metric]["systematic"], sys_[metric]["sigma"]


def _fmt(v, spec=".3f"):
    return "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) else format(v, spec)


def _value(row):
    v = row["value"]
    if isinstance(v, dict):
        return v.get("name", "")
    return f"{v:g}" if isinstance(v, float) else str(v)


def table(doc):
    """Markdown: one line per run; per metric the raw value, its floor between the two ensembles
    and the noise-corrected estimate ± sigma, in % (the reference's chaos floor on its line)."""
    lines = ["| case | knob | value | dt [s] | CPU s/start | speed-up | starts | "
             + " | ".join(f"{LABELS.get(m, 'below surface')} %: raw (floor) → systematic ± σ" for m in METRICS + (DIAGNOSTIC,))
             + " | ≤ 5 % (systematic) | ≤ 5 % raw |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for case, ref in doc["reference"].items():
        fl = ref["floor"]
        lines.append(f"| {case} | reference (chaos floor) | dt {ref['dt']:g} | {ref['dt']:g} | {ref['cpu_s']:.1f} | "
                     f"{_fmt(ref['paper_cpu_s'] / ref['cpu_s'] if ref['paper_cpu_s'] else None, '.2f')} | {ref['starts']} | "
                     + " | ".join(f"({100 * fl[m]:.1f})" for m in METRICS + (DIAGNOSTIC,)) + " | | |")
        for row in doc["runs"]:
            if row["case"] != case:
                continue
            sys_ = row["systematic"]
            cells = [f"{100 * sys_[m]['measured']:.1f} ({100 * sys_[m]['floor']:.1f}) → "
                     f"{100 * sys_[m]['systematic']:.1f} ± {100 * sys_[m]['sigma']:.1f}" for m in METRICS + (DIAGNOSTIC,)] \
                if sys_ else ["failed: " + "; ".join(row["messages"])[:60], "", "", ""]
            judged = ("yes" if row["resolved"] else "yes (not resolved)") if row.get("within_target") else "no"
            cells += [judged, "yes" if row.get("within_target_raw") else "no"]
            lines.append(f"| {case} | {row['knob']} | {_value(row)} | {row['dt']:g} | {row['cpu_s']:.2f} | "
                         f"{_fmt(row['speedup'], '.1f')} | {row['starts_ok']}/{row['starts']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


KNOB_STYLE = {"dt": ("tab:blue", "o"), "water_interval": ("tab:orange", "s"), "rebuild_period": ("tab:green", "^"),
              "smoothing": ("tab:red", "D"), "transfer": ("tab:purple", "v"), "E_w_scale": ("tab:brown", "P"),
              "precision": ("tab:pink", "X"), "law": ("tab:olive", "*"), "candidate": ("tab:cyan", "h"),
              "defaults": ("black", "*"), "perturbation": ("tab:gray", "<")}


def figure(doc, case, path):
    """Error against CPU seconds per start (log axes), one panel per metric and one for the worst:
    the noise-corrected estimate of each setting (filled, ± sigma bars) and its raw metric (open
    grey circle), the Pareto front of the estimates, the reference's chaos floor (grey band) and
    the 5 % target."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in doc["runs"] if r["case"] == case and r["error"]]
    ref = doc["reference"][case]
    fig, axes = plt.subplots(2, 2, figsize=(11, 8.5), sharex=True)
    panels = [("worst", "worst of the three metrics")] + [(m, LABELS[m]) for m in METRICS]
    for ax, (key, title) in zip(axes.flat, panels):
        cost = np.array([r["cpu_s"] for r in rows])
        est = np.array([estimate(r, key) for r in rows])
        err, sigma = est[:, 0], est[:, 1]
        raw = np.array([worst(r["error"]) if key == "worst" else r["error"][key] for r in rows])
        fl = max(ref["floor"].values()) if key == "worst" else ref["floor"][key]
        bottom = 0.3 * min(np.min(err[err > 0], initial=fl), fl, TARGET)
        shown = np.maximum(err, bottom)  # a zero estimate drawn at the axis bottom
        ax.scatter(cost, np.maximum(raw, bottom), facecolors="none", edgecolors="0.55", s=30, label="raw metric", zorder=2)
        for knob, (color, marker) in KNOB_STYLE.items():
            sel = [k for k, r in enumerate(rows) if r["knob"] == knob]
            if sel:
                ax.errorbar(cost[sel], shown[sel], yerr=[shown[sel] - np.maximum(err[sel] - sigma[sel], bottom),
                                                         sigma[sel]], fmt="none", ecolor=color, lw=0.8, zorder=3)
                ax.scatter(cost[sel], shown[sel], c=color, marker=marker, s=70 if knob == "defaults" else 40,
                           label=knob.replace("_", " "), zorder=4, edgecolors="k", linewidths=0.4)
        for k, r in enumerate(rows):
            ax.annotate(_value(r), (cost[k], shown[k]), fontsize=6, xytext=(3, 3), textcoords="offset points")
        front = tr.pareto_front(cost, err)
        ax.step(cost[front], shown[front], where="post", color="k", lw=1.0, ls="--", label="Pareto front", zorder=2)
        ax.axhspan(bottom, fl, color="0.85", zorder=0, label=f"chaos floor, 2 x {ref['starts']} reference starts")
        ax.axhline(TARGET, color="tab:red", lw=0.8, label="5 % target")
        if ref["paper_cpu_s"]:
            ax.axvline(ref["paper_cpu_s"], color="0.4", lw=0.8, ls=":", label="paper's settings")
            ax.axvline(ref["paper_cpu_s"] / 10, color="tab:green", lw=0.8, ls=":", label="10x faster")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(bottom, max(ax.get_ylim()[1], 1.5 * TARGET))  # the target always in view
        ax.set_title(title, fontsize=10)
        ax.set_ylabel("systematic error (fraction of the reference)")
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("CPU seconds per start (one run of the window)")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=7, fontsize=8)
    fig.suptitle(f"{case}: noise-corrected error (± σ, bootstrap) against cost, {ref['window_s']:g} s window, "
                 f"reference dt = {ref['dt']:g} s from {ref['starts']} starts; bottom edge: estimate 0", fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 0.97))
    files.save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path


def validate(out, jobs, meta, log=print):
    """The validation (module docstring) of the runs in OUT/runs; ``meta``: job name -> (case, knob,
    value) of the validation's cases. Writes OUT/validation.json and OUT/validation.md; returns the
    validation.json dict. The jobs of one setting (the study's and those that ran more of its starts,
    engines.studies.tradeoffs.more_starts_name) are read as one ensemble."""
    log = log or (lambda *a: None)
    parts = {}
    for j in jobs:
        parts.setdefault(tr.job_name(*meta[j.name]), []).append(os.path.join(out, "runs", j.name, "result.json"))
    results = {name: load(*paths) for name, paths in parts.items()}
    doc = validation(results, {name: meta[name] for name in parts}, log)
    files.write_json(os.path.join(out, "validation.json"), doc, indent=1, default=float)
    files.write_text(os.path.join(out, "validation.md"), validation_table(doc))
    return doc


def validation_table(doc):
    """Markdown: one line per scene (the fast setting), then one per candidate setting tried; per
    metric the noise-corrected estimate ± sigma in % (– where the scene has no such metric), the
    cost and the verdict."""
    n_blocks = max([int(m.rsplit("_", 1)[1]) for e in doc["scenes"].values() for m in e.get("metrics", {})
                    if m.startswith("block_mean_")], default=0)
    metrics = list(METRICS) + [f"block_mean_{b}" for b in range(1, n_blocks + 1)]
    heads = [LABELS[m] for m in METRICS] + [f"block {b} mean" for b in range(1, n_blocks + 1)]
    lines = ["| scene | starts (paper/fast) | fast dt [s] | CPU s/start paper / fast | speed-up | "
             + " | ".join(f"{h} %" for h in heads) + " | verdict |",
             "|" + "---|" * (6 + len(metrics))]
    rows = [(scene, e) for scene, e in doc["scenes"].items()]
    rows += [(f"{scene}, {name}", c) for scene, e in doc["scenes"].items() for name, c in e.get("candidates", {}).items()]
    for label, e in rows:
        if "metrics" not in e:
            lines.append(f"| {label} | " + " | ".join([""] * (4 + len(metrics))) + f" | {e['verdict']} |")
            continue
        cells = [f"{100 * e['metrics'][m]['systematic']:.1f} ± {100 * e['metrics'][m]['sigma']:.1f}"
                 if m in e["metrics"] else "–" for m in metrics]
        need = f" (n = {e['starts_needed']} would decide it)" if "starts_needed" in e else ""
        lines.append(f"| {label} | {e['starts']['paper']}/{e['starts']['fast']} | {e['dt_fast']:.3g} | "
                     f"{e['cpu_s']['paper']:.1f} / {e['cpu_s']['fast']:.2f} | {e['speedup']:.1f} | "
                     + " | ".join(cells) + f" | {e['verdict']}{need} |")
    return "\n".join(lines) + "\n"
