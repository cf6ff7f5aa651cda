"""The LMS modules, in the order their layouts are recognised, and their class-list formats."""

from __future__ import annotations

from types import ModuleType

from grader.lms import blackboard, canvas, gradescope, moodle
from grader.lms.classlist import ClassListFormat

LMS: dict[str, ModuleType] = {
    # A download is read as the LMS's whose names fit the most of its entries
    # (grader.lms.download.layout); on a tie, the first here: Gradescope (its metadata file is
    # unmistakable), Moodle before Canvas (a Moodle file name can also look like a Canvas
    # one), Blackboard last.
    "gradescope": gradescope,
    "moodle": moodle,
    "canvas": canvas,
    "blackboard": blackboard,
}

CLASS_LISTS: dict[str, ClassListFormat] = {
    # Detection order: the most specific header first (Canvas and Blackboard both have a
    # column that Gradescope's lacks; Moodle's "Email address" is its own).
    "canvas": canvas.CLASS_LIST,
    "blackboard": blackboard.CLASS_LIST,
    "gradescope": gradescope.CLASS_LIST,
    "moodle": moodle.CLASS_LIST,
}
