"""Moodle, end to end without kernels: participants export + "Download all submissions" → import."""

from __future__ import annotations

import pytest

from grader.discover import discover
from grader.gradebook import number
from grader.lms.export import write_export
from problems.roster import read_roster
from tests.grader.lms.conftest import generate, grade, read_csv, results
from tests.grader.lms.exports import (
    CLASS,
    GARCIA1,
    GARCIA2,
    MULLER,
    NUNEZ,
    WEI,
    moodle_participants,
    moodle_prefix,
    notebook,
    write_zip,
)

GARCIAS = ("S1003", "S1004")


def _download(root, hw, name, folder_suffix="", files=True):
    """The zip as Moodle ≥ 3.1 writes it: one folder per student and plugin."""
    def entry(p, sid, right=True, inner="hw.ipynb", plugin="file", data=None):
        data = notebook(hw, sid, right) if data is None else data
        if files:  # "download submissions in folders" off: flat, prefixed file names
            return {f"{moodle_prefix(p)}_assignsubmission_{plugin}_{inner.replace('/', '_')}":
                    data}
        folder = f"{moodle_prefix(p)}_assignsubmission_{plugin}{folder_suffix}"
        return {f"{folder}/{inner}": data}

    content = {**entry(MULLER, "S1001"), **entry(NUNEZ, "S1002"),
               **entry(GARCIA1, "S1003"), **entry(GARCIA2, "S1004", right=False),
               **entry(WEI, "lwei@uni.example", inner="work/hw.ipynb")}
    content.update(entry(NUNEZ, "", inner="onlinetext.html", plugin="onlinetext",
                         data="<p>hi</p>"))
    content["__MACOSX/._hw.ipynb"] = b"\0"
    return write_zip(root / name, content)


@pytest.fixture(scope="module", params=[False, True], ids=["by-name", "by-participant-id"])
def moodle(request, tmp_path_factory):
    """Graded from the participants export — with or without the grading worksheet's
    Identifier column — and a folder-per-student zip (newer Moodle: no trailing "_")."""
    root = tmp_path_factory.mktemp("moodle")
    hw = generate(root, "participants.csv", moodle_participants(identifier=request.param))
    download = _download(root, hw, "HW1-12345.zip", files=False)
    return hw, grade(hw, download), request.param


def test_ids_are_the_id_number_or_else_the_email(tmp_path):
    (tmp_path / "p.csv").write_text(moodle_participants(), encoding="utf-8")
    roster = read_roster(tmp_path / "p.csv")
    assert roster.format == "moodle"
    assert roster.ids == ("S1001", "S1002", "S1003", "S1004", "lwei@uni.example", "S1006")
    assert any("have no ID number" in n and "lines 6" in n for n in roster.notes)


def test_students_are_matched_by_name_or_participant_id_and_it_is_said(moodle):
    _, report, by_pid = moodle
    got = results(report)
    for sid in ("S1001", "S1002", "lwei@uni.example"):
        assert got[sid].status == "graded" and got[sid].points == got[sid].max_points > 0
    assert got["S1006"].status == "missing"
    said = report.notes[0]
    assert ("participant id" in said) if by_pid else ("matched by name" in said)
    if by_pid:
        assert got["S1003"].points == got["S1003"].max_points and got["S1004"].points == 0
        assert report.not_graded == ()
    else:  # two students named Ana García: not guessed
        assert {got[s].status for s in GARCIAS} == {"missing"}
        assert len(report.not_graded) == 2
        assert all("2 roster students match the name 'Ana García' (S1003, S1004); not "
                   "guessing" in line for line in report.not_graded)


def test_online_text_and_system_files_are_listed_not_graded(moodle):
    _, report, _ = moodle
    ignored = sorted(p.path.name for p in report.problems if p.ignored)
    assert ignored == ["__MACOSX", "onlinetext.html"]


def test_export_is_what_moodle_imports(moodle):
    hw, report, by_pid = moodle
    out, _ = write_export(hw, "moodle")
    table = read_csv(out)
    assert table[0] == ["First name", "Last name", "ID number", "Email address", "Homework 1",
                        "Feedback"]
    assert [r[:4] for r in table[1:]] == [[p.first, p.last, p.number, p.email] for p in CLASS]
    full = number(results(report)["S1001"].max_points)
    scores = {r[3]: r[4] for r in table[1:]}
    assert scores["jmuller@uni.example"] == scores["lwei@uni.example"] == full
    assert scores["soneil@uni.example"] == ""
    assert scores["agarcia2@uni.example"] == ("0" if by_pid else "")
    feedback = {r[3]: r[5] for r in table[1:]}
    assert feedback["jmuller@uni.example"].startswith(f"{full} of {full} points; Q1 ")
    assert feedback["soneil@uni.example"] == "no submission"


@pytest.mark.parametrize("layout", ["files", "folders", "folders_"])
def test_every_moodle_layout_gives_the_same_pairs(tmp_path, moodle, layout):
    hw, _, _ = moodle
    z = _download(tmp_path, hw, "d.zip", folder_suffix="_" if layout == "folders_" else "",
                  files=layout == "files")
    import zipfile

    zipfile.ZipFile(z).extractall(tmp_path / "d")
    rows = read_roster(hw.parent / "participants.csv").rows
    found = discover(tmp_path / "d", [r["id"] for r in rows], rows)
    assert found.layout == "moodle"
    assert {s.student_id for s in found.submissions} >= {"S1001", "S1002", "lwei@uni.example"}
    assert all(s.path.name.endswith("hw.ipynb") for s in found.submissions)
