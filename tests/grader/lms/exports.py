"""Realistic LMS files, built from the formats the LMSs document (docs/lms.md), for the tests.

A small class of six with non-ASCII names and two students of the same name; each builder
writes what that LMS would hand an instructor: its class list and its bulk download.
"""

from __future__ import annotations

import csv
import io
import json
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Person:
    first: str
    last: str
    email: str
    login: str  # Canvas SIS Login ID, Blackboard Username
    number: str  # Canvas SIS User ID, Moodle ID number, Gradescope SID
    canvas: int  # Canvas user id
    participant: int  # Moodle participant id (the assignment's own)

    @property
    def full(self) -> str:
        return f"{self.first} {self.last}"

    @property
    def sortable(self) -> str:
        return f"{self.last}, {self.first}"


MULLER = Person("Jürgen", "Müller", "jmuller@uni.example", "jmuller", "S1001", 4501, 700101)
NUNEZ = Person("Zoë", "Ñúñez", "znunez@uni.example", "znunez", "S1002", 4502, 700102)
GARCIA1 = Person("Ana", "García", "agarcia1@uni.example", "agarcia1", "S1003", 4503, 700103)
GARCIA2 = Person("Ana", "García", "agarcia2@uni.example", "agarcia2", "S1004", 4504, 700104)
WEI = Person("Li", "Wei", "lwei@uni.example", "", "", 4505, 700105)  # no SIS login, no number
ONEIL = Person("Sam", "O'Neil", "soneil@uni.example", "soneil", "S1006", 4506, 700106)
CLASS = (MULLER, NUNEZ, GARCIA1, GARCIA2, WEI, ONEIL)


def csv_text(rows, delimiter=",") -> str:
    buffer = io.StringIO(newline="")
    csv.writer(buffer, delimiter=delimiter).writerows(rows)
    return buffer.getvalue()


def write_zip(path: Path, files: dict[str, bytes | str]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files.items():
            z.writestr(name, data)
    return path


# ------------------------------------------------------------------------------------ Canvas

def canvas_gradebook(people=CLASS) -> str:
    """Grades → Export: header, the (indented) Points Possible row, students, Test Student."""
    rows = [["Student", "ID", "SIS User ID", "SIS Login ID", "Section", "Homework 1 (77001)",
             "Current Score", "Final Score"],
            ["    Points Possible", "", "", "", "", "10", "(read only)", "(read only)"]]
    rows += [[p.sortable, str(p.canvas), p.number, p.login, "Rigid bodies 01", "", "", ""]
             for p in people]
    rows.append(["Student, Test", "9999", "", "", "Rigid bodies 01", "", "", ""])
    return csv_text(rows)


def canvas_file_name(p: Person, attachment: int, original: str, late: bool = False) -> str:
    """As Canvas's ContentZipper names a file: sortable name lower-cased, non-word characters
    removed, ``LATE``, user id, attachment id, display name."""
    name = re.sub(r"_(\d+)_", r"\1", p.sortable).lower()
    prefix = re.sub(r"[^\w]", "", "_".join([name, *(["LATE"] if late else []), str(p.canvas)]))
    return f"{prefix}_{attachment}_{original}"


# ------------------------------------------------------------------------------------ Moodle

def moodle_participants(people=CLASS, identifier: bool = False) -> str:
    """Participants → download as CSV (with the grading worksheet's Identifier if asked)."""
    head = ["First name", "Last name", "ID number", "Email address", "Roles", "Groups"]
    head += ["Identifier"] if identifier else []
    rows = [head]
    for p in people:
        rows.append([p.first, p.last, p.number, p.email, "Student", "",
                     *([f"Participant {p.participant}"] if identifier else [])])
    return csv_text(rows)


def moodle_prefix(p: Person) -> str:
    return f"{p.full.replace('_', ' ')}_{p.participant}"


# -------------------------------------------------------------------------------- Gradescope

def gradescope_roster(people=CLASS) -> str:
    rows = [["First Name", "Last Name", "SID", "Email", "Role", "Sections"]]
    rows += [[p.first, p.last, p.number, p.email, "Student", ""] for p in people]
    return csv_text(rows)


def gradescope_metadata(submissions: dict[str, tuple[list[Person], str]]) -> str:
    """``submission_metadata.yml`` as Gradescope writes it (Ruby symbols as keys)."""
    out = []
    for folder, (people, created) in submissions.items():
        out.append(f"{folder}:\n  :submitters:")
        for p in people:
            out.append(f"  - :name: {p.full}\n    :sid: '{p.number}'\n    :email: {p.email}")
        out.append(f"  :created_at: {created}\n  :score: 0.0\n  :status: processed\n"
                   "  :results: {}\n  :history: []")
    return "\n".join(out) + "\n"


# -------------------------------------------------------------------------------- Blackboard

def blackboard_grade_center(people=CLASS) -> bytes:
    """Work Offline → Download: tab-delimited UTF-16 (Blackboard's ``.xls``)."""
    rows = [["Last Name", "First Name", "Username", "Student ID", "Last Access",
             "Availability", "HW1 [Total Pts: 10 Score] |3301"]]
    rows += [[p.last, p.first, p.login or p.email.split("@")[0], p.number, "", "Yes", ""]
             for p in people]
    rows.append(["PreviewUser", "Instructor", "instr_previewuser", "", "", "Yes", ""])
    return csv_text(rows, delimiter="\t").encode("utf-16")


def blackboard_file_name(assignment: str, username: str, time: str, original: str | None) -> str:
    base = f"{assignment}_{username}_attempt_{time}"
    return f"{base}_{original}" if original else f"{base}.txt"


# --------------------------------------------------------------------------------- notebooks

def notebook(hw: Path, sid: str, right: bool = True) -> str:
    """The student's solutions notebook (every answer right) or with every answer replaced by
    a string (every answer invalid: no points)."""
    nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text(encoding="utf-8"))
    if not right:
        for cell in nb["cells"]:
            src = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
            cell["source"] = "\n".join(
                re.sub(r"^(q\d+_\w+) = .*$", r"\1 = 'no idea'", line)
                for line in src.splitlines())
    return json.dumps(nb)
