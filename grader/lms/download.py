"""A bulk download of submissions → the ``(student id, notebook)`` pairs of :mod:`grader.discover`.

Each LMS module's ``match_download(folder, students)`` recognises its own layout from file and
folder names (or returns None) and proposes :class:`Candidate` notebooks, each matched to a
roster student through the LMS's own identifiers (:class:`Students`) — never from the notebook's
content. :func:`settle` then decides, once for every LMS:

* one candidate for a student → that notebook is graded;
* several, with an order the LMS gives (Canvas attachment ids, Blackboard attempt times,
  Gradescope submission times) → the newest is graded, and a note says which and what was left;
* several with no such order → not guessed: the student's submission fails with the list;
* files that match no one, or are not notebooks (``.DS_Store``, a PDF, an online-text page) →
  listed with the reason and not graded.

The layout is recognised in the folder given, or in its only sub-folder (a zip that holds one
folder, a download unzipped into a folder of its own).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from grader.discover import Discovery, Problem, Submission
from grader.lms.classlist import cell, fold

NOTEBOOK = ".ipynb"
SYSTEM_FILES = frozenset({".ds_store", "thumbs.db", "desktop.ini", "__macosx"})


@dataclass(frozen=True)
class Candidate:
    """A notebook the download attributes to a roster student.

    ``newness`` orders several candidates of one student (larger is newer), or is None when
    the LMS gives no order. ``how`` says how the file was matched (for people).
    """

    student_id: str
    path: Path
    newness: tuple | None
    late: bool = False
    how: str = ""


@dataclass
class Matched:
    """What an LMS module found in a download folder."""

    layout: str
    candidates: list[Candidate] = field(default_factory=list)
    problems: list[Problem] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def stray(self, path: Path, why: str) -> None:
        """A file that is not a submission (reported, not counted as ungraded)."""
        self.problems.append(Problem(path, f"{path.name}: {why}; ignored", ignored=True))

    def unmatched(self, path: Path, why: str) -> None:
        """A notebook that belongs to no roster student (reported as not graded)."""
        self.problems.append(Problem(path, f"{path.name}: {why}; not graded"))


class Students:
    """The roster, indexed by the identifiers an LMS puts in its downloads.

    Parameters
    ----------
    rows : sequence of dict
        The roster rows (each with ``"id"`` and the class list's own columns).
    """

    def __init__(self, rows: Sequence[Mapping[str, str]]):
        self.rows = tuple(rows)
        self.ids = tuple(r["id"] for r in self.rows)
        self._index: dict[str, dict[str, list[str]]] = {}  # column -> folded value -> ids

    def by_column(self, column: str, value: str) -> list[str]:
        """Ids of the students whose ``column`` equals ``value`` (compared by ``fold``)."""
        if column not in self._index:
            index: dict[str, list[str]] = {}
            for r in self.rows:
                key = fold(r["id"] if column == "id" else cell(r, column))
                if key:
                    index.setdefault(key, []).append(r["id"])
            self._index[column] = index
        return list(self._index[column].get(fold(value), [])) if value else []

    def has_column(self, column: str) -> bool:
        return any(cell(r, column) for r in self.rows)

    def by_any(self, pairs: Iterable[tuple[str, str]]) -> tuple[list[str], str]:
        """The first ``(column, value)`` that names exactly one student: ``([id], how)``;
        otherwise the ids it named (several: ambiguous) or ``[]``, and how."""
        seen: list[str] = []
        for column, value in pairs:
            if not value:
                continue
            ids = self.by_column(column, value)
            if len(ids) == 1:
                return ids, f"{column} {value!r}"
            seen = seen or ids
        return seen, ""


def is_system_file(path: Path) -> bool:
    return path.name.lower() in SYSTEM_FILES or path.name.startswith("._")


def files_under(folder: Path) -> list[Path]:
    """Every regular file below ``folder`` (symbolic links are not followed), sorted."""
    out = []
    for p in sorted(folder.rglob("*")):
        if p.is_symlink() or not p.is_file():
            continue
        out.append(p)
    return out


def download_root(folder: Path, recognise) -> tuple[Path, object] | None:
    """``(folder, match)`` where ``recognise(folder)`` succeeds: ``folder`` or its only child."""
    match = recognise(folder)
    if match is not None:
        return folder, match
    children = [c for c in folder.iterdir() if not is_system_file(c) and not c.name.startswith(".")]
    if len(children) == 1 and children[0].is_dir() and not children[0].is_symlink():
        match = recognise(children[0])
        if match is not None:
            return children[0], match
    return None


def settle(student_ids: Sequence[str], matched: Matched) -> Discovery:
    """The module docstring's rules, applied to what an LMS module found."""
    by_id: dict[str, list[Candidate]] = {}
    for c in matched.candidates:
        by_id.setdefault(c.student_id, []).append(c)
    submissions, missing = [], []
    problems, notes = list(matched.problems), list(matched.notes)
    for sid in student_ids:
        found = by_id.get(sid, [])
        if not found:
            missing.append(sid)
            continue
        chosen, note = _choose(sid, found)
        if chosen is None:
            problems.append(Problem(found[0].path, note, sid))
            continue
        submissions.append(Submission(sid, chosen.path, late=chosen.late, source=chosen.how))
        if note:
            notes.append(note)
        if chosen.late:
            notes.append(f"{sid}: submitted late ({chosen.path.name})")
    return Discovery(tuple(submissions), tuple(missing), tuple(problems), tuple(notes),
                     matched.layout)


def _choose(sid: str, found: list[Candidate]) -> tuple[Candidate | None, str]:
    if len(found) == 1:
        return found[0], ""
    distinct = len({c.path.name for c in found}) == len(found)

    def label(c: Candidate) -> str:
        return c.path.name if distinct else f"{c.path.parent.name}/{c.path.name}"

    names = ", ".join(label(c) for c in found)
    if any(c.newness is None for c in found):
        return None, (f"{len(found)} notebooks ({names}) and no way to tell which is newest; "
                      "not guessing which one to grade")
    ordered = sorted(found, key=lambda c: c.newness)
    older = ", ".join(label(c) for c in ordered[:-1])
    return ordered[-1], (f"{sid}: {len(found)} notebooks; graded the newest, "
                         f"{label(ordered[-1])} (not {older})")


def discover_download(folder: Path, student_rows: Sequence[Mapping[str, str]]) -> Discovery | None:
    """The discovery of an LMS download in ``folder``, or None when it is no LMS's layout."""
    from grader.lms.registry import LMS

    students = Students(student_rows)
    for module in LMS.values():
        found = download_root(folder, lambda f, m=module: m.match_download(f, students))
        if found is not None:
            return settle(students.ids, found[1])
    return None
