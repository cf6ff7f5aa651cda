"""Blackboard, end to end without kernels: Grade Center export + assignment download → upload."""

from __future__ import annotations

from pathlib import Path

import pytest

from grader.gradebook import number
from grader.lms.export import write_export
from grader.lms.registry import CLASS_LISTS
from problems.roster import read_roster as read_any_roster
from tests.grader.lms.conftest import generate, grade, read_csv, results
from tests.grader.lms.exports import (
    blackboard_file_name,
    blackboard_grade_center,
    notebook,
    write_zip,
)


def read_roster(path, roster_format=None):
    """An eulertop roster or an LMS class list (the formats grader.lms knows)."""
    return read_any_roster(path, roster_format, CLASS_LISTS)

USERS = ("jmuller", "znunez", "agarcia1", "agarcia2", "lwei", "soneil")


@pytest.fixture(scope="module")
def blackboard(tmp_path_factory):
    """Two attempts by one student, receipts, a PDF, a missing student; the Grade Center
    export as Blackboard writes it (tab-delimited UTF-16, with the preview user)."""
    root = tmp_path_factory.mktemp("blackboard")
    hw = generate(root, "gc_export.xls", blackboard_grade_center())

    def attempt(user, time, right=True, original="hw.ipynb"):
        data = notebook(hw, user, right) if original.endswith(".ipynb") else b"%PDF-1.4\n"
        return {blackboard_file_name("HW_1", user, time, original): data,
                blackboard_file_name("HW_1", user, time, None): "Name: …\nDate Submitted: …\n"}

    download = write_zip(root / "gradebook_HW1.zip", {
        **attempt("jmuller", "2024-03-01-10-00-00"),
        **attempt("znunez", "2024-03-01-09-00-00", right=False),
        **attempt("znunez", "2024-03-01-11-30-00"),
        **attempt("agarcia1", "2024-03-01-08-00-00"),
        **attempt("agarcia1", "2024-03-01-08-00-00", original="work.pdf"),
        **attempt("agarcia2", "2024-03-01-08-00-00", right=False),
        **attempt("lwei", "2024-03-02-23-59-59"),
    })
    return hw, grade(hw, download)


def test_the_grade_center_export_is_read_with_usernames_as_ids(tmp_path):
    (tmp_path / "gc.xls").write_bytes(blackboard_grade_center())
    roster = read_roster(tmp_path / "gc.xls")
    assert (roster.format, roster.ids) == ("blackboard", USERS)
    assert any("left out Blackboard's preview user" in n for n in roster.notes)
    assert roster.rows[0]["First Name"] == "Jürgen"


def test_attempts_are_matched_by_username_and_the_newest_graded(blackboard):
    _, report = blackboard
    got = results(report)
    for sid in ("jmuller", "znunez", "agarcia1", "lwei"):
        assert got[sid].points == got[sid].max_points > 0, sid
    assert got["agarcia2"].points == 0 and got["soneil"].status == "missing"
    newest = "HW_1_znunez_attempt_2024-03-01-11-30-00_hw.ipynb"
    assert any(n.startswith(f"znunez: 2 notebooks; graded the newest, {newest}")
               for n in report.notes)
    assert [p.path.name for p in report.problems if p.ignored] == [
        "HW_1_agarcia1_attempt_2024-03-01-08-00-00_work.pdf"]
    assert report.not_graded == ()


def test_export_is_the_grade_center_upload(blackboard):
    hw, report = blackboard
    out, _ = write_export(hw, "blackboard", column_id="3301")
    text = out.read_text(encoding="utf-8")
    full = number(results(report)["jmuller"].max_points)
    assert text.splitlines()[0] == \
        f'"Last Name","First Name","Username","Homework 1 [Total Pts: {full} Score] |3301"'
    table = read_csv(out)
    assert [r[2] for r in table[1:]] == list(USERS)
    assert [r[3] for r in table[1:]] == [full, full, full, "0", full, ""]


def test_a_students_file_name_neither_changes_the_layout_nor_claims_a_classmate(tmp_path,
                                                                                blackboard):
    """Ñúñez's files: ``hw_1_2_final.ipynb`` (which also reads as a Canvas download name) and a
    wrong notebook named like Müller's attempt. Before, the whole download was read as Canvas's
    and no one in the class was graded; now the class is Blackboard's, Müller is graded on his
    own attempt, and the later attempt is Ñúñez's own."""
    hw, _ = blackboard
    forged = blackboard_file_name("HW_1", "jmuller", "2024-03-09-10-00-00", "hw.ipynb")
    download = write_zip(tmp_path / "d.zip", {
        blackboard_file_name("HW_1", "jmuller", "2024-03-01-10-00-00", "hw.ipynb"):
            notebook(hw, "jmuller"),
        blackboard_file_name("HW_1", "znunez", "2024-03-01-11-00-00", "hw_1_2_final.ipynb"):
            notebook(hw, "znunez"),
        blackboard_file_name("HW_1", "znunez", "2024-03-02-11-00-00", forged):
            notebook(hw, "znunez", right=False)})
    report = grade(hw, download, out=tmp_path / "graded")
    got = results(report)
    assert got["jmuller"].points == got["jmuller"].max_points > 0
    assert (got["znunez"].status, got["znunez"].points) == ("graded", 0)
    assert report.not_graded == ()


def test_attempt_times_need_the_policy_s_zone(blackboard, tmp_path):
    """Blackboard writes attempt times in the server's clock, without an offset (issue 32):
    without a late policy they are not needed; with one they are read in its ``zone``, and
    without a zone the run refuses, naming the file, before it writes anything."""
    import json
    import shutil
    from datetime import datetime, timedelta, timezone

    from grader.assignment import UsageError
    from problems.deadlines import LatePolicy

    hw, report = blackboard
    assert results(report)["jmuller"].submitted == {}
    copy = Path(shutil.copytree(hw, tmp_path / "HW"))
    manifest = json.loads((copy / "assignment.json").read_text())
    due = datetime(2024, 3, 1, 9, 0, tzinfo=timezone(timedelta(hours=-6)))
    manifest["late"] = LatePolicy(due=due, percent=10).record()
    (copy / "assignment.json").write_text(json.dumps(manifest))
    download = next(hw.parent.glob("gradebook_HW1.zip"))
    before = {p: p.read_bytes() for p in copy.rglob("*") if p.is_file()}
    with pytest.raises(UsageError, match=r"jmuller: Blackboard's attempt time in .*"
                                         r"has no time zone offset"):
        grade(copy, download)
    assert {p: p.read_bytes() for p in copy.rglob("*") if p.is_file()} == before
    manifest["late"]["zone"] = "America/Chicago"
    (copy / "assignment.json").write_text(json.dumps(manifest))
    got = results(grade(copy, download))
    assert got["jmuller"].submitted["at"] == "2024-03-01T10:00:00-06:00"
    assert got["jmuller"].late["periods"] == 1  # an hour after a 09:00 due time
