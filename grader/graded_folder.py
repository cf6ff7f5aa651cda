"""The output folder of a class run (floor 4): its layout, its default (``HW/graded``) and the
lock that keeps two runs apart. Only the run writes records; the report and the LMS exports
read them by this layout.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from grader.assignment import UsageError

RESULTS, FEEDBACK, GRADES, LOCK = "results", "feedback", "grades.csv", ".lock"
ANSWERS, DOWNLOAD, LMS_SUBMISSIONS = "answers.csv", "download", "submissions.csv"
REPORT = "report.html"
"""The class report's page (with its CSV files beside it)."""


def graded_folder(hw: Path, out: Path | None = None) -> Path:
    """The output folder: ``out`` if given, else ``HW/graded`` (the one place that default is
    derived)."""
    return Path(hw) / "graded" if out is None else Path(out)


class RunInProgress(UsageError):
    """Another grading run holds the output folder's lock."""


@contextmanager
def run_lock(out: Path) -> Iterator[None]:
    """Hold ``OUT/.lock`` (``fcntl.flock``) for the run, or raise :class:`RunInProgress`.

    The file is removed when the run ends. Removing a lock file races with a run that opened it
    just before: that run could then lock the removed file while a third run creates and locks
    a new one. So a run that gets the lock checks that the path still names the file it locked
    (same device and inode) and otherwise opens it again; the holder removes it only while it
    still holds the lock.
    """
    path = out / LOCK
    for _ in range(100):
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip()
            os.close(fd)
            who = f" (pid {holder})" if holder.isdigit() else ""
            raise RunInProgress(f"{out}: another 'eulertop grade' run{who} is in progress on "
                                "this folder; wait for it to finish") from None
        if _same_file(fd, path):
            break
        os.close(fd)  # locked a file that its holder removed meanwhile: take the new one
    else:
        raise RunInProgress(f"{out}: cannot take the lock {path} (it keeps being replaced)")
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
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
