"""Each LMS's file names, parsed as that LMS writes them; links in a download never followed."""

from __future__ import annotations

import pytest

from grader.discover import discover
from grader.lms import blackboard, canvas, moodle


@pytest.mark.parametrize(("name", "parts"), [
    ("müllerjürgen_4501_90001_hw.ipynb", ("müllerjürgen", None, "4501", "90001", "hw.ipynb")),
    ("weili_LATE_4505_9_hw-1.ipynb", ("weili", "LATE", "4505", "9", "hw-1.ipynb")),
    ("weili_late_4505_9_hw.ipynb", ("weili", "late", "4505", "9", "hw.ipynb")),  # older Canvas
    ("obrien2_4_77_8_my_hw_2.ipynb", ("obrien2", None, "4", "77", "8_my_hw_2.ipynb")),
    ("anon_x7Kq2_81_hw.ipynb", (None, None, "anon_x7Kq2", "81", "hw.ipynb")),
    ("LATE_anon_x7Kq2_81_hw.ipynb", (None, "LATE", "anon_x7Kq2", "81", "hw.ipynb")),
])
def test_canvas_names(name, parts):
    got = canvas.parse_file_name(name)
    assert (got["name"], got["late"], got["user"], got["attachment"], got["original"]) == parts


@pytest.mark.parametrize(("name", "who", "pid", "plugin", "file"), [
    ("Jürgen Müller_700101_assignsubmission_file_hw.ipynb", "Jürgen Müller", "700101", "file",
     "hw.ipynb"),
    ("Jürgen Müller_700101_assignsubmission_file_", "Jürgen Müller", "700101", "file", ""),
    ("Jürgen Müller_700101_assignsubmission_file", "Jürgen Müller", "700101", "file", None),
    ("Team 3-Ana García_7_assignsubmission_onlinetext_onlinetext.html", "Team 3-Ana García",
     "7", "onlinetext", "onlinetext.html"),
])
def test_moodle_names(name, who, pid, plugin, file):
    m = moodle.ENTRY.match(name)
    assert (m["name"], m["pid"], m["plugin"], m["file"]) == (who, pid, plugin, file)


def test_blackboard_usernames_with_underscores_are_told_from_the_assignment_name():
    name = "HW_1_two_parts_ann_lee_attempt_2024-03-01-10-00-00_hw_1.ipynb"
    assert blackboard._username(name, ["lee", "ann_lee", "bob"]) == "ann_lee"
    assert blackboard.ATTEMPT.search(name)["file"] == "hw_1.ipynb"


@pytest.mark.parametrize("layout", ["canvas", "moodle", "blackboard"])
def test_links_in_a_download_folder_are_not_followed(tmp_path, layout):
    secret = tmp_path / "key.ipynb"
    secret.write_text("{}")
    folder = tmp_path / "d"
    folder.mkdir()
    real, link = {
        "canvas": ("leeann_1_10_hw.ipynb", "leeann_1_11_hw.ipynb"),
        "moodle": ("Ann Lee_5_assignsubmission_file_hw.ipynb",
                   "Ann Lee_5_assignsubmission_file_x.ipynb"),
        "blackboard": ("HW_ann_attempt_2024-03-01-10-00-00_hw.ipynb",
                       "HW_ann_attempt_2024-03-02-10-00-00_hw.ipynb"),
    }[layout]
    (folder / real).write_text("{}")
    (folder / link).symlink_to(secret)  # newer than the real one: it would win if followed
    rows = [{"id": "ann", "ID": "1", "First name": "Ann", "Last name": "Lee",
             "Username": "ann"}]
    found = discover(folder, ["ann"], rows)
    assert found.layout == layout
    assert [s.path.name for s in found.submissions] == [real]
    assert [p.path.name for p in found.problems] == [link]
