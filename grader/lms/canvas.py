"""Canvas: its gradebook export as a class list, "Download Submissions", and gradebook import.

Class list — the gradebook export (Grades → Export → CSV)
    Header ``Student, ID, SIS User ID, SIS Login ID, Section, <assignment> (<id>), …`` (a TA's
    export may lack the two SIS columns), then a ``Points Possible`` row (older exports indent
    it with spaces, and may have a ``Muted`` row), then one row per student, the course's
    ``Test Student`` (``Student, Test``) last. **Student id**: the SIS Login ID, or — where it
    is empty — the Canvas user ID (the ``ID`` column).

Bulk download — "Download Submissions" (a zip of flat files)
    ``<sortable name>[_LATE]_<canvas user id>_<attachment id>_<file name>``: the sortable name
    lower-cased with every non-word character removed (and ``_<digits>_`` in it reduced to the
    digits), ``LATE`` (``late`` in older Canvas) when the submission was late, the user id,
    then the id and display name of the uploaded file — a re-uploaded file name gains ``-1``,
    ``-2`` before its extension, and a later upload a larger attachment id. Anonymous grading
    writes ``anon_<id>`` for the user id. The student's own file name comes last, so the
    *first* ``_<user id>_<attachment id>_`` is Canvas's (as Canvas itself reads it back when
    graded files are uploaded). **Matched** by the Canvas user id against the class list's
    ``ID`` column; of several notebooks the one with the largest attachment id (the newest
    upload) is graded. Where a name can be read as two roster users' (a sortable name that
    holds ``_<digits>_`` after all: punctuation between the digits and ``_`` survives Canvas's
    reduction), the reading whose name part is that user's sortable name on the class list is
    taken; when none or several are, the file is listed and graded for no one.

Import — Grades → Import
    ``Student, ID, SIS User ID, SIS Login ID, Section, <title> (<assignment id>)``, a
    ``Points Possible`` row, then one row per student; Canvas matches students by ID (then the
    SIS columns) and the column by its ``(<assignment id>)`` — or, without it, by title,
    creating a new assignment when none has that title.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

from grader.lms.classlist import ClassListFormat, Grades, ImportError_, cell, fold
from grader.lms.download import NOTEBOOK, Candidate, Matched, Students, is_system_file


def _skip(row: Mapping[str, str]) -> str | None:
    student = fold(cell(row, "Student"))
    if student == "points possible":
        return "Canvas's 'Points Possible' row"
    if not student and any(fold(v or "") == "muted" for v in row.values()):
        return "Canvas's 'Muted' row"
    if student in ("student, test", "test student"):
        return "Canvas's Test Student (the course's student view)"
    return None


CLASS_LIST = ClassListFormat(
    name="canvas",
    label="Canvas gradebook export",
    required=("Student", "ID", "Section"),
    id_columns=("SIS Login ID", "ID"),
    name_columns=("Student",),
    skip=_skip,
)

FILE_NAME = re.compile(
    r"^(?:(?P<name>.*?)_)??(?:(?P<late>LATE|late)_)?"
    r"(?P<user>\d+|anon_[A-Za-z0-9]+)_(?P<attachment>\d+)_(?P<original>.+)$")
"""A file of "Download Submissions" (module docstring), read at its first possible split."""
_IDS = re.compile(r"(?:(?P<late>LATE|late)_)?(?P<user>\d+|anon_[A-Za-z0-9]+)_"
                  r"(?P<attachment>\d+)_(?P<original>.+)$")


def parse_file_name(name: str) -> dict | None:
    """The parts of a Canvas download file name, or None.

    Examples
    --------
    >>> parse_file_name("müllerjürgen_LATE_4521_99001_hw3-1.ipynb")["user"]
    '4521'
    >>> parse_file_name("alice.ipynb") is None
    True
    """
    m = FILE_NAME.match(name)
    return m.groupdict() if m else None


def readings(name: str) -> list[dict]:
    """Every way ``name`` splits into Canvas's parts, first split first.

    Examples
    --------
    >>> [r["user"] for r in readings("lee_ann_77_5_hw_2_3_x.ipynb")]
    ['77', '2']
    """
    starts = [0] + [i + 1 for i, c in enumerate(name) if c == "_"]
    found = [(s, _IDS.match(name, s)) for s in starts]
    return [{"name": name[:s - 1] if s else None, **m.groupdict()} for s, m in found if m]


def name_in_file_names(sortable: str) -> str:
    """A sortable name as Canvas writes it into download file names (module docstring).

    Examples
    --------
    >>> name_in_file_names("O'Neil_2_, Sam")
    'oneil2sam'
    """
    return re.sub(r"\W", "", re.sub(r"_(\d+)_", r"\1", sortable)).lower()


def recognises(entry: Path) -> bool:
    """Is ``entry`` a file named as Canvas's download names one?"""
    return entry.is_file() and "_assignsubmission_" not in entry.name \
        and parse_file_name(entry.name) is not None


def match_download(folder: Path, students: Students) -> Matched | None:
    """What ``folder``, recognised as Canvas's, holds; None for a folder of ``<id>.ipynb``."""
    entries = sorted(folder.iterdir())
    if any(e.name.endswith(NOTEBOOK) and e.stem in students.ids for e in entries):
        return None  # an eulertop folder of <id>.ipynb, not a Canvas download
    found = Matched("canvas")
    have_ids = students.has_column("ID")
    for entry in entries:
        _one(entry, students, have_ids, found)
    return found


def _one(entry: Path, students: Students, have_ids: bool, found: Matched) -> None:
    parts = parse_file_name(entry.name)
    if is_system_file(entry):
        return found.stray(entry, "a system file, not a submission")
    if entry.is_dir() or entry.is_symlink() or parts is None:
        kind = "a folder" if entry.is_dir() else "a file"
        return found.stray(entry, f"{kind} not named as Canvas names submissions")
    if not entry.name.endswith(NOTEBOOK):
        return found.stray(entry, f"not a notebook (.ipynb) — Canvas user {parts['user']}")
    user = parts["user"]
    if user.startswith("anon_"):
        return found.unmatched(entry, "anonymous grading hides who submitted it (turn "
                                      "anonymity off in Canvas, then download again)")
    if not have_ids:
        return found.unmatched(entry, "the roster has no Canvas 'ID' column to match Canvas "
                                      f"user {user}: generate with the Canvas gradebook "
                                      "export as --roster")
    parts, why = _owner(entry.name, students)
    if why:
        return found.unmatched(entry, why)
    found.candidates.append(Candidate(students.by_column("ID", parts["user"])[0], entry,
                                      (int(parts["attachment"]),),
                                      late=parts["late"] is not None,
                                      how=f"Canvas user id {parts['user']}"))


def _owner(name: str, students: Students) -> tuple[dict, str]:
    """The reading of ``name`` that names its owner, and ``""``; or a reading and why no one
    (module docstring)."""
    options = readings(name)
    by_user: dict[str, dict] = {}
    for r in options:
        if students.by_column("ID", r["user"]):
            by_user.setdefault(r["user"], r)  # each user's first reading
    if len(by_user) > 1:
        named = [r for r in by_user.values() if _named(r, students)]
        if len(named) != 1:
            return options[0], (f"its name reads as Canvas user {' or '.join(by_user)}, and "
                                "the class list's names tell it for neither; not guessing whose")
        by_user = {named[0]["user"]: named[0]}
    reading = next(iter(by_user.values()), options[0])
    ids = students.by_column("ID", reading["user"])
    if len(ids) != 1:
        is_ = "is on the roster twice" if ids else "is not on the roster"
        return reading, f"Canvas user {reading['user']} {is_}"
    return reading, ""


def _named(reading: dict, students: Students) -> bool:
    """Is the reading's name part the sortable name the class list gives its user?"""
    ids = students.by_column("ID", reading["user"])
    sortable = cell(students.row(ids[0]), "Student") if len(ids) == 1 else ""
    return bool(sortable) and fold(name_in_file_names(sortable)) == fold(reading["name"] or "")


IMPORT_KEYS = ("ID", "SIS User ID", "SIS Login ID")


def write_import(grades: Grades) -> list[list[str]]:
    """Rows of the file Canvas's gradebook import takes (module docstring)."""
    from grader.gradebook import number

    lacking = [r["id"] for r in grades.rows if not any(cell(r, k) for k in IMPORT_KEYS)]
    if lacking:
        raise ImportError_(
            f"Canvas matches students by ID, SIS User ID or SIS Login ID, and the roster has "
            f"none of them for {', '.join(lacking[:5])}{' …' if len(lacking) > 5 else ''}: "
            "export with --roster <Canvas gradebook export>")
    column = f"{grades.title} ({grades.column_id})" if grades.column_id else grades.title
    table = [["Student", *IMPORT_KEYS, "Section", column],
             ["Points Possible", "", "", "", "", number(grades.max_points)]]
    for r in grades.rows:
        table.append([cell(r, "Student"), *(cell(r, k) for k in IMPORT_KEYS),
                      cell(r, "Section"), grades.scores[r["id"]]])
    return table
