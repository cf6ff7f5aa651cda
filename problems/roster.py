"""Reading the class roster: a UTF-8 CSV with a header and at least a column ``id`` — or the
class list of an LMS (Canvas, Moodle, Blackboard, Gradescope) as the LMS exports it.

An LMS class list is recognised from its header (or named with ``--roster-format``); its
format (:mod:`grader.lms.classlist`) says which of its columns gives the student id, and rows
that are not students (Canvas's ``Points Possible`` row, its Test Student) are left out, with a
note. The id is added as a first column ``id``; the LMS's own columns are kept unchanged, for
matching submissions and for the gradebook the LMS imports (``eulertop export``). UTF-16 files
and tab-delimited files (Blackboard's ``.xls`` download) are read too.

A student id becomes a file name (``release/<id>.ipynb``, ``SUBMISSIONS/<id>.ipynb``) and the
key the grader uses to pick a student's variant, so it is checked strictly here, once, before
anything is written: no path characters, no leading dot or dash, no duplicates — not even
duplicates that differ only in case, since ``Alice.ipynb`` and ``alice.ipynb`` are one file on
macOS and Windows. Every other column (``name``, ``email`` …) is carried along unchanged.

Problems are reported as :class:`RosterError` (a ``ValueError``) naming the file, the line and
the column, so the instructor can fix the CSV without guessing.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ID_COLUMN = "id"
MAX_ID_LENGTH = 100

# Letters and digits first (so an id is never hidden, never `.`/`..`, never read as an option),
# then letters, digits, `.`, `_`, `-`, `@` (e-mail addresses); no trailing dot, which Windows
# drops from file names.
_ID_PATTERN = re.compile(r"[A-Za-z0-9](?:[A-Za-z0-9._@-]*[A-Za-z0-9_@-])?")
ID_RULE = (
    "ids must start with a letter or digit and contain only ASCII letters, digits and "
    f"'.', '_', '-', '@' (not ending with '.'), at most {MAX_ID_LENGTH} characters"
)


class RosterError(ValueError):
    """The roster file cannot be used; the message names the file, line and column."""


@dataclass(frozen=True)
class Roster:
    """A class list, in the file's order.

    Attributes
    ----------
    columns : tuple of str
        The header, as written (surrounding spaces removed); the id column is named ``"id"``.
    rows : tuple of dict
        One ``{column: value}`` per student, every column present (``""`` when the row is short).
    """

    columns: tuple[str, ...]
    rows: tuple[dict[str, str], ...]
    format: str = ""  # "" for an eulertop roster, else the LMS's (grader.lms.registry)
    notes: tuple[str, ...] = ()  # rows left out, ids from a fallback column (not stored)

    @property
    def ids(self) -> tuple[str, ...]:
        """The student ids, in the file's order."""
        return tuple(row[ID_COLUMN] for row in self.rows)

    def to_dict(self) -> dict:
        """Plain JSON: ``{"columns": [...], "rows": [{...}, ...]}``."""
        d = {"columns": list(self.columns), "rows": [dict(r) for r in self.rows]}
        if self.format:
            d["format"] = self.format
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Roster:
        """Inverse of :meth:`to_dict` (``notes`` are not stored)."""
        return cls(columns=tuple(d["columns"]), rows=tuple(dict(r) for r in d["rows"]),
                   format=d.get("format", ""))


def id_problem(student_id: str) -> str | None:
    """Why ``student_id`` cannot be used as a student id, or None when it can.

    Examples
    --------
    >>> id_problem("alice.smith@uni.example") is None
    True
    >>> id_problem("../x")
    "'../x' would be a path, not a file name"
    """
    if student_id == "":
        return "empty id"
    if "/" in student_id or "\\" in student_id or student_id in (".", ".."):
        return f"{student_id!r} would be a path, not a file name"
    if len(student_id) > MAX_ID_LENGTH:
        return f"id {student_id[:20]!r}… is longer than {MAX_ID_LENGTH} characters"
    if not _ID_PATTERN.fullmatch(student_id):
        return f"{student_id!r} is not allowed: {ID_RULE}"
    return None


ROSTER_FORMATS = ("eulertop", "canvas", "moodle", "blackboard", "gradescope")
"""``--roster-format`` values: ``eulertop`` is the CSV with a column ``id``."""


def read_roster(path: Path | str, roster_format: str | None = None,
                class_lists: Mapping[str, Any] | None = None) -> Roster:
    """Read and check a roster CSV.

    Parameters
    ----------
    path : path-like
        A UTF-8 CSV file (a byte-order mark, as Excel writes it, is accepted; UTF-16 with its
        byte-order mark too; tab-delimited when the header holds more tabs than commas) with a
        header row that has a column ``id`` (any case, surrounding spaces ignored) — or an LMS
        class list (module docstring).
    roster_format : str, optional
        One of :data:`ROSTER_FORMATS`; default: recognised from the header (an LMS's class
        list when its columns are there, else a column ``id``).
    class_lists : mapping, optional
        The LMS class-list formats, by ``--roster-format`` name
        (:data:`grader.lms.registry.CLASS_LISTS`, passed in by the front ends: the formats are
        the grader's, a floor above this one); without them only an eulertop roster is read.

    Returns
    -------
    Roster

    Raises
    ------
    RosterError
        The file cannot be read or decoded, has no ``id`` column, no students, a row with more
        fields than the header, an empty or unsafe id, or duplicate ids (all of them named, with
        their lines).
    """
    path = Path(path)
    if roster_format is not None and roster_format not in ROSTER_FORMATS:
        raise RosterError(f"unknown roster format {roster_format!r} (choose from "
                          f"{', '.join(ROSTER_FORMATS)})")
    text = _read_text(path)
    first = next((line for line in text.splitlines() if line.strip()), "")
    delimiter = "\t" if first.count("\t") > first.count(",") else ","
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    try:
        header = next((r for r in reader if any(f.strip() for f in r)), None)
        if header is None:
            raise RosterError(f"{path}: the roster is empty (expected a header with a column 'id')")
        lms = _lms_format(path, header, roster_format, class_lists or {})
        if lms is not None:
            return _read_class_list(path, reader, header, lms)
        columns = _columns(f"{path}, line {reader.line_num}", header)
        rows, lines = _rows(path, reader, columns)
    except csv.Error as e:
        raise RosterError(f"{path}, line {reader.line_num}: not valid CSV: {e}") from None
    if not rows:
        raise RosterError(f"{path}: the roster has a header but no students")
    _check_ids(path, rows, lines)
    return Roster(columns=columns, rows=tuple(rows))


def _lms_format(path: Path, header: list[str], roster_format: str | None,
                class_lists: Mapping[str, Any]):
    """The LMS class-list format of ``header`` among ``class_lists`` (None: an eulertop
    roster)."""
    if roster_format == "eulertop":
        return None
    if roster_format is None:
        return next((f for f in class_lists.values() if f.matches(header)), None)
    if roster_format not in class_lists:
        raise RosterError(f"{path}: the {roster_format} class-list format is not known here")
    fmt = class_lists[roster_format]
    if not fmt.matches(header):
        found = ", ".join(repr(c.strip()) for c in header)
        raise RosterError(f"{path}, line 1: not a {fmt.label}: it needs the columns "
                          f"{', '.join(map(repr, fmt.required))} (found: {found})")
    return fmt


def _read_class_list(path: Path, reader, header: list[str], fmt) -> Roster:
    """An LMS class list (module docstring): rows that are students, each with its ``id``."""
    keep = [i for i, c in enumerate(header) if c.strip()]
    columns = [header[i].strip() for i in keep]
    seen = sorted({c for c in columns if columns.count(c) > 1})
    if seen:
        raise RosterError(f"{path}, line 1: duplicate column names: {seen}")
    rows, lines, notes, used = [], [], [], []
    for fields in reader:
        if not any(f.strip() for f in fields):
            continue
        padded = [*fields, *[""] * (len(header) - len(fields))]
        row = {c: padded[i] for c, i in zip(columns, keep, strict=True)}
        reason = fmt.skip(row)
        if reason:
            notes.append(f"{path}, line {reader.line_num}: left out {reason}")
            continue
        sid, column = fmt.student_id(row)
        used.append((column, reader.line_num))
        rows.append({"id": sid, **{c: v for c, v in row.items() if c != "id"}})
        lines.append(reader.line_num)
    if not rows:
        raise RosterError(f"{path}: the {fmt.label} lists no students")
    where = " or ".join(repr(c) for c in fmt.id_columns)
    _check_ids(path, rows, lines, column=f"{where} (the student id of a {fmt.label})")
    notes += fmt.describe_fallbacks(columns, used)
    names = ("id", *(c for c in columns if c != "id"))
    return Roster(columns=names, rows=tuple(rows), format=fmt.name, notes=tuple(notes))


def _read_text(path: Path) -> str:
    try:
        data = path.read_bytes()
    except OSError as e:
        raise RosterError(f"{path}: cannot read the roster: {e.strerror or e}") from None
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return data.decode("utf-16")
        except UnicodeDecodeError:
            raise RosterError(f"{path}: starts as UTF-16 but is not valid UTF-16") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data[: e.start].count(b"\n") + 1
        raise RosterError(
            f"{path}, line {line}: not UTF-8 (byte 0x{data[e.start]:02x}); "
            "save the roster as CSV UTF-8"
        ) from None


def _columns(where: str, header: list[str]) -> tuple[str, ...]:
    columns = [c.strip() for c in header]
    ids = [i for i, c in enumerate(columns) if c.lower() == ID_COLUMN]
    if not ids:
        raise RosterError(
            f"{where}: no column 'id' in the header (found: {', '.join(map(repr, columns))})"
        )
    if len(ids) > 1:
        raise RosterError(f"{where}: the column 'id' appears {len(ids)} times")
    columns[ids[0]] = ID_COLUMN
    seen = [c for c in columns if columns.count(c) > 1]
    if seen:
        raise RosterError(f"{where}: duplicate column names: {sorted(set(seen))}")
    if "" in columns:
        raise RosterError(f"{where}: column {columns.index('') + 1} has no name")
    return tuple(columns)


def _rows(path: Path, reader, columns: tuple[str, ...]) -> tuple[list[dict], list[int]]:
    rows, lines = [], []
    for fields in reader:
        if not any(f.strip() for f in fields):
            continue  # blank lines are layout, not students
        if len(fields) > len(columns):
            raise RosterError(
                f"{path}, line {reader.line_num}: {len(fields)} fields but the header has "
                f"{len(columns)} columns"
            )
        padded = [*fields, *[""] * (len(columns) - len(fields))]
        row = dict(zip(columns, padded, strict=True))
        row[ID_COLUMN] = row[ID_COLUMN].strip()
        rows.append(row)
        lines.append(reader.line_num)
    return rows, lines


def _check_ids(path: Path, rows: list[dict], lines: list[int], column: str = "'id'") -> None:
    for row, line in zip(rows, lines, strict=True):
        problem = id_problem(row[ID_COLUMN])
        if problem:
            raise RosterError(f"{path}, line {line}, column {column}: {problem}")
    by_folded: dict[str, list[tuple[str, int]]] = {}
    for row, line in zip(rows, lines, strict=True):
        by_folded.setdefault(row[ID_COLUMN].casefold(), []).append((row[ID_COLUMN], line))
    clashes = [group for group in by_folded.values() if len(group) > 1]
    if clashes:
        described = "; ".join(
            " and ".join(f"{sid!r} (line {line})" for sid, line in group) for group in clashes
        )
        raise RosterError(
            f"{path}, column {column}: duplicate ids (compared ignoring case, since they name "
            f"files): {described}"
        )
