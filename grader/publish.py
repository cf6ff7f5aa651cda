"""A class's records and the views of them, staged into the transaction that changes them: one
record with its feedback page (:func:`stage_record`), then the gradebook, the answers table,
every other page and the class report from the records (:func:`stage_views`,
:func:`stage_report`) — what a grading run and a rescore both end with; and what every record
goes through before it is written, in that order: follow-through credit, the reviews of its
written answers, then the instructor's overrides (:func:`settled`).

Floor 6 of grader/ (where grade_one runs; where submissions come from; grader/API.md).
"""

from __future__ import annotations

import json
import sys
import threading
from collections.abc import Callable, Mapping, Sequence, Set
from contextlib import suppress
from pathlib import Path
from typing import Any

from grader.assignment import Assignment
from grader.follow_through import FollowThrough
from grader.gradebook import feedback_html
from grader.graded_folder import ANSWERS, FEEDBACK, GRADES, PAGES, REPORT, RESULTS
from grader.late import policy_of
from grader.overrides import Override, apply_overrides
from grader.results import StudentResult, read_result, result_json
from grader.reviews import Reviews, apply_reviews
from grader.table_rows import answers_lines, grades_line, headers, spliced, table_columns
from grader.transaction import Transaction

NO_REVIEWS = Reviews()


def settled(a: Assignment, result: StudentResult, follow: FollowThrough | None,
            overrides: Sequence[Override], reviews: Reviews = NO_REVIEWS) -> StudentResult:
    """``result`` (compared with the key) as it is recorded: follow-through credit, the
    reviews of its written answers (:func:`grader.reviews.apply_reviews`), then the overrides
    of answers, the late penalty and an override of the total
    (:func:`grader.overrides.apply_overrides`) — the one way every record of a grading run and
    of a rescore is finished."""
    if follow is not None:
        result = follow.apply(result, a.expected(result.student_id))
    result = apply_reviews(result, reviews, a.written_expected(result.student_id))
    return apply_overrides(result, overrides, policy_of(a.manifest))


def _page(a: Assignment, result: StudentResult, reveal: bool) -> str:
    key = None
    if reveal:
        key = {k.variable: k.answer.value for k in a.expected(result.student_id)}
    return feedback_html(a.title, result, a.students[result.student_id]["questions"], key)


def stage_record(tx: Transaction, a: Assignment, out: Path, result: StudentResult,
                 reveal: bool) -> None:
    """Stage ``result``'s record and its feedback page."""
    tx.write(out / RESULTS / f"{result.student_id}.json", result_json(result))
    tx.write(out / FEEDBACK / f"{result.student_id}.html", _page(a, result, reveal),
             durable=False)


def prepare_report() -> None:
    """Import what the class report draws with (matplotlib: about a second) in a thread of
    its own, while the kernels' zygotes start — when the grader has nothing else to do."""
    def load() -> None:
        with suppress(Exception):
            import grader.report.page  # noqa: F401

    threading.Thread(target=load, name="eulertop-report-imports", daemon=True).start()


def stage_report(tx: Transaction, a: Assignment, out: Path,
                 results: Mapping[str, StudentResult | None],
                 notebooks: Mapping[str, Path], command: str = "eulertop grade") -> None:
    """Stage ``OUT/report.html`` (:mod:`grader.report`) with its code comparison over
    ``notebooks`` (student id → the notebook graded); a fault there is reported and leaves the
    old report, never stopping the grades."""
    from grader.report import build_report
    from grader.report.classdata import class_data
    from grader.report.write import report_files

    try:
        report = build_report(class_data(a, results), dict(notebooks))
        files = report_files(report, out / REPORT)
    except Exception as e:
        sys.stderr.write(f"{command}: the class report could not be written "
                         f"({type(e).__name__}: {e}); the grades are complete\n")
        return
    for path, text in files.items():
        tx.write(path, text, durable=False)


class RowCache:
    """Each student's encoded rows of ``grades.csv`` and ``answers.csv``, kept with the record
    (the very object) and the table's columns they were made from: a change that rewrites a
    few records of a class held in memory re-encodes only their rows (the review desk's
    reviews, :mod:`grader.review`). A CSV is encoded row by row, so the rows joined are the
    table's text, byte for byte."""

    def __init__(self) -> None:
        self._rows: dict[tuple[str, str], tuple[Any, Any, str]] = {}

    def text(self, table: str, sid: str, record: StudentResult | None, columns: Any,
             make: Callable[[], str]) -> str:
        """``make()``, or what it gave for the same record and columns before."""
        hit = self._rows.get((table, sid))
        if hit is not None and hit[0] is record and hit[1] == columns:
            return hit[2]
        text = make()
        self._rows[(table, sid)] = (record, columns, text)
        return text

    def fill(self, a: Assignment, results: Mapping[str, StudentResult | None]) -> None:
        """Every row of ``results`` encoded now (a session's load), not at its first change."""
        _tables(a, {sid: r for sid, r in results.items() if r is not None}, self)


def _tables(a: Assignment, present: Mapping[str, StudentResult],
            cache: RowCache) -> tuple[str, str]:
    """The text of ``grades.csv`` and ``answers.csv``, row by row through ``cache``."""
    columns = table_columns(a, present)
    key = tuple(sorted(columns.items()))
    grades, answers = ([head] for head in headers(a, columns))
    for row in a.rows:
        sid, r = row["id"], present.get(row["id"])
        grades.append(cache.text("grades", sid, r, (key, a.columns),
                                 lambda row=row, r=r: grades_line(a, row, r, columns)))
        answers.append(cache.text("answers", sid, r, None,
                                  lambda row=row, r=r: answers_lines(row, r)))
    return "".join(grades), "".join(answers)


REPORT_STALE = '<p class="stale" role="status">'
"""The notice a report page carries once the grades changed after it was made."""


def stale_page(text: str) -> str | None:
    """The report page ``text`` with :data:`REPORT_STALE`'s notice at the top of its body (None when
    it has one already): the grades changed since it was made, by a change that does not
    rebuild the report (an override, a review, an extension)."""
    if REPORT_STALE in text or "<body>" not in text:
        return None
    notice = (f"{REPORT_STALE}<strong>Out of date:</strong> grades changed after this report was "
              "made (an override, a review or an extension). <code>eulertop report HW</code>, "
              "or the next <code>eulertop rescore</code> or <code>eulertop grade</code>, "
              "brings it up to date.</p>")
    return text.replace("<body>", "<body>" + notice, 1)


def stage_stale_report(tx: Transaction, out: Path) -> None:
    """Stage ``OUT/report.html`` with its out-of-date notice (:func:`stale_page`), for a change
    that leaves the report to a later command; nothing when there is no report or it has the
    notice already."""
    try:
        text = (out / REPORT).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return
    marked = stale_page(text)
    if marked is not None:
        tx.write(out / REPORT, marked, durable=False)


def stage_views(tx: Transaction, a: Assignment, out: Path,
                results: Mapping[str, StudentResult | None], reveal: bool,
                published: Set[str] = frozenset(), pages: Set[str] | None = None,
                cache: RowCache | None = None) -> None:
    """Stage the gradebook, the answers table and the feedback pages of ``pages`` (None: every
    student, and :data:`~grader.graded_folder.PAGES` saying what they show) from ``results``;
    but the pages of ``published`` (staged with their records). A file whose text is unchanged
    is left as it is (:meth:`Transaction.write`). ``cache``: the rows of records met before,
    kept (:class:`RowCache`)."""
    present = {sid: r for sid, r in results.items() if r is not None}
    grades, answers = _tables(a, present, cache if cache is not None else RowCache())
    tx.write(out / GRADES, grades, durable=False)
    tx.write(out / ANSWERS, answers, durable=False)
    for sid, r in present.items():
        if sid not in published and (pages is None or sid in pages):
            tx.write(out / FEEDBACK / f"{sid}.html", _page(a, r, reveal), durable=False)
    if pages is None:  # every page is as ``reveal`` says now
        tx.write(out / PAGES, json.dumps({"reveal": reveal}) + "\n", durable=False)


def pages_reveal(out: Path) -> bool | None:
    """Whether every feedback page in ``out`` shows its student's key values (:data:`PAGES`):
    None where that is not known (pages written before it was kept, or since mixed)."""
    try:
        reveal = json.loads((out / PAGES).read_text(encoding="utf-8")).get("reveal")
    except (OSError, UnicodeDecodeError, ValueError, AttributeError):
        return None
    return reveal if type(reveal) is bool else None


def stage_scoped_views(tx: Transaction, a: Assignment, out: Path,
                       before: Mapping[str, StudentResult | None],
                       after: Mapping[str, StudentResult | None], reveal: bool,
                       published: Set[str] = frozenset()) -> None:
    """Stage the gradebook and the answers table of a change that read only the records of
    the students it reached (``before``: as they were, ``after``: as they are now): their
    lines made again and every other line's bytes kept (:func:`grader.table_rows.spliced`);
    where the files cannot tell that, the other records are read and the tables made whole
    (:func:`stage_views`), as a change of the whole class makes them. Either way the same
    text. No page but those of ``published`` (staged with their records)."""
    tables = spliced(a, out, before, after)
    if tables is None:
        others = records(a, out, frozenset(a.ids) - frozenset(after))
        stage_views(tx, a, out, {**others, **after}, reveal, published, pages=frozenset())
        return
    tx.write(out / GRADES, tables[0], durable=False)
    tx.write(out / ANSWERS, tables[1], durable=False)


def report_notebooks(out: Path) -> dict[str, Path]:
    """The notebooks the last grading run of ``out`` graded (from its audit trail), those still
    there: what a rescore's class report compares, as that run's did."""
    from grader.audit import read_trail

    for line in reversed(read_trail(out)):
        if line.get("event") == "grade" and "notebooks" in line:
            return {sid: Path(p) for sid, p in line["notebooks"].items() if Path(p).is_file()}
    return {}


def records(a: Assignment, out: Path,
            only: Set[str] | None = None) -> dict[str, StudentResult | None]:
    """Every roster student's record in ``out`` (None: none yet); ``only``: those of the
    students it names, alone."""
    return {sid: read_result(out / RESULTS / f"{sid}.json") for sid in a.ids
            if only is None or sid in only}
