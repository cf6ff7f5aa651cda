"""The progress display of a grading run, on stderr.

On a terminal, one line redrawn in place (a bar, the counts, the last student); anywhere else
(a log, a CI job, a pipe) one plain line per finished student, so nothing is full of ``\\r``.
Called from the worker threads, hence the lock: this is the run's one piece of shared state.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import sys
import threading
from typing import TextIO

from grader.gradebook import number
from grader.plain_text import printable
from grader.results import StudentResult

BAR_WIDTH = 24


class Progress:
    """Counts finished students out of ``total`` and shows it (module docstring)."""

    def __init__(self, total: int, stream: TextIO | None = None, tty: bool | None = None):
        self.total = total
        self.stream = sys.stderr if stream is None else stream
        self.tty = self.stream.isatty() if tty is None else tty
        self.done = 0
        self.failed = 0
        self._lock = threading.Lock()

    def __call__(self, result: StudentResult) -> None:
        """One more student finished."""
        with self._lock:
            self.done += 1
            self.failed += result.status == "failed"
            self.stream.write(self._line(result))
            self.stream.flush()

    def _line(self, r: StudentResult) -> str:
        score = f"{number(r.points)}/{number(r.max_points)}" if r.status == "graded" else r.status
        who = printable(r.student_id, newlines=False)
        if not self.tty:
            return f"[{self.done}/{self.total}] {who}: {score}\n"
        filled = BAR_WIDTH * self.done // max(self.total, 1)
        bar = "#" * filled + "-" * (BAR_WIDTH - filled)
        failed = f", {self.failed} failed" if self.failed else ""
        end = "\n" if self.done == self.total else ""
        return f"\r\x1b[K[{bar}] {self.done}/{self.total}{failed}  {who}: {score}{end}"
