"""Everything that talks to YADE: bulk body I/O (yade_io, the yadebulk bridge), the paper's law
as an engine (paper_law_engine), the water engine for any YADE script (water_engine), a scene's
bodies and engines (coupling), deposition of packings, checkpoints.

Importing this package closes the Python console and XML-RPC server that the ``yade`` launcher
opens on all interfaces (listeners.close_yade_servers; PORE_DEM_KEEP_YADE_SERVERS=1 keeps them).

May import: YADE, engines.model, engines.compiled, engines.reference (the recording contract),
packing.
"""
from engines.yade.listeners import close_yade_servers

close_yade_servers()
