"""A run as a user starts it: scene files and their schema (scene), checks before anything is
written (preflight), the scene scripts' command line (command_line), the runner and its outputs
(runner), provenance, and the sweep runner for batches and Dask clusters (sweep). The studies'
runs: seed 003's biaxial test (biaxial) and study (biaxial_study), the speed/accuracy study
(tradeoffs), the stability map (stability).

May import: every layer before it (engines.model ... engines.studies, packing, postproc) and YADE.
"""
