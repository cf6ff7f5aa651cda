"""Canvas, end to end without kernels: gradebook export + "Download Submissions" zip → import."""

from __future__ import annotations

import dataclasses

import pytest

from grader.gradebook import number
from grader.lms.export import write_export
from grader.lms.registry import CLASS_LISTS
from problems.roster import read_roster as read_any_roster
from tests.grader.lms.conftest import generate, grade, read_csv, results
from tests.grader.lms.exports import (
    CLASS,
    GARCIA1,
    GARCIA2,
    MULLER,
    NUNEZ,
    WEI,
    Person,
    canvas_file_name,
    canvas_gradebook,
    notebook,
    write_zip,
)


def read_roster(path, roster_format=None):
    """An eulertop roster or an LMS class list (the formats grader.lms knows)."""
    return read_any_roster(path, roster_format, CLASS_LISTS)

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
    assert table[0] == ["id", "file", "late", "submitted at", "matched by", "not graded"]
    rows = {r[0]: r for r in table[1:] if not r[5]}
    assert rows["4505"][2] == "yes" and rows["jmuller"][2] == ""
    assert rows["4505"][3] == ""  # Canvas's download says late, not when
    assert rows["znunez"][1] == "ñúñezzoë_4502_90010_hw-1.ipynb"
    assert rows["jmuller"][4] == "Canvas user id 4501"
    set_aside = {r[1]: (r[0], r[5]) for r in table[1:] if r[5]}
    assert set_aside["ñúñezzoë_4502_90002_hw.ipynb"] == (
        "znunez", "older than ñúñezzoë_4502_90010_hw-1.ipynb, which was graded")
    assert set_aside["dropdrop_4999_90007_hw.ipynb"][0] == ""
    assert "is not on the roster" in set_aside["dropdrop_4999_90007_hw.ipynb"][1]


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
                        "status", "mistake", "overridden"]
    got = results(report)
    for sid, r in got.items():
        mine = [row for row in table[1:] if row[0] == sid]
        assert [row[3] for row in mine] == [a.variable for a in r.answers]
        assert sum(float(row[5]) for row in mine) == pytest.approx(r.points)
    wrong = [row for row in table[1:] if row[0] == "agarcia2"]
    assert wrong and all(row[4] == '"no idea"' and row[7] == "invalid" for row in wrong)


# A student whose sortable name Canvas writes as "eve_4501_99999": Canvas's own reduction of
# "_<digits>_" does not see digits followed by punctuation, which it then removes.
EVE_BEFORE = Person("Eve", "Adams", "eadams@uni.example", "eadams", "S1099", 4599, 700199)
EVE = dataclasses.replace(EVE_BEFORE, first="_99999", last="Eve_4501,")


@pytest.fixture(scope="module")
def with_eve(tmp_path_factory):
    """The class and Eve, generated from a gradebook export made before Eve renamed herself;
    a download where Müller submitted the right answers and Eve, under her new name, wrong
    ones."""
    root = tmp_path_factory.mktemp("eve")
    hw = generate(root, "gradebook.csv", canvas_gradebook((*CLASS, EVE_BEFORE)))
    assert canvas_file_name(EVE, 90100, "hw.ipynb") == "eve_4501_99999_4599_90100_hw.ipynb"
    download = write_zip(root / "d.zip", {
        canvas_file_name(MULLER, 90001, "hw.ipynb"): notebook(hw, "jmuller"),
        canvas_file_name(EVE, 90100, "hw.ipynb"): notebook(hw, "eadams", right=False)})
    (root / "fresh.csv").write_text(canvas_gradebook((*CLASS, EVE)), encoding="utf-8")
    return hw, download, read_roster(root / "fresh.csv").rows


@pytest.mark.parametrize("fresh", [False, True], ids=["old-class-list", "fresh-class-list"])
def test_a_name_holding_a_classmates_ids_does_not_claim_their_upload(tmp_path, with_eve, fresh):
    """Read at its first split, Eve's file is Müller's, and newer than his (99999 > 90001):
    before, Müller was graded on Eve's notebook, 0 of 7 points. Now the reading whose name
    part is its user's name on the class list is taken — Eve's, when the class list knows her
    new name — and with none, the file is graded for no one."""
    hw, download, rows = with_eve
    report = grade(hw, download, out=tmp_path / "graded", class_list=rows if fresh else ())
    got = results(report)
    assert (got["jmuller"].status, got["jmuller"].points) == ("graded", got["jmuller"].max_points)
    if fresh:
        assert (got["eadams"].status, got["eadams"].points) == ("graded", 0)
        assert report.not_graded == ()
    else:
        assert got["eadams"].status == "missing"
        assert report.not_graded == (
            "eve_4501_99999_4599_90100_hw.ipynb: its name reads as Canvas user 4501 or 4599, "
            "and the class list's names tell it for neither; not guessing whose; not graded",)


def test_an_upload_named_like_a_classmates_entry_stays_its_uploaders(tmp_path, canvas):
    """Ñúñez uploads a wrong notebook named as Canvas names Müller's: it is her newest upload,
    and Müller's own is graded."""
    hw, _, _ = canvas
    download = write_zip(tmp_path / "d.zip", {
        canvas_file_name(MULLER, 90001, "hw.ipynb"): notebook(hw, "jmuller"),
        canvas_file_name(NUNEZ, 90002, "hw.ipynb"): notebook(hw, "znunez"),
        canvas_file_name(NUNEZ, 90003, canvas_file_name(MULLER, 90009, "hw.ipynb")):
            notebook(hw, "znunez", right=False)})
    got = results(grade(hw, download, out=tmp_path / "graded"))
    assert got["jmuller"].points == got["jmuller"].max_points
    assert (got["znunez"].status, got["znunez"].points) == ("graded", 0)
