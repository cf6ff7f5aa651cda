"""Blackboard Learn (Original): Grade Center export as a class list, assignment download, upload.

Class list — Grade Center → Work Offline → Download (user information)
    Header ``Last Name, First Name, Username, Student ID, Last Access, Availability, …``,
    tab-delimited UTF-16 (``.xls``) or comma-delimited (``.csv``). **Student id**: the
    Username (Blackboard's own key for a student). The course's preview user
    (``…_previewuser``) is left out.

Bulk download — Grade Center column → Assignment File Download (a zip)
    ``<assignment>_<username>_attempt_<YYYY-MM-DD-HH-MM-SS>_<file name>`` per file, and
    ``<assignment>_<username>_attempt_<time>.txt``, the submission's receipt. The student's
    own file name comes last, so the *first* ``_attempt_<time>`` is Blackboard's, and the
    username is read before it. **Matched** by the Username; of several attempts the newest
    (its time) is graded.

Upload — Grade Center → Work Offline → Upload
    ``Last Name, First Name, Username, <title> [Total Pts: <N> Score] |<column id>``, every
    field quoted; Blackboard matches students by Username and the column by its
    ``|<column id>`` (``--assignment-id``) — without one it creates a new column.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

from grader.lms.classlist import ClassListFormat, Grades, ImportError_, cell
from grader.lms.download import NOTEBOOK, Candidate, Matched, Students, is_system_file


def _skip(row: Mapping[str, str]) -> str | None:
    if cell(row, "Username").endswith("_previewuser"):
        return "Blackboard's preview user"
    return None


CLASS_LIST = ClassListFormat(
    name="blackboard",
    label="Blackboard Grade Center export",
    required=("Last Name", "First Name", "Username"),
    id_columns=("Username",),
    name_columns=("First Name", "Last Name"),
    skip=_skip,
)

ATTEMPT = re.compile(r"_attempt_(?P<time>\d{4}-\d{2}-\d{2}-\d{2}-\d{2}-\d{2})"
                     r"(?:_(?P<file>.+)|\.txt)$")
"""Blackboard's part of a download file name; ``search`` finds the first, Blackboard's own."""


def _username(name: str, usernames: list[str]) -> str | None:
    """The username in ``<assignment>_<username>_attempt_…`` (the longest roster one that fits;
    assignment names and usernames may both hold ``_``)."""
    head = name[: ATTEMPT.search(name).start()]
    fits = [u for u in usernames if head.endswith(f"_{u}") or head == u]
    return max(fits, key=len) if fits else None


def recognises(entry: Path) -> bool:
    """Is ``entry`` a file named as Blackboard's download names one?"""
    return entry.is_file() and ATTEMPT.search(entry.name) is not None


def match_download(folder: Path, students: Students) -> Matched | None:
    """What ``folder``, recognised as Blackboard's (:func:`grader.lms.download.layout`), holds."""
    entries = sorted(folder.iterdir())
    found = Matched("blackboard")
    key = "Username" if students.has_column("Username") else "id"
    usernames = [cell(r, key) if key != "id" else r["id"] for r in students.rows]
    for entry in entries:
        m = ATTEMPT.search(entry.name)
        if is_system_file(entry) or m is None or not entry.is_file() or entry.is_symlink():
            found.stray(entry, "a system file, not a submission" if is_system_file(entry)
                        else "not named as Blackboard names submissions")
            continue
        user = _username(entry.name, usernames)
        if m["file"] is None:
            continue  # the attempt's receipt (.txt): what Blackboard says, not a submission
        if not entry.name.endswith(NOTEBOOK):
            found.stray(entry, f"not a notebook (.ipynb) — {user or 'unknown user'}'s attempt")
        elif user is None:
            found.unmatched(entry, "its username is not on the roster")
        else:
            ids = students.by_column(key, user)
            day, clock = m["time"][:10], m["time"][11:].replace("-", ":")
            found.candidates.append(Candidate(
                ids[0], entry, (m["time"],), how=f"Blackboard username {user!r}",
                submitted_at=f"{day}T{clock}",  # the server's local time: no offset
                time_source=f"Blackboard's attempt time in {entry.name}"))
    return found


def write_import(grades: Grades) -> list[list[str]]:
    """Rows of the Grade Center upload (module docstring); the writer quotes every field."""
    from grader.gradebook import number

    lacking = [r["id"] for r in grades.rows if not cell(r, "Username")]
    if lacking:
        raise ImportError_(
            "Blackboard matches students by Username, and the roster has none for "
            f"{', '.join(lacking[:5])}{' …' if len(lacking) > 5 else ''}: export with "
            "--roster <Blackboard Grade Center export>")
    column = f"{grades.title} [Total Pts: {number(grades.max_points)} Score]"
    if grades.column_id:
        column += f" |{grades.column_id}"
    table = [["Last Name", "First Name", "Username", column]]
    for r in grades.rows:
        table.append([cell(r, "Last Name"), cell(r, "First Name"), cell(r, "Username"),
                      grades.scores[r["id"]]])
    return table
