"""Whose variant a graded notebook is: its parameters cell against the student's parameters.

A student's answers are compared with the key of *their* variant. A notebook whose parameters
cell holds other values (a classmate's copy renamed, a notebook of the variant a student had
before a reroll) is graded all the same and named so; a record keeps the hash of the
parameters it was graded as, so a rescore after a reroll says whose records now compare a
notebook of the old variant with the new key (it used to say only "rescore", s005 40 → 6
points). The class is graded with the fake execution stage of the report's tests (no kernel:
the submissions are the solutions).
"""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from eulertop.cli import main
from grader.notebook_metadata import (
    SHOWN_PARAMETERS,
    notebook_parameters,
    other_variant,
)
from grader.pipeline import grade_assignment
from grader.rescore import VARIANT_CHANGED
from grader.results import read_result
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute

STUDENTS = ("s1", "s2", "s3")


# -- reading a parameters cell


def _cell(source, cell_id="parameters", **metadata):
    return {"cell_type": "code", "id": cell_id, "metadata": metadata, "source": source,
            "outputs": [], "execution_count": None}


def test_the_parameters_cell_is_read_as_literals_never_run():
    source = ["# Your parameters: use them as given.\n", "\n", "# Question 1: a top\n",
              "q1_M = 1.5  # kg\n", "q1_r = [0.1, -0.2, 3e-05]  # m\n", "q1_n = -2\n",
              "q1_on = True\n", "q1_half = q1_M / 2\n", "import os\n", "q1_x, q1_y = 1, 2\n",
              "q1_s = 'loops'"]
    assert notebook_parameters([_cell(source)]) == {
        "q1_M": 1.5, "q1_r": [0.1, -0.2, 3e-05], "q1_n": -2, "q1_on": True, "q1_s": "loops"}
    # found by its metadata's role where its id was changed; one source string as well
    assert notebook_parameters([_cell("q2_g = 9.8", "x1", eulertop={"role": "parameters"})]) \
        == {"q2_g": 9.8}


@pytest.mark.parametrize("cells", [
    None, "cells", [], [_cell("q1_M = 1.5", "other")],
    [{**_cell("q1_M = 1.5"), "cell_type": "markdown"}],
    [_cell("q1_M = (")],  # not Python
    [_cell("q1_M = 1.5\n" + "#" * 100_001)],  # longer than any generated cell: not parsed
    [_cell(["q1_M = 1.5\n", 7])],  # a damaged source
], ids=["none", "not-a-list", "no-cells", "other-id", "markdown", "syntax", "long", "damaged"])
def test_no_parameters_cell_or_one_that_cannot_be_read_tells_nothing(cells):
    assert notebook_parameters(cells) is None


def test_a_value_reassigned_by_code_is_not_taken_from_an_earlier_line():
    assert notebook_parameters([_cell("q1_M = 1.5\nq1_M = q1_M * 2\n")]) == {}


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=300) | st.lists(st.sampled_from(
    ["q1_M = ", "1.5", "-", "[", "]", "(", ")", ", ", "\n", "1e999", "'s'", "True", "*", "j",
     "0x1", "lambda: 0", "# x", "=", "q2_g", "{1: 2}", "{1}", "b''", "...", "\\"]),
    max_size=40).map("".join))
def test_any_text_in_the_parameters_cell_is_read_or_told_nothing(source):
    """The cell is the student's: whatever it holds, reading it never raises, and what is
    read is the value of a name assigned a literal."""
    found = notebook_parameters([_cell(source)])
    assert found is None or all(isinstance(k, str) and k.isidentifier() for k in found)


# -- comparing them with the student's


OWN = {"q1_M": 1.5, "q1_r": [0.1, 0.2, 0.3], "q1_on": True, "q2_g": 9.8, "q2_h": 0.25}


@pytest.mark.parametrize("found", [
    OWN,
    {**OWN, "q1_extra": 3.0},  # a line the student added
    {k: v for k, v in OWN.items() if k != "q2_h"},  # a line the student deleted
    {},  # an emptied cell says nothing
    {"q1_M": 1.5, "q1_r": (0.1, 0.2, 0.3), "q1_on": True, "q2_g": 9.8, "q2_h": 0.25},
], ids=["same", "added", "deleted", "emptied", "tuple"])
def test_the_students_own_values_are_not_named(found):
    assert other_variant(found, OWN) == ""


def test_other_values_are_named_beside_the_students_own_and_counted_past_three():
    found = {"q1_M": 2.0, "q1_r": [0.1, 0.2, 0.4], "q1_on": 1, "q2_g": 9.8, "q2_h": 0.5}
    assert SHOWN_PARAMETERS == 3
    assert other_variant(found, OWN) == (
        "another variant's notebook: its parameters are not this student's (q1_M = 2.0 where "
        "theirs is 1.5; q1_r = [0.1, 0.2, 0.4] where theirs is [0.1, 0.2, 0.3]; q1_on = 1 "
        "where theirs is True; 1 more differ)")


def test_a_long_value_is_shown_cut():
    found = {**OWN, "q1_r": [0.123456789] * 20}
    said = other_variant(found, OWN)
    assert said.startswith("another variant's notebook: its parameters are not this student's "
                           "(q1_r = [0.123456789, 0.123456789, 0.123456789,… where theirs is "
                           "[0.1, 0.2, 0.3])")  # 39 characters of the literal, and the cut


def test_a_cell_of_other_parameters_altogether_is_named_by_them():
    assert other_variant({"q1_a": 1.0, "q1_b": 2.0}, OWN) == (
        "another variant's notebook: its parameters cell holds none of this student's "
        "parameters (q1_a, q1_b instead)")


# -- grading, a reroll, and a rescore


def _hash(parameters: dict) -> str:
    """The hash of a student's parameters, written out here as the record's docs define it."""
    text = json.dumps(parameters, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()


def _parameters(hw: Path, sid: str) -> dict:
    manifest = json.loads((hw / "assignment.json").read_text(encoding="utf-8"))
    return {f"q{q['question']}_{name}": value
            for q in manifest["students"][sid]["questions"] for name, value in q["params"].items()}


def _grade(hw: Path, submissions: Path) -> dict:
    grade_assignment(hw, submissions, limits="LIMITS", execute=LiteralExecute(), jobs=1,
                     yes=True)
    return {sid: read_result(hw / "graded" / "results" / f"{sid}.json") for sid in STUDENTS}


@pytest.fixture
def rerolled(tmp_path, capsys):
    """A class graded on its solutions, then s2 rerolled: (HW, the old notebooks, records, s2's
    parameters before the reroll, as the manifest recorded them)."""
    hw = tmp_path / "HW"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in STUDENTS)), hw, FAMILIES,
                        problems=["sleeping_top", "steady_precession"], seed=4)
    old = tmp_path / "old"
    shutil.copytree(hw / "solutions", old)
    records = _grade(hw, old)
    before = _parameters(hw, "s2")
    assert main(["generate", "--reroll", "s2", "--out", str(hw)]) == 0
    assert _parameters(hw, "s2") != before
    said = capsys.readouterr().err
    assert "s2: reroll 1; graded already: their record holds the answers of their old " \
        "variant's notebook" in said
    return hw, old, records, before


def test_a_record_keeps_the_hash_of_the_parameters_it_was_graded_as(rerolled):
    hw, _, records, _ = rerolled
    for sid in ("s1", "s3"):
        assert records[sid].execution["variant"] == _hash(_parameters(hw, sid))
        assert "foreign" not in records[sid].execution
        assert records[sid].points == records[sid].max_points


def test_a_rescore_after_a_reroll_says_whose_variant_changed(rerolled, capsys):
    hw, _, before, _ = rerolled
    capsys.readouterr()
    assert main(["rescore", str(hw), "--dry-run"]) == 0
    assert "s2; their stored answers are compared with their new keys all the same, and their " \
        "records would say so;" in capsys.readouterr().out
    assert read_result(hw / "graded" / "results" / "s2.json") == before["s2"]  # nothing written
    assert main(["rescore", str(hw)]) == 0
    out = capsys.readouterr().out
    assert ("eulertop rescore: 1 student(s) graded as a variant of theirs that has changed "
            "since (a reroll?): s2;") in out
    lines = [line for line in out.splitlines() if "→" in line]
    assert lines and all(line.split()[0] == "s2" for line in lines)
    assert all(line.endswith("(rescore; their variant changed after grading)") for line in lines)
    after = {sid: read_result(hw / "graded" / "results" / f"{sid}.json") for sid in STUDENTS}
    assert after["s2"].execution["foreign"] == VARIANT_CHANGED
    assert after["s2"].message.count(VARIANT_CHANGED) == 1
    assert after["s2"].points < before["s2"].points  # the old answers against the new key
    assert after["s2"].execution["variant"] == before["s2"].execution["variant"]
    for sid in ("s1", "s3"):  # nobody else's record changed
        assert after[sid] == before[sid]
    trail = (hw / "graded" / "audit.jsonl").read_text(encoding="utf-8").splitlines()
    assert json.loads(trail[-1])["other_variant"] == ["s2"]
    # once said, it is not said again in the record
    assert main(["rescore", str(hw)]) == 0
    again = read_result(hw / "graded" / "results" / "s2.json")
    assert again.message.count(VARIANT_CHANGED) == 1


def test_the_old_notebook_graded_after_a_reroll_is_named_another_variants(rerolled):
    hw, old, _, found = rerolled  # found: the old notebook's values, from the old manifest
    records = _grade(hw, old)  # the key changed: s2 is graded again, their old notebook
    now = _parameters(hw, "s2")
    differ = [name for name in now if name in found and found[name] != now[name]]
    assert differ  # the premise: the reroll drew other values of parameters of the same name
    first = differ[0]
    assert records["s2"].execution["foreign"].startswith(
        f"another variant's notebook: its parameters are not this student's ({first} = "
        f"{found[first]!r} where theirs is {now[first]!r}")
    assert records["s2"].execution["variant"] == _hash(now)
    # the notebook of their new variant is theirs
    new = hw.parent / "new"
    shutil.copytree(old, new)
    shutil.copy(hw / "solutions" / "s2.ipynb", new / "s2.ipynb")
    records = _grade(hw, new)
    assert "foreign" not in records["s2"].execution
    assert records["s2"].points == records["s2"].max_points


def test_every_families_notebook_holds_exactly_the_parameters_the_manifest_records(tmp_path):
    """No student's own notebook may ever be named another variant's: for every built-in
    family, the parameters cell read back equals the manifest's parameters, value for value."""
    from grader.assignment import load_assignment

    hw = tmp_path / "HW"
    ids = tuple(f"s{i}" for i in range(6))
    generate_assignment(Roster(("id",), tuple({"id": s} for s in ids)), hw, FAMILIES,
                        problems=list(FAMILIES), seed=11)
    a = load_assignment(hw)
    for sid in ids:
        own = a.parameters(sid)
        assert own == _parameters(hw, sid) and len(own) > len(FAMILIES)
        for folder in ("release", "solutions"):
            cells = json.loads((hw / folder / f"{sid}.ipynb").read_text())["cells"]
            found = notebook_parameters(cells)
            assert found == own
            assert all(type(found[k]) is type(own[k]) for k in own)
            assert other_variant(found, own) == ""
