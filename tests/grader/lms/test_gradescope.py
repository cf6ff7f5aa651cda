"""Gradescope, end to end without kernels: roster + "Export Submissions" zip → score upload."""

from __future__ import annotations

import pytest

from grader.gradebook import number
from grader.lms.export import write_export
from grader.lms.gradescope import created_at
from tests.grader.lms.conftest import generate, grade, read_csv, results
from tests.grader.lms.exports import (
    CLASS,
    GARCIA1,
    GARCIA2,
    MULLER,
    NUNEZ,
    WEI,
    Person,
    gradescope_metadata,
    gradescope_roster,
    notebook,
    write_zip,
)

STRANGER = Person("Eve", "Nobody", "eve@elsewhere.example", "", "X999", 0, 0)
TOP = "assignment_412345_export"


@pytest.fixture(scope="module")
def gradescope(tmp_path_factory):
    """A group submission, a student in two submissions (the later one, by the clock, in
    another time zone), a PDF beside a notebook, a stranger, __MACOSX, a missing student —
    in Gradescope's zip, whose one top folder holds everything."""
    root = tmp_path_factory.mktemp("gradescope")
    hw = generate(root, "roster.csv", gradescope_roster())
    meta = gradescope_metadata({
        "submission_2001": ([MULLER], "2024-03-01 20:00:00.123456789 -08:00"),
        "submission_2002": ([NUNEZ, GARCIA1], "2024-03-01 21:00:00.000000000 -08:00"),
        "submission_2003": ([GARCIA2], "2024-03-02 09:00:00.000000000 +01:00"),  # 08:00 UTC
        "submission_2010": ([GARCIA2], "2024-03-02 01:30:00.000000000 -08:00"),  # 09:30 UTC
        "submission_2004": ([WEI], "2024-03-01 10:00:00.000000000 -08:00"),
        "submission_2099": ([STRANGER], "2024-03-01 10:00:00.000000000 -08:00"),
    })
    download = write_zip(root / "submissions.zip", {
        f"{TOP}/submission_metadata.yml": meta,
        f"{TOP}/submission_2001/hw.ipynb": notebook(hw, "S1001"),
        f"{TOP}/submission_2002/hw.ipynb": notebook(hw, "S1002"),
        f"{TOP}/submission_2003/hw.ipynb": notebook(hw, "S1004"),
        f"{TOP}/submission_2010/hw.ipynb": notebook(hw, "S1004", right=False),
        f"{TOP}/submission_2004/hw.ipynb": notebook(hw, "lwei@uni.example"),
        f"{TOP}/submission_2004/derivation.pdf": b"%PDF-1.4\n",
        f"{TOP}/submission_2099/hw.ipynb": notebook(hw, "S1001"),
        "__MACOSX/._submission_metadata.yml": b"\0",
    })
    return hw, grade(hw, download)


def test_created_at_is_compared_as_a_time_not_as_text():
    assert created_at("2024-03-02 01:30:00.000000000 -08:00") > \
        created_at("2024-03-02 09:00:00.000000000 +01:00")


def test_submitters_are_matched_by_sid_and_groups_share_their_notebook(gradescope):
    hw, report = gradescope
    got = results(report)
    for sid in ("S1001", "S1002", "lwei@uni.example"):
        assert got[sid].status == "graded" and got[sid].points == got[sid].max_points > 0, sid
    assert got["S1006"].status == "missing"
    # the group's notebook holds Ñúñez's answers: García is graded on it, against her own key
    assert got["S1003"].status == "graded"
    assert "names student 'S1002'; it was graded as 'S1003'" in got["S1003"].message
    rows = {r[0]: r for r in read_csv(hw / "graded" / "submissions.csv")[1:]}
    assert rows["S1003"][1] == rows["S1002"][1] == f"{TOP}/submission_2002/hw.ipynb"
    assert rows["S1002"][4] == "Gradescope SID 'S1002'"


def test_of_two_submissions_the_newest_by_the_clock_is_graded(gradescope):
    _, report = gradescope
    assert results(report)["S1004"].points == 0  # submission_2010, 09:30 UTC, all invalid
    assert "S1004: 2 notebooks; graded the newest, submission_2010/hw.ipynb (not " \
        "submission_2003/hw.ipynb)" in report.notes


def test_strangers_and_strays_are_listed(gradescope):
    _, report = gradescope
    assert report.not_graded == (
        "submission_2099: submitter Eve Nobody (SID X999, eve@elsewhere.example) is not on "
        "the roster; not graded",)
    assert sorted(p.path.name for p in report.problems if p.ignored) == ["derivation.pdf"]


def test_export_is_the_score_upload(gradescope):
    hw, report = gradescope
    out, _ = write_export(hw, "gradescope")
    table = read_csv(out)
    assert table[0] == ["Email", "SID", "Score"]
    assert [r[:2] for r in table[1:]] == [[p.email, p.number] for p in CLASS]
    full = number(results(report)["S1001"].max_points)
    scores = [r[2] for r in table[1:]]
    assert scores[:2] + scores[3:] == [full, full, "0", full, ""]
    assert scores[2] == number(results(report)["S1003"].points)


def test_each_submission_s_time_is_recorded_from_the_metadata(gradescope):
    """For the late policy (issue 32): ``:created_at:`` with its offset, and where it came
    from; the newest of two submissions gives its own time."""
    _, report = gradescope
    got = results(report)
    assert got["S1001"].submitted == {
        "at": "2024-03-01T20:00:00.123456-08:00",  # as YAML reads it: to the microsecond
        "source": "Gradescope's :created_at: of submission_2001"}
    assert got["S1004"].submitted["at"] == "2024-03-02T01:30:00-08:00"
    assert got["S1006"].submitted == {}  # missing
