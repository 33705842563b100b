"""A run as a user starts it: scene files and their schema (scene), checks before anything is
written (preflight), the scene scripts' command line (command_line), the runner and its outputs
(runner), what the scripts print and how loud (talk), provenance, the warm-up of make deps
(warmup), the demo's numbers the documents quote (demo_numbers), the sweep runner for batches and
Dask clusters (sweep), and the cases of the cross-check of the YADE path against the reference (crosscheck; it runs scenes through both, so it
lives here rather than beside the reference, which imports nothing of the fast code). The studies'
runs: seed 003's biaxial test (biaxial) and study (biaxial_study), the speed/accuracy study
(tradeoffs), the stability map (stability).

May import: every layer before it (engines.model ... engines.studies, packing, postproc) and YADE.
"""
