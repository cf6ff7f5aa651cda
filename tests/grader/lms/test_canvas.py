"""Canvas, end to end without kernels: gradebook export + "Download Submissions" zip → import."""

from __future__ import annotations

import pytest

from grader.gradebook import number
from grader.lms.export import write_export
from tests.grader.lms.conftest import generate, grade, read_csv, results
from tests.grader.lms.exports import (
    CLASS,
    GARCIA1,
    GARCIA2,
    MULLER,
    NUNEZ,
    WEI,
    canvas_file_name,
    canvas_gradebook,
    notebook,
    write_zip,
)

RIGHT = {"jmuller", "znunez", "agarcia1", "4505"}


@pytest.fixture(scope="module")
def canvas(tmp_path_factory):
    """A Canvas class graded from its own zip: a resubmission, a late file, a PDF beside a
    notebook, a .DS_Store, a user not on the roster, one student without a submission."""
    root = tmp_path_factory.mktemp("canvas")
    hw = generate(root, "gradebook.csv", canvas_gradebook())
    download = write_zip(root / "course-homework-1-submissions.zip", {
        canvas_file_name(MULLER, 90001, "hw.ipynb"): notebook(hw, "jmuller"),
        canvas_file_name(NUNEZ, 90002, "hw.ipynb"): notebook(hw, "znunez", right=False),
        canvas_file_name(NUNEZ, 90010, "hw-1.ipynb"): notebook(hw, "znunez"),
        canvas_file_name(GARCIA1, 90003, "hw.ipynb"): notebook(hw, "agarcia1"),
        canvas_file_name(GARCIA1, 90005, "scan.pdf"): b"%PDF-1.4\n",
        canvas_file_name(GARCIA2, 90004, "hw.ipynb"): notebook(hw, "agarcia2", right=False),
        canvas_file_name(WEI, 90006, "homework.ipynb", late=True): notebook(hw, "4505"),
        ".DS_Store": b"\0\0\0\1Bud1",
        "dropdrop_4999_90007_hw.ipynb": notebook(hw, "jmuller"),
    })
    return hw, download, grade(hw, download)


def test_the_file_names_are_canvas_own():
    assert canvas_file_name(MULLER, 90001, "hw.ipynb") == "müllerjürgen_4501_90001_hw.ipynb"
    assert canvas_file_name(WEI, 1, "a.ipynb", late=True) == "weili_LATE_4505_1_a.ipynb"


def test_every_student_is_matched_by_canvas_user_id(canvas):
    _, _, report = canvas
    got = results(report)
    assert set(got) == {"jmuller", "znunez", "agarcia1", "agarcia2", "4505", "soneil"}
    for sid in RIGHT:
        assert got[sid].status == "graded"
        assert got[sid].points == got[sid].max_points > 0, sid
    assert (got["agarcia2"].status, got["agarcia2"].points) == ("graded", 0)
    assert got["soneil"].status == "missing"


def test_the_newest_upload_is_graded_and_lateness_kept(canvas):
    hw, _, report = canvas
    assert any("znunez: 2 notebooks; graded the newest" in n and "hw-1.ipynb" in n
               for n in report.notes)
    assert "4505: submitted late (weili_LATE_4505_90006_homework.ipynb)" in report.notes
    table = read_csv(hw / "graded" / "submissions.csv")
    assert table[0] == ["id", "file", "late", "matched by"]
    rows = {r[0]: r for r in table[1:]}
    assert rows["4505"][2] == "yes" and rows["jmuller"][2] == ""
    assert rows["znunez"][1] == "ñúñezzoë_4502_90010_hw-1.ipynb"
    assert rows["jmuller"][3] == "Canvas user id 4501"


def test_strays_and_strangers_are_listed_with_the_reason(canvas):
    _, _, report = canvas
    ignored = {p.path.name: p.message for p in report.problems if p.ignored}
    assert "not a notebook" in ignored["garcíaana_4503_90005_scan.pdf"]
    assert "system file" in ignored[".DS_Store"]
    stray = [p.message for p in report.problems if not p.ignored]
    assert stray == ["dropdrop_4999_90007_hw.ipynb: Canvas user 4999 is not on the roster; "
                     "not graded"]
    assert report.not_graded == tuple(stray)


def test_the_zip_is_extracted_inside_the_output_folder_only(canvas):
    hw, download, _ = canvas
    extracted = hw / "graded" / "download"
    assert (extracted / "müllerjürgen_4501_90001_hw.ipynb").is_file()
    assert sorted(p.name for p in download.parent.iterdir()) == [
        "HW", "course-homework-1-submissions.zip", "gradebook.csv"]


def test_a_second_run_on_the_same_zip_regrades_nothing(canvas):
    hw, download, _ = canvas
    again = grade(hw, download)
    assert again.graded_now == ()
    assert set(again.unchanged) == {"jmuller", "znunez", "agarcia1", "agarcia2", "4505",
                                    "soneil"}


def test_export_is_what_canvas_imports(canvas):
    hw, _, report = canvas
    out, _ = write_export(hw, "canvas", column_id="77001")
    table = read_csv(out)
    assert table[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section",
                        "Homework 1 (77001)"]
    full = number(results(report)["jmuller"].max_points)
    assert table[1] == ["Points Possible", "", "", "", "", full]
    assert [r[:4] for r in table[2:]] == [[p.sortable, str(p.canvas), p.number, p.login]
                                          for p in CLASS]
    scores = {r[1]: r[5] for r in table[2:]}
    assert scores == {"4501": full, "4502": full, "4503": full, "4504": "0", "4505": full,
                      "4506": ""}


def test_without_an_assignment_id_the_title_alone_and_missing_as_zero(canvas, tmp_path):
    hw, _, _ = canvas
    out, _ = write_export(hw, "canvas", tmp_path / "c.csv", missing_as_zero=True)
    table = read_csv(out)
    assert table[0][-1] == "Homework 1"
    assert table[-1][1] == "4506" and table[-1][-1] == "0"


def test_answers_csv_is_the_long_format_of_the_records(canvas):
    hw, _, report = canvas
    table = read_csv(hw / "graded" / "answers.csv")
    assert table[0] == ["id", "question", "answer", "variable", "submitted", "points", "max",
                        "status", "mistake"]
    got = results(report)
    for sid, r in got.items():
        mine = [row for row in table[1:] if row[0] == sid]
        assert [row[3] for row in mine] == [a.variable for a in r.answers]
        assert sum(float(row[5]) for row in mine) == pytest.approx(r.points)
    wrong = [row for row in table[1:] if row[0] == "agarcia2"]
    assert wrong and all(row[4] == '"no idea"' and row[7] == "invalid" for row in wrong)
