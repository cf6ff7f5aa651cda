"""A bulk download of submissions → the ``(student id, notebook)`` pairs of :mod:`grader.discover`.

Each LMS module says which entries of a folder are named as its downloads name them
(``recognises(entry)``); the folder is read as the download of the LMS that recognises the most
of its entries (ties in :data:`grader.lms.registry.LMS` order), so that a student's file name,
which can make only that student's own entries look like another LMS's, cannot change how the
class is read. That module's ``match_download(folder, students)`` then proposes
:class:`Candidate` notebooks, each matched to a roster student through the identifiers the LMS
itself writes into its names (:class:`Students`), in positions the student's own file name
cannot reach — never from the notebook's content. :func:`settle` then decides, once for every
LMS:

* one candidate for a student → that notebook is graded;
* several, with an order the LMS gives (Canvas attachment ids, Blackboard attempt times,
  Gradescope submission times) → the newest is graded, and a note says which and what was left;
* several with no such order → not guessed: the student's submission fails with the list;
* a candidate refused from the archive (:mod:`grader.lms.archive`) and chosen → its student's
  invalid submission, saying why;
* files that match no one, or are not notebooks (``.DS_Store``, a PDF, an online-text page) →
  listed with the reason and not graded.

Every file matched to a student and not graded is kept in :attr:`Discovery.set_aside` with why,
for ``submissions.csv`` (:func:`submissions_table`). The layout is recognised in the folder
given, or in its only sub-folder (a zip that holds one folder, a download unzipped into a folder
of its own).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from grader.lms.classlist import cell, fold
from grader.submissions import Discovery, Problem, Submission

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
    submitted_at: str = ""  # when it came in, as the LMS wrote it (ISO 8601, maybe no offset)
    time_source: str = ""


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
        self._rows = {r["id"]: r for r in self.rows}
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

    def row(self, student_id: str) -> Mapping[str, str]:
        """The roster row of ``student_id``."""
        return self._rows[student_id]

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


def settle(student_ids: Sequence[str], matched: Matched,
           refused: Mapping[Path, str] | None = None) -> Discovery:
    """The module docstring's rules, applied to what an LMS module found.

    ``refused`` maps the placeholder of each entry refused from the archive to why
    (:attr:`grader.lms.archive.Extraction.refused`).
    """
    refused = refused or {}
    by_id: dict[str, list[Candidate]] = {}
    for c in matched.candidates:
        by_id.setdefault(c.student_id, []).append(c)
    submissions, missing, set_aside = [], [], []
    problems, notes = list(matched.problems), list(matched.notes)
    for sid in student_ids:
        found = by_id.get(sid, [])
        if not found:
            missing.append(sid)
            continue
        chosen, note = _choose(sid, found)
        set_aside += [Problem(c.path, refused.get(c.path) or _not_chosen(chosen, note), sid)
                      for c in found if c is not chosen]
        if chosen is None:
            why = list(dict.fromkeys(refused[c.path] for c in found if c.path in refused))
            message = f"invalid submission: {'; '.join(why)}" if why else note
            problems.append(Problem(found[0].path, message, sid))
            continue
        submissions.append(Submission(sid, chosen.path, late=chosen.late, source=chosen.how,
                                      submitted_at=chosen.submitted_at,
                                      time_source=chosen.time_source))
        if note:
            notes.append(note)
        if chosen.late and chosen.path not in refused:
            notes.append(f"{sid}: submitted late ({chosen.path.name})")
    return Discovery(tuple(submissions), tuple(missing), tuple(problems), tuple(notes),
                     matched.layout, tuple(set_aside))


def _not_chosen(chosen: Candidate | None, note: str) -> str:
    return note if chosen is None else f"older than {chosen.path.name}, which was graded"


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


def submissions_table(found: Discovery, root: Path) -> list[list[str]]:
    """``OUT/submissions.csv``: every file of an LMS download — the one graded for each student
    and how it was matched, then each one set aside or not graded, with its owner where known
    and why."""
    table = [["id", "file", "late", "submitted at", "matched by", "not graded"]]
    for s in found.submissions:
        table.append([s.student_id, _relative(s.path, root), "yes" if s.late else "",
                      s.submitted_at, s.source, ""])
    listed = {p.path for p in found.set_aside}
    for p in (*found.set_aside, *(p for p in found.problems if p.path not in listed)):
        table.append([p.student_id or "", _relative(p.path, root), "", "", "", p.message])
    return table


def _relative(path: Path, root: Path) -> str:
    return str(path.relative_to(root)) if path.is_relative_to(root) else path.name
