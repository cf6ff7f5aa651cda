"""What the feedback pages show of the key: every page alike, whichever command wrote it last.

A change of some students (an override, a review, an extension) writes their pages alone; a
page shows the student's key values when the command writing it was given ``--reveal``. So
after ``rescore --reveal``, an override without it used to hide the key on that student's
page alone. Now the class's pages are all written again when the command's flag is not what
they show (``HW/graded/pages.json``), or when that is not known. The class is graded with the
fake execution stage of the report's tests (no kernel: the submissions are the solutions).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from eulertop.cli import main
from grader.assignment import load_assignment
from grader.graded_folder import FEEDBACK, PAGES, RESULTS
from grader.pipeline import _Writer, grade_assignment
from grader.results import read_result
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute

STUDENTS = ("s1", "s2", "s3", "s4")
KEY_COLUMN = "<th>key</th>"  # the answers table's column of key values, shown with --reveal


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Path:
    hw = tmp_path_factory.mktemp("reveal") / "HW"
    roster = Roster(("id",), tuple({"id": sid} for sid in STUDENTS))
    generate_assignment(roster, hw, FAMILIES, problems=["sleeping_top"], seed=4)
    return hw


def _graded(generated: Path, tmp_path: Path, reveal: bool) -> Path:
    hw = tmp_path / "HW"
    shutil.copytree(generated, hw)
    # the solutions handed in (yes: graded all the same): full marks, the key values on the page
    grade_assignment(hw, hw / "solutions", limits="LIMITS", execute=LiteralExecute(), jobs=1,
                     reveal=reveal, yes=True)
    return hw


def _pages(hw: Path) -> dict[str, str]:
    return {sid: (hw / "graded" / FEEDBACK / f"{sid}.html").read_text(encoding="utf-8")
            for sid in STUDENTS}


def _shown(hw: Path) -> bool | None:
    return json.loads((hw / "graded" / PAGES).read_text(encoding="utf-8"))["reveal"]


def _override(hw: Path, capsys, *flags: str) -> str:
    assert main(["override", str(hw), "s1", "--points", "0.5", "--reason", "r", *flags]) == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("reveal", [True, False])
def test_grading_writes_every_page_and_says_what_they_show(generated, tmp_path, reveal):
    hw = _graded(generated, tmp_path, reveal)
    assert all((KEY_COLUMN in page) is reveal for page in _pages(hw).values())
    assert _shown(hw) is reveal


@pytest.mark.parametrize("first, then", [(True, False), (False, True)])
def test_an_override_told_otherwise_writes_every_page_as_it_is_told(
        generated, tmp_path, capsys, first, then):
    hw = _graded(generated, tmp_path, first)
    out = _override(hw, capsys, *(["--reveal"] if then else []))
    pages = _pages(hw)
    assert all((KEY_COLUMN in page) is then for page in pages.values()), \
        "a class with pages of both kinds"
    assert _shown(hw) is then
    assert (f"every student's feedback page written again {'with' if then else 'without'} "
            f"their key values") in out
    assert ("they showed them" if first else "they did not show them") in out


@pytest.mark.parametrize("reveal", [True, False])
def test_an_override_told_the_same_writes_that_students_page_alone(
        generated, tmp_path, capsys, reveal):
    hw = _graded(generated, tmp_path, reveal)
    feedback = hw / "graded" / FEEDBACK
    before = {sid: (feedback / f"{sid}.html").stat().st_mtime_ns for sid in STUDENTS}
    text = _pages(hw)
    out = _override(hw, capsys, *(["--reveal"] if reveal else []))
    after = {sid: (feedback / f"{sid}.html").stat().st_mtime_ns for sid in STUDENTS}
    assert [sid for sid in STUDENTS if after[sid] != before[sid]] == ["s1"]
    assert _pages(hw)["s1"] != text["s1"] and (KEY_COLUMN in _pages(hw)["s1"]) is reveal
    assert "written again" not in out
    assert _shown(hw) is reveal


def test_a_class_whose_pages_are_not_known_has_them_all_written_once(
        generated, tmp_path, capsys):
    """Graded before ``pages.json`` was kept (here: with the key shown, then the file gone)."""
    hw = _graded(generated, tmp_path, True)
    (hw / "graded" / PAGES).unlink()
    out = _override(hw, capsys)
    assert "(what they showed was not recorded)" in out
    assert not any(KEY_COLUMN in page for page in _pages(hw).values())
    assert _shown(hw) is False
    assert "written again" not in _override(hw, capsys)  # known from now on


def test_a_regrade_told_otherwise_leaves_what_the_pages_show_unknown_until_it_ends(
        generated, tmp_path):
    """A grading run commits each student's page as it goes, and every page at its end; cut
    off between the two, the class holds pages of both kinds: ``pages.json`` is gone with the
    first page it writes, so the next change of one student writes them all."""
    hw = _graded(generated, tmp_path, True)
    out = hw / "graded"
    writer = _Writer(load_assignment(hw), out, (), False, None, {})
    try:
        writer(read_result(out / RESULTS / "s2.json"))
    finally:
        writer.close()
    assert KEY_COLUMN not in _pages(hw)["s2"] and KEY_COLUMN in _pages(hw)["s3"]
    assert not (out / PAGES).exists()
