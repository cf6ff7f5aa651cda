"""Moodle, end to end without kernels: participants export + "Download all submissions" → import."""

from __future__ import annotations

import dataclasses
import json
import re
import unicodedata

import pytest

from grader.discover import discover
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
    ONEIL,
    WEI,
    moodle_participants,
    moodle_prefix,
    notebook,
    write_zip,
)


def read_roster(path, roster_format=None):
    """An eulertop roster or an LMS class list (the formats grader.lms knows)."""
    return read_any_roster(path, roster_format, CLASS_LISTS)

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


def _entries(hw, person, sid, files, *uploads):
    """``person``'s entries as Moodle writes them: ``uploads`` are (file name, right) pairs."""
    prefix = f"{moodle_prefix(person)}_assignsubmission_file"
    return {(f"{prefix}_{name}" if files else f"{prefix}/{name}"): notebook(hw, sid, right)
            for name, right in uploads}


@pytest.mark.parametrize("files", [True, False], ids=["files", "folders"])
def test_an_upload_named_like_a_classmates_entry_stays_its_uploaders(tmp_path, moodle, files):
    """Ñúñez uploads, beside her own notebook, two wrong ones named like Müller's entry and like
    O'Neil's (the second after a '-', the team-prefix rule's mark). Before, in the files
    layout (by name and by participant id alike): Müller, who submitted, failed with 0 of 7
    points ("2 notebooks … not guessing"), and O'Neil, who did not, was graded on Ñúñez's
    notebook. Now both files stay Ñúñez's, and the harm is hers alone."""
    hw, _, _ = moodle
    forged = [(f"{moodle_prefix(MULLER)}_assignsubmission_file_hw.ipynb", False),
              (f"x-{moodle_prefix(ONEIL)}_assignsubmission_file_hw.ipynb", False)]
    download = write_zip(tmp_path / "d.zip", {
        **_entries(hw, MULLER, "S1001", files, ("hw.ipynb", True)),
        **_entries(hw, NUNEZ, "S1002", files, ("hw.ipynb", True), *forged)})
    out = tmp_path / "graded"
    got = results(grade(hw, download, out=out))
    assert (got["S1001"].status, got["S1001"].points) == ("graded", got["S1001"].max_points)
    assert got["S1006"].status == "missing"
    assert got["S1002"].status == "failed"
    assert got["S1002"].message.startswith("3 notebooks (")
    table = read_csv(out / "submissions.csv")
    assert sorted(r[0] for r in table[1:]) == ["S1001", "S1002", "S1002", "S1002"]
    assert [r[1] for r in table[1:] if r[0] == "S1001"] == [
        next(iter(_entries(hw, MULLER, "S1001", files, ("hw.ipynb", True))))]


@pytest.fixture(scope="module")
def by_name(tmp_path_factory):
    """An assignment generated from the participants export alone (matched by name)."""
    return generate(tmp_path_factory.mktemp("by_name"), "participants.csv", moodle_participants())


def test_a_name_two_participants_carry_is_graded_for_no_one(tmp_path, by_name):
    """Matched by name, a second participant id under Müller's name (someone not on the class
    list, or a student who renamed themself) is not taken for Müller: both files are listed
    and neither is graded, rather than one of them failing Müller or being graded as his."""
    impostor = dataclasses.replace(MULLER, participant=700199)
    download = write_zip(tmp_path / "d.zip", {
        **_entries(by_name, MULLER, "S1001", False, ("hw.ipynb", True)),
        **_entries(by_name, impostor, "S1001", False, ("hw.ipynb", False)),
        **_entries(by_name, NUNEZ, "S1002", False, ("hw.ipynb", True))})
    report = grade(by_name, download, out=tmp_path / "graded")
    got = results(report)
    assert got["S1001"].status == "missing"
    assert got["S1002"].points == got["S1002"].max_points
    assert len(report.not_graded) == 2
    assert all("the name of S1001, which 2 Moodle participants (700101, 700199) carry" in line
               for line in report.not_graded)


def _repeated(hw, sid):
    """The student's notebook with 9 MiB of one repeated character (it deflates some
    1000-fold)."""
    nb = json.loads(notebook(hw, sid))
    nb["cells"].append({"cell_type": "markdown", "metadata": {}, "source": "x" * 9 * 1024**2})
    return json.dumps(nb)


NAMES = {"case": ("HW.ipynb", "hw.ipynb"),
         "normalisation": tuple(unicodedata.normalize(f, "Müller.ipynb") for f in ("NFC", "NFD"))}


@pytest.mark.parametrize("unsafe", ["ratio", "case", "normalisation"])
def test_one_students_unsafe_upload_is_their_invalid_submission_alone(tmp_path, moodle,
                                                                     unsafe):
    """Ñúñez uploads a 9 MiB notebook of repeated output, or two notebooks whose names differ
    only in case or in Unicode form. Before, the whole download was refused and no one in the
    class had a record; now Ñúñez's submission is invalid, saying why, and her classmates are
    graded in full."""
    hw, _, _ = moodle
    prefix = f"{moodle_prefix(NUNEZ)}_assignsubmission_file"
    mine = ({f"{prefix}_hw.ipynb": _repeated(hw, "S1002")} if unsafe == "ratio" else
            {f"{prefix}/{name}": notebook(hw, "S1002") for name in NAMES[unsafe]})
    download = write_zip(tmp_path / "d.zip", {
        **_entries(hw, MULLER, "S1001", False, ("hw.ipynb", True)), **mine,
        **_entries(hw, WEI, "lwei@uni.example", True, ("hw.ipynb", True))})
    out = tmp_path / "graded"
    got = results(grade(hw, download, out=out))
    for sid in ("S1001", "lwei@uni.example"):
        assert (got[sid].status, got[sid].points) == ("graded", got[sid].max_points)
    assert (got["S1002"].status, got["S1002"].points) == ("failed", 0)
    why = {"ratio": r"expands \d+ times, to 9\.\d+ MiB \(at most 200 times\): a zip bomb\?",
           "case": r"differ only in case or Unicode form",
           "normalisation": r"differ only in case or Unicode form"}[unsafe]
    assert re.match(rf"invalid submission: '{re.escape(prefix)}[_/].*{why}",
                    got["S1002"].message)
    listed = [r for r in read_csv(out / "submissions.csv")[1:] if r[0] == "S1002"]
    assert listed and all(re.search(why, r[5]) for r in listed)
