"""A change of one student reads and writes only that student (issue 34): an override, a key
change of one student's answer, a review and an extension read that student's record alone,
and rewrite their record, their page and their lines of ``grades.csv`` and ``answers.csv``,
keeping every other line's bytes — and the class is then byte for byte what a full
``rescore`` makes of the same inputs (key, overrides, reviews, manifest), on a copy of the
class that went through none of those scoped changes.

The class is the written-answers class of :mod:`tests.grader.test_written` (four students, a
family's written part and a standalone one), graded with the fake execution stage. Time
stamps are fixed (``graded_at``) so that records compare byte for byte.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

import grader.grade_one
import grader.publish
from eulertop.cli import main
from grader.assignment import load_assignment
from grader.graded_folder import GRADES, RESULTS
from grader.overrides import OVERRIDES, read_overrides
from grader.publish import stale_page
from grader.rescore import Amendment, Loaded, amended_class, rescore
from grader.results import read_result
from grader.reviews import REVIEWS, Review, read_reviews
from grader.written import text_sha256
from tests.grader.test_written import OWN, Graded, _class

STAMP = "2026-03-01T12:00:00+00:00"
INPUTS = ("key.json", "assignment.json", f"graded/{OVERRIDES}", f"graded/{REVIEWS}")
"""What a change writes that the records are made from: a full rescore reads these."""
REPORT = ("graded/report.html", "graded/report.csv", "graded/report_items.csv")
TRAIL = "graded/audit.jsonl"
GRADES_PATH = f"graded/{GRADES}"


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Graded:
    return _class(tmp_path_factory.mktemp("scoped"))


@pytest.fixture
def copies(pristine, tmp_path, monkeypatch) -> tuple[Path, Path]:
    """Two copies of the graded class (HW folders): one for the scoped changes, one for the
    full rescores; every record's ``graded_at`` one fixed time."""
    monkeypatch.setattr(grader.grade_one, "now", lambda: STAMP)
    made = []
    for name in ("scoped", "full"):
        shutil.copytree(pristine.hw.parent, tmp_path / name, symlinks=True)
        made.append(tmp_path / name / "HW")
    return made[0], made[1]


def _files(hw: Path) -> dict[str, bytes]:
    return {p.relative_to(hw).as_posix(): p.read_bytes()
            for p in (hw / "graded").rglob("*") if p.is_file() and p.name != ".lock"}


def _variable(hw: Path, sid: str) -> str:
    """``sid``'s first answer that earned its points."""
    record = read_result(hw / "graded" / RESULTS / f"{sid}.json")
    return next(a.variable for a in record.answers
                if a.verdict.status == "correct" and a.verdict.max_points > 0)


def _review(hw: Path, sid: str) -> int:
    """A review of ``sid``'s standalone written answer (items 1 and 3), made as the review desk
    makes it but from a class not loaded: the scoped path."""
    a, out = load_assignment(hw), hw / "graded"
    value = next(x.submitted for x in read_result(out / RESULTS / f"{sid}.json").answers
                 if x.variable == OWN)
    reviews = read_reviews(out)
    review = Review(sid, OWN, (0, 2), 0.5, "ok", "tester", STAMP, text_sha256(value))
    amendment = Amendment("review", f"review of {sid}'s {OWN}",
                          reviews=reviews.with_review(review), students=frozenset({sid}),
                          report=False, details={"student": sid, "answer": OWN})
    amended_class(Loaded(hw, out, a, read_overrides(out), reviews, None), amendment)
    return 0


def _steps(hw: Path) -> list[tuple[str, str | None, Callable[[], int]]]:
    """The changes, in order: each (what, the one student it reaches or None, a callable
    making it on ``hw``)."""
    h = str(hw)
    ada, bob, cyd = (_variable(hw, sid) for sid in ("ada", "bob", "cyd"))
    return [
        ("the class's first override (a column added)", "ada",
         lambda: main(["override", h, "ada", ada, "--points", "0", "--reason", "copied"])),
        ("an override of a total beside another", "bob",
         lambda: main(["override", h, "bob", "--points", "1", "--reason", "late work"])),
        ("one student's key", "cyd",
         lambda: main(["key", "set", h, f"cyd:{cyd}", "--points", "7"])),
        ("a review of one", "dee", lambda: _review(hw, "dee")),
        ("an override taken back, another kept", "ada",
         lambda: main(["override", h, "ada", ada, "--remove"])),
        ("the last override taken back (the column dropped)", "bob",
         lambda: main(["override", h, "bob", "--remove"])),
        ("a late policy (the whole class)", None,
         lambda: main(["late", "set", h, "--due", "2020-01-01T00:00:00+00:00",
                       "--penalty", "10%/day"])),
        ("an extension of one (the late columns kept)", "bob",
         lambda: main(["late", "extend", h, "bob", "--due", "2030-01-01T00:00:00+00:00",
                       "--reason", "ill"])),
        ("an override after an extension", "bob",
         lambda: main(["override", h, "bob", bob, "--points", "0.5", "--reason", "partly"])),
    ]


def _reads(monkeypatch) -> list[str]:
    """The students whose records the publishing step reads from now on, in order."""
    read: list[str] = []

    def counted(path: Path):
        read.append(Path(path).stem)
        return read_result(path)

    monkeypatch.setattr(grader.publish, "read_result", counted)
    return read


def _full_rescore_of(scoped: Path, full: Path) -> None:
    """``full`` given the inputs ``scoped`` has now, then rescored whole."""
    for name in INPUTS:
        if (scoped / name).exists():
            shutil.copyfile(scoped / name, full / name)
    rescore(full)


def _same_as_full(scoped: Path, full: Path) -> dict[str, bytes]:
    """``full`` rescored whole from ``scoped``'s inputs: every file of ``graded/`` the same
    (the report and the trail apart); ``scoped``'s files."""
    _full_rescore_of(scoped, full)
    now, made = _files(scoped), _files(full)
    assert sorted(now) == sorted(made)
    assert sorted(n for n in now if now[n] != made[n] and n not in REPORT and n != TRAIL) == []
    return now


def test_a_scoped_change_leaves_the_class_as_a_full_rescore_makes_it(copies, capsys,
                                                                     monkeypatch):
    scoped, full = copies
    for what, student, step in _steps(scoped):
        before = _files(scoped)
        read = _reads(monkeypatch)
        assert step() == 0, (what, capsys.readouterr())
        if student is not None:
            assert read == [student], what  # that student's record alone
        read.clear()
        now = _same_as_full(scoped, full)
        if student is not None:  # the report left to a later command, marked so
            page = before[REPORT[0]].decode()
            assert now[REPORT[0]].decode() in (page, stale_page(page)), what
            assert all(now[name] == before[name] for name in REPORT[1:]), what


def test_tables_not_as_the_records_made_them_are_made_from_every_record(copies, monkeypatch):
    """A gradebook whose line of the student is not what their record made, or an answers
    table that is missing, is made again from every record: the same text as a full
    rescore's."""
    scoped, full = copies
    grades = scoped / GRADES_PATH
    lines = grades.read_bytes().split(b"\r\n")
    lines[1] = lines[1].replace(b",", b";", 1)  # ada's line, edited by hand
    grades.write_bytes(b"\r\n".join(lines))
    read = _reads(monkeypatch)
    variable = _variable(scoped, "ada")
    assert main(["override", str(scoped), "ada", variable, "--points", "0",
                 "--reason", "r"]) == 0
    assert read == ["ada", "bob", "cyd", "dee"]  # ada's, then the others'
    _same_as_full(scoped, full)
    (scoped / "graded" / "answers.csv").unlink()
    read.clear()
    assert main(["override", str(scoped), "ada", variable, "--remove"]) == 0
    assert read == ["ada", "bob", "cyd", "dee"]
    _same_as_full(scoped, full)
