"""Ctrl-C during ``eulertop grade`` in a real terminal (issue 13): one Ctrl-C stops the run
within seconds with exit status 130 and says how many were graded; no student in flight is
recorded (least of all as "failed"); the sandboxes, in sessions of their own, never see the
terminal's SIGINT; the resumed run's grades equal an uninterrupted run's."""

from __future__ import annotations

import fcntl
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import termios
import time
from dataclasses import replace
from pathlib import Path

import pytest
from nbformat.v4 import new_code_cell

from grader.results import read_result
from grader.sandbox import available
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

ROOT = Path(__file__).resolve().parents[2]
STUDENTS = tuple(f"s{i}" for i in range(8))


@pytest.fixture(scope="module")
def slow_class(tmp_path_factory):
    """Eight correct submissions that each take about two seconds."""
    if available() is None:
        pytest.fail("bubblewrap is not installed (README); this test must run", pytrace=False)
    root = tmp_path_factory.mktemp("interrupt")
    hw, subs = root / "HW", root / "subs"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in STUDENTS)), hw, FAMILIES,
                        problems=["inertia_tensor"], seed=8)
    subs.mkdir()
    for sid in STUDENTS:
        nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
        nb["cells"].insert(1, new_code_cell("import time\ntime.sleep(2)", id="slow"))
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    return hw, subs


def _grade_argv(hw: Path, subs: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "eulertop", "grade", str(hw), str(subs), "--out", str(out),
            "--jobs", "2"]


def _in_terminal(argv: list[str]) -> tuple[subprocess.Popen, int]:
    """Start ``argv`` as the foreground job of a new pseudo-terminal; (process, master fd)."""
    master, slave = os.openpty()

    def controlling_terminal() -> None:
        fcntl.ioctl(0, termios.TIOCSCTTY, 0)
        # as a shell does for a foreground job: a test run started in the background (where
        # SIGINT is ignored, and a child inherits that) must not make Ctrl-C do nothing
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen(argv, stdin=slave, stdout=slave, stderr=slave, cwd=ROOT,
                            start_new_session=True, preexec_fn=controlling_terminal)
    os.close(slave)
    return proc, master


def _read_all(master: int) -> str:
    chunks = []
    while select.select([master], [], [], 0.1)[0]:
        try:
            chunk = os.read(master, 65536)
        except OSError:
            break
        if not chunk:
            break
        chunks.append(chunk)
    return b"".join(chunks).decode(errors="replace")


def _stable(r):
    return replace(r, graded_at="")


def test_one_ctrl_c_stops_the_run_and_the_resumed_run_equals_an_uninterrupted_one(
        slow_class, tmp_path):
    hw, subs = slow_class
    out = tmp_path / "interrupted"
    proc, master = _in_terminal(_grade_argv(hw, subs, out))
    screen = []
    try:
        deadline = time.monotonic() + 120
        while not list((out / "results").glob("*.json")):  # the first student is done
            assert proc.poll() is None and time.monotonic() < deadline
            screen.append(_read_all(master))
        time.sleep(0.3)
        os.write(master, b"\x03")  # Ctrl-C, as typed: the terminal sends SIGINT
        t0 = time.monotonic()
        code = proc.wait(timeout=30)
        seconds = time.monotonic() - t0
        screen.append(_read_all(master))
    finally:
        if proc.poll() is None:
            proc.kill()
        os.close(master)
    text = "".join(screen)
    assert code == 130, text[-2000:]
    assert seconds < 8, seconds
    kept = {p.stem: read_result(p) for p in (out / "results").glob("*.json")}
    assert 1 <= len(kept) < len(STUDENTS)
    assert f"interrupted after grading {len(kept)} of {len(STUDENTS)}" in text
    assert "run the same command again" in text
    for r in kept.values():  # what was recorded is whole; nobody was recorded as failed
        assert r.status == "graded" and r.points == r.max_points, r.message
    assert not list((out / "results").glob(".*.tmp"))
    assert not (out / ".lock").exists()

    resumed = subprocess.run(_grade_argv(hw, subs, out), cwd=ROOT, capture_output=True,
                             text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert f"{len(kept)} unchanged, kept" in resumed.stdout
    reference = tmp_path / "uninterrupted"
    whole = subprocess.run(_grade_argv(hw, subs, reference), cwd=ROOT, capture_output=True,
                           text=True, timeout=300)
    assert whole.returncode == 0, whole.stderr[-2000:]
    for sid in STUDENTS:
        a = read_result(out / "results" / f"{sid}.json")
        b = read_result(reference / "results" / f"{sid}.json")
        assert _stable(a) == _stable(b), sid
    assert (out / "grades.csv").read_text() == (reference / "grades.csv").read_text()
    shutil.rmtree(out)
