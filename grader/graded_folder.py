"""The output folder of a class run (floor 4): its layout, its default (``HW/graded``) and the
lock that keeps two commands apart. Only the run writes records; the report and the LMS exports
read them by this layout.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import fcntl
import os
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from grader.assignment import UsageError

RESULTS, FEEDBACK, GRADES, LOCK = "results", "feedback", "grades.csv", ".lock"
ANSWERS, DOWNLOAD, LMS_SUBMISSIONS = "answers.csv", "download", "submissions.csv"
REPORT = "report.html"
"""The class report's page (with its CSV files beside it)."""
PAGES = "pages.json"
"""What every feedback page shows: ``{"reveal": true}`` when each page has its student's key
values, ``false`` when none has, as the command that last wrote every page was told
(``--reveal``); absent where that is not known."""


def graded_folder(hw: Path, out: Path | None = None) -> Path:
    """The output folder: ``out`` if given, else ``HW/graded`` (the one place that default is
    derived)."""
    return Path(hw) / "graded" if out is None else Path(out)


class RunInProgress(UsageError):
    """Another command held the output folder's lock for longer than the caller would wait."""


def _holder(fd: int) -> str:
    """Who holds the lock, as its holder wrote it: ``pid 123: eulertop grade``, or ``""``."""
    pid, _, command = os.pread(fd, 256, 0).decode(errors="replace").strip().partition(" ")
    if not pid.isdigit():
        return ""
    return f"pid {pid}" + (f": {command}" if command else "")


def _take(path: Path, wait: float, out: Path, command: str) -> int:
    """An open descriptor of ``path`` holding its exclusive lock, waiting up to ``wait``
    seconds (saying so once on stderr); :class:`RunInProgress` after that."""
    deadline, said = time.monotonic() + wait, False
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            if time.monotonic() >= deadline:
                raise RunInProgress(
                    f"{out}: another command ({holder or 'a grading run'}) still holds this "
                    f"folder after {wait:g} s of waiting; run this again when it has finished "
                    "(or give --wait SECONDS)") from None
            if not said:
                sys.stderr.write(f"{command}: waiting for another command on {out} "
                                 f"({holder or 'its holder unknown'}) to finish …\n")
                said = True
            time.sleep(min(0.05, max(0.0, deadline - time.monotonic())))
            continue
        if _same_file(fd, path):
            return fd
        os.close(fd)  # locked a file that its holder removed meanwhile: take the new one


@contextmanager
def run_lock(out: Path, *, command: str = "eulertop grade", wait: float = 0.0) -> Iterator[None]:
    """Hold ``OUT/.lock`` (``fcntl.flock``) for the command, waiting up to ``wait`` seconds for
    one holding it; :class:`RunInProgress` after that. Every command that changes the class
    holds it while it reads, checks and writes, so that two never interleave
    (:func:`grader.transaction.class_lock`).

    The file is removed when the command ends. Removing a lock file races with a command that
    opened it just before: that one could then lock the removed file while a third creates and
    locks a new one. So a command that gets the lock checks that the path still names the file
    it locked (same device and inode) and otherwise opens it again; the holder removes it only
    while it still holds the lock.
    """
    path = out / LOCK
    fd = _take(path, wait, out, command)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()} {command}".encode(), 0)
        yield
    finally:
        try:
            if _same_file(fd, path):
                os.unlink(path)
        finally:
            os.close(fd)  # releases the lock


def _same_file(fd: int, path: Path) -> bool:
    """Does ``path`` still name the open file ``fd``?"""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (st.st_dev, st.st_ino) == (mine.st_dev, mine.st_ino)
