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

import json
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import nbformat
import pytest

import grader.assignment
import grader.grade_one
import grader.publish
from eulertop.cli import main
from grader.assignment import load_assignment
from grader.graded_folder import GRADES, RESULTS
from grader.overrides import OVERRIDES, read_overrides
from grader.pipeline import grade_assignment
from grader.publish import stale_page
from grader.rescore import Amendment, Loaded, amended_class, rescore
from grader.results import read_result
from grader.reviews import REVIEWS, Review, read_reviews
from grader.written import text_sha256
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute
from tests.grader.test_written import OWN, Graded, _class

STAMP = "2026-03-01T12:00:00+00:00"
INPUTS = ("key.json", "assignment.json", f"graded/{OVERRIDES}", f"graded/{REVIEWS}")
"""What a change writes that the records are made from: a full rescore reads these."""
REPORT = ("graded/report.html", "graded/report.csv", "graded/report_items.csv")
TRAIL = "graded/audit.jsonl"
GRADES_PATH = f"graded/{GRADES}"
KEYED = ("one student's key",)
"""The steps that change the key: the others settle the stored comparisons again."""


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


def _comparisons(monkeypatch) -> list[str]:
    """The students whose answers are compared with the key, or whose whole key entry is
    read (its answers built: an expression answer parses with sympy), from now on."""
    met: list[str] = []
    compare, key_answers = grader.grade_one.compare, grader.assignment.key_answers

    def comparing(expected, extracted):
        met.append(f"compared {expected[0].variable if expected else ''}")
        return compare(expected, extracted)

    def reading(key, student_id):
        met.append(f"key of {student_id}")
        return key_answers(key, student_id)

    monkeypatch.setattr(grader.grade_one, "compare", comparing)
    monkeypatch.setattr(grader.assignment, "key_answers", reading)
    return met


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
        read, met = _reads(monkeypatch), _comparisons(monkeypatch)
        assert step() == 0, (what, capsys.readouterr())
        if student is not None:
            assert read == [student], what  # that student's record alone
        if what in KEYED:  # the key changed: that student's answers compared with it again
            assert met and "key of " + str(student) in met, (what, met)
        elif student is not None:  # its stored comparisons settled again: no key read
            assert met == [], (what, met)
        else:  # the whole class: compared with nothing (its report reads every key)
            assert not [m for m in met if m.startswith("compared")], (what, met)
        read.clear()
        monkeypatch.undo()
        monkeypatch.setattr(grader.grade_one, "now", lambda: STAMP)
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


PROBE = ("import sys; from eulertop.cli import main; code = main(sys.argv[1:]); "
         "print('sympy imported:', 'sympy' in sys.modules); sys.exit(code)")
"""A command run in a fresh process, saying whether it imported sympy (which parsing an
expression answer of the key needs)."""


def _sympy_imported(*args: str) -> bool:
    done = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True,
                          text=True, check=False, cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout.strip().splitlines()[-1] == "sympy imported: True"


def _every_family_class(folder: Path) -> Path:
    """A class of three given every built-in family (expression answers among them), each
    handing in the key's own values as literals, graded with the fake execution stage."""
    roster = Roster(("id", "name"), tuple({"id": s, "name": s} for s in ("s1", "s2", "s3")))
    hw = folder / "HW"
    generate_assignment(roster, hw, FAMILIES, seed=34)
    key = json.loads((hw / "key.json").read_text())
    (folder / "subs").mkdir()
    for sid, entry in key["students"].items():
        code = "\n".join(f"q{q['question']}_{x['name']} = {x['value']!r}"
                         for q in entry["questions"] for x in q["answers"])
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)])
        (folder / "subs" / f"{sid}.ipynb").write_text(nbformat.writes(nb))
    grade_assignment(hw, folder / "subs", limits="literal", execute=LiteralExecute())
    return hw


def test_a_change_of_one_student_parses_no_expression_unless_their_key_changes(tmp_path):
    """In a class of every built-in family (expression answers among them), an override, its
    removal and an extension settle the stored comparisons in a fresh process that never
    imports sympy; a change of that student's key compares again, and does."""
    folder = _every_family_class(tmp_path)
    hw, sid, results = str(folder), "s2", folder / "graded" / RESULTS
    kinds = {k.answer.kind for k in load_assignment(folder).expected(sid)}
    assert "expression" in kinds
    variable = read_result(results / f"{sid}.json").answers[0].variable
    assert not _sympy_imported("override", hw, sid, variable, "--points", "0",
                               "--reason", "copied")
    assert read_result(results / f"{sid}.json").overridden[variable]["points"] == 0
    assert not _sympy_imported("override", hw, sid, "--points", "1", "--reason", "total")
    assert not _sympy_imported("override", hw, sid, variable, "--remove")
    _sympy_imported("late", "set", hw, "--due", "2020-01-01T00:00:00+00:00",  # the class's:
                    "--penalty", "10%/day")  # its report reads every key
    assert not _sympy_imported("late", "extend", hw, sid, "--due", "2030-01-01T00:00:00+00:00",
                               "--reason", "ill")
    assert _sympy_imported("key", "set", hw, f"{sid}:{variable}", "--points", "7")
