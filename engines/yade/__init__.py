"""Everything that talks to YADE: bulk body I/O (yade_io, the yadebulk bridge), the paper's law
as an engine (paper_law_engine), the water engine for any YADE script (water_engine), a scene's
bodies and engines (coupling), deposition of packings, checkpoints.

May import: YADE, engines.model, engines.compiled, engines.reference (the recording contract),
packing.
"""
