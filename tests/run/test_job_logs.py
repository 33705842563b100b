"""The sweep runner's job logs (and job.json, sweep.json) never hold YADE's console cookie nor
its listeners' ports: those banner lines are left out, everything else is kept in order."""
import json
import os
import sys

import pytest

from engines import ROOT
from engines.run.sweep import Job, run_sweep

COOKIE_LINE = "TCP python prompt on localhost:9001, auth cookie `dsuyae'"
XMLRPC_LINE = "XMLRPC info provider on http://localhost:21001"


def _files(root, name):
    return {f: (root / name / f).read_text() for f in ("stdout.log", "stderr.log", "job.json")} | \
        {"sweep.json": (root / "sweep.json").read_text()}


def test_the_banner_lines_are_left_out_of_the_logs(tmp_path):
    code = ("import sys\n"
            f"print('Welcome to Yade'); print({XMLRPC_LINE!r}); print('out 1'); sys.stdout.flush()\n"
            f"sys.stderr.write({COOKIE_LINE!r} + '\\nRunning script x.py\\nerr 1\\n' + 'x' * 70000 + '\\nerr 2')\n"
            "sys.exit(3)\n")
    (tmp_path / "banner.py").write_text(code)  # not in the command line, which job.json records
    rec = run_sweep([Job("j", (sys.executable, str(tmp_path / "banner.py")))], str(tmp_path), log=None)[0]
    logs = _files(tmp_path, "j")
    assert logs["stdout.log"] == "Welcome to Yade\nout 1\n"
    assert logs["stderr.log"] == "Running script x.py\nerr 1\n" + "x" * 70000 + "\nerr 2"  # no newline at the end
    assert rec["status"] == "failed" and rec["stderr_tail"].endswith("err 2")
    assert not any("dsuyae" in text or "21001" in text for text in logs.values())


@pytest.mark.check
def test_a_yade_jobs_files_hold_no_cookie(tmp_path):
    script = tmp_path / "s.py"
    script.write_text("import yade.runtime\nprint('cookie', len(yade.runtime.cookie))\n")
    rec = run_sweep([Job("y", ("yade", "-n", "-x", str(script)))], str(tmp_path / "sweep"), log=None)[0]
    assert rec["status"] == "ok", rec["stderr_tail"]
    logs = _files(tmp_path / "sweep", "y")
    assert "cookie 6" in logs["stdout.log"] and "Running script" in logs["stderr.log"]
    assert not any("auth cookie" in text or "localhost:" in text for text in logs.values()), logs
