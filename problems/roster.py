"""Reading the class roster: a UTF-8 CSV with a header and at least a column ``id``.

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
from dataclasses import dataclass
from pathlib import Path

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

    @property
    def ids(self) -> tuple[str, ...]:
        """The student ids, in the file's order."""
        return tuple(row[ID_COLUMN] for row in self.rows)

    def to_dict(self) -> dict:
        """Plain JSON: ``{"columns": [...], "rows": [{...}, ...]}``."""
        return {"columns": list(self.columns), "rows": [dict(r) for r in self.rows]}

    @classmethod
    def from_dict(cls, d: dict) -> Roster:
        """Inverse of :meth:`to_dict`."""
        return cls(columns=tuple(d["columns"]), rows=tuple(dict(r) for r in d["rows"]))


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


def read_roster(path: Path | str) -> Roster:
    """Read and check a roster CSV.

    Parameters
    ----------
    path : path-like
        A UTF-8 CSV file (a byte-order mark, as Excel writes it, is accepted) with a header
        row that has a column ``id`` (any case, surrounding spaces ignored).

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
    text = _read_text(path)
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next((r for r in reader if any(f.strip() for f in r)), None)
        if header is None:
            raise RosterError(f"{path}: the roster is empty (expected a header with a column 'id')")
        columns = _columns(f"{path}, line {reader.line_num}", header)
        rows, lines = _rows(path, reader, columns)
    except csv.Error as e:
        raise RosterError(f"{path}, line {reader.line_num}: not valid CSV: {e}") from None
    if not rows:
        raise RosterError(f"{path}: the roster has a header but no students")
    _check_ids(path, rows, lines)
    return Roster(columns=columns, rows=tuple(rows))


def _read_text(path: Path) -> str:
    try:
        data = path.read_bytes()
    except OSError as e:
        raise RosterError(f"{path}: cannot read the roster: {e.strerror or e}") from None
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


def _check_ids(path: Path, rows: list[dict], lines: list[int]) -> None:
    for row, line in zip(rows, lines, strict=True):
        problem = id_problem(row[ID_COLUMN])
        if problem:
            raise RosterError(f"{path}, line {line}, column 'id': {problem}")
    by_folded: dict[str, list[tuple[str, int]]] = {}
    for row, line in zip(rows, lines, strict=True):
        by_folded.setdefault(row[ID_COLUMN].casefold(), []).append((row[ID_COLUMN], line))
    clashes = [group for group in by_folded.values() if len(group) > 1]
    if clashes:
        described = "; ".join(
            " and ".join(f"{sid!r} (line {line})" for sid, line in group) for group in clashes
        )
        raise RosterError(
            f"{path}, column 'id': duplicate ids (compared ignoring case, since they name "
            f"files): {described}"
        )
