"""``grades.csv`` and ``answers.csv`` as each student's lines (issue 34): the one builder of a
student's lines of both tables (:func:`grades_line`, :func:`answers_lines`), the columns the
whole class decides (:func:`table_columns`), and the tables with a few students' lines made
again from their records while every other line keeps its bytes (:func:`spliced`) — what a
change of one student writes without reading the other records.

A CSV is encoded row by row (:func:`grader.gradebook.gradebook_csv`), every cell on one line
(control characters escaped), so a table's text is its header's line and then each roster
student's lines, in roster order, each ending in ``\\r\\n``: ``grades.csv`` one line a student,
``answers.csv`` one a recorded answer (none for a student without a record).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import csv
from collections.abc import Mapping
from itertools import product
from pathlib import Path

from grader.assignment import Assignment
from grader.gradebook import (
    ANSWER_COLUMNS,
    WRITTEN_STATUSES,
    answers_rows,
    gradebook_csv,
    gradebook_rows,
    ran_code,
)
from grader.graded_folder import ANSWERS, GRADES
from grader.results import StudentResult

END = "\r\n"
"""The end of every line of a table."""

COLUMNS = ("sandbox_column", "override_column", "late_columns", "pending_column")
"""The optional columns of ``grades.csv`` (:func:`grader.gradebook.gradebook_rows`)."""

Records = Mapping[str, StudentResult | None]


def table_columns(a: Assignment, present: Mapping[str, StudentResult]) -> dict[str, bool]:
    """Which optional columns ``grades.csv`` has, as the assignment and the records
    ``present`` (the whole class's) decide them."""
    return {"sandbox_column": any(ran_code(r) and not r.sandboxed for r in present.values()),
            "override_column": any(r.overridden for r in present.values()),
            "late_columns": "late" in a.manifest or any(r.late for r in present.values()),
            "pending_column": bool(a.written()) or any(
                x.verdict.status in WRITTEN_STATUSES for r in present.values()
                for x in r.answers)}


def headers(a: Assignment, columns: Mapping[str, bool]) -> tuple[str, str]:
    """The header lines of ``grades.csv`` (with ``columns``) and ``answers.csv``."""
    return (gradebook_csv(gradebook_rows(a.columns, [], a.questions, {}, **columns)),
            gradebook_csv([list(ANSWER_COLUMNS)]))


def grades_line(a: Assignment, row: Mapping[str, str], record: StudentResult | None,
                columns: Mapping[str, bool]) -> str:
    """The roster ``row``'s line of ``grades.csv`` (``record`` None: not graded yet)."""
    mine = {row["id"]: record} if record is not None else {}
    return gradebook_csv(gradebook_rows(a.columns, [row], a.questions, mine, **columns)[1:])


def answers_lines(row: Mapping[str, str], record: StudentResult | None) -> str:
    """The roster ``row``'s lines of ``answers.csv`` (none without a record)."""
    mine = {row["id"]: record} if record is not None else {}
    return gradebook_csv(answers_rows([row], mine)[1:])


def spliced(a: Assignment, out: Path, before: Records, after: Records) -> tuple[str, str] | None:
    """The text of ``grades.csv`` and ``answers.csv`` of ``out`` with the lines of the students
    of ``after`` (their records now; ``before``: as they were) made again, and every other line
    as the files hold it — or None where the files cannot tell it, and the caller makes the
    tables from every record: a file missing or unreadable, a student's lines not what their
    record before made, or a column the whole class decides that only the other records
    could settle (the late and pending columns, or the sandbox column, coming or going).
    The ``overridden`` column, the last, may come or go: every other student's cell in it is
    empty then."""
    try:
        grades, answers = ((out / name).read_bytes().decode("utf-8")
                           for name in (GRADES, ANSWERS))
    except (OSError, UnicodeDecodeError):
        return None
    lines = grades.split(END)
    if len(lines) != len(a.rows) + 2 or lines[-1]:
        return None
    was = _columns_of(a, lines[0] + END)
    now = None if was is None else _columns_now(a, lines, was, after)
    if now is None or not answers.startswith(headers(a, now)[1]):
        return None
    try:
        return _grades(a, lines, was, now, before, after), _answers(a, answers, before, after)
    except _Unlike:
        return None


def _columns_of(a: Assignment, header: str) -> dict[str, bool] | None:
    """The optional columns of the ``grades.csv`` whose header line is ``header``."""
    for flags in product((False, True), repeat=len(COLUMNS)):
        columns = dict(zip(COLUMNS, flags, strict=True))
        if headers(a, columns)[0] == header:
            return columns
    return None


def _columns_now(a: Assignment, lines: list[str], was: dict[str, bool],
                 after: Records) -> dict[str, bool] | None:
    """The optional columns once ``after``'s records replace theirs: what the assignment and
    those records need, or what another student's line has (None: only their records know)."""
    need = table_columns(a, {sid: r for sid, r in after.items() if r is not None})
    now = dict(need)
    for name in COLUMNS:
        if was[name] and not need[name]:
            if name not in ("sandbox_column", "override_column"):
                return None  # a late or pending column: the other records decide it
            now[name] = _others_have(a, lines, name, after)
    if {n: v for n, v in now.items() if n != "override_column"} != \
            {n: v for n, v in was.items() if n != "override_column"}:
        return None
    return now


def _others_have(a: Assignment, lines: list[str], name: str, after: Records) -> bool:
    """Whether another student's line of ``grades.csv`` needs column ``name``: ``no`` in
    ``sandboxed`` (code that ran unsandboxed), anything in ``overridden``."""
    head = next(csv.reader([lines[0]]))
    at = head.index("sandboxed" if name == "sandbox_column" else "overridden")
    others = [line for row, line in zip(a.rows, lines[1:-1], strict=True)
              if row["id"] not in after]
    cells = [cells[at] if len(cells) > at else "" for cells in csv.reader(others)]
    return any(c == "no" for c in cells) if name == "sandbox_column" else any(cells)


def _grades(a: Assignment, lines: list[str], was: dict[str, bool], now: dict[str, bool],
            before: Records, after: Records) -> str:
    """``grades.csv``'s text (:func:`spliced`): raises :class:`_Unlike` for a student of
    ``after`` whose line is not what their record before made."""
    added = now["override_column"] and not was["override_column"]
    dropped = was["override_column"] and not now["override_column"]
    text = [headers(a, now)[0]]
    for row, line in zip(a.rows, lines[1:-1], strict=True):
        sid = row["id"]
        if sid in after:
            if grades_line(a, row, before.get(sid), was) != line + END:
                raise _Unlike(sid)
            text.append(grades_line(a, row, after[sid], now))
        else:  # an empty last cell added or taken away
            text.append((line + "," if added else line[:-1] if dropped else line) + END)
    return "".join(text)


def _answers(a: Assignment, text: str, before: Records, after: Records) -> str:
    """``answers.csv``'s text (:func:`spliced`): each student's lines of ``after`` found where
    their record before put them, once, and replaced; raises :class:`_Unlike` otherwise."""
    rows = {row["id"]: row for row in a.rows}
    for sid in after:
        old, new = (answers_lines(rows[sid], r.get(sid)) for r in (before, after))
        if old == new:
            continue
        at = text.find(END + old) + len(END)
        if not old or at < len(END) or text.find(END + old, at) >= 0 or \
                text.startswith(old.split(",", 1)[0] + ",", at + len(old)):
            raise _Unlike(sid)
        text = text[:at] + new + text[at + len(old):]
    return text


class _Unlike(Exception):
    """A student's lines in a table are not what their record made."""
