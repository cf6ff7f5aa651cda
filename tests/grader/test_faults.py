"""Faults and load (issue 5): a killed grader, two graders at once, grading twice, a crowd.

References: an uninterrupted run of the same class (what a killed-then-resumed run must equal),
the records on disk read back as strict JSON (nothing half-written), and this machine's
``/proc`` and temporary folder seen from outside: no process carrying the run's marker (the
run folder's name ``eulertop-<grader pid>-…``, on the command line of every sandbox, zygote and
kernel) and no run folder left. Every ``eulertop grade`` here is a separate process with its
own ``TMPDIR``.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest

from grader.results import read_result
from grader.sandbox import RUN_FOLDER, available, remove_stale_run_folders
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

ROOT = Path(__file__).resolve().parents[2]
STUDENTS = ("alice", "bob", "carol")
SLEEP = 4.0  # s, bob's extra cell: the moment to kill the grader, or to start a second one

@pytest.fixture(scope="module", autouse=True)
def _required_here():
    """Fail, never skip: a missing sandbox must not pass silently (CI installs bubblewrap).
    Module-scoped, so it runs before the module's other fixtures start any kernel."""
    if available() is None:
        pytest.fail("bubblewrap (bwrap) is not installed: `apt-get install bubblewrap` "
                    "(README); the battery must run, never skip", pytrace=False)


def _load_bench():
    spec = importlib.util.spec_from_file_location("bench_load", ROOT / "benchmarks" /
                                                  "bench_load.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


bench_load = _load_bench()


def grade(hw: Path, subs: Path, tmp: Path, *extra: str) -> subprocess.Popen:
    """``eulertop grade HW SUBS --jobs 1`` as a new process (own session, own TMPDIR)."""
    return subprocess.Popen(
        [sys.executable, "-m", "eulertop", "grade", str(hw), str(subs), "--jobs", "1",
         "--timeout", "60", *extra], cwd=ROOT, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, text=True, start_new_session=True,
        env={**os.environ, "TMPDIR": str(tmp), "PYTHONPATH": str(ROOT)})


def wait_for(path: Path, proc: subprocess.Popen, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert proc.poll() is None and time.monotonic() < deadline, proc.poll()
        time.sleep(0.05)


def results_of(hw: Path) -> dict:
    return {s: read_result(hw / "graded" / "results" / f"{s}.json") for s in STUDENTS}


def stable(results: dict) -> dict:
    return {s: replace(r, graded_at="") for s, r in results.items()}


def make_class(root: Path) -> tuple[Path, Path, Path]:
    hw, subs, tmp = root / "HW", root / "subs", root / "tmp"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in STUDENTS)), hw, FAMILIES,
                        problems=["inertia_tensor"], seed=3)
    subs.mkdir()
    tmp.mkdir()
    for sid in STUDENTS:
        nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
        if sid == "bob":
            nb["cells"].append({"cell_type": "code", "id": "slow", "metadata": {},
                                "outputs": [], "execution_count": None,
                                "source": f"import time; time.sleep({SLEEP})"})
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    return hw, subs, tmp


def left_behind(pid: int, tmp: Path) -> tuple[list[int], list[str]]:
    """Processes carrying grader ``pid``'s run marker, and run folders in ``tmp``."""
    deadline = time.monotonic() + 5
    while bench_load.marked(f"eulertop-{pid}-") and time.monotonic() < deadline:
        time.sleep(0.05)
    return (bench_load.marked(f"eulertop-{pid}-"),
            [p.name for p in tmp.iterdir() if RUN_FOLDER.fullmatch(p.name)])


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """One uninterrupted run; while bob sleeps in it, a second run on the same folder that
    will not wait long enough for it."""
    hw, subs, tmp = make_class(tmp_path_factory.mktemp("faults"))
    first = grade(hw, subs, tmp)
    try:
        wait_for(hw / "graded" / "results" / "alice.json", first)  # bob is sleeping now
        second = grade(hw, subs, tmp, "--wait", "0.5")
        second_code = second.wait(60)
        second_err = second.stderr.read()
        second.stderr.close()
        assert first.poll() is None  # the second one gave up while the first ran
        code = first.wait(60)
    finally:
        first.kill()
        first.stderr.close()
    return hw, subs, tmp, code, (second_code, second_err), results_of(hw), first.pid


def test_a_second_run_is_told_a_run_is_in_progress(reference):
    _, _, _, code, (second_code, second_err), results, _ = reference
    assert code == 0 and second_code == 2
    assert "waiting for another command" in second_err and "eulertop grade" in second_err
    assert "still holds this folder after 0.5 s" in second_err
    assert all(r is not None and r.status == "graded" for r in results.values())  # intact
    assert all(r.points == r.max_points and r.sandboxed for r in results.values())


def test_a_finished_run_leaves_nothing(reference):
    _, _, tmp, _, _, _, pid = reference
    assert left_behind(pid, tmp) == ([], [])


def test_sigkill_mid_run_then_rerun_equals_an_uninterrupted_run(reference, tmp_path):
    hw0, subs, *_ = reference
    hw = Path(shutil.copytree(hw0, tmp_path / "HW", ignore=shutil.ignore_patterns("graded")))
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    killed = grade(hw, subs, tmp)
    try:
        wait_for(hw / "graded" / "results" / "alice.json", killed)
        time.sleep(0.5)  # bob's kernel is running, carol's is prewarmed
        assert bench_load.marked(f"eulertop-{killed.pid}-")  # sandboxes, zygote, kernels
        os.kill(killed.pid, signal.SIGKILL)
        killed.wait()
    finally:
        killed.kill()
        killed.stderr.close()
    processes, folders = left_behind(killed.pid, tmp)
    assert processes == []  # bwrap --die-with-parent took every sandbox and kernel with it
    assert len(folders) == 1  # the killed run could not remove its run folder …
    assert not (hw / "graded" / "results" / "bob.json").exists()
    rerun = grade(hw, subs, tmp)
    assert rerun.wait(60) == 0
    rerun.stderr.close()
    assert stable(results_of(hw)) == stable(reference[5])  # complete, and as uninterrupted
    assert left_behind(rerun.pid, tmp) == ([], [])  # … the next run removed it
    assert not [p for p in (hw / "graded").rglob(".*") if p.name != ".lock"]


def test_grading_twice_gives_identical_records_but_the_timestamp(reference):
    hw, subs, tmp, *_, results, _ = reference
    again = grade(hw, subs, tmp, "--force")
    assert again.wait(60) == 0
    again.stderr.close()
    regraded = results_of(hw)
    assert all(regraded[s].graded_at >= results[s].graded_at for s in STUDENTS)
    assert stable(regraded) == stable(results)
    text = lambda r: json.dumps({k: v for k, v in r.to_dict().items()  # noqa: E731
                                 if k != "graded_at"}, sort_keys=True)
    assert [text(regraded[s]) for s in STUDENTS] == [text(results[s]) for s in STUDENTS]


def test_only_stale_run_folders_of_dead_graders_are_removed(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f"eulertop-{dead.pid}-0123abcd"
    (stale / "p0" / "0").mkdir(parents=True)
    (stale / "p0" / "0" / "left.txt").write_text("x")
    alive = tmp_path / f"eulertop-{os.getppid()}-0123abcd"  # a live process's
    alive.mkdir()
    lookalikes = [tmp_path / f"eulertop-{dead.pid}-0123abcdX", tmp_path / f"eulertop-{dead.pid}",
                  tmp_path / "eulertop-x-0123abcd", tmp_path / f"other-{dead.pid}-0123abcd"]
    for p in lookalikes:
        p.mkdir()
    target = tmp_path / "not-ours"
    target.mkdir()
    (target / "keep.txt").write_text("keep")
    link = tmp_path / f"eulertop-{dead.pid}-fedcba98"
    link.symlink_to(target)
    assert remove_stale_run_folders(tmp_path) == [stale]
    assert not stale.exists() and alive.exists() and all(p.exists() for p in lookalikes)
    assert (target / "keep.txt").read_text() == "keep" and link.is_symlink()


def test_a_live_run_folder_is_kept_whatever_its_pid_says(tmp_path):
    """A grader in another PID namespace sharing /tmp names its folder by a pid this one cannot
    see: its folder must survive this one's sweep while that grader holds its owner lock (it
    once did not: a live run's folder was removed under it, and the run failed), and go once
    that grader has gone."""
    from grader.sandbox import OWNER

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    elsewhere = tmp_path / f"eulertop-{dead.pid}-0123abcd"  # its pid means nothing here
    elsewhere.mkdir()
    holder = subprocess.Popen(
        [sys.executable, "-c", "import fcntl, os, sys, time\n"
         f"fd = os.open({str(elsewhere / OWNER)!r}, os.O_RDWR | os.O_CREAT, 0o600)\n"
         "fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True); time.sleep(60)"],
        stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        assert remove_stale_run_folders(tmp_path) == [] and elsewhere.is_dir()
    finally:
        holder.kill()
        holder.wait()
    assert remove_stale_run_folders(tmp_path) == [elsewhere]  # its grader gone: stale


def test_a_crowd_with_attackers_is_graded_and_leaves_nothing(tmp_path):
    """The small version of ``benchmarks/bench_load.py``: 20 submissions, 2 adversarial."""
    r = bench_load.run_load(tmp_path, students=20, jobs=2, timeout=20,
                            attacks=bench_load.KEEP_ATTACKS)
    assert r["exit"] == 0, r["stderr"]
    assert r["honest"] == 18 and r["honest_wrong"] == []
    assert sorted(a for a, _, _ in r["attackers"].values()) == ["fork_bomb", "orphan"]
    assert r["sandboxed"]
    assert r["left_processes"] == [] and r["left_folders"] == []
