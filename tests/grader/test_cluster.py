"""Grading on Dask distributed (``eulertop grade --cluster``, :mod:`grader.executors.dask`).

A real ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1 (subprocesses, no
mock) grade a class of 40 real notebooks with real kernels, in each worker's sandbox; one
worker is killed (SIGKILL, with its kernels) in the middle. The records must equal those of
a local run of the same class byte for byte apart from ``graded_at``, every student must be
written exactly once, and the scores must be the key's (full marks for the reference
solutions, none for the planted wrong answer). ``--cluster local:N`` is run through the CLI;
the one-line refusals (no Dask, a malformed address, an unreachable scheduler) exit 2.
"""

from __future__ import annotations

import collections
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import distributed  # noqa: F401 - in the "test" extra: missing, the module fails, never skips
import pytest

from eulertop.cli import main
from grader.executors import dask as cluster_module
from grader.limits import Limits
from grader.pipeline import grade_assignment
from grader.results import read_result
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

CLASS = tuple(f"s{i:02d}" for i in range(40))
WRONG = frozenset(CLASS[3::7])  # planted wrong inertia diagonal
ERRORS = frozenset({CLASS[5]})  # a cell that raises (graded anyway: every cell runs)
WRONG_DIAG = "q1_I_diag = [1.0, 2.0, 3.0]\n"
LIMITS = Limits(cell_timeout=5.0, total_timeout=60.0)


def _cell(source: str) -> dict:
    return {"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
            "source": source}


@pytest.fixture(scope="module")
def klass(tmp_path_factory) -> tuple[Path, Path]:
    """An assignment (one family) for 40 students and their submissions: the reference
    solutions, with a wrong answer planted in :data:`WRONG` and a raising cell in ERRORS."""
    root = tmp_path_factory.mktemp("cluster")
    hw, subs = root / "HW", root / "subs"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in CLASS)), hw, FAMILIES,
                        problems=["inertia_tensor"], seed=17)
    subs.mkdir()
    for sid in CLASS:
        nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text(encoding="utf-8"))
        if sid in WRONG:
            nb["cells"].append(_cell(WRONG_DIAG))
        if sid in ERRORS:
            nb["cells"].append(_cell("raise RuntimeError('a student bug')\n"))
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb), encoding="utf-8")
    return hw, subs


@pytest.fixture(scope="module")
def local_run(klass, tmp_path_factory) -> Path:
    """The same class graded on this machine (the local pool), for comparison."""
    hw, subs = klass
    out = tmp_path_factory.mktemp("local") / "graded"
    grade_assignment(hw, subs, out, limits=LIMITS, jobs=2)
    return out


def _record_text(path: Path) -> str:
    """A record's text without its one volatile field."""
    record = json.loads(path.read_text(encoding="utf-8"))
    assert record.pop("graded_at")
    return json.dumps(record, sort_keys=True, indent=1, ensure_ascii=False)


def assert_same_as_local(out: Path, local: Path, ids=CLASS) -> None:
    for sid in ids:
        assert _record_text(out / "results" / f"{sid}.json") == \
            _record_text(local / "results" / f"{sid}.json"), sid
    for table in ("grades.csv", "answers.csv"):
        assert (out / table).read_bytes() == (local / table).read_bytes(), table


def assert_scores(out: Path) -> None:
    """Scores from the key, not from the grader: full marks for each reference solution."""
    for sid in CLASS:
        r = read_result(out / "results" / f"{sid}.json")
        assert r.status == "graded", (sid, r.message)
        assert r.sandboxed and "bubblewrap" in r.execution["isolation"], sid
        diag = next(a for a in r.answers if a.variable == "q1_I_diag")
        if sid in WRONG:
            assert diag.verdict.points == 0 and r.points < r.max_points, sid
        else:
            assert r.points == r.max_points > 0, (sid, r.message)
    erred = read_result(out / "results" / f"{CLASS[5]}.json")
    assert "RuntimeError" in json.dumps(erred.execution)


# --------------------------------------------------------------------------------------------
# a real scheduler and two real workers


def _dask(*argv: str, log: Path) -> subprocess.Popen:
    """``python -m dask ...`` in a session of its own (so its kernels die with it)."""
    return subprocess.Popen([sys.executable, "-m", "dask", *argv], stdout=log.open("wb"),
                            stderr=subprocess.STDOUT, start_new_session=True)


def _kill(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait(timeout=30)


def _wait_for(path: Path, proc: subprocess.Popen, seconds: float = 60.0) -> dict:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if path.is_file():
            try:
                return json.loads(path.read_text(encoding="utf-8"))
            except json.JSONDecodeError:
                pass  # being written
        assert proc.poll() is None, "the dask scheduler exited"
        time.sleep(0.1)
    raise AssertionError(f"no scheduler file {path} after {seconds} s")


@pytest.fixture
def dask_cluster(tmp_path):
    """(scheduler address, [worker processes]): started here, killed at the end."""
    from distributed import Client

    procs = []
    try:
        info = tmp_path / "scheduler.json"
        procs.append(_dask("scheduler", "--host", "127.0.0.1", "--port", "0",
                           "--no-dashboard", "--scheduler-file", str(info),
                           log=tmp_path / "scheduler.log"))
        address = _wait_for(info, procs[0])["address"]
        workers = [_dask("worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                         "--host", "127.0.0.1", "--death-timeout", "60",
                         log=tmp_path / f"worker{i}.log") for i in range(2)]
        procs += workers
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for proc in reversed(procs):
            _kill(proc)


@pytest.mark.slow
def test_a_real_cluster_that_loses_a_worker_grades_like_a_local_run(
        klass, local_run, dask_cluster, tmp_path):
    hw, subs = klass
    address, workers = dask_cluster
    out = tmp_path / "graded"
    written = collections.Counter()
    killed_after = []

    from distributed import Client

    watcher = Client(address, timeout=60)
    victim = next(w for w, pid in watcher.run(os.getpid).items() if pid == workers[1].pid)

    def progress(result):
        written[result.student_id] += 1
        if sum(written.values()) == 10:  # in the middle: the other 30 are queued or running
            killed_after.append(len(watcher.processing(workers=[victim])[victim]))
            _kill(workers[1])

    try:
        report = grade_assignment(hw, subs, out, limits=LIMITS, cluster=address,
                                  progress=progress)
    finally:
        watcher.close()
    assert killed_after and killed_after[0] >= 1  # it died holding a task: rescheduled
    assert workers[1].poll() is not None
    assert workers[0].poll() is None  # the survivor did the rest
    assert written == collections.Counter(CLASS)  # each student written once, no more
    assert sorted(report.graded_now) == sorted(CLASS)
    assert not report.not_graded
    assert_same_as_local(out, local_run)
    assert_scores(out)


@pytest.mark.slow
def test_local_cluster_from_the_command_line_then_resume(klass, local_run, tmp_path, capsys):
    hw, _ = klass
    subs = tmp_path / "subs"
    subs.mkdir()
    few = CLASS[:6]
    for sid in few:
        (subs / f"{sid}.ipynb").write_bytes((klass[1] / f"{sid}.ipynb").read_bytes())
    out = tmp_path / "graded"
    argv = ["grade", str(hw), str(subs), "--out", str(out), "--cluster", "local:2",
            "--timeout", "60", "--cell-timeout", "5"]
    assert main(argv) == 0
    for sid in few:
        assert _record_text(out / "results" / f"{sid}.json") == \
            _record_text(local_run / "results" / f"{sid}.json"), sid
    assert read_result(out / "results" / f"{CLASS[10]}.json").status == "missing"
    capsys.readouterr()
    assert main(argv) == 0  # resume: nothing to run, no cluster started
    assert f"{len(CLASS)} unchanged" in capsys.readouterr().out


# --------------------------------------------------------------------------------------------
# refusals: one line, exit 2, nothing written


def test_without_dask_cluster_says_what_to_install(klass, tmp_path):
    hw, subs = klass
    out = tmp_path / "graded"
    code = ("import sys; sys.modules['distributed'] = None; from eulertop.cli import main; "
            f"sys.exit(main(['grade', {str(hw)!r}, {str(subs)!r}, '--out', {str(out)!r}, "
            "'--cluster', 'local:2']))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0
    assert "pip install 'eulertop[cluster]'" in done.stderr
    assert "Traceback" not in done.stderr
    assert not out.exists()


@pytest.mark.parametrize("spec", ["local:0", "local:", "local:two"])
def test_a_malformed_local_cluster_is_refused(klass, tmp_path, capsys, spec):
    hw, subs = klass
    assert main(["grade", str(hw), str(subs), "--out", str(tmp_path / "g"), "--cluster",
                 spec]) == 2
    err = capsys.readouterr().err
    assert "local:N" in err and err.count("\n") == 1
    assert not (tmp_path / "g").exists()


def test_an_unreachable_scheduler_is_refused(klass, tmp_path, capsys, monkeypatch):
    hw, subs = klass
    monkeypatch.setattr(cluster_module, "CONNECT_SECONDS", 1.0)
    sub = tmp_path / "subs"
    sub.mkdir()
    (sub / f"{CLASS[0]}.ipynb").write_bytes((subs / f"{CLASS[0]}.ipynb").read_bytes())
    assert main(["grade", str(hw), str(sub), "--out", str(tmp_path / "g"), "--cluster",
                 "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err
    assert err.count("\n") == 1
    assert not (tmp_path / "g" / "results" / f"{CLASS[0]}.json").exists()


# --------------------------------------------------------------------------------------------
# the client's own resubmission: a task that ends in KilledWorker


def execute_dying_once(path, variables, limits):
    """Kill this worker process the first time it sees ``s01``'s submission (a marker file
    beside the submissions records that it happened); run the rest for real, sandboxed."""
    from grader.execute import execute_submission

    marker = Path(os.environ["EULERTOP_TEST_MARKER"])
    if path.name == f"{CLASS[1]}.ipynb" and not marker.exists():
        marker.write_text("died", encoding="utf-8")
        os._exit(1)
    return execute_submission(path, variables, limits)


@pytest.mark.slow
def test_a_task_that_kills_its_worker_is_resubmitted(klass, local_run, tmp_path, monkeypatch):
    """With no failure allowed per task by the scheduler, a worker death surfaces as
    KilledWorker; the client resubmits the task, and the student is graded once, as locally."""
    import dask
    from distributed import Client, LocalCluster

    from grader.assignment import load_assignment
    from grader.compare import key_answers
    from grader.executors.dask import grade_on_cluster
    from grader.submissions import Submission

    hw, subs = klass
    marker = tmp_path / "died"
    monkeypatch.setenv("EULERTOP_TEST_MARKER", str(marker))  # inherited by the workers
    a = load_assignment(hw)
    few = CLASS[:3]
    to_run = [(Submission(sid, subs / f"{sid}.ipynb"), key_answers(a.key, sid), a.key_hash(sid),
               None, a.parameters(sid)) for sid in few]
    written = collections.Counter()
    records = {}

    def publish(result):
        written[result.student_id] += 1
        records[result.student_id] = result

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
            LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None) as lc, \
            Client(lc) as client:
        assert grade_on_cluster(client, to_run, LIMITS, publish,
                                execute=execute_dying_once) == 3
    assert marker.read_text(encoding="utf-8") == "died"
    assert written == collections.Counter(few)
    for sid in few:
        local = read_result(local_run / "results" / f"{sid}.json")
        assert records[sid].status == "graded" and records[sid].points == local.points
        # the student's parameters went with the task: the record says which it was graded as
        assert records[sid].execution["variant"] == local.execution["variant"]
        assert records[sid].answers == local.answers
