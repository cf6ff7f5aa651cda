"""Moodle: participants or grades export as a class list, "Download all submissions", grade import.

Class list — Participants (download table as CSV) or Grades → Export → Plain text file
    Header with ``First name, Last name, ID number, Email address`` among other columns
    (Institution, Department, grade items …). **Student id**: the ID number, or — where it is
    empty — the email address.

Bulk download — Assignment → "Download all submissions" (a zip)
    One file per submitted file, ``<Full name>_<participant id>_assignsubmission_file_<file
    name>`` — or, with "Download submissions in folders" (the default since Moodle 3.1), one
    folder per student, ``<Full name>_<participant id>_assignsubmission_file_`` (newer Moodle
    drops the trailing ``_``), holding the files. Moodle replaces every ``_`` of the full name
    with a space, so the name ends at the *first* ``_``: the owner is read from that first
    ``<name>_<id>_assignsubmission_<plugin>`` and never from the student's own file name, which
    follows it (a file uploaded as ``Ann Lee_7_assignsubmission_file_x.ipynb`` stays its
    uploader's). With team submissions the name is prefixed ``<group>-``; with blind marking it
    is ``Participant``. The participant id is the assignment's own, not the user id nor the ID
    number. Online-text pages (``…_assignsubmission_onlinetext_…``) are not notebooks.
    **Matched** by the participant id when the class list has an ``Identifier`` column
    (Moodle's grading worksheet writes ``Participant <id>``) or a ``Participant id`` column;
    otherwise **by name** — "First Last" or "Last First" of the class list, compared without
    case — and a name that two students share is not guessed, nor one that the download gives
    to two participant ids (someone not on the class list, or a student who renamed themself,
    carries it too): those files are listed and graded for no one. The notes say which was
    used. Sources: ``mod/assign/locallib.php`` (``download_submissions``) and, since Moodle
    4.1, ``mod/assign/classes/downloader.php`` (``get_student_prefix``).

Import — Grades → Import → CSV file
    ``First name, Last name, ID number, Email address, <title>, Feedback``: in the import form,
    map "Email address" (or "ID number") to the user field of the same name, the title column
    to the assignment's grade item and "Feedback" to its feedback.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
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

ENTRY = re.compile(r"^(?P<name>[^_]*)_(?P<pid>\d+)_assignsubmission_(?P<plugin>[A-Za-z0-9]+)"
                   r"(?:_(?P<file>.*))?$")
"""A file or folder of "Download all submissions": the name holds no ``_`` (module
docstring), so the first ``_<id>_assignsubmission_`` is Moodle's own."""


def recognises(entry: Path) -> bool:
    """Is ``entry`` named as Moodle's download names a file or folder?"""
    return ENTRY.match(entry.name) is not None


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
    """What ``folder``, recognised as Moodle's (:func:`grader.lms.download.layout`), holds."""
    found = Matched("moodle")
    names = _Names(students)
    found.notes.append(
        "Moodle download matched by participant id (the class list's Identifier column)"
        if names.pids else
        "Moodle download matched by name: Moodle names its files by full name and its own "
        "participant id, not by ID number (add the grading worksheet's Identifier column to "
        "the class list to match by participant id)")
    owned = []
    for entry in sorted(folder.iterdir()):
        parts = ENTRY.match(entry.name)
        if entry.is_symlink():
            found.stray(entry, "a symbolic link, not followed")
        elif is_system_file(entry) or parts is None:
            found.stray(entry, "a system file, not a submission" if is_system_file(entry)
                        else "not named as Moodle names submissions")
        else:
            owned.append((entry, parts, *names.find(parts["name"], parts["pid"])))
    shared = {} if names.pids else _shared_names(owned)
    for entry, parts, ids, how in owned:
        owner, how = _owner(ids, how, shared)
        for f in files_under(entry) if entry.is_dir() else [entry]:
            _one(f, parts, owner, how, found)
    return found


def _shared_names(owned: list) -> dict[str, str]:
    """Student id → why their name cannot be trusted here: entries of two participant ids
    matched to them by name."""
    pids: dict[str, set[str]] = {}
    for _, parts, ids, _ in owned:
        if len(ids) == 1:
            pids.setdefault(ids[0], set()).add(parts["pid"])
    return {sid: (f"the name of {sid}, which {len(p)} Moodle participants "
                  f"({', '.join(sorted(p))}) carry in this download; not guessing whose this is "
                  "(match by participant id: add the grading worksheet's Identifier column to "
                  "the class list)")
            for sid, p in pids.items() if len(p) > 1}


def _owner(ids: list[str], how: str, shared: dict[str, str]) -> tuple[str | None, str]:
    """``(student id, how matched)``, or ``(None, why no one)``."""
    if len(ids) > 1:
        return None, f"{len(ids)} roster students match the {how} ({', '.join(ids)}); not guessing"
    if not ids:
        return None, f"no roster student matches the {how}"
    return (None, shared[ids[0]]) if ids[0] in shared else (ids[0], how)


def _one(path: Path, parts: re.Match, owner: str | None, how: str, found: Matched) -> None:
    if is_system_file(path):
        return found.stray(path, "a system file, not a submission")
    if not path.name.endswith(NOTEBOOK):
        return found.stray(path, f"not a notebook (.ipynb) — {parts['name']}'s "
                                 f"{parts['plugin']} submission")
    if owner is None:
        return found.unmatched(path, how)
    found.candidates.append(Candidate(owner, path, None, how=how))


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
