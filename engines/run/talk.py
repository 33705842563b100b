"""What the scene scripts say, at three levels: ``--quiet`` (errors and the end line only), the
default (also the notes, the start line, progress lines and figures) and ``--verbose`` (also
where the compiled kernels are cached and the provenance). Every such line goes through ``say``."""
QUIET, NORMAL, VERBOSE = 0, 1, 2
level = NORMAL


def set_level(quiet=False, verbose=False):
    """The level of this process from the --quiet and --verbose options."""
    global level
    level = QUIET if quiet else VERBOSE if verbose else NORMAL


def say(text, at=NORMAL):
    """Print ``text`` (flushed) when this process's level is ``at`` or louder."""
    if level >= at:
        print(text, flush=True)



UNITS = (("_N_per_m", "N/m", 1.0), ("_s", "ms", 1e3), ("_m", "mm", 1e3))  # a result's name's suffix: its unit
DETAIL = ("heave_rise_m", "bed_top_initial_m", "bed_top_max_m", "t_last_row_s", "porosity_last_row")  # not headline


def headline(results):
    """The headline numbers of a run's ``results`` (summary.json, nested dicts): {dotted name:
    value (NaN for None)}, without the details (DETAIL: the heave's definition, the bed's tops, the
    last row's time and porosity)."""
    from engines.studies.ensemble import flat_results
    return {k: v for k, v in flat_results(results).items() if k not in DETAIL}


def label(name):
    """(label, unit, factor) of a result's dotted name: the unit suffix of its last part shown as
    the unit (seconds in ms, metres in mm; none for a porosity), the block pressures' group left out."""
    label, unit, factor = name.removeprefix("peak_block_pressures."), "", 1.0
    for suffix, u, f in UNITS:
        if name.endswith(suffix):
            label, unit, factor = label[:-len(suffix)], u, f
            break
    return label.replace(".", " "), unit, factor


def quantity(name, value):
    """A result (``name``: its dotted path in summary.json's results) as "label value unit"; NaN
    (None in the file: e.g. a heave that did not happen) as "none"."""
    text, unit, factor = label(name)
    if value != value:
        return f"{text} none"
    return f"{text} {value * factor:.4g} {unit}".rstrip()


def result_lines(results):
    """The lines of a run's headline ``results`` (summary.json), one per number with its unit, a
    block's peak pressure and its time on one line ("U_block1 peak 221.9 N/m at 28.1 ms")."""
    flat, lines = headline(results), []
    for name, value in flat.items():
        if name.endswith(".t_s") and name[:-4] + ".U_max_N_per_m" in flat:
            continue  # said with its peak
        time = flat.get(name.removesuffix(".U_max_N_per_m") + ".t_s") if name.endswith(".U_max_N_per_m") else None
        if time is not None and value == value:
            lines.append(f"{label(name)[0].removesuffix(' U_max')} peak {value:.4g} N/m at {time * 1e3:.4g} ms")
        else:
            lines.append(quantity(name, value))
    return lines


def results_table(runs):
    """A text table of the headline results of ``runs`` ([(name, results)]), one row per run, a
    column per result (its unit in the header; "-" where a run has none)."""
    rows = [(name, headline(results)) for name, results in runs]
    keys = list(dict.fromkeys(k for _, h in rows for k in h))
    heads = [f"{label(k)[0]} [{label(k)[1]}]" if label(k)[1] else label(k)[0] for k in keys]
    cells = [[name] + [("-" if k not in h else "none" if h[k] != h[k] else f"{h[k] * label(k)[2]:.4g}") for k in keys]
             for name, h in rows]
    widths = [max(len(x) for x in col) for col in zip(["run"] + heads, *cells)]
    return "\n".join("  ".join(x.ljust(w) for x, w in zip(line, widths)).rstrip() for line in [["run"] + heads] + cells)


def interval_lines(statistics):
    """The lines of an ensemble's results (ensemble.json's "results": {dotted name: {"n", "mean",
    "ci95_low", "ci95_high", ...}}), the headline ones: "label mean unit (95 % interval low to high, n starts)"."""
    lines = []
    for name, st in statistics.items():
        if name in DETAIL:
            continue
        text, unit, f = label(name)
        mean, lo, hi = (st.get(k) for k in ("mean", "ci95_low", "ci95_high"))
        if mean is None or mean != mean:
            lines.append(f"{text} none")
            continue
        interval = f"95 % interval {lo * f:.4g} to {hi * f:.4g}" if lo is not None and lo == lo else "no interval"
        lines.append(f"{text} {mean * f:.4g} {unit} ({interval}, {st.get('n')} starts)".replace("  ", " "))
    return lines
