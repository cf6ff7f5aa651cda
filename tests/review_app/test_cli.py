"""``eulertop review`` as a TA runs it (issue 31): a process that prints its address with the
token and serves until Ctrl-C, then rebuilds the class report; two such processes on one class
with reviews sent to both at once, every one landing attributed; usage errors in one line."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from grader.audit import read_trail
from grader.reviews import REVIEWS
from tests.review_app.client import ask
from tests.review_app.desk_class import FAMILY_WRITTEN, OWN, RUBRIC

ROOT = Path(__file__).resolve().parents[2]


class Desk:
    """``eulertop review HW --no-browser --grader NAME`` in a process of its own."""

    def __init__(self, hw: Path, grader: str, *extra: str) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "eulertop", "review", str(hw), "--no-browser",
             "--grader", grader, *extra], cwd=ROOT, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.lines = [self.process.stdout.readline() for _ in range(3)]
        found = re.search(r"http://127\.0\.0\.1:\d+/\?token=\S+", "".join(self.lines))
        assert found, [*self.lines, self.process.stderr.read()]
        self.url = found.group(0)

    def stop(self) -> tuple[int, str, str]:
        self.process.send_signal(signal.SIGINT)
        out, err = self.process.communicate(timeout=60)
        return self.process.returncode, out, err


def _ids(desk: Desk, question: str) -> dict[str, str]:
    rows = ask(desk.url, "GET", f"/api/written?question={question}&names=1").json()
    return {r["student"]: r["id"] for r in rows if r["status"] == "pending"}


def test_the_command_prints_its_address_serves_and_stops_on_ctrl_c(desk_class):
    report = desk_class.out / "report.html"
    before = report.read_text(encoding="utf-8")
    desk = Desk(desk_class.hw, "ta-cli")
    assert desk.lines[0].startswith("eulertop review: Torque-free spin: 2 written question(s), "
                                    "6 student(s), reviewing as ta-cli")
    assert ask(desk.url, "GET", "/api/questions", token=None).status == 401
    answer = _ids(desk, OWN)["dee"]
    reply = ask(desk.url, "POST", "/api/review", {"id": answer, "rubric": [0, 1, 2]})
    assert reply.json()["points"] == sum(RUBRIC)
    status, out, err = desk.stop()
    assert status == 0 and "stopping" in out and "Traceback" not in err
    after = report.read_text(encoding="utf-8")
    assert after != before and "Written answers" in after
    with pytest.raises(OSError):  # nothing listens there any more
        socket.create_connection(("127.0.0.1", int(desk.url.split(":")[2].split("/")[0])), 2)


def test_two_desk_processes_on_one_class_review_at_once(desk_class):
    """Each process sends its reviews as fast as it can, both at once (one thread each):
    every review lands in reviews.json and the trail, signed by its desk's grader, and each
    desk lists the other's."""
    desks = {"ta-a": Desk(desk_class.hw, "ta-a"), "ta-b": Desk(desk_class.hw, "ta-b")}
    plans = {"ta-a": (OWN, _ids(desks["ta-a"], OWN)),
             "ta-b": (FAMILY_WRITTEN, _ids(desks["ta-b"], FAMILY_WRITTEN))}
    start, errors = threading.Barrier(2), []

    def review(grader: str) -> None:
        ids = plans[grader][1]
        start.wait()
        for answer in ids.values():
            reply = ask(desks[grader].url, "POST", "/api/review", {"id": answer, "rubric": [0]})
            if reply.status != 200:
                errors.append(reply.text)

    threads = [threading.Thread(target=review, args=(g,)) for g in desks]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert errors == []
    want = sorted((sid, question, grader) for grader, (question, ids) in plans.items()
                  for sid in ids)
    assert len(want) == 11
    stored = json.loads((desk_class.out / REVIEWS).read_text())["reviews"]
    assert sorted((r["student"], r["answer"], r["by"]) for r in stored) == want
    lines = [x for x in read_trail(desk_class.out) if x["event"] == "review"]
    assert sorted((x["student"], x["answer"], x["review"]["by"]) for x in lines) == want
    for grader, desk in desks.items():
        other = "ta-b" if grader == "ta-a" else "ta-a"
        question = plans[other][0]
        rows = ask(desk.url, "GET", f"/api/written?question={question}").json()
        assert {r["review"]["by"] for r in rows if r["review"]} == {other}
    for desk in desks.values():
        assert desk.stop()[0] == 0


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "eulertop", "review", *args, "--no-browser"],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)


def test_usage_errors_are_one_line_and_exit_2(desk_class, tmp_path):
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    port = taken.getsockname()[1]
    try:
        cases = {"nothing graded": _run(str(tmp_path)),
                 "a port in use": _run(str(desk_class.hw), "--port", str(port)),
                 "no such port": _run(str(desk_class.hw), "--port", "70000")}
    finally:
        taken.close()
    for why, done in cases.items():
        lines = done.stderr.strip().splitlines()
        assert (done.returncode, len(lines)) == (2, 1), (why, done.stderr)
        assert lines[0].startswith("eulertop review: ") and "Traceback" not in done.stderr
    assert f"--port {port}" in cases["a port in use"].stderr


def test_the_browser_is_opened_through_a_private_file(desk_class, tmp_path):
    """Without --no-browser the address goes to the browser in a file only its user can
    read, never on a command line; here the 'browser' is a script that records what it was
    given (BROWSER, as Python's webbrowser reads it)."""
    seen = tmp_path / "seen.txt"
    browser = tmp_path / "browser.sh"
    browser.write_text(f'#!/bin/sh\necho "$1" > {seen}\nstat -c %a "${{1#file://}}" >> {seen}\n'
                       f'cat "${{1#file://}}" >> {seen}\n')
    browser.chmod(0o755)
    process = subprocess.Popen(
        [sys.executable, "-m", "eulertop", "review", str(desk_class.hw)], cwd=ROOT,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "BROWSER": str(browser), "PYTHONUNBUFFERED": "1"})
    url = re.search(r"http://\S+", "".join(process.stdout.readline() for _ in range(2))).group(0)
    for _ in range(100):
        if seen.exists() and len(seen.read_text().splitlines()) >= 3:
            break
        time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    process.communicate(timeout=60)
    given, mode, *page = seen.read_text().splitlines()
    assert given.startswith("file://") and url not in given
    assert mode == "600" and url.replace("&", "&amp;") in "".join(page)
    assert not Path(given.removeprefix("file://")).exists()  # removed when the desk stops
