# Two entry points for a fresh Debian 12 machine: `make demo` and `make test`.
# Everything runs under Debian's Python (/usr/bin/python3), the interpreter YADE uses.
PY      := /usr/bin/python3
YADE    := yade
OUT     ?= out
DEBS    := yade python3-pytest python3-numpy python3-scipy python3-matplotlib python3-vtk9 gcc libc6-dev \
           python3-distributed
EXT_SO  := engines/yadebulk/_yadebulk.so
export PYTHONPATH := $(CURDIR)
export MPLBACKEND := Agg

.PHONY: deps ext demo test bench packings biaxial clean

# Install what is missing (needs root; apt-get update first as Debian requires).
deps:
	@missing=""; for p in $(DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y $$missing; \
	fi
	@$(MAKE) --no-print-directory ext || echo "warning: engines/yadebulk not built: YADE I/O falls back to per-body calls"

# The bulk-I/O bridge to YADE (engines/yadebulk: C, no YADE headers, seconds to build).
ext: $(EXT_SO)

$(EXT_SO): engines/yadebulk/yadebulk.c
	gcc -O2 -fPIC -shared -Wall -Wextra -o $@ $< -ldl

# The main job: Tarumi & Hakuno quick sand, case 1, with its figures.
demo: deps
	$(YADE) -n -x yade_scripts/quicksand.py --case 1 --out $(OUT)/quicksand-case1

# The YADE <-> reference cross-check (exits non-zero on a failed case), then the unit tests
# (YADEBULK_REQUIRED: a missing or failing bulk-I/O bridge fails its tests instead of skipping).
test: deps
	$(YADE) -n -x yade_scripts/crosscheck.py --out $(OUT)/crosscheck
	YADEBULK_REQUIRED=1 $(PY) -m pytest -q tests

# Cost studies (minutes): pore core sizes, YADE path against YADE alone, water sub-cycling.
bench: deps
	$(PY) benchmarks/pores.py --json $(OUT)/bench-pores.json
	$(YADE) -n -x benchmarks/coupling.py --json $(OUT)/bench-coupling.json
	$(YADE) -n -x benchmarks/water_interval.py --json $(OUT)/bench-water-interval.json

# Redeposit the preset packings into $(OUT)/ (the 1089-disc deposit of Fig. 14-15 takes a few minutes);
# `deposit.py --scene quicksand_case1 --replace` would overwrite the tracked preset file instead.
packings: deps
	$(YADE) -n -x yade_scripts/deposit.py --scene quicksand_case1 --out $(OUT)/packings/quicksand-case1.csv
	$(YADE) -n -x yade_scripts/deposit.py --scene liquefaction_case1 --out $(OUT)/packings/liquefaction-case1.csv
	$(YADE) -n -x yade_scripts/deposit.py --scene deposit_1089 --out $(OUT)/deposit_1089/packing.csv

# Seed 003 (about 85 CPU minutes, niced, resumable: finished jobs are kept): biaxial tests of the
# paper's specimen, φ*(φe), E50, eq 4-6 and their sensitivity, through the sweep runner
# (docs/BIAXIAL.md). `biaxial_study.py --estimate` prints what is left to run and its predicted
# cost. SCHEDULER=tcp://host:8786 runs the jobs on a Dask cluster instead of the local cores.
biaxial: deps
	nice -n 10 $(PY) yade_scripts/biaxial_study.py --out $(OUT)/biaxial $(if $(SCHEDULER),--scheduler $(SCHEDULER))

clean:
	rm -rf $(OUT) .pytest_cache
