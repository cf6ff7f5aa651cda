"""Gradescope: its roster as a class list, "Export Submissions", and a score upload.

Class list — Roster → Download Roster
    Header ``First Name, Last Name, SID, Email, …`` (or ``Name, SID, Email``). **Student id**:
    the SID, or — where it is empty — the email address.

Bulk download — Assignment → Review Grades → "Export Submissions" (a zip)
    One folder ``assignment_<n>_export/`` holding ``submission_metadata.yml`` and one folder
    ``submission_<id>/`` per active submission with the files submitted. The metadata maps each
    ``submission_<id>`` to ``:submitters:`` (a list — several for a group — of ``:name:``,
    ``:sid:``, ``:email:``) and ``:created_at:``. **Matched** by SID (against the class list's
    ``SID`` column or the student id), then by email; every member of a group gets the
    group's notebook. Of several submissions naming one student the newest (``:created_at:``)
    is graded.

Upload — a score upload
    ``Email, SID, Score``, one row per student.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import re
from datetime import datetime
from pathlib import Path

from grader.lms.classlist import ClassListFormat, Grades, ImportError_, cell
from grader.lms.download import (
    NOTEBOOK,
    Candidate,
    Matched,
    Students,
    files_under,
    is_system_file,
)
from grader.submissions import Problem

CLASS_LIST = ClassListFormat(
    name="gradescope",
    label="Gradescope roster",
    required=("SID", "Email"),
    id_columns=("SID", "Email"),
    email_columns=("Email",),
    name_columns=("First Name", "Last Name", "Name"),
)

METADATA = "submission_metadata.yml"
MAX_METADATA_BYTES = 50 * 1024**2
_TIME = re.compile(r"^(\d{4}-\d{2}-\d{2}[ T]\d{2}:\d{2}:\d{2})(?:\.\d+)?\s*([+-]\d{2}:?\d{2}|Z)?")


def created_at(value: object) -> float:
    """``:created_at:`` as a POSIX time (0 when absent or unreadable).

    Examples
    --------
    >>> created_at("2024-03-01 23:59:30.123456789 -08:00") - created_at("2024-03-02 07:59:30 Z")
    0.0
    """
    if isinstance(value, datetime):
        return value.timestamp()
    m = _TIME.match(str(value or ""))
    if not m:
        return 0.0
    zone = (m.group(2) or "Z").replace("Z", "+00:00")
    return datetime.fromisoformat(m.group(1).replace(" ", "T") + zone).timestamp()


def _iso(value: object) -> str:
    """``:created_at:`` as ISO 8601 (its offset kept; ``""`` when absent or unreadable: the
    grading run then names it)."""
    if isinstance(value, datetime):
        return value.isoformat()
    m = _TIME.match(str(value or ""))
    if not m:
        return str(value or "")
    zone = (m.group(2) or "").replace("Z", "+00:00")
    if zone and ":" not in zone:
        zone = zone[:3] + ":" + zone[3:]
    return m.group(1).replace(" ", "T") + zone


def _metadata(path: Path) -> dict | str:
    """The metadata as a dict, or why it cannot be read."""
    import yaml

    try:
        if path.stat().st_size > MAX_METADATA_BYTES:
            return f"larger than {MAX_METADATA_BYTES // 1024**2} MB"
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as e:
        return str(e).splitlines()[0]
    return data if isinstance(data, dict) else "not a mapping of submissions"


def _field(record: dict, name: str) -> object:
    return record.get(f":{name}", record.get(name))


def recognises(entry: Path) -> bool:
    """Is ``entry`` the metadata file or a submission folder of Gradescope's export?"""
    if entry.name == METADATA:
        return entry.is_file()
    return entry.is_dir() and re.fullmatch(r"submission_\d+", entry.name) is not None


def match_download(folder: Path, students: Students) -> Matched | None:
    """Gradescope's layout in ``folder`` (``submission_metadata.yml`` present), or None."""
    meta_path = folder / METADATA
    if not meta_path.is_file():
        return None
    found = Matched("gradescope")
    meta = _metadata(meta_path)
    if isinstance(meta, str):
        found.problems.append(Problem(meta_path, f"{METADATA} cannot be read: {meta}"))
        meta = {}
    for entry in sorted(folder.iterdir()):
        if entry.name == METADATA:
            continue
        if is_system_file(entry) or not entry.is_dir() or entry.is_symlink():
            found.stray(entry, "not a submission folder of a Gradescope export")
        elif not isinstance(meta.get(entry.name), dict):
            found.unmatched(entry, f"not described in {METADATA}")
        else:
            _submission(entry, meta[entry.name], students, found)
    return found


def _submission(folder: Path, record: dict, students: Students, found: Matched) -> None:
    files = [f for f in files_under(folder) if not is_system_file(f)]
    notebooks = [f for f in files if f.name.endswith(NOTEBOOK)]
    for f in files:
        if f not in notebooks:
            found.stray(f, f"not a notebook (.ipynb) — in {folder.name}")
    submitters = _field(record, "submitters") or []
    when = created_at(_field(record, "created_at"))
    number = int(re.sub(r"\D", "", folder.name) or 0)
    for person in submitters if isinstance(submitters, list) else []:
        person = person if isinstance(person, dict) else {}
        sid, email = (str(_field(person, k) or "").strip() for k in ("sid", "email"))
        ids, how = students.by_any([("SID", sid), ("id", sid), ("Email", email), ("id", email),
                                    ("Email address", email)])
        who = f"{_field(person, 'name') or '?'} (SID {sid or '-'}, {email or 'no email'})"
        if len(ids) != 1:
            why = "matches several roster students" if ids else "is not on the roster"
            found.unmatched(folder, f"submitter {who} {why}")
            continue
        if not notebooks:
            found.problems.append(Problem(folder, f"{folder.name}: {who} submitted no "
                                                   "notebook (.ipynb)"))
        for nb in notebooks:
            found.candidates.append(Candidate(
                ids[0], nb, (when, number) if len(notebooks) == 1 else None,
                how=f"Gradescope {how}", submitted_at=_iso(_field(record, "created_at")),
                time_source=f"Gradescope's :created_at: of {folder.name}"))


def write_import(grades: Grades) -> list[list[str]]:
    """Rows of the score upload (module docstring)."""
    fmt = CLASS_LIST
    lacking = [r["id"] for r in grades.rows if not (cell(r, "SID") or fmt.email(r)
                                                     or cell(r, "Email address"))]
    if lacking:
        raise ImportError_(
            "Gradescope matches students by email or SID, and the roster has neither for "
            f"{', '.join(lacking[:5])}{' …' if len(lacking) > 5 else ''}: export with "
            "--roster <Gradescope roster>")
    table = [["Email", "SID", "Score"]]
    for r in grades.rows:
        table.append([fmt.email(r) or cell(r, "Email address"), cell(r, "SID"),
                      grades.scores[r["id"]]])
    return table
