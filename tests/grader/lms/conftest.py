"""Helpers of the LMS tests: generate an assignment from an LMS class list, grade without kernels.

Grading uses the fake execution stage of ``tests/grader/test_pipeline.py`` (``FakeExecute``:
the answers are read from the notebook's literal assignments), so no kernel starts here; the
real execution runs once, end to end, in ``test_end_to_end.py``.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from grader.lms.registry import CLASS_LISTS
from grader.pipeline import grade_assignment
from problems.generate import generate_assignment
from problems.roster import read_roster as read_any_roster
from problems.templates import FAMILIES
from tests.grader.test_pipeline import FakeExecute


def read_roster(path, roster_format=None):
    """An eulertop roster or an LMS class list (the formats grader.lms knows)."""
    return read_any_roster(path, roster_format, CLASS_LISTS)

PROBLEMS = ["inertia_tensor", "euler_rotation"]


def generate(root: Path, class_list: str, content: str | bytes, **read) -> Path:
    """Write ``content`` as ``root/class_list``, read it as the roster, generate ``root/HW``."""
    path = root / class_list
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    hw = root / "HW"
    generate_assignment(read_roster(path, **read), hw, FAMILIES, problems=PROBLEMS, seed=11,
                        title="Homework 1")
    return hw


def grade(hw: Path, submissions: Path, **kw):
    """Grade with the fake execution stage; the run's report."""
    return grade_assignment(hw, submissions, limits="LIMITS", execute=FakeExecute(), jobs=2,
                            **kw)


def read_csv(path: Path, delimiter: str = ",") -> list[list[str]]:
    return list(csv.reader(io.StringIO(Path(path).read_text(encoding="utf-8"), newline=""),
                           delimiter=delimiter))


def results(report) -> dict:
    return {r.student_id: r for r in report.results}
