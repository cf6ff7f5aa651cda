"""The class report written (``OUT/report.html`` and its two CSV files beside it): the last
step, composing :mod:`grader.report.assemble` (the analyses) and :mod:`grader.report.page`.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from grader.assignment import Assignment, load_assignment
from grader.gradebook import gradebook_csv
from grader.graded_folder import REPORT, graded_folder
from grader.report.assemble import ClassReport, build_report, items_csv
from grader.report.classdata import load_class
from grader.report.page import report_html
from grader.report.students import student_rows
from grader.results import atomic_write_text


def companion_paths(page: Path) -> tuple[Path, Path]:
    """The CSV files written beside a page: ``report.html`` → ``report.csv`` (students) and
    ``report_items.csv`` (items)."""
    page = Path(page)
    return page.with_suffix(".csv"), page.with_name(f"{page.stem}_items.csv")


def report_files(report: ClassReport, page: Path) -> dict[Path, str]:
    """The page (at ``page``) and its two CSV files beside it (:func:`companion_paths`): each
    path and its text, written by the caller (a class's change stages them in its
    transaction)."""
    page = Path(page)
    students_path, items_path = companion_paths(page)
    table = student_rows(report.data, report.slips, report.pairs, report.code)
    students = gradebook_csv(table)
    return {students_path: students, items_path: items_csv(report),
            page: report_html(report, table, students, students_path.name)}


def write_report(report: ClassReport, page: Path) -> Path:
    """Write the page to ``page`` and its two CSV files beside it (:func:`report_files`),
    each atomically; returns ``page``."""
    page = Path(page)
    page.parent.mkdir(parents=True, exist_ok=True)
    for path, text in report_files(report, page).items():
        atomic_write_text(path, text)
    return page


def report_for(hw: Path | Assignment, graded: Path | None = None,
               submissions: Mapping[str, Path] | None = None,
               page: Path | None = None) -> tuple[ClassReport, Path]:
    """Load, analyse and write in one call: ``(report, path of the page)``; the page goes to
    ``page`` (default ``GRADED/report.html``, ``GRADED`` defaulting to ``hw/graded``). ``hw``:
    the assignment folder, or the assignment already loaded from it."""
    a = hw if isinstance(hw, Assignment) else load_assignment(hw)
    graded = graded_folder(a.folder, graded)
    data = load_class(a, graded)
    report = build_report(data, submissions)
    return report, write_report(report, graded / REPORT if page is None else page)
