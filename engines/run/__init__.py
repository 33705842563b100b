"""A run as a user starts it: scene files and their schema (scene), checks before anything is
written (preflight), the scene scripts' command line (command_line), the runner and its outputs
(runner), provenance, and the sweep runner for batches and Dask clusters (sweep).

May import: every layer before it (engines.model ... engines.studies, packing, postproc) and YADE.
"""
