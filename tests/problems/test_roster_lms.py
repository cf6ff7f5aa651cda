"""Class lists as Canvas, Moodle, Blackboard and Gradescope export them, read as rosters."""

from __future__ import annotations

import pytest

from grader.lms.registry import CLASS_LISTS
from problems.roster import Roster, RosterError
from problems.roster import read_roster as read_any_roster
from tests.grader.lms.exports import (
    blackboard_grade_center,
    canvas_gradebook,
    gradescope_roster,
    moodle_participants,
)


def read_roster(path, roster_format=None):
    """An eulertop roster or an LMS class list (the formats grader.lms knows)."""
    return read_any_roster(path, roster_format, CLASS_LISTS)

CANVAS_HEAD = "Student,ID,SIS User ID,SIS Login ID,Section,HW (1)\n"


@pytest.mark.parametrize(("content", "fmt", "ids"), [
    (canvas_gradebook(), "canvas", ("jmuller", "znunez", "agarcia1", "agarcia2", "4505",
                                    "soneil")),
    (moodle_participants(), "moodle", ("S1001", "S1002", "S1003", "S1004",
                                       "lwei@uni.example", "S1006")),
    (gradescope_roster(), "gradescope", ("S1001", "S1002", "S1003", "S1004",
                                         "lwei@uni.example", "S1006")),
    (blackboard_grade_center(), "blackboard", ("jmuller", "znunez", "agarcia1", "agarcia2",
                                               "lwei", "soneil")),
])
def test_each_lms_class_list_is_recognised_from_its_header(write_roster, content, fmt, ids):
    roster = read_roster(write_roster(content))
    assert (roster.format, roster.ids) == (fmt, ids)
    assert roster.columns[0] == "id" and len(roster.columns) > 4
    assert Roster.from_dict(roster.to_dict()) == Roster(roster.columns, roster.rows, fmt)


def test_canvas_rows_that_are_not_students_are_left_out_and_said(write_roster):
    path = write_roster(CANVAS_HEAD + "Points Possible,,,,,10\n"
                        ",,,,,Muted\n"
                        "\"Müller, Jürgen\",4501,S1,jm,A,\n"
                        "\"Student, Test\",9999,,,A,\n")
    roster = read_roster(path)
    assert roster.ids == ("jm",)
    assert [n.split(": ", 1)[1] for n in roster.notes] == [
        "left out Canvas's 'Points Possible' row", "left out Canvas's 'Muted' row",
        "left out Canvas's Test Student (the course's student view)"]
    assert roster.rows[0]["Student"] == "Müller, Jürgen" and roster.rows[0]["ID"] == "4501"


def test_a_ta_export_without_sis_columns_uses_canvas_ids(write_roster):
    roster = read_roster(write_roster("Student,ID,Section\n\"Lee, Ann\",4501,A\n"))
    assert roster.ids == ("4501",)
    assert roster.notes == ("the class list has no SIS Login ID column: the student ids are "
                            "the ID",)


@pytest.mark.parametrize(("content", "fragments"), [
    (CANVAS_HEAD + "\"A, B\",1,,same,X,\n\"C, D\",2,,same,X,\n",
     ["duplicate ids", "'same' (line 2) and 'same' (line 3)", "'SIS Login ID' or 'ID'"]),
    (CANVAS_HEAD + "\"A, B\",,,,X,\n", ["line 2", "empty id"]),
    ("First name,Last name,ID number,Email address\nAnn,Lee,,\n", ["line 2", "empty id"]),
    ("First Name,Last Name,SID,Email\nAnn,Lee,12 34,a@x\n", ["line 2", "'12 34'"]),
])
def test_bad_lms_ids_are_refused_with_their_lines(write_roster, content, fragments):
    with pytest.raises(RosterError) as info:
        read_roster(write_roster(content))
    for fragment in fragments:
        assert fragment in str(info.value)


def test_roster_format_forces_a_reading(write_roster):
    path = write_roster(CANVAS_HEAD + "\"A, B\",4501,,,X,\n")
    assert read_roster(path, "eulertop").ids == ("4501",)  # Canvas's ID taken as column 'id'
    with pytest.raises(RosterError, match="not a Moodle participants or grades export: it "
                                          "needs the columns 'First name', 'Last name'"):
        read_roster(path, "moodle")
    with pytest.raises(RosterError, match="unknown roster format 'sakai'"):
        read_roster(path, "sakai")


def test_an_eulertop_roster_is_unchanged(write_roster):
    roster = read_roster(write_roster("id,name,email\nann,Ann,a@x\n"))
    assert (roster.format, roster.columns) == ("", ("id", "name", "email"))
    assert "format" not in roster.to_dict()
