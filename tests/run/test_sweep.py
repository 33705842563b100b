"""The sweep runner: local processes, a Dask LocalCluster, failures reported, resume, yade-batch tables."""
import json
import os
import sys

import pytest

from engines.run.sweep import Job, jobs_from_table, read_record, run_sweep

# a job: appends one line to runs.txt in its directory (counts its runs), writes x², or fails
# with a message on stderr when its argument is negative and no "fixed" file exists
JOB = """
import os, sys
out, x = sys.argv[1], float(sys.argv[2])
open(os.path.join(out, "runs.txt"), "a").write("run\\n")
if x < 0 and not os.path.exists(os.path.join(os.path.dirname(out), "fixed")):
    sys.exit("negative x refused: " + str(x))
open(os.path.join(out, "result.json"), "w").write('{"y": %r}' % (x * x))
"""


def _jobs(values):
    return [Job(f"x={v:g}", (sys.executable, "-c", JOB, "{out}", v)) for v in values]


def _runs(root, name):
    with open(os.path.join(root, name, "runs.txt")) as f:
        return len(f.readlines())


def _check_sweep(root, scheduler=None, workers=2):
    jobs = _jobs([1, 2, -3, 4])
    recs = run_sweep(jobs, root, workers=workers, scheduler=scheduler, log=None)
    assert [r["name"] for r in recs] == ["x=1", "x=2", "x=-3", "x=4"]
    assert [r["status"] for r in recs] == ["ok", "ok", "failed", "ok"]
    bad = read_record(root, "x=-3")
    assert bad["returncode"] == 1 and "negative x refused: -3.0" in bad["stderr_tail"]
    for v in (1, 2, 4):
        with open(os.path.join(root, f"x={v}", "result.json")) as f:
            assert json.load(f)["y"] == v * v
        rec = read_record(root, f"x={v}")
        assert rec["command"][-2] == os.path.abspath(os.path.join(root, f"x={v}")) and rec["wall_s"] >= 0
    with open(os.path.join(root, "sweep.json")) as f:
        assert json.load(f)["failed"] == ["x=-3"]
    # resume: the ok jobs are kept, the failed one runs again (and now succeeds)
    open(os.path.join(root, "fixed"), "w").close()
    recs = run_sweep(jobs, root, workers=workers, scheduler=scheduler, log=None)
    assert all(r["status"] == "ok" for r in recs)
    assert [bool(r.get("kept")) for r in recs] == [True, True, False, True]
    assert [_runs(root, j.name) for j in jobs] == [1, 1, 2, 1]
    # a changed command is not taken for done
    recs = run_sweep(_jobs([1]) + [Job("x=2", (sys.executable, "-c", JOB, "{out}", 5))], root, workers=workers,
                     scheduler=scheduler, log=None)
    assert [bool(r.get("kept")) for r in recs] == [True, False] and _runs(root, "x=2") == 2


def test_local_sweep_reports_failures_and_resumes(tmp_path):
    _check_sweep(str(tmp_path / "local"))


ENV_JOB = "import json, os, sys; json.dump(dict(os.environ), open(os.path.join(sys.argv[1], 'env.json'), 'w'))"


@pytest.mark.check
def test_dask_local_cluster_sweep(tmp_path):
    """The sweep on a Dask cluster as on the local pool; its jobs see the environment of the sweep,
    not the Dask nanny's MALLOC_TRIM_THRESHOLD_ (which the worker itself holds)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        _check_sweep(str(tmp_path / "dask"), scheduler=cluster.scheduler_address)
        with distributed.Client(cluster) as client:
            assert "MALLOC_TRIM_THRESHOLD_" in client.submit(lambda: dict(os.environ)).result()
        run_sweep([Job("env", (sys.executable, "-c", ENV_JOB, "{out}"))], str(tmp_path / "env"),
                  scheduler=cluster.scheduler_address, log=None)
    with open(tmp_path / "env" / "env" / "env.json") as f:
        env = json.load(f)
    assert "MALLOC_TRIM_THRESHOLD_" not in env and env["SWEEP_JOB_DIR"] == str(tmp_path / "env" / "env")


def test_bad_jobs_are_refused(tmp_path):
    with pytest.raises(ValueError, match="job name"):
        Job("a/b", ("true",))
    with pytest.raises(ValueError, match="unique"):
        run_sweep([Job("a", ("true",)), Job("a", ("true",))], str(tmp_path), log=None)
    with pytest.raises(ValueError, match="workers"):
        run_sweep([Job("a", ("true",))], str(tmp_path), workers=0, log=None)
    rec = run_sweep([Job("missing", ("/nonexistent/program",))], str(tmp_path), log=None)[0]
    assert rec["status"] == "failed" and "could not start" in rec["stderr_tail"]


@pytest.mark.check
def test_yade_batch_table_becomes_jobs(tmp_path):
    script = tmp_path / "s.py"
    script.write_text("from yade import utils\n"
                      "utils.readParamsFromTable(a=1, b=2.0, noTableOk=False)\n"
                      "from yade.params import table\n"
                      "import os\n"
                      "open(os.path.join(os.environ['SWEEP_JOB_DIR'], 'ab.txt'), 'w').write(str(table.a * table.b))\n")
    tab = tmp_path / "t.table"
    tab.write_text("description a b\n# a comment\nfirst 3 0.5\nsecond 4 =\n")
    jobs = jobs_from_table(str(tab), str(script))
    assert [j.name for j in jobs] == ["first", "second"]
    recs = run_sweep(jobs, str(tmp_path / "sweep"), log=None)
    assert [r["status"] for r in recs] == ["ok", "ok"], recs[0]["stderr_tail"]
    assert [(tmp_path / "sweep" / n / "ab.txt").read_text() for n in ("first", "second")] == ["1.5", "2.0"]
    with pytest.raises(ValueError, match="missing.table: no such table file"):
        jobs_from_table(str(tmp_path / "missing.table"), str(script))


def test_a_runner_failure_is_reported_not_lost(tmp_path, monkeypatch):
    from engines.run import sweep

    def broken(job, root, cwd):
        raise OSError("disk full")
    monkeypatch.setattr(sweep, "run_job", broken)
    rec = run_sweep([Job("a", ("true",))], str(tmp_path), log=None)[0]
    assert rec["status"] == "failed" and "disk full" in rec["stderr_tail"]


def test_cpu_seconds_and_timeout_are_recorded(tmp_path):
    # a job busy for 0.5 s of CPU (in a child it waits for), one asleep for 0.5 s, one stopped by its timeout
    busy = "import subprocess, sys; subprocess.run([sys.executable, '-c', " \
           "'import time\\nt = time.process_time()\\nwhile time.process_time() - t < 0.5: pass'])"
    jobs = [Job("busy", (sys.executable, "-c", busy)), Job("asleep", (sys.executable, "-c", "import time; time.sleep(0.5)")),
            Job("late", (sys.executable, "-c", "import time; time.sleep(30)"), timeout=0.5)]
    busy_rec, asleep_rec, late_rec = run_sweep(jobs, str(tmp_path), workers=1, log=None)
    assert busy_rec["status"] == "ok" and 0.45 < busy_rec["cpu_s"] < busy_rec["wall_s"] + 0.05
    assert asleep_rec["status"] == "ok" and asleep_rec["wall_s"] >= 0.5 and asleep_rec["cpu_s"] < 0.3
    assert late_rec["status"] == "failed" and late_rec["returncode"] == -9 and late_rec["wall_s"] < 10
    assert "timeout after 0.5 s" in late_rec["stderr_tail"]


def test_the_dask_clusters_of_the_tests_and_benchmarks_listen_on_127_0_0_1_only():
    """Every LocalCluster binds 127.0.0.1 without a dashboard, and so does every `dask scheduler`
    and `dask worker` started (their arguments: --host 127.0.0.1 --no-dashboard)."""
    import ast
    import glob

    from engines import ROOT
    found = []
    for path in glob.glob(os.path.join(ROOT, "tests", "**", "*.py"), recursive=True) + \
            glob.glob(os.path.join(ROOT, "benchmarks", "*.py")):
        for node in ast.walk(ast.parse(open(path).read())):
            if not isinstance(node, ast.Call):
                continue
            words = [a.value for a in node.args if isinstance(a, ast.Constant)]
            if getattr(node.func, "attr", getattr(node.func, "id", "")) == "LocalCluster":
                kw = {k.arg: ast.literal_eval(k.value) for k in node.keywords
                      if k.arg in ("host", "dashboard_address")}
                found.append((path, kw.get("host"), "dashboard_address" in kw and kw["dashboard_address"] is None))
            elif words[:1] in (["scheduler"], ["worker"]):  # dask's command line
                host = words[words.index("--host") + 1] if "--host" in words else None
                found.append((path, host, "--no-dashboard" in words))
    assert len(found) >= 5  # three LocalClusters, a scheduler, a worker
    assert [f for f in found if f[1:] != ("127.0.0.1", True)] == []
