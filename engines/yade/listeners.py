"""YADE's network listeners closed: every ``yade`` process starts, before its script's first
line, a Python console (a ``socketserver.ThreadingTCPServer``, port 9000 and up, guarded by a
6-letter cookie it prints) and an XML-RPC server (``xmlrpc.server.SimpleXMLRPCServer``, port
21000 and up, with an anonymous ``stop()``), both bound to all interfaces although the banner says
"localhost". A run needs neither: ``close_yade_servers()`` closes both, found among the live
objects (YADE keeps no other handle on them); importing ``engines.yade`` calls it, and so does the
first line of every script in yade_scripts/. Setting the environment variable
PORE_DEM_KEEP_YADE_SERVERS=1 keeps them (to connect to a run with YADE's own tools). YADE imported
into Debian's python3 starts none: then nothing is found and nothing is done. What remains
YADE's: the second or so between its start and the script's first line (docs/SWEEPS.md).
"""
import gc
import os
import socket
import socketserver
import sys
import threading

KEEP = "PORE_DEM_KEEP_YADE_SERVERS"  # "1": leave YADE's servers open


def yade_servers():
    """The open listeners YADE's launcher started in this process (yade.remote), [] without them."""
    remote = sys.modules.get("yade.remote")
    if remote is None:
        return []
    # type(), not isinstance: no object's own __class__ is asked (a proxy's may raise)
    return [o for o in gc.get_objects()
            if issubclass(type(o), socketserver.BaseServer)
            and (o.RequestHandlerClass is remote.PythonConsoleSocketEmulator
                 or type(getattr(o, "instance", None)) is remote.InfoProvider)
            and o.socket.fileno() != -1]


def close_yade_servers():
    """Stop and close YADE's console and XML-RPC server (module docstring) unless
    PORE_DEM_KEEP_YADE_SERVERS=1; returns the addresses closed, (host, port) each."""
    if os.environ.get(KEEP) == "1":
        return []
    servers = yade_servers()
    # shutdown() asks the serve_forever loop to end and waits for it; the loop looks every 0.5 s,
    # or at once when its socket is shut down (Linux wakes a poll on a listening socket then)
    stops = [threading.Thread(target=s.shutdown, daemon=True) for s in servers]
    for t in stops:
        t.start()
    for s in servers:
        try:
            s.socket.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass  # not connected: the loop then ends at its next look
    for t in stops:
        t.join(timeout=5)
    for s in servers:
        s.server_close()
    return [s.server_address for s in servers]
