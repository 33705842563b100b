"""The warm-up of ``make deps``: every numba kernel compiled once, into the keyed cache folder
(engines.compiled.cache), with the argument types the presets and the engine pass it, so that a
first ``make demo`` steps within seconds.

Each of RUNS is a short run of a script a user types (a few rebuilds' worth of steps), in its own
``yade -n -x`` process in a temporary folder: the paper's law, YADE's law, flat walls, the seismic
box (side-wall ties and the cosine base motion; the El Centro record), a fast preset (dt = "auto",
water sub-cycling) and the WaterEngine in the scripts of yade_scripts/examples/. The kernels those
processes compile land in the cache folder this process sets (NUMBA_CACHE_DIR, passed on), so the
next run of the same code loads them instead of compiling. No YADE is imported here.
"""
import os
import subprocess
import tempfile
import time

from engines import ROOT, files
from engines.compiled import cache

STEPS = "0.0015"  # [s] at dt = 1e-6 s: 1,500 steps, a pore rebuild (every 1,000 steps) included
QS, LIQ, EX = "yade_scripts/quicksand.py", "yade_scripts/liquefaction.py", "yade_scripts/examples/"
# (what it warms, script, arguments); "{out}" is the run's folder, "{root}" the project's
RUNS = (
    ("quick sand, the paper's law", QS, ["--case", "1", "--duration", STEPS, "--out", "{out}"]),
    ("quick sand, YADE's law", QS, ["--case", "1", "--set", 'contact.law="yade"', "--set", 'contact.spring="a"',
                                    "--duration", STEPS, "--out", "{out}"]),
    ("quick sand, flat walls", QS, ["--scene", "{root}/yade_scripts/scenes/quicksand_case1_flat.toml", "--duration", STEPS,
                                    "--out", "{out}"]),
    ("seismic box, side-wall ties and base motion", LIQ, ["--case", "1", "--duration", STEPS, "--out", "{out}"]),
    ("seismic box, the El Centro record", LIQ, ["--case", "6", "--duration", STEPS, "--out", "{out}"]),
    ("seismic box, the fast numerics", LIQ, ["--scene", "{root}/yade_scripts/scenes/liquefaction_case2_fast.toml",
                                             "--duration", "0.002", "--out", "{out}"]),
    ("WaterEngine, ViscElMat column", EX + "viscel_column.py", ["--steps", "200"]),
    ("WaterEngine, FrictMat box", EX + "frictmat_box.py", ["--steps", "200"]),
    ("WaterEngine, makeCloud discs", EX + "makecloud_discs.py", ["--steps", "200"]),
    ("WaterEngine, aabbWalls box (flat walls)", EX + "aabb_box.py", ["--steps", "200"]),
)


def command(script, args, out):
    """The command line of one warm-up run writing into ``out``."""
    return ["yade", "-n", "-x", os.path.join(ROOT, script)] + [a.replace("{out}", out).replace("{root}", ROOT) for a in args]


STAMP = "warmed-up"  # the file a complete warm-up leaves in the keyed cache folder


def warm(runs=RUNS, say=print, again=False):
    """Run ``runs`` one after the other (each line said with ``say``), unless the keyed cache folder
    holds the STAMP of a complete warm-up (``again``: run them anyway); returns 0, or 1 after the
    first that fails (its output's last lines said)."""
    folder = cache.use()
    stamp = os.path.join(folder, STAMP) if folder else None
    if stamp and os.path.exists(stamp) and not again:
        say(f"warm-up: the numba kernels of this version of the code are compiled already ({folder})")
        return 0
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""), MPLBACKEND="Agg")
    say(f"warm-up: the numba kernels into {folder} ({len(runs)} short runs; the first compile takes about "
        f"{cache.COMPILE_SECONDS} s)" if cache.fresh else f"warm-up: the numba kernels in {folder}, "
                                                          f"{len(runs)} short runs")
    t_all = time.time()
    with tempfile.TemporaryDirectory(prefix="pore-dem-warmup-") as tmp:
        for i, (what, script, args) in enumerate(runs, 1):
            t0 = time.time()
            out = os.path.join(tmp, str(i))
            done = subprocess.run(command(script, args, out), cwd=tmp, env=env, stdin=subprocess.DEVNULL,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            if done.returncode != 0:
                tail = "\n    ".join(done.stdout.strip().splitlines()[-8:])
                say(f"warm-up {i}/{len(runs)}: {what}: failed (exit status {done.returncode}):\n    {tail}")
                return 1
            say(f"warm-up {i}/{len(runs)}: {what} ({time.time() - t0:.0f} s)")
    if stamp:
        files.write_text(stamp, f"{len(runs)} runs, {time.time() - t_all:.0f} s, {time.strftime('%Y-%m-%dT%H:%M:%S')}\n")
    say(f"warm-up done in {time.time() - t_all:.0f} s")
    return 0
