"""What every LMS class list shares: a format record, detection from the header, the student id.

A class list downloaded from an LMS is a CSV whose header names the LMS's own columns. Its
format is recognised from those column names alone (:func:`detect`), and each format says which
of its columns names the student (:attr:`ClassListFormat.id_columns`: the first non-empty one in
a row) — that id names the student's variant and files, so it must be stable: it is an
identifier the LMS keeps for the student (a login, a student number), never a display name.
Every other column is kept unchanged, for matching submissions and for export.

Rows that are not students (Canvas's ``Points Possible`` row, its ``Test Student``, Blackboard's
preview user) are left out by :attr:`ClassListFormat.skip`, which says why.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import unicodedata
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field


def fold(text: str) -> str:
    """A name or header compared as people mean it: NFC, case-folded, single spaces.

    Examples
    --------
    >>> fold("  Mu\u0308ller,   JÜRGEN ") == fold("müller, jürgen")
    True
    """
    return " ".join(unicodedata.normalize("NFC", text).casefold().split())


def cell(row: Mapping[str, str], column: str) -> str:
    """``row[column]`` with the column name compared by :func:`fold`; ``""`` when absent.

    The roster's own key ``"id"`` answers only to ``"id"``: Canvas's ``ID`` (its user id) is
    another column.

    Examples
    --------
    >>> cell({"id": "jm", "ID": "4501"}, "ID"), cell({"id": "jm"}, "ID")
    ('4501', '')
    """
    wanted = fold(column)
    for name, value in row.items():
        if name == "id" and column != "id":
            continue
        if fold(name) == wanted:
            return (value or "").strip()
    return ""


def has_columns(header: Iterable[str], columns: Iterable[str]) -> bool:
    """Does ``header`` hold every one of ``columns`` (compared by :func:`fold`)?"""
    present = {fold(h) for h in header}
    return all(fold(c) in present for c in columns)


@dataclass(frozen=True)
class ClassListFormat:
    """One LMS's class list.

    Attributes
    ----------
    name : str
        The ``--roster-format`` value (``"canvas"`` …).
    label : str
        What people call the file (``"Canvas gradebook export"``).
    required : tuple of str
        Header columns that identify the format (any case).
    id_columns : tuple of str
        Where the student id comes from: the first of these columns that is non-empty in a row.
    email_columns, name_columns : tuple of str
        Where an e-mail address and the name parts are (for matching submissions and export).
    skip : callable
        ``skip(row) -> reason or None``: rows that are not students.
    """

    name: str
    label: str
    required: tuple[str, ...]
    id_columns: tuple[str, ...]
    email_columns: tuple[str, ...] = ()
    name_columns: tuple[str, ...] = ()
    skip: Callable[[Mapping[str, str]], str | None] = field(default=lambda row: None)

    def matches(self, header: Sequence[str]) -> bool:
        return has_columns(header, self.required)

    def describe_fallbacks(self, header: Sequence[str],
                           used: Sequence[tuple[str, int]]) -> list[str]:
        """:func:`describe_fallbacks` of this format."""
        return describe_fallbacks(self, header, used)

    def student_id(self, row: Mapping[str, str]) -> tuple[str, str]:
        """``(id, column it came from)``; ``("", "")`` when every id column is empty."""
        for column in self.id_columns:
            value = cell(row, column)
            if value:
                return value, column
        return "", ""

    def email(self, row: Mapping[str, str]) -> str:
        return next((cell(row, c) for c in self.email_columns if cell(row, c)), "")

    def full_name(self, row: Mapping[str, str]) -> str:
        """The name parts joined with spaces, in :attr:`name_columns` order."""
        return " ".join(p for p in (cell(row, c) for c in self.name_columns) if p)


def detect(header: Sequence[str], formats: Iterable[ClassListFormat]) -> ClassListFormat | None:
    """The first of ``formats`` whose required columns are all in ``header``."""
    return next((f for f in formats if f.matches(header)), None)


ID_FALLBACK_NOTE = "{count} student(s) have no {first}: their id is their {other} (lines {lines})"


def describe_fallbacks(fmt: ClassListFormat, header: Sequence[str],
                       used: Sequence[tuple[str, int]]) -> list[str]:
    """Notes on ids that did not come from the format's first id column.

    ``used``: the (id column, line) of every student. A first column absent from ``header``
    altogether gives one note; otherwise each fallback column lists its lines.
    """
    present = [c for c in fmt.id_columns if has_columns(header, [c])]
    if present and present[0] != fmt.id_columns[0]:
        return [f"the class list has no {fmt.id_columns[0]} column: the student ids are "
                f"the {present[0]}"]
    notes = []
    for column in fmt.id_columns[1:]:
        lines = [line for c, line in used if c == column]
        if lines:
            notes.append(ID_FALLBACK_NOTE.format(
                count=len(lines), first=fmt.id_columns[0], other=column,
                lines=", ".join(map(str, lines[:10])) + (" …" if len(lines) > 10 else "")))
    return notes


def merge_rows(rows: Sequence[Mapping[str, str]],
               class_list: Sequence[Mapping[str, str]]) -> tuple[dict, ...]:
    """``rows`` with the columns of the ``class_list`` row of the same id added (a fresher
    class list's values win); students absent from it keep their row, extra ones are ignored.

    Examples
    --------
    >>> merge_rows([{"id": "a", "name": "A"}], [{"id": "a", "ID": "7"}, {"id": "b"}])
    ({'id': 'a', 'name': 'A', 'ID': '7'},)
    """
    by_id = {r["id"]: r for r in class_list}
    return tuple({**r, **by_id.get(r["id"], {})} for r in rows)


@dataclass(frozen=True)
class Grades:
    """What an LMS import file is written from (:mod:`grader.lms.export`).

    Attributes
    ----------
    rows : tuple of dict
        The roster rows, in roster order (``"id"`` and the class list's columns).
    scores : dict
        Student id → points as written (``"12.5"``), or ``""`` where no score is due (a
        missing submission without ``--missing-as-zero``).
    feedback : dict
        Student id → one line for the student (per-question points, what went wrong).
    title : str
        The assignment's title.
    max_points : float
        Points possible.
    column_id : str or None
        The LMS's id of the gradebook column (``--assignment-id``), when given.
    """

    rows: tuple[dict, ...]
    scores: dict
    feedback: dict
    title: str
    max_points: float
    column_id: str | None = None


class ImportError_(ValueError):
    """The roster lacks what an LMS's import needs to match students; the message says what."""
