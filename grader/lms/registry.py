"""The LMS modules, in the order their layouts are recognised, and their class-list formats;
which LMS's download a folder is, and its discovery (:func:`discover_download`).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from types import ModuleType

from grader.lms import blackboard, canvas, gradescope, moodle
from grader.lms.classlist import ClassListFormat
from grader.lms.download import Students, is_system_file, settle
from grader.submissions import Discovery

LMS: dict[str, ModuleType] = {
    # A download is read as the LMS's whose names fit the most of its entries
    # (grader.lms.download.layout); on a tie, the first here: Gradescope (its metadata file is
    # unmistakable), Moodle before Canvas (a Moodle file name can also look like a Canvas
    # one), Blackboard last.
    "gradescope": gradescope,
    "moodle": moodle,
    "canvas": canvas,
    "blackboard": blackboard,
}

CLASS_LISTS: dict[str, ClassListFormat] = {
    # Detection order: the most specific header first (Canvas and Blackboard both have a
    # column that Gradescope's lacks; Moodle's "Email address" is its own).
    "canvas": canvas.CLASS_LIST,
    "blackboard": blackboard.CLASS_LIST,
    "gradescope": gradescope.CLASS_LIST,
    "moodle": moodle.CLASS_LIST,
}


def _roots(folder: Path) -> list[Path]:
    """``folder``, then its only sub-folder (if it has exactly one)."""
    children = [c for c in folder.iterdir() if not is_system_file(c) and not c.name.startswith(".")]
    only = children[0] if len(children) == 1 and children[0].is_dir() \
        and not children[0].is_symlink() else None
    return [folder] + ([only] if only else [])


def layout(folder: Path) -> ModuleType | None:
    """The LMS module that recognises the most entries of ``folder`` (ties: registry order), or
    None when none recognises any (module docstring)."""
    entries = [e for e in folder.iterdir() if not is_system_file(e)]
    counts = {m: sum(map(m.recognises, entries)) for m in LMS.values()}
    best = max(counts, key=counts.get, default=None)
    return best if best is not None and counts[best] else None


def discover_download(folder: Path, student_rows: Sequence[Mapping[str, str]],
                      refused: Mapping[Path, str] | None = None) -> Discovery | None:
    """The discovery of an LMS download in ``folder``, or None when it is no LMS's layout."""
    students = Students(student_rows)
    for root in _roots(folder):
        module = layout(root)
        found = module.match_download(root, students) if module else None
        if found is not None:
            return settle(students.ids, found, refused)
    return None
