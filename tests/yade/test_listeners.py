"""YADE's console and XML-RPC server (open on all interfaces from the launcher's start) are closed
by the project's scripts at their first line and by importing engines.yade, unless
PORE_DEM_KEEP_YADE_SERVERS=1; only YADE's own servers are touched."""
import glob
import json
import os
import socketserver
import subprocess
import threading

import pytest

from engines import ROOT
from engines.yade.listeners import KEEP, close_yade_servers

LINE = "import engines.yade  # noqa: F401"
SCRIPTS = sorted(p for p in glob.glob(os.path.join(ROOT, "yade_scripts", "**", "*.py"), recursive=True)
                 if not p.endswith("__init__.py"))

# this process's listening TCP ports (from /proc: its socket inodes among the kernel's listening sockets)
LISTENING = """
import os
def listening():
    inodes = set()
    for fd in os.listdir('/proc/self/fd'):
        try:
            link = os.readlink('/proc/self/fd/' + fd)
        except OSError:
            continue
        if link.startswith('socket:['):
            inodes.add(link[8:-1])
    ports = []
    for name in ('tcp', 'tcp6'):
        for row in open('/proc/self/net/' + name).read().splitlines()[1:]:
            f = row.split()
            if f[3] == '0A' and f[9] in inodes:
                ports.append(int(f[1].rsplit(':', 1)[1], 16))
    return sorted(ports)
"""
# run under yade: what listens at the script's first line
FIRST_LINE = LISTENING + """
import json
print('PORTS', json.dumps(listening()))
"""
# run under yade: the first lines of SCRIPT up to its closing line; what listens before and after
PROBE = LISTENING + """
import json, sys
script = os.environ['PROBED_SCRIPT']
lines = open(script).read().splitlines(True)
head = ''.join(lines[:next(k for k, l in enumerate(lines) if l.startswith(%r)) + 1])
before = listening()
sys.argv[0] = script
exec(compile(head, script, 'exec'), {'__name__': '__main__'})
print('PORTS', json.dumps([before, listening()]))
""" % LINE


def test_every_script_closes_the_servers_first():
    """The line after the bootstrap (the first import of the project) is the closing import."""
    assert len(SCRIPTS) >= 15
    wrong = []
    for path in SCRIPTS:
        lines = [line for line in open(path).read().splitlines() if line.strip()]
        boot = next(k for k, line in enumerate(lines) if line.startswith("sys.path.insert(0, "))
        if not lines[boot + 1].startswith(LINE):
            wrong.append(os.path.relpath(path, ROOT))
    assert wrong == []


class _Handler(socketserver.BaseRequestHandler):
    def handle(self):
        pass


def _serve(handler, **kw):
    """A server on 127.0.0.1 (a free port), serving in a thread, as YADE's launcher starts its own."""
    if kw:
        import xmlrpc.server
        server = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
        server.register_instance(kw["instance"])
    else:
        server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def test_only_yades_own_servers_are_closed(monkeypatch):
    remote = pytest.importorskip("yade.remote")
    assert close_yade_servers() == []  # YADE imported into python3 starts none
    console = _serve(remote.PythonConsoleSocketEmulator)
    info = _serve(None, instance=remote.InfoProvider())
    other = _serve(_Handler)  # a server of someone else's (a Dask worker's, a user's)
    try:
        monkeypatch.setenv(KEEP, "1")
        assert close_yade_servers() == [] and console.socket.fileno() != -1
        monkeypatch.delenv(KEEP)
        assert sorted(close_yade_servers()) == sorted([console.server_address, info.server_address])
        assert console.socket.fileno() == -1 and info.socket.fileno() == -1 and other.socket.fileno() != -1
        assert close_yade_servers() == []  # closed once
    finally:
        other.shutdown()
        other.server_close()


def _probe(tmp_path, script, keep):
    probe = tmp_path / "probe.py"
    probe.write_text(PROBE)
    env = {k: v for k, v in os.environ.items() if k != KEEP}
    env.update(PROBED_SCRIPT=script, **({KEEP: "1"} if keep else {}))
    run = subprocess.run(["yade", "-n", "-x", str(probe)], capture_output=True, text=True, env=env, cwd=tmp_path,
                         timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    return json.loads(run.stdout.split("PORTS", 1)[1])


@pytest.mark.check
@pytest.mark.parametrize("name", ["quicksand.py", "sweep.py"])
def test_no_listening_socket_after_a_scripts_first_line(tmp_path, name):
    script = os.path.join(ROOT, "yade_scripts", name)
    before, after = _probe(tmp_path, script, keep=False)
    assert len(before) == 2 and after == []  # the console and the XML-RPC server, then none
    before, after = _probe(tmp_path, script, keep=True)
    assert len(before) == 2 and after == before


@pytest.mark.check
def test_the_projects_own_launches_start_no_listener(tmp_path):
    """A sweep job or an ensemble's start (engines.run.sweep.YADE) has no server from its start."""
    from engines.run.sweep import YADE, Job, run_sweep, yade_environment
    probe = tmp_path / "first.py"
    probe.write_text(FIRST_LINE)
    env = {k: v for k, v in os.environ.items() if k not in (KEEP, "PYTHONPATH")}
    run = subprocess.run(["yade", "-n", "-x", str(probe)], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert len(json.loads(run.stdout.split("PORTS", 1)[1])) == 2  # YADE's own start: two servers
    rec = run_sweep([Job("j", (*YADE, "-x", str(probe)), yade_environment())], str(tmp_path / "sweep"), log=None)[0]
    assert rec["status"] == "ok", rec["stderr_tail"]
    out = (tmp_path / "sweep" / "j" / "stdout.log").read_text()
    assert json.loads(out.split("PORTS", 1)[1]) == []
    rec = run_sweep([Job("keep", (*YADE, "-x", str(probe)), {**yade_environment(), KEEP: "1"})], str(tmp_path / "sweep"),
                    log=None)[0]
    out = (tmp_path / "sweep" / "keep" / "stdout.log").read_text()
    assert rec["status"] == "ok" and len(json.loads(out.split("PORTS", 1)[1])) == 2  # the opt-out
