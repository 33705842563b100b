# Two entry points for a fresh Debian 12 machine: `make demo` and `make test`.
# Everything runs under Debian's Python (/usr/bin/python3), the interpreter YADE uses.
PY      := /usr/bin/python3
YADE    := yade
OUT     ?= out
DEBS    := yade python3-pytest python3-numpy python3-scipy python3-matplotlib python3-numba python3-vtk9 gcc g++ libc6-dev \
           python3-distributed python3-venv python3-pip python3-setuptools
EXT_SO  := engines/yade/yadebulk/_yadebulk.so
# SHORT=1: a study target's short form (one case, one start, SHORT_S of simulated time), which
# `make check` runs (tests/test_documented_commands.py, where the targets without one are listed
# with the reason); its numbers mean nothing. Use it with OUT=<a scratch folder>.
SHORT_S := 0.002
SHORT_RUN = $(if $(SHORT),--duration $(SHORT_S))
export PYTHONPATH := $(CURDIR)
export MPLBACKEND := Agg

.PHONY: deps ext install warmup demo demo-numbers readings test check test-fast precision bench bench-seismic bench-scaling bench-ground bench-before-after ground packings biaxial liquefaction reconstruction tradeoffs validation stability remesh-transfer mutants mutants-kernels resistance resistance-ground liquefaction-bands clean

# Install what is missing (needs root; apt-get update first as Debian requires).
deps:
	@missing=""; for p in $(DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y $$missing; \
	fi
	@$(MAKE) --no-print-directory ext || echo "warning: engines/yade/yadebulk not built: YADE I/O falls back to per-body calls"
	@$(MAKE) --no-print-directory install
	@$(MAKE) --no-print-directory warmup || echo "warning: the warm-up failed: a first run compiles the kernels it needs (about a minute)"

# numba's kernels compiled once per version of the code (engines/run/warmup.py: short runs of the
# presets and the examples; skipped when done for this code), so that a first run steps at once.
warmup:
	@$(PY) yade_scripts/warmup.py

# The project for Debian's python3 (the interpreter `yade` runs), editable: a script of your own
# anywhere imports engines, packing and postproc without PYTHONPATH (the last checkout installed wins).
install:
	@cd / && env -u PYTHONPATH $(PY) -c "import engines, os, sys; sys.exit(os.path.dirname(engines.ROOT + '/') != '$(CURDIR)')" 2>/dev/null || \
	  { echo "installing the project for $(PY) (editable, $(CURDIR))"; \
	    $(PY) -m pip install -q --no-build-isolation --no-deps --break-system-packages --root-user-action=ignore -e $(CURDIR); }

# The bulk-I/O bridge to YADE (engines/yade/yadebulk: C and a little C++, no YADE headers, seconds to build).
ext: $(EXT_SO)

$(EXT_SO): engines/yade/yadebulk/yadebulk.c engines/yade/yadebulk/steps.cpp
	g++ -O2 -fPIC -shared -Wall -Wextra -o $@ -x c engines/yade/yadebulk/yadebulk.c -x c++ engines/yade/yadebulk/steps.cpp -ldl

# The main job: Tarumi & Hakuno quick sand, case 1, with its figures (a second demo replaces the first).
demo: deps
	$(YADE) -n -x yade_scripts/quicksand.py --case 1 --overwrite --out $(OUT)/quicksand-case1

# The demo's numbers quoted in README.md and docs/OUTPUTS.md: the demo timed and 8 perturbed starts of
# it (a few minutes) -> docs/demo/demo.json and the paragraphs between the demo-numbers marks.
demo-numbers: deps
	$(PY) yade_scripts/demo_numbers.py --out $(OUT)/demo-numbers

# The effective-stress reading judged on the quick sand (docs/READINGS.md E8): the bottom band's r_u at
# the heave's onset and at the surface's heave from 8 perturbed starts of case 1, again with every
# contact frictionless, and on the bed settled in its water (about two minutes)
# -> docs/readings/quicksand_ru.json, quicksand_ru_mu0.json, quicksand_ru_submerged.json.
readings: deps
	$(YADE) -n -x yade_scripts/quicksand.py --case 1 --starts 8 --quiet --overwrite --out $(OUT)/readings-quicksand
	$(PY) -m postproc.readings $(OUT)/readings-quicksand docs/readings/quicksand_ru.json
	$(YADE) -n -x yade_scripts/quicksand.py --case 1 --starts 8 --quiet --overwrite --set contact.mu=0 \
	   --out $(OUT)/readings-quicksand-mu0
	$(PY) -m postproc.readings $(OUT)/readings-quicksand-mu0 docs/readings/quicksand_ru_mu0.json
	$(YADE) -n -x yade_scripts/quicksand.py --scene quicksand_case1_submerged --starts 8 --quiet --overwrite \
	   --out $(OUT)/readings-quicksand-submerged
	$(PY) -m postproc.readings $(OUT)/readings-quicksand-submerged docs/readings/quicksand_ru_submerged.json

# The YADE <-> reference cross-check (exits non-zero on a failed case), then the tests but the
# batteries of `make check` (YADEBULK_REQUIRED: a missing or failing bulk-I/O bridge fails its tests
# instead of skipping).
test: deps
	$(YADE) -n -x yade_scripts/crosscheck.py --out $(OUT)/crosscheck
	YADEBULK_REQUIRED=1 $(PY) -m pytest -q -m "not check" tests

# The batteries that start YADE processes or send real signals (tests marked `check`: stops at chosen
# moments, two runs on one folder, a full disk, YADE's listeners; docs/RELIABILITY.md); at most 30 min.
check: deps
	YADEBULK_REQUIRED=1 $(PY) -m pytest -q -m check tests

# The NumPy core alone (tests of engines/model, engines/compiled, engines/reference, packing/ and the
# layering of the tree): no YADE needed, about 50 CPU s with a warm numba cache (README). Run `make deps` once first.
test-fast:
	$(PY) -m pytest -q -m "not check" tests/files tests/model tests/compiled tests/reference tests/packing tests/test_layers.py

# The reference in float32, float64 and longdouble on the quick-sand column (docs/CROSSCHECK.md):
# $(OUT)/precision/precision.json; exits 1 when a precision misses its bound (PRECISION_BOUNDS).
precision: deps
	$(YADE) -n -x yade_scripts/crosscheck.py --precision --out $(OUT)/precision

# Mutation testing of the NumPy modules (mutmut in a venv over Debian's Python; about 6,700 mutants, a couple of hours
# on a shared machine): out/mutants/summary.json, survivors in out/mutants/survivors.txt. Not part of `make test`.
# Continue an interrupted run with `$(MUTANT_VENV)/bin/python tests/mutants.py --again [--only engines/X.py ...]`.
MUTANT_VENV := $(OUT)/venv-mutants
$(MUTANT_VENV)/bin/mutmut:
	$(PY) -m venv --system-site-packages $(MUTANT_VENV)
	$(MUTANT_VENV)/bin/pip install -q "mutmut==3.8.1"

mutants: deps $(MUTANT_VENV)/bin/mutmut
	$(MUTANT_VENV)/bin/python tests/mutants.py --out $(OUT)/mutants

# Mutation testing of the numba kernels (mutmut skips decorated functions): a seeded sample of N mutants of
# the @jit bodies of engines/compiled, each killed by tests/compiled + the tests naming it, then the cross-check,
# with a fresh numba cache each (minutes of CPU per mutant): $(OUT)/mutants-kernels/summary.json, survivors.txt.
# Resumable: the same command skips the mutants done. JOBS mutants at once (a work copy each). Not part of `make test`.
N    ?= 200
SEED ?= 1
JOBS ?= 1
mutants-kernels: deps
	$(PY) tests/kernel_mutants.py --n $(N) --seed $(SEED) --jobs $(JOBS) --out $(OUT)/mutants-kernels

# Cost studies (tens of minutes): pore core sizes, our engines against YADE alone at 240-10,000
# bodies, water sub-cycling; the seismic-size scene at the paper's settings (180,000 steps).
bench: deps
	$(YADE) -n -x benchmarks/pores.py --json $(OUT)/bench-pores.json
	$(YADE) -n -x benchmarks/rebuild.py --json $(OUT)/bench-rebuild.json
	$(YADE) -n -x benchmarks/coupling.py --json $(OUT)/bench-coupling.json
	$(YADE) -n -x benchmarks/water_interval.py --json $(OUT)/bench-water-interval.json
	$(YADE) -n -x benchmarks/seismic_case.py --json $(OUT)/bench-seismic.json

# The pore core from 1,000 to 100,000 discs (water step, rebuild, YADE's step, memory; docs/PERFORMANCE.md).
bench-scaling: deps
	$(YADE) -n -x benchmarks/pores.py --sizes 1000 3000 10000 30000 100000 --json $(OUT)/bench-scaling.json

bench-seismic: deps
	$(YADE) -n -x benchmarks/seismic_case.py --json $(OUT)/bench-seismic.json

# The paper's statement "full liquefaction (zero effective stress) was not reached in 2D" measured
# (docs/LIQUEFACTION.md, "Effective stress by band"): cases 1-7 (the fast preset where validated), 8
# perturbed starts each, one at a time, then min p'/p'_0 and max r_u per band with their 95 %
# intervals -> docs/liquefaction/bands.json and the page's table (about 20 CPU minutes).
liquefaction-bands: deps
	@for n in 1 2 3 4 5 6 7; do $(LIQ_RUN) $(LIQ_SCENE) --starts 8 --jobs 1 --quiet --overwrite \
	   --out $(OUT)/liq-bands/case$$n || exit 1; done
	$(PY) -m postproc.liquefaction_bands $(OUT)/liq-bands docs/liquefaction/bands.json

# The 10,000-disc wet ground (yade_scripts/scenes/ground_10000.toml): our step against YADE alone on its discs.
bench-ground: deps
	$(YADE) -n -x benchmarks/ground.py --json $(OUT)/bench-ground.json

# An older engine (OLD, by default commit 26fe280, one Python engine; checked out
# under $(OUT)) and today's, on the seismic box, in turns on this machine: the speed-up (a few minutes).
OLD ?= 26fe280
OLD_TREE := $(OUT)/tree-$(OLD)
bench-before-after: deps
	test -d $(OLD_TREE) || git worktree add --detach $(OLD_TREE) $(OLD)
	-$(MAKE) --no-print-directory -C $(OLD_TREE) ext 2>/dev/null
	$(YADE) -n -x benchmarks/before_after.py --old-tree $(OLD_TREE) --json $(OUT)/bench-before-after-$(OLD).json

# Redeposit the preset packings into $(OUT)/ (the 1089-disc deposit of Fig. 14-15 takes a few minutes;
# SHORT=1 leaves it out);
# `deposit.py --scene quicksand_case1 --replace` would overwrite the tracked preset file instead.
packings: deps
	$(YADE) -n -x yade_scripts/deposit.py --scene quicksand_case1 --out $(OUT)/packings/quicksand-case1.csv
	$(YADE) -n -x yade_scripts/deposit.py --scene yade_scripts/scenes/quicksand_case1_flat.toml \
	  --from $(OUT)/packings/quicksand-case1.csv --out $(OUT)/packings/quicksand-case1-flat.csv
	$(YADE) -n -x yade_scripts/deposit.py --scene quicksand_case1_submerged --out $(OUT)/packings/quicksand-case1-submerged.csv
	$(YADE) -n -x yade_scripts/deposit.py --scene liquefaction_case1 --out $(OUT)/packings/liquefaction-case1.csv
	$(if $(SHORT),,$(YADE) -n -x yade_scripts/deposit.py --scene deposit_1089 --out $(OUT)/deposit_1089/packing.csv)

# Seed 003 (about 85 CPU minutes, niced, resumable: finished jobs are kept): biaxial tests of the
# paper's specimen, φ*(φe), E50, eq 4-6 and their sensitivity, through the sweep runner
# (docs/BIAXIAL.md). `biaxial_study.py --estimate` prints what is left to run and its predicted
# cost. SCHEDULER=tcp://host:8786 runs the jobs on a Dask cluster instead of the local cores.
# SHORT=1: the main grid's 3 jobs on one packing, biaxial_study.py --quick's specimen.
biaxial: deps
	nice -n 10 $(PY) yade_scripts/biaxial_study.py --out $(OUT)/biaxial $(if $(SCHEDULER),--scheduler $(SCHEDULER)) \
	  $(if $(SHORT),--quick --parts main --seeds 1)

# Seismic liquefaction (seed 000 §6): the seven cases over 0.18 s, each an ensemble of LIQ_STARTS
# starts perturbed by 1e-7 m, with the fast numerics where the validation passed for the case (its
# yade_scripts/scenes/liquefaction_case<N>_fast.toml; docs/TRADEOFFS.md) and the paper's (dt = 1e-6 s)
# otherwise; cases 1 and 3 again with the water-conserving transfer, the drainage time of the still
# box (drainage.json), then the study: $(OUT)/liquefaction/summary.json, trends.md (each trend with
# its 95 % interval and verdict), Fig. 40, 41, 46. LIQ_JOBS starts run at a time (LIQ_JOBS=2 uses
# both cores of a machine of your own); LIQ_CASES="1 2" runs a subset, the study uses what is there;
# LIQ_STARTS=1 runs single runs (which decide no trend).
LIQ_CASES ?= $(if $(SHORT),1,1 2 3 4 5 6 7)
LIQ_CONSERVING ?= $(if $(SHORT),,1 3)
LIQ_STARTS ?= $(if $(SHORT),1,8)
LIQ_JOBS ?= 2
LIQ_RUN := $(YADE) -n -x yade_scripts/liquefaction.py
LIQ_SCENE = $$(f=yade_scripts/scenes/liquefaction_case$${n}_fast.toml; if [ -f $$f ]; then echo --scene $$f; else echo --case $$n; fi)
LIQ_ENSEMBLE = $(if $(filter 1,$(LIQ_STARTS)),,--starts $(LIQ_STARTS) --jobs $(LIQ_JOBS))
liquefaction: deps
	@for n in $(LIQ_CASES); do $(LIQ_RUN) $(LIQ_SCENE) $(LIQ_ENSEMBLE) $(SHORT_RUN) --overwrite --out $(OUT)/liquefaction/case$$n || exit 1; done
	@for n in $(LIQ_CONSERVING); do $(LIQ_RUN) $(LIQ_SCENE) --transfer conserving $(LIQ_ENSEMBLE) $(SHORT_RUN) --overwrite \
	   --out $(OUT)/liquefaction/case$$n-conserving || exit 1; done
	$(PY) yade_scripts/liquefaction_drainage.py --json $(OUT)/liquefaction/drainage.json
	$(PY) -m postproc.liquefaction --study $(OUT)/liquefaction

# The 10,000-disc wet ground (issue 25) shaken 0.1 s by case 1's cosine: history, pressure blocks,
# snapshots and depth.png (pore pressure and porosity by depth over time) in $(OUT)/ground/run
# (about 11 minutes of one core).
ground: deps
	$(LIQ_RUN) --scene yade_scripts/scenes/ground_10000.toml $(SHORT_RUN) --overwrite --out $(OUT)/ground/run

# The seismic study's reconstruction (docs/LIQUEFACTION.md, "Reconstruction"): the paper's unknowns
# (case 3's permeabilities x3/x10/x30, E_w x3/x10, the box wider and narrower with the same discs, a
# denser packing) on ensembles of 8 starts of the cases each touches, against make liquefaction's
# ensembles (LIQ_BASELINE) -> $(OUT)/reconstruction/{reconstruction.json,reconstruction.md,
# reconstruction.png}; resumable (a re-run skips the finished jobs, continues a stopped ensemble);
# about 55 CPU-minutes (2026-12-02: 42 for all but the narrower box).
LIQ_BASELINE ?= $(OUT)/liquefaction
reconstruction: deps
	nice -n 10 $(PY) yade_scripts/liquefaction_reconstruction.py --out $(OUT)/reconstruction \
	   --baseline $(LIQ_BASELINE) --workers $(LIQ_JOBS) $(if $(SCHEDULER),--scheduler $(SCHEDULER))

# The liquefaction resistance curve (issue 42 item 3; engines/studies/resistance.py): seismic case 1's
# box under its 50 Hz cosine at 5 amplitudes (1500 gal x sqrt(2)^k, k = -2..2), ensembles of
# RES_STARTS starts over 30 cycles, loose (the preset's) and dense (deposited with mu = 0) packings,
# through the sweep runner (resumable: finished ensembles are kept; SCHEDULER as below) ->
# $(OUT)/resistance/ and docs/resistance/{resistance.json,resistance.png}. SHORT=1: milliseconds
# runs into $(OUT)/resistance-short/ (the pipeline only; the check test runs it).
RES_STARTS ?= 8
resistance: deps
	nice -n 10 $(PY) yade_scripts/resistance.py --workers $(LIQ_JOBS) $(if $(SCHEDULER),--scheduler $(SCHEDULER)) \
	   $(if $(SHORT),--short --out $(OUT)/resistance-short,--starts $(RES_STARTS) --out $(OUT)/resistance --docs docs/resistance)

# The 10,000-disc ground (yade_scripts/scenes/ground_10000.toml) under case 1's cosine for the curve's 30
# cycles, one run (about an hour of one core; a re-run resumes it), read beside the resistance curve
# as an illustration: needs make resistance's runs; -> $(OUT)/resistance-ground, docs/resistance/.
resistance-ground: deps
	@d=$(OUT)/resistance-ground; if grep -qs '"status": "completed"' $$d/summary.json; then echo "$$d: completed"; \
	 elif [ -f $$d/checkpoint.npz ]; then $(LIQ_RUN) --resume $$d; \
	 else $(LIQ_RUN) --scene yade_scripts/scenes/ground_10000.toml --duration 0.6 --out $$d; fi
	nice -n 10 $(PY) yade_scripts/resistance.py --out $(OUT)/resistance --analyse-only --ground $(OUT)/resistance-ground \
	   --docs docs/resistance

# Speed against accuracy (docs/TRADEOFFS.md): every numerical knob of quick-sand case 1
# and the seismic box (liquefaction cases 1, 4) from 5 perturbed starts (20 for the seismic rows
# that are judged) against a dt = 5e-7 s reference, through the sweep runner (resumable: a re-run
# skips the finished settings; about 60 CPU-minutes, one process at a time so that the costs are
# comparable; SCHEDULER=tcp://host:8786
# runs it on a Dask cluster) -> $(OUT)/tradeoffs/{tradeoffs.json,table.md,tradeoffs_*.png}.
tradeoffs: deps
	nice -n 10 $(PY) yade_scripts/tradeoffs.py study --out $(OUT)/tradeoffs $(if $(SCHEDULER),--scheduler $(SCHEDULER))

# The fast setting validated where it is offered (docs/TRADEOFFS.md, "Validation"): on every preset
# scene (quick sand 1-2, liquefaction 1-7) over its whole duration, 20 starts at the scene's
# perturbation each, the fast setting against the paper's numerics (dt = 1e-6 s, rebuilds every 1000
# steps, water every step), one job at a time (about 90 CPU-minutes; resumable: a re-run skips the
# finished jobs; SCHEDULER as above) -> $(OUT)/validation/{validation.json,validation.md};
# docs/tradeoffs/validation.json is its copy, which the tests read.
validation: deps
	nice -n 10 $(PY) yade_scripts/tradeoffs.py study --validation --out $(OUT)/validation $(if $(SCHEDULER),--scheduler $(SCHEDULER))

# The stability map: ~40 short runs at the extremes of dt, E_w, k1, k2, eps_m, f_max
# (a few CPU-minutes) -> $(OUT)/stability/{map.json,map.png}.
stability: deps
	nice -n 10 $(YADE) -n -j 1 -x yade_scripts/stability.py --out $(OUT)/stability $(if $(SHORT),--window 0.0002)

# The re-meshing transfers on the four examples, 8 starts each (docs/ENGINE.md: the rule); resumable
remesh-transfer: deps
	nice -n 10 $(YADE) -n -x benchmarks/remesh_transfer.py --json docs/engine/remesh_transfer.json

clean:
	rm -rf $(OUT) .pytest_cache
