"""``eulertop generate`` with an LMS class list, ``grade`` with a zip, ``export``: the commands."""

from __future__ import annotations

import json

import pytest

from eulertop.cli import build_parser, main
from grader import cli as grader_cli
from tests.grader.lms.conftest import read_csv
from tests.grader.lms.exports import (
    MULLER,
    WEI,
    canvas_file_name,
    canvas_gradebook,
    notebook,
    write_zip,
)
from tests.grader.test_pipeline import FakeExecute


@pytest.fixture
def canvas_hw(tmp_path, capsys):
    (tmp_path / "gradebook.csv").write_text(canvas_gradebook(), encoding="utf-8")
    code = main(["generate", "--roster", str(tmp_path / "gradebook.csv"), "--out",
                 str(tmp_path / "HW"), "--problems", "inertia_tensor", "--seed", "4",
                 "--title", "HW 1"])
    assert code == 0
    return tmp_path / "HW", capsys.readouterr()


def _grade(hw, submissions, capsys):
    args = build_parser("grade").parse_args(["grade", str(hw), str(submissions)])
    code = grader_cli.run_grade(args, execute=FakeExecute())
    return code, capsys.readouterr()


def test_generate_reads_the_canvas_export_and_says_what_it_left_out(canvas_hw):
    hw, out = canvas_hw
    assert "left out Canvas's 'Points Possible' row" in out.err
    assert "1 student(s) have no SIS Login ID: their id is their ID" in out.err
    manifest = json.loads((hw / "assignment.json").read_text(encoding="utf-8"))
    assert manifest["roster"]["format"] == "canvas"
    assert sorted(p.stem for p in (hw / "release").iterdir()) == sorted(
        ["jmuller", "znunez", "agarcia1", "agarcia2", "4505", "soneil"])


def test_grade_a_zip_then_export_with_the_commands(canvas_hw, tmp_path, capsys):
    hw, _ = canvas_hw
    download = write_zip(tmp_path / "subs.zip", {
        canvas_file_name(MULLER, 1, "hw.ipynb"): notebook(hw, "jmuller"),
        canvas_file_name(WEI, 2, "hw.ipynb", late=True): notebook(hw, "4505")})
    code, out = _grade(hw, download, capsys)
    assert code == 0, out.err
    assert "eulertop grade: 4505: submitted late" in out.err
    code = main(["export", str(hw), "--to", "canvas", "--assignment-id", "12"])
    out = capsys.readouterr()
    assert code == 0 and f"wrote {hw / 'graded' / 'canvas-import.csv'}" in out.out
    table = read_csv(hw / "graded" / "canvas-import.csv")
    assert table[0][-1] == "HW 1 (12)" and len(table) == 2 + 6


@pytest.mark.parametrize(("extra", "fragment"), [
    ([], "no results/ here — run 'eulertop grade' first"),
    (["--roster", "MISSING.csv"], "cannot read the roster"),
])
def test_export_usage_errors_exit_2(canvas_hw, capsys, extra, fragment):
    hw, _ = canvas_hw
    if extra:
        (hw / "graded" / "results").mkdir(parents=True)
    code = main(["export", str(hw), "--to", "moodle", *extra])
    err = capsys.readouterr().err
    assert code == 2 and fragment in err and "Traceback" not in err
    assert err.count("\n") == 1


def test_export_to_an_lms_whose_identifiers_the_roster_lacks(tmp_path, capsys):
    (tmp_path / "r.csv").write_text("id,name\nann,Ann\n", encoding="utf-8")
    assert main(["generate", "--roster", str(tmp_path / "r.csv"), "--out", str(tmp_path / "HW"),
                 "--problems", "inertia_tensor", "--seed", "1"]) == 0
    (tmp_path / "HW" / "graded" / "results").mkdir(parents=True)
    capsys.readouterr()
    assert main(["export", str(tmp_path / "HW"), "--to", "blackboard"]) == 2
    assert "Blackboard matches students by Username, and the roster has none for ann" in \
        capsys.readouterr().err
    (tmp_path / "bb.csv").write_text("Last Name,First Name,Username\nLee,Ann,ann\n",
                                     encoding="utf-8")
    assert main(["export", str(tmp_path / "HW"), "--to", "blackboard", "--roster",
                 str(tmp_path / "bb.csv")]) == 0
    table = read_csv(tmp_path / "HW" / "graded" / "blackboard-import.csv")
    assert table[1] == ["Lee", "Ann", "ann", ""]  # no record: blank, not 0


def test_an_unsafe_zip_is_one_line_and_exit_2(canvas_hw, tmp_path, capsys):
    hw, _ = canvas_hw
    download = write_zip(tmp_path / "subs.zip", {"../x.ipynb": "{}"})
    code, out = _grade(hw, download, capsys)
    assert code == 2 and out.err.startswith("eulertop grade: ") and out.err.count("\n") == 1
    assert "'../x.ipynb': '..' in the path" in out.err


def test_grade_roster_brings_the_lms_identifiers_to_a_plain_roster(tmp_path, capsys):
    """Generated from a one-column roster of SIS logins; the Canvas download is matched once
    the Canvas gradebook export is given to ``grade --roster``."""
    (tmp_path / "ids.csv").write_text("id\njmuller\nznunez\n", encoding="utf-8")
    hw = tmp_path / "HW"
    assert main(["generate", "--roster", str(tmp_path / "ids.csv"), "--out", str(hw),
                 "--problems", "inertia_tensor", "--seed", "2"]) == 0
    download = write_zip(tmp_path / "subs.zip", {
        canvas_file_name(MULLER, 1, "hw.ipynb"): notebook(hw, "jmuller")})
    code, out = _grade(hw, download, capsys)
    assert code == 1
    assert "the roster has no Canvas 'ID' column to match Canvas user 4501" in out.err
    (tmp_path / "gradebook.csv").write_text(canvas_gradebook(), encoding="utf-8")
    args = build_parser("grade").parse_args(["grade", str(hw), str(download), "--roster",
                                             str(tmp_path / "gradebook.csv")])
    assert grader_cli.run_grade(args, execute=FakeExecute()) == 0
    record = json.loads((hw / "graded" / "results" / "jmuller.json").read_text())
    assert record["status"] == "graded" and record["points"] == record["max_points"] > 0
