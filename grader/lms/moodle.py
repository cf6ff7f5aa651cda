"""Moodle: participants or grades export as a class list, "Download all submissions", grade import.

Class list — Participants (download table as CSV) or Grades → Export → Plain text file
    Header with ``First name, Last name, ID number, Email address`` among other columns
    (Institution, Department, grade items …). **Student id**: the ID number, or — where it is
    empty — the email address.

Bulk download — Assignment → "Download all submissions" (a zip)
    One file per submitted file, ``<Full name>_<participant id>_assignsubmission_file_<file
    name>`` — or, with "Download submissions in folders" (the default since Moodle 3.1), one
    folder per student, ``<Full name>_<participant id>_assignsubmission_file_`` (newer Moodle
    drops the trailing ``_``), holding the files. The full name has ``_`` replaced by spaces;
    with team submissions it is prefixed ``<group>-``; with blind marking it is
    ``Participant``. The participant id is the assignment's own, not the user id nor the ID
    number. Online-text pages (``…_assignsubmission_onlinetext_…``) are not notebooks.
    **Matched** by the participant id when the class list has an ``Identifier`` column
    (Moodle's grading worksheet writes ``Participant <id>``) or a ``Participant id`` column;
    otherwise **by name** — "First Last" or "Last First" of the class list, compared without
    case — and a name that two students share is not guessed. The notes say which was used.

Import — Grades → Import → CSV file
    ``First name, Last name, ID number, Email address, <title>, Feedback``: in the import form,
    map "Email address" (or "ID number") to the user field of the same name, the title column
    to the assignment's grade item and "Feedback" to its feedback.
"""

from __future__ import annotations

import re
from pathlib import Path

from grader.lms.classlist import ClassListFormat, Grades, ImportError_, cell, fold
from grader.lms.download import (
    NOTEBOOK,
    Candidate,
    Matched,
    Students,
    files_under,
    is_system_file,
)

CLASS_LIST = ClassListFormat(
    name="moodle",
    label="Moodle participants or grades export",
    required=("First name", "Last name", "Email address"),
    id_columns=("ID number", "Email address"),
    email_columns=("Email address",),
    name_columns=("First name", "Last name"),
)

ENTRY = re.compile(r"^(?P<name>.+)_(?P<pid>\d+)_assignsubmission_(?P<plugin>[A-Za-z]+)"
                   r"(?:_(?P<file>.*))?$")
"""A file or folder of "Download all submissions" (module docstring)."""

_NOT_IN_FILE_NAMES = re.compile(r'[\\/:*?"<>|\x00-\x1f]')


def _name_key(name: str) -> str:
    """A full name as it is compared: Moodle's file-name cleaning undone as far as it can be."""
    return fold(_NOT_IN_FILE_NAMES.sub("", name.replace("_", " ")))


class _Names:
    """Roster students by participant id, or else by "First Last" / "Last First"."""

    def __init__(self, students: Students):
        self.students = students
        self.pids: dict[str, list[str]] = {}
        for r in students.rows:
            pid = cell(r, "Participant id") or \
                cell(r, "Identifier").removeprefix("Participant").strip()
            if pid:
                self.pids.setdefault(pid, []).append(r["id"])
        self.names: dict[str, set[str]] = {}
        for r in students.rows:
            first, last = cell(r, "First name"), cell(r, "Last name")
            for full in (f"{first} {last}", f"{last} {first}"):
                self.names.setdefault(_name_key(full), set()).add(r["id"])

    def find(self, name: str, pid: str) -> tuple[list[str], str]:
        if self.pids:
            return self.pids.get(pid, []), f"Moodle participant id {pid}"
        # team submissions prefix "<group>-": try the name after each "-" too
        tails = [name] + [name[i + 1:] for i, c in enumerate(name) if c == "-"]
        person = next((t for t in tails if _name_key(t) in self.names), name)
        return sorted(self.names.get(_name_key(person), ())), f"name {person!r}"


def match_download(folder: Path, students: Students) -> Matched | None:
    """Moodle's layout in ``folder``, or None."""
    entries = sorted(folder.iterdir())
    if not any(ENTRY.match(e.name) for e in entries):
        return None
    found = Matched("moodle")
    names = _Names(students)
    found.notes.append(
        "Moodle download matched by participant id (the class list's Identifier column)"
        if names.pids else
        "Moodle download matched by name: Moodle names its files by full name and its own "
        "participant id, not by ID number (add the grading worksheet's Identifier column to "
        "the class list to match by participant id)")
    for entry in entries:
        parts = ENTRY.match(entry.name)
        if entry.is_symlink():
            found.stray(entry, "a symbolic link, not followed")
            continue
        if is_system_file(entry) or parts is None:
            found.stray(entry, "a system file, not a submission" if is_system_file(entry)
                        else "not named as Moodle names submissions")
            continue
        files = files_under(entry) if entry.is_dir() else [entry]
        ids, how = names.find(parts["name"], parts["pid"])
        for f in files:
            _one(f, parts, ids, how, found)
    return found


def _one(path: Path, parts: re.Match, ids: list[str], how: str, found: Matched) -> None:
    if is_system_file(path):
        return found.stray(path, "a system file, not a submission")
    if not path.name.endswith(NOTEBOOK):
        return found.stray(path, f"not a notebook (.ipynb) — {parts['name']}'s "
                                 f"{parts['plugin']} submission")
    if len(ids) != 1:
        why = (f"{len(ids)} roster students match the {how} ({', '.join(ids)}); not guessing"
               if ids else f"no roster student matches the {how}")
        return found.unmatched(path, why)
    found.candidates.append(Candidate(ids[0], path, None, how=how))


def write_import(grades: Grades) -> list[list[str]]:
    """Rows of a CSV for Moodle's "Import grades" (module docstring)."""
    keys = ("ID number", "Email address")
    lacking = [r["id"] for r in grades.rows if not any(cell(r, k) for k in keys)]
    if lacking:
        raise ImportError_(
            "Moodle's import matches students by email address or ID number, and the roster "
            f"has neither for {', '.join(lacking[:5])}{' …' if len(lacking) > 5 else ''}: "
            "export with --roster <Moodle participants or grades export>")
    table = [["First name", "Last name", *keys, grades.title, "Feedback"]]
    for r in grades.rows:
        table.append([cell(r, "First name"), cell(r, "Last name"), *(cell(r, k) for k in keys),
                      grades.scores[r["id"]], grades.feedback.get(r["id"], "")])
    return table
