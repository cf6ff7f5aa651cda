"""The family self-test's run of a solutions notebook (``eulertop problems test``): the notebook
run as a submission (:func:`grader.grade_one.run_one`: the same safe read, sandbox and retries
as a student's) and compared with its key — the grader's half of
:func:`problems.selftest.full_marks`, handed to it by the front end.

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import time
from pathlib import Path

from grader.compare import compare, key_answers, variable_names
from grader.grade_one import run_one
from grader.limits import Limits
from problems.selftest import SolutionsRun


def grade_solutions(notebook: Path, key_entry: dict, seconds: float) -> SolutionsRun:
    """Run ``notebook`` as a submission within ``seconds`` and compare its answers with
    ``key_entry`` (one student's entry of ``key.json``); the verdicts."""
    expected = key_answers({"students": {"selftest": key_entry}}, "selftest")
    start = time.monotonic()
    run = run_one(Path(notebook), variable_names(expected), Limits(total_timeout=seconds))
    duration = time.monotonic() - start
    if run.execution is None:
        return SolutionsRun("error", run.problem, (), False, duration)
    execution = run.execution
    results = compare(expected, execution.answers)
    verdicts = tuple((r.question, r.variable, r.verdict.status, r.verdict.message)
                     for r in results)
    return SolutionsRun(execution.status, execution.message, verdicts,
                        bool(execution.sandboxed), duration)
