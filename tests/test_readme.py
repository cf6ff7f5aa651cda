"""README.md speaks to users, and its numbers agree with each other (issue 13)."""

from __future__ import annotations

import re
from pathlib import Path

from problems.notebook import TITLE_CELL

README = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")


def _section(title: str) -> str:
    match = re.search(rf"^## {re.escape(title)}\n(.*?)(?=^## )", README, re.S | re.M)
    assert match, f"README has no section {title!r}"
    return match.group(1)


def test_the_speed_against_nbgrader_is_one_number_from_a_named_command():
    """Every "N× nbgrader" in the README is the bench_grade.py row's bold ratio."""
    row = next(line for line in README.splitlines() if "benchmarks/bench_grade.py" in line
               and line.startswith("|"))
    measured = re.search(r"\*\*(\d+(?:\.\d+)?)×\*\*", row).group(1)
    claims = re.findall(r"(\d+(?:\.\d+)?)× nbgrader", README)
    assert claims and set(claims) == {measured}
    for line in README.splitlines():  # and each claim names the command it comes from
        if re.search(r"\d× nbgrader", line):
            assert "bench_grade.py" in line


def test_every_measured_row_names_its_command():
    table = [line for line in _section("Performance").splitlines() if line.startswith("| ")]
    for row in table[2:]:  # past the header and its rule
        assert re.search(r"`[^`]*(python|eulertop)[^`]*`", row), row


def test_for_students_gives_one_install_command_the_notebook_repeats():
    students = _section("For students")
    commands = re.findall(r"^%pip install \S+$", students, re.M)
    assert commands == ["%pip install eulertop"]
    assert commands[0] in TITLE_CELL and "!eulertop check" in TITLE_CELL
    assert "eulertop check" in students and "JupyterHub" in students and "Colab" in students


def test_no_wording_about_how_the_project_was_built():
    for phrase in (r"\bour (machines|issue tracker|team)\b", r"\bissue \d+\b", r"\bwe\b",
                   r"\bhelper\b", r"\blead engineer\b"):
        assert not re.search(phrase, README, re.I), phrase
