"""A class's records written, and the views of them rebuilt (floor 6): each record with its
feedback page as soon as it is made (:func:`publish_record`), then the gradebook, the answers
table, every page and the class report from the records on disk (:func:`rebuild`,
:func:`class_report`) — what a grading run and a rescore both end with.

Floor 6 of grader/ (where grade_one runs; where submissions come from; grader/API.md).
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Mapping, Sequence, Set
from contextlib import suppress
from pathlib import Path

from grader.assignment import Assignment
from grader.gradebook import answers_rows, feedback_html, gradebook_csv, gradebook_rows, ran_code
from grader.graded_folder import ANSWERS, FEEDBACK, GRADES, REPORT, RESULTS
from grader.results import StudentResult, atomic_write_text, write_result


def publish_record(a: Assignment, out: Path, result: StudentResult, reveal: bool) -> None:
    write_result(out / RESULTS, result)
    key = None
    if reveal:
        key = {k.variable: k.answer.value for k in a.expected(result.student_id)}
    page = feedback_html(a.title, result, a.students[result.student_id]["questions"], key)
    atomic_write_text(out / FEEDBACK / f"{result.student_id}.html", page)


def publish_all(a: Assignment, out: Path, results: Sequence[StudentResult], reveal: bool,
                 progress: Callable[[StudentResult], None] | None) -> None:
    """Publish the records that need no kernel (missing, invalid, unchanged-but-rewritten)."""
    for result in results:
        publish_record(a, out, result, reveal)
        if progress:
            progress(result)


def prepare_report() -> None:
    """Import what the class report draws with (matplotlib: about a second) in a thread of
    its own, while the kernels' zygotes start — when the grader has nothing else to do."""
    def load() -> None:
        with suppress(Exception):
            import grader.report.page  # noqa: F401

    threading.Thread(target=load, name="eulertop-report-imports", daemon=True).start()


def class_report(a: Assignment, out: Path, results: Mapping[str, StudentResult | None],
                 notebooks: Mapping[str, Path]) -> None:
    """``OUT/report.html`` (:mod:`grader.report`), its code comparison over ``notebooks``
    (student id → the notebook graded); a fault there is reported, never fatal to the grades
    already written."""
    from grader.report import build_report, write_report
    from grader.report.classdata import class_data

    try:
        report = build_report(class_data(a, results), dict(notebooks))
        write_report(report, out / REPORT)
    except Exception as e:
        sys.stderr.write(f"eulertop grade: the class report could not be written "
                         f"({type(e).__name__}: {e}); the grades are complete\n")


def rebuild(a: Assignment, out: Path, results: Mapping[str, StudentResult | None],
             reveal: bool, published: Set[str] = frozenset()) -> None:
    """The gradebook and every feedback page, from the records on disk; but the pages of
    ``published`` (written by :func:`publish_record` in this run, from these same records)."""
    present = {sid: r for sid, r in results.items() if r is not None}
    unsandboxed = any(ran_code(r) and not r.sandboxed for r in present.values())
    table = gradebook_rows(a.columns, a.rows, a.questions, present, sandbox_column=unsandboxed)
    atomic_write_text(out / GRADES, gradebook_csv(table))
    atomic_write_text(out / ANSWERS, gradebook_csv(answers_rows(a.rows, present)))
    for sid, r in present.items():
        if sid in published:
            continue
        key = ({k.variable: k.answer.value for k in a.expected(sid)} if reveal else None)
        page = feedback_html(a.title, r, a.students[sid]["questions"], key)
        atomic_write_text(out / FEEDBACK / f"{sid}.html", page)


def report_notebooks(out: Path) -> dict[str, Path]:
    """The notebooks the last grading run of ``out`` graded (from its audit trail), those still
    there: what a rescore's class report compares, as that run's did."""
    from grader.audit import read_trail

    for line in reversed(read_trail(out)):
        if line.get("event") == "grade" and "notebooks" in line:
            return {sid: Path(p) for sid, p in line["notebooks"].items() if Path(p).is_file()}
    return {}
