"""What discovery finds (floor 0): a :class:`Submission` to grade, a :class:`Problem` that
cannot be graded as it stands, and the whole :class:`Discovery` of a submissions folder —
shared by :mod:`grader.discover` and every LMS format of :mod:`grader.lms`.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

SUFFIX = ".ipynb"


@dataclass(frozen=True)
class Submission:
    """The one notebook submitted by a roster student."""

    student_id: str
    path: Path
    late: bool = False  # the LMS marked it late (grader/lms)
    source: str = ""  # how an LMS download matched it to the student (grader/lms)
    submitted_at: str = ""  # when it came in, as the LMS wrote it ("": it does not say)
    time_source: str = ""  # where that time is from, for people ("Gradescope's created_at")


@dataclass(frozen=True)
class Problem:
    """Something in SUBMISSIONS that cannot be graded as it stands.

    ``student_id`` is the roster id it concerns, or None when it concerns no roster student.
    ``ignored`` marks a stray file that is not a submission at all (reported, not counted as
    an ungraded submission).
    """

    path: Path
    message: str
    student_id: str | None = None
    ignored: bool = False


@dataclass(frozen=True)
class Discovery:
    """The submissions folder sorted out (module docstring); tuples in roster / name order."""

    submissions: tuple[Submission, ...]
    missing: tuple[str, ...]
    problems: tuple[Problem, ...]
    notes: tuple[str, ...] = ()  # what an LMS download's matching decided (late, newest …)
    layout: str = "folder"  # or the LMS whose bulk download it was (grader/lms)
    set_aside: tuple[Problem, ...] = ()  # files matched to a student and not graded, and why
