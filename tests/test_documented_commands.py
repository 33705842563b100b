"""Every documented command works: each `yade ...`, `yade-batch ...`, `python3 ...` and `make ...`
line of the code blocks (fenced or indented) of README.md and docs/*.md is run as written, but
short, by the rules of RULES (each a rewrite with its reason, or an exemption with its reason), and
the files it names exist afterwards. A command that no rule matches fails the test, so that a new
documented command is considered here.

The generic rewrites, applied to every command run (their reasons beside them):
- the command runs in a temporary folder of its page (commands of one page in order, as a reader
  follows them: a `--resume` finds the run above it), so that `out/...` is the test's, and the
  project's paths (yade_scripts/, docs/, ...) are made absolute;
- an optional `[...]` part is kept unless it holds a placeholder (an upper-case word such as FILE)
  or is one of alternatives `a | b` (the first kept when it holds none);
- `python3` is Debian's /usr/bin/python3 (the one YADE runs), PYTHONPATH the tree (as the Makefile);
- `make TARGET` runs with `-o deps` (the machine is set up: `make check` ran deps first),
  `OUT=<the page's folder>/out` and `SHORT=1` (the Makefile's short form of a study) where the
  target has one (MAKE_TARGETS; the others are exempt there with their reason).

The files a command names: the `out/...` paths of its command line and those its comment says it
writes (`-> out/x`, `into out/x`, `in out/x`); `{a,b}` and `<name>` in them are expanded/globbed.
Every tracked file of the tree is unchanged afterwards (no example overwrites one).
"""
import glob
import os
import re
import resource
import shlex
import signal
import subprocess
import time
import zlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import pytest

from engines import ROOT

pytestmark = pytest.mark.check

PAGES = ["README.md"] + sorted(os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "docs", "*.md")))
SHORT = "0.002"  # [s] the simulated time of a short run: 2,000 steps of the presets' dt
LATER = "0.004"  # [s] the later end a resume of a short run goes on to
LATEST = "0.006"  # [s] the end of a resume that names a later --duration
WORKERS = 2  # pages at a time (each page in a folder of its own; the machine has 2 cores)
TIMEOUT = 300  # [s] the longest one command may take
ENV = dict(os.environ, PYTHONPATH=ROOT, MPLBACKEND="Agg", OMP_NUM_THREADS="1")
COMMAND = re.compile(r"^(?:yade|yade-batch|python3|/usr/bin/python3|make|nohup|mkdir|\$[A-Z]+)\b")
FENCE = re.compile(r"^```[^\n]*\n(.*?)^```", re.M | re.S)
PLACEHOLDER = re.compile(r"\b[A-Z][A-Z0-9_]{2,}\b")  # FILE, PATH, HOST ... in an optional part
OPTIONAL = re.compile(r"\s\[([^\[\]]*)\]")


# --- reading the pages -------------------------------------------------------------------------

def code_blocks(text):
    """The fenced code blocks and the indented ones (4 spaces after a blank line) of Markdown ``text``."""
    blocks = FENCE.findall(text)
    lines, block = FENCE.sub("", text).split("\n"), None
    for prev, line in zip([""] + lines, lines):
        if block is None and line.startswith("    ") and not prev.strip():
            block = [line[4:]]
        elif block is not None and (line.startswith("    ") or not line.strip()):
            block.append(line[4:])
        elif block is not None:
            blocks.append("\n".join(block))
            block = None
    return blocks + (["\n".join(block)] if block else [])


def block_commands(block):
    """(command, comment) of each command line of a code block: continuation lines joined, shell
    variables of the block (NAME="...") substituted, a loop's body kept as written."""
    out, names, lines = [], {}, block.split("\n")
    i = 0
    while i < len(lines):
        line = lines[i]
        while line.rstrip().endswith("\\") and i + 1 < len(lines):
            i += 1
            line = line.rstrip()[:-1].rstrip() + " " + lines[i].strip()
        i += 1
        line = line.strip()
        m = re.match(r'^([A-Z]+)="([^"]*)"$', line)
        if m:
            names[m.group(1)] = m.group(2)
            continue
        for name, value in names.items():
            line = line.replace("$" + name, value)
        if COMMAND.match(line):
            command, _, comment = line.partition("  #")
            if command.startswith("python3 -c") or "python3 -c" in command:  # its own '#'s are code
                command, comment = line, ""
            out.append((command.strip(), comment.strip()))
    return out


def doc_commands():
    """{page: [(command, comment), ...]} in the pages' order."""
    found = {}
    for page in PAGES:
        with open(os.path.join(ROOT, page), encoding="utf-8") as f:
            found[page] = [c for b in code_blocks(f.read()) for c in block_commands(b)]
    return found


def test_the_reader_finds_commands_in_both_kinds_of_block():
    text = ("intro\n\n```\nyade -n -x a.py --out out/x \\\n    --vtk   # -> out/x/vtk/\nls y\n```\n\nprose\n\n"
            '    Q="yade -n -x b.py"\n    $Q --out DIR\n    make demo    # the demo\n\n  - item\n')
    cmds = [c for b in code_blocks(text) for c in block_commands(b)]
    assert cmds == [("yade -n -x a.py --out out/x --vtk", "-> out/x/vtk/"), ("yade -n -x b.py --out DIR", ""),
                    ("make demo", "the demo")]
    assert named_outputs("x --out out/a --json out/b.json", "-> out/c/{d.json,e.md} into out/<k>.png") == \
        ["out/a", "out/b.json", "out/c/d.json", "out/c/e.md", "out/*.png"]
    assert optional_parts("a [--duration 0.06] [--jobs 2 | --scheduler X] [--scheduler-file FILE]") == \
        "a --duration 0.06 --jobs 2"
    assert set_option("a --duration 0.06 --out x", "--duration", "0.002") == "a --duration 0.002 --out x"
    assert set_option("a --out x", "--starts", "2") == "a --out x --starts 2"


# --- the rules -----------------------------------------------------------------------------------

def set_option(cmd, name, value):
    """``cmd`` with option ``name`` given ``value`` (in place of its value, or appended)."""
    pattern = re.compile(rf"(\s{re.escape(name)})(?:\s+(?!-)\S+)?(?=\s|$)")
    return pattern.sub(lambda m: f"{m.group(1)} {value}".rstrip(), cmd, count=1) if pattern.search(cmd) \
        else f"{cmd} {name} {value}".rstrip()


def run_short(cmd):
    return set_option(cmd, "--duration", SHORT)


QS_TABLE = "case duration water.q_w\n1 %s 5e-4\n" % SHORT   # the example table's first line, short
BX_TABLE = ("description phi_e sigma3 n_discs max_strain strain_rate\n"
            "phi15_small 15 100 150 1.5 400\n")               # the --quick specimen of biaxial_study.py
JOBS = ('[{"name": "qs", "argv": ["yade", "-n", "-x", "%s/yade_scripts/quicksand.py", "--duration", "%s", '
        '"--out", "{out}"]}]\n' % (ROOT, SHORT))
MY_SCENE = 'extends = "quicksand_case1"\n[scene]\nname = "mine"\n[water]\nk1 = 150.0\n'
QUICK_BIAXIAL = "--n-discs 150 --max-strain 1.5 --strain-rate 400"


@dataclass
class Rule:
    """A documented command's treatment: ``pattern`` (a regular expression searched in the
    command), ``reason``; ``rewrite`` (the command -> the commands run, None: exempt), ``files``
    (created in the page's folder first: name -> text), ``outputs`` (more files it must write;
    {out}: its --out) and ``refuses`` (where the page leaves nothing for it: its last command must
    refuse in one line, exit status 2, and write nothing)."""
    pattern: str
    reason: str
    rewrite: object = None
    files: dict = field(default_factory=dict)
    outputs: tuple = ()
    refuses: bool = False


def exempt(pattern, reason):
    return Rule(pattern, reason)


RULES = [
    # the scene scripts: one run, one start, milliseconds
    Rule(r"^yade -n -x yade_scripts/(quicksand|liquefaction)\.py (?!.*--resume)(?!.*--starts)(?!.*--scene my_scene)",
         f"a run of {SHORT} s (--duration {SHORT}: the presets run 0.06-0.18 s)",
         lambda c: [run_short(c)]),
    Rule(r"^yade -n -x yade_scripts/quicksand\.py --scene my_scene\.toml",
         "my_scene.toml is the reader's own: here a scene extending a preset by its name, run short",
         lambda c: [run_short(c)], files={"my_scene.toml": MY_SCENE}),
    Rule(r"^yade -n -x yade_scripts/(quicksand|liquefaction)\.py .*--starts \S+",
         f"an ensemble of 2 starts of {SHORT} s (--starts 2: the statistics need two; 8 or 16 cost 4-8x)",
         lambda c: [run_short(set_option(c, "--starts", "2")).replace("$p", p) for p in
                    (["1e-9", "1e-8", "1e-7"] if "$p" in c else [""])],
         outputs=("{out}/ensemble.json",)),
    Rule(r"^yade -n -x yade_scripts/(quicksand|liquefaction)\.py --resume out/(qs1|qs2|liq1-8)\b",
         f"the run above it finished its short end: --duration {LATER} makes the resume continue it (a "
         f"--duration written: {LATEST}, later than a resume above it)",
         lambda c: [set_option(c, "--duration", LATEST if "--duration" in c else LATER)]),
    Rule(r"^yade -n -x yade_scripts/liquefaction\.py --resume out/liq1$",
         f"resumes out/liq1, which the page does not make: a short run of case 1 first, then on to {LATER} s",
         lambda c: [f"yade -n -x yade_scripts/liquefaction.py --case 1 --duration {SHORT} --out out/liq1",
                    set_option(c, "--duration", LATER)]),
    Rule(r"^mkdir -p out/[\w/.-]+$", "as written (a folder the next command needs)", lambda c: [c]),
    Rule(r"^yade-batch -j 2 (--log \S+ )?yade_scripts/quicksand_sweep\.table yade_scripts/quicksand\.py$",
         "the example table's first line, short (sweep.table in the page's folder): yade-batch writes its "
         "logs beside the table; tests/run/test_batch.py reads every line of the table",
         lambda c: [c.replace("yade_scripts/quicksand_sweep.table", "sweep.table")], files={"sweep.table": QS_TABLE},
         outputs=("out/batch/*/summary.json",)),
    Rule(r"^yade-batch -j 2 (--log \S+ )?yade_scripts/biaxial_sweep\.table yade_scripts/biaxial\.py$",
         "the biaxial table's first job at one σ3 on biaxial_study.py --quick's specimen (150 discs, 1.5 %)",
         lambda c: [c.replace("yade_scripts/biaxial_sweep.table", "biaxial.table")], files={"biaxial.table": BX_TABLE},
         outputs=("out/biaxial-batch/phi15_small/summary.json",)),
    Rule(r"^(/usr/bin/python3|yade -n -x) yade_scripts/sweep\.py --table yade_scripts/quicksand_sweep\.table "
         r"--script yade_scripts/quicksand\.py --out out/sweep$",
         "the example table's first line, short", lambda c: [c.replace("yade_scripts/quicksand_sweep.table", "sweep.table")],
         files={"sweep.table": QS_TABLE}, outputs=("out/sweep/sweep.json",)),
    Rule(r"^(/usr/bin/python3|yade -n -x) yade_scripts/sweep\.py --table yade_scripts/biaxial_sweep\.table",
         "the biaxial table's first job, short (as its yade-batch line)",
         lambda c: [c.replace("yade_scripts/biaxial_sweep.table", "biaxial.table")], files={"biaxial.table": BX_TABLE},
         outputs=("out/sweep/sweep.json",)),
    Rule(r"^/usr/bin/python3 yade_scripts/sweep\.py --jobs jobs\.json --out out/sweep --workers 2$",
         "jobs.json is the reader's own: here one short quick-sand job",
         lambda c: [c], files={"jobs.json": JOBS}, outputs=("out/sweep/qs/summary.json",)),
    exempt(r"yade_scripts/sweep\.py .*--scheduler-file out/sweep-dask/scheduler\.json",
           "needs the Dask scheduler and workers the lines before it start: tests/run/test_sweep_cluster.py "
           "(make check) runs this sweep on such a cluster"),
    Rule(r"^/usr/bin/python3 -c \"import json,glob; .*out/batch/\*",
         "reads the yade-batch jobs above it, as written", lambda c: [c]),
    Rule(r"^/usr/bin/python3 -m postproc\.ensemble --compare out/qs-p1e-9 out/qs-p1e-8 out/qs-p1e-7",
         f"the short ensembles above it: the windows within their {SHORT} s (--window 0.001 0.002)",
         lambda c: [re.sub(r"--window \S+ \S+", "--window 0.001 0.002", c)]),
    Rule(r"^yade -n -x yade_scripts/deposit\.py --scene quicksand_case1$",
         "the deposit as written (the 96-disc preset, seconds)", lambda c: [c],
         outputs=("out/packings/quicksand-case1.csv",)),  # the file is named by the scene's [scene] name
    Rule(r"^/usr/bin/python3 -m postproc\.vtk out/quicksand-case1$",
         "the demo's folder (make demo) first, a short run of case 1 into it",
         lambda c: [f"yade -n -x yade_scripts/quicksand.py --case 1 --duration {SHORT} --out out/quicksand-case1", c],
         outputs=("out/quicksand-case1/vtk",)),
    Rule(r"^/usr/bin/python3 -m postproc\.liquefaction --study out/liquefaction$",
         "the study of the short `make liquefaction` above it", lambda c: [c]),
    Rule(r"^/usr/bin/python3 yade_scripts/liquefaction_drainage\.py --json out/liquefaction/drainage\.json$",
         "as written (seconds: the drainage of the still box)", lambda c: [c]),
    # seed 003
    Rule(r"^yade -n -x yade_scripts/biaxial\.py --phi-e 15 --sigma3 100,200,300 --out out/bx15$",
         f"biaxial_study.py --quick's specimen ({QUICK_BIAXIAL}); the full test takes minutes",
         lambda c: [f"{c} {QUICK_BIAXIAL}"], outputs=("out/bx15/summary.json", "out/bx15/packing_sigma3_200.csv")),
    Rule(r"^yade -n -x yade_scripts/biaxial_stability\.py --block DIR/packing_sigma3_200 --out DIR2$",
         "DIR is a biaxial run's folder: out/bx15 of the judged command above it; DIR2 out/bx15-dt",
         lambda c: [c.replace("DIR2", "out/bx15-dt").replace("DIR/", "out/bx15/")], outputs=("out/bx15-dt",)),
    Rule(r"^/usr/bin/python3 yade_scripts/calibrate\.py .*--fit docs/biaxial/judged_fit\.json --out out/calibrate$",
         "--no-verify: the verification is 9 biaxial tests of 1,000 discs (minutes each); φe and kn as written",
         lambda c: [c + " --no-verify"], outputs=("out/calibrate/calibration.json",)),
    exempt(r"^/usr/bin/python3 yade_scripts/biaxial_study\.py --parts (judged|hypotheses) --workers 1 --out",
           "a study of 30-60 biaxial tests (hours); its parts are tested on synthetic runs "
           "(tests/studies/test_biaxial_judged.py, tests/seeds) and biaxial.py runs above"),
    Rule(r"^/usr/bin/python3 yade_scripts/biaxial_study\.py --out out/biaxial_hypotheses --parts hypotheses --analyse-only$",
         "as written, where the page ran no hypotheses job (the study is exempt above): it refuses in one line",
         lambda c: [c], refuses=True),
    Rule(r"^/usr/bin/python3 yade_scripts/resistance\.py --out out/resistance --analyse-only$",
         "as written, where the page ran no study (make resistance is exempt: hours; tests/run/test_resistance.py "
         "runs it short): it refuses in one line", lambda c: [c], refuses=True),
    exempt(r"^nohup nice -n 10 /usr/bin/python3 yade_scripts/biaxial_study\.py",
           "the same study in the background (hours); its foreground line is in BIAXIAL.md's Commands"),
    # companions, cross-check, benchmarks, studies
    Rule(r"^/usr/bin/python3 yade_scripts/particle_potential\.py --out out/particle-potential$",
         "α = 1 only (--alpha 1): α = 2 is the same code with another exponent; both take 47 s (2026-12-05)",
         lambda c: [c + " --alpha 1"]),
    Rule(r"^/usr/bin/python3 yade_scripts/sand_layer\.py --realisations 25 --seed 0 --out out/sand-layer$",
         "as written (seconds)", lambda c: [c]),
    exempt(r"^yade -n -x yade_scripts/crosscheck\.py --out out/crosscheck$",
           "the whole cross-check (14 cases, minutes): make test's first half runs it"),
    exempt(r"^yade -n -x yade_scripts/crosscheck\.py --out out/cc --only seismic_box$",
           "one case of the cross-check (40 CPU s): make test runs the script with every case, this one included"),
    exempt(r"^yade -n -x benchmarks/", "a cost measurement: its length and an idle machine are its point "
           "(make bench, docs/PERFORMANCE.md)"),
    exempt(r"^/usr/bin/python3 benchmarks/suite_times\.py ", "times make deps and make test in fresh clones: "
           "minutes of an idle machine, and make test itself runs around this test"),
    exempt(r"^/usr/bin/python3 yade_scripts/tradeoffs\.py study ",
           "the trade study's runs (tens of CPU minutes through the sweep runner); make tradeoffs SHORT=1 runs "
           "its short form (MAKE_TARGETS)"),
    exempt(r"^yade -n -j 1 -x yade_scripts/tradeoffs\.py speed --points .*\.\.\.",
           "`...` stands for the reader's settings; tests/studies test the speed measurement's numbers"),
    exempt(r"^make liquefaction LIQ_", "the target of the line above it with other cases or starts (variables "
           "only): that line runs it short, and SHORT=1 sets these variables itself"),
    Rule(r"^make \S+", "a Makefile target: MAKE_TARGETS says how (short, or exempt and why)", "make"),
]

# Every target of the Makefile: None (runs with SHORT=1, with the files it must write) or the reason
# it is exempt.
SHORT_TARGETS = {
    "ground": ("out/ground/run/summary.json",),
    "liquefaction": ("out/liquefaction/summary.json", "out/liquefaction/case1/summary.json"),
    "stability": ("out/stability/map.json",),
    "packings": ("out/packings/quicksand-case1.csv", "out/packings/quicksand-case1-flat.csv",
                 "out/packings/liquefaction-case1.csv"),
    "biaxial": ("out/biaxial/study.json", "out/biaxial/fit.json", "out/biaxial/table.md"),
}
EXEMPT_TARGETS = {
    "deps": "installs with apt-get (root); make check ran it",
    "ext": "make deps builds it; tests/yade test the bridge",
    "install": "make deps runs it; tests/run/test_install.py checks it",
    "warmup": "make deps runs it (6 minutes on a fresh key); tests/run/test_warmup.py",
    "demo": "make check depends on deps; the demo's command line runs in README's and OUTPUTS' rules",
    "demo-numbers": "rewrites the tracked docs/demo/demo.json and README's numbers: its purpose",
    "test": "the suite itself (and the whole cross-check)",
    "check": "the suite of this test itself",
    "test-fast": "a part of make test",
    "precision": "the reference in three precisions (minutes); tests/reference",
    "mutants": "mutation testing, hours",
    "liquefaction-bands": "56 seismic runs (about 20 CPU minutes), rewrites the tracked docs/liquefaction/bands.json; tests/postproc/test_liquefaction_bands.py tests the table and tests/studies its verdicts",
    "resistance": "SHORT=1 runs in tests/run/test_resistance.py (twice: it checks the resume); the full curve is 80 runs, about 2 CPU hours",
    "resistance-ground": "one run of 10,000 discs for 0.6 s (about an hour of one core) and make resistance's runs; "
                         "tests/run/test_resistance.py tests its reading and refusals",
    "remesh-transfer": "the transfer study, 64 runs (about an hour of CPU), rewrites the tracked docs/engine/remesh_transfer.json; tests/studies/test_remesh_transfer_rule.py tests its rule",
    "mutants-kernels": "mutation testing of the numba kernels (CPU hours); tests/test_kernel_mutants.py tests the driver",
    "readings": "rewrites the tracked docs/readings/quicksand_ru.json, quicksand_ru_mu0.json and quicksand_ru_submerged.json "
                "from 8 starts each; tests/postproc/test_readings.py, and tests/run/test_quicksand_reading.py judges a fresh ensemble",
    "bench": "cost measurements (tens of minutes, an idle machine)",
    "bench-seismic": "a cost measurement", "bench-scaling": "a cost measurement",
    "bench-ground": "a cost measurement", "bench-before-after": "a cost measurement of an older checkout",
    "clean": "removes out/",
    "reconstruction": "no short form: its jobs are the study's ensembles of 8 starts over 0.18 s per variant "
                      "(55 CPU minutes, engines/run/reconstruction.py), run by the liquefaction script, which runs "
                      "short above; tests/run/test_reconstruction.py tests its jobs and analysis",
    "tradeoffs": "no short form: each knob's error is against a reference over the study's whole window from "
                 "5-20 starts (60 CPU minutes); tests/studies test its analysis, tradeoffs.py study --analyse-only's "
                 "refusal runs below",
    "validation": "no short form: the validation is whole runs of every preset by its definition (30 CPU minutes, "
                  "more for the scenes it gives more starts)",
}
MAKE_ENV = {"SHORT": "1"}


def makefile_targets():
    with open(os.path.join(ROOT, "Makefile"), encoding="utf-8") as f:
        phony = re.search(r"^\.PHONY:(.*)$", f.read(), re.M).group(1)
    return phony.split()


def test_every_makefile_target_is_short_or_exempt_with_a_reason():
    """A new target must be considered: short (SHORT=1) with the files it writes, or exempt and why."""
    targets = makefile_targets()
    assert sorted(targets) == sorted(set(SHORT_TARGETS) | set(EXEMPT_TARGETS))
    assert not set(SHORT_TARGETS) & set(EXEMPT_TARGETS) and all(EXEMPT_TARGETS.values())


def optional_parts(cmd):
    """``cmd`` with each optional ``[...]`` part kept (its first alternative) unless it holds a placeholder."""
    def keep(m):
        first = m.group(1).split("|")[0].strip()
        return "" if PLACEHOLDER.search(first) else " " + first
    return OPTIONAL.sub(keep, cmd)


def absolute(cmd):
    """The project's paths of ``cmd`` made absolute (the command runs in a temporary folder)."""
    return re.sub(r"(?<![\w/.\-])(yade_scripts|benchmarks|docs|engines|postproc|packing)/", ROOT + r"/\1/", cmd)


def named_outputs(cmd, comment):
    """The out/ paths ``cmd`` and its comment (after ->, into, in) name, as glob patterns."""
    words = re.findall(r"(?<![\w/])out/[^\s'\"]+", cmd)
    words += re.findall(r"(?:->|\binto|\bin)\s+(out/(?:\{[^}]*\}|[^\s,;(){])+)", comment)
    paths = []
    for w in words:
        w = re.sub(r"<[^>]*>|@", "*", w.rstrip(".,;:)`"))
        m = re.search(r"\{([^}]*)\}", w)
        paths += [w[:m.start()] + x + w[m.end():] for x in m.group(1).split(",")] if m else [w]
    return paths


def rule_of(cmd):
    """The first rule whose pattern is found in ``cmd`` with its optional parts resolved."""
    matched = [r for r in RULES if re.search(r.pattern, optional_parts(cmd))]
    return matched[0] if matched else None


def make_commands(cmd):
    """The make line run short: -o deps, OUT in the page's folder, SHORT=1; None when exempt."""
    words = shlex.split(cmd)
    target = words[1]
    if target in EXEMPT_TARGETS:
        return None, EXEMPT_TARGETS[target]
    assert target in SHORT_TARGETS, f"`{cmd}`: make {target} is in neither SHORT_TARGETS nor EXEMPT_TARGETS"
    extra = " ".join(shlex.quote(w) for w in words[2:])
    return [f"make -s --no-print-directory -C {ROOT} -o deps {target} {extra} SHORT=1 OUT=\"$(pwd)/out\""], SHORT_TARGETS[target]


def plan(page, commands):
    """[(documented command, [commands run] or None, reason, files first, outputs, refuses)] of a page."""
    steps = []
    for cmd, comment in commands:
        rule = rule_of(cmd)
        assert rule, f"{page}: `{cmd}` matches no rule of tests/test_documented_commands.py: add one (run short or exempt)"
        if rule.rewrite == "make":
            run, outputs = make_commands(cmd)
            steps.append((cmd, run, rule.reason, {}, tuple(outputs) if run else (), False))
            continue
        if rule.rewrite is None:
            steps.append((cmd, None, rule.reason, {}, (), False))
            continue
        unique = "out/dir-%08x" % zlib.crc32(cmd.encode())  # a folder for --out DIR
        written = re.sub(r"--out DIR\b", f"--out {unique}", optional_parts(cmd))
        run = [absolute(c) for c in rule.rewrite(written)]
        outs = [m.group(1) for c in rule.rewrite(written) for m in [re.search(r"--out (\S+)", c)] if m]
        outputs = [p for c in rule.rewrite(written) for p in named_outputs(c, comment)] + \
            [p.format(out=o) for p in rule.outputs for o in (outs if "{out}" in p else [None])]
        steps.append((cmd, run, rule.reason, rule.files, () if rule.refuses else tuple(outputs), rule.refuses))
    return steps


def test_every_documented_command_has_a_rule():
    """Cheap: every command of the pages is matched by a rule (the runs below need make check)."""
    unmatched = [f"{page}: `{c}`" for page, commands in doc_commands().items() for c, _ in commands if not rule_of(c)]
    assert not unmatched, "commands that match no rule (add one: run short, or exempt):\n" + "\n".join(unmatched)


def tracked_files():
    names = subprocess.run(["git", "-C", ROOT, "ls-files", "-z"], capture_output=True, text=True, check=True).stdout
    return {n: os.stat(os.path.join(ROOT, n)).st_mtime_ns for n in names.split("\0") if n and os.path.exists(os.path.join(ROOT, n))}


def run_page(page, steps, folder):
    """Run a page's steps in order in ``folder``; [(command, problem)], and the wall seconds of each run."""
    os.makedirs(folder)
    problems, walls = [], []
    for cmd, run, reason, files, outputs, refuses in steps:
        if run is None:
            continue
        for name, text in files.items():
            with open(os.path.join(folder, name), "w", encoding="utf-8") as f:
                f.write(text)
        for c in run:
            t0 = time.monotonic()
            proc = subprocess.Popen(c, shell=True, cwd=folder, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    text=True, start_new_session=True)
            try:
                proc.stdout, proc.stderr = proc.communicate(timeout=TIMEOUT)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)  # the command's whole process group (yade-batch's jobs too)
                proc.communicate()
                problems.append((cmd, f"`{c}` ran over {TIMEOUT} s"))
                break
            walls.append((c, time.monotonic() - t0))
            if refuses and c == run[-1]:
                if proc.returncode != 2 or len(proc.stderr.strip().splitlines()) != 1:
                    problems.append((cmd, f"`{c}` should refuse in one line (exit 2), gave exit {proc.returncode}: "
                                          f"{proc.stderr.strip()[-600:]}"))
            elif proc.returncode != 0:
                problems.append((cmd, f"`{c}` exit {proc.returncode}: {(proc.stderr or proc.stdout).strip()[-600:]}"))
                break
        else:
            missing = [p for p in outputs if not glob.glob(os.path.join(folder, p)) + glob.glob(os.path.join(folder, p + ".*"))]
            if missing:
                problems.append((cmd, f"wrote none of {missing}"))
    return problems, walls


def test_documented_commands_run(tmp_path):
    """Each page's commands, in order, in a folder of the page (WORKERS pages at a time)."""
    before = tracked_files()
    pages = {page: plan(page, cmds) for page, cmds in doc_commands().items()}
    pages = {p: s for p, s in sorted(pages.items(), key=lambda ps: -sum(len(r or ()) for _, r, *_ in ps[1]))
             if any(run for _, run, *_ in s)}  # the longest pages first
    with ThreadPoolExecutor(WORKERS) as pool:
        results = dict(zip(pages, pool.map(lambda p: run_page(p, pages[p], str(tmp_path / p.replace("/", "_"))), pages)))
    problems = [f"{page}: `{cmd}`: {what}" for page, (probs, _) in results.items() for cmd, what in probs]
    slowest = sorted((w, c) for _, walls in results.values() for c, w in walls)[-5:]
    print(f"\n{sum(len(w) for _, w in results.values())} commands run, CPU of the processes "
          f"{resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime:.0f} s; slowest:\n" +
          "\n".join(f"{w:.0f} s {c}" for w, c in slowest))
    changed = sorted(n for n, t in tracked_files().items() if before.get(n) != t)
    assert not problems, "\n".join(problems)
    assert not changed, f"documented commands changed tracked files: {changed}"


def test_short_study_targets_not_in_the_docs_run(tmp_path):
    """The SHORT targets that no page's code block names run here (the others run with their page)."""
    named = {shlex.split(c)[1] for cmds in doc_commands().values() for c, _ in cmds if c.startswith("make ")}
    steps = [(f"make {t}", make_commands(f"make {t}")[0], "SHORT=1", {}, SHORT_TARGETS[t], False)
             for t in SHORT_TARGETS if t not in named]
    problems, _ = run_page("Makefile", steps, str(tmp_path / "make"))
    assert not problems, problems


SCRIPTS = sorted(glob.glob(os.path.join(ROOT, "yade_scripts", "*.py")))
POSTPROC = sorted(os.path.basename(p)[:-3] for p in glob.glob(os.path.join(ROOT, "postproc", "*.py"))
                  if "__main__" in open(p, encoding="utf-8").read())


@pytest.mark.parametrize("argv", [[s] for s in SCRIPTS if not s.endswith("__init__.py")]
                         + [[os.path.join(ROOT, "yade_scripts", "tradeoffs.py"), c] for c in ("run", "study", "speed")]
                         + [["-m", f"postproc.{m}"] for m in POSTPROC], ids=lambda a: " ".join(os.path.basename(w) for w in a))
def test_help_everywhere(argv):
    """`--help` of every script and command line of postproc prints its usage and exits 0 (under
    Debian's python3, which imports YADE as `yade -n -x` does; the scripts' options are the same)."""
    proc = subprocess.run(["/usr/bin/python3", *argv, "--help"], cwd=ROOT, env=ENV, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr[-800:]
    assert "usage" in proc.stdout.lower() or "--out" in proc.stdout, proc.stdout[:400]


EMPTY_INPUTS = [
    ["-m", "postproc.liquefaction", "--study", "{empty}"],
    ["-m", "postproc.plots", "{empty}"],
    ["-m", "postproc.vtk", "{empty}"],
    ["-m", "postproc.ensemble", "{empty}"],
    ["yade_scripts/biaxial_study.py", "--out", "{empty}", "--analyse-only"],
    ["yade_scripts/tradeoffs.py", "study", "--out", "{empty}", "--analyse-only"],
    ["yade_scripts/liquefaction_reconstruction.py", "--out", "{empty}/study", "--baseline", "{empty}", "--analyse-only"],
    ["yade_scripts/stability.py", "--out", "{empty}", "--plot-only"],
    ["yade_scripts/resistance.py", "--out", "{empty}", "--analyse-only"],
]


@pytest.mark.parametrize("argv", EMPTY_INPUTS, ids=lambda a: " ".join(a[:2]))
def test_empty_inputs_are_refused_in_one_line(tmp_path, argv):
    """An analysis of an empty folder refuses in one line (exit 2) and writes nothing."""
    empty = tmp_path / "empty"
    empty.mkdir()
    proc = subprocess.run(["/usr/bin/python3", *[w.format(empty=empty) for w in argv]], cwd=ROOT, env=ENV,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr[-800:]
    assert not os.listdir(empty)
