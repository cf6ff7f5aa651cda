"""The class report of an assignment whose question is a spec's pool (``[[questions]] pool =
["sleeping_top", "steady_precession"]``): the question is named by its pool, each answer by the
families of the students asked it — not the whole question by the first student's family."""

from __future__ import annotations

import csv
import io
import json
from collections import Counter

import numpy as np
import pytest

from grader.pipeline import grade_assignment
from grader.report import build_report, load_class
from grader.report.assemble import items_csv
from grader.report.page import items_section
from problems.generate import Question, generate_assignment, student_answers
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute, student_notebook

POOL = ("sleeping_top", "steady_precession")
N = 12


@pytest.fixture(scope="module")
def pooled_class(tmp_path_factory):
    """``N`` students, every answer right, question 1 drawn from :data:`POOL`, question 2 one
    family; graded by the real pipeline. Returns the folder and each student's families."""
    folder = tmp_path_factory.mktemp("pooled")
    ids = tuple(f"s{i:02d}" for i in range(N))
    hw = folder / "HW"
    questions = [Question("|".join(POOL), POOL), Question.of("inertia_tensor")]
    generate_assignment(Roster(("id",), tuple({"id": s} for s in ids)), hw, FAMILIES,
                        questions=questions, seed=7)
    key = json.loads((hw / "key.json").read_text())
    subs = folder / "subs"
    subs.mkdir()
    rng = np.random.default_rng(3)
    for sid in ids:
        values = {v: a.value for v, a in student_answers(key, sid).items()}
        release = json.loads((hw / "release" / f"{sid}.ipynb").read_text())
        (subs / f"{sid}.ipynb").write_text(json.dumps(student_notebook(release, values, rng)))
    grade_assignment(hw, subs, limits="literal", execute=LiteralExecute(), jobs=2)
    manifest = json.loads((hw / "assignment.json").read_text())
    drawn = {sid: [q["family"] for q in manifest["students"][sid]["questions"]] for sid in ids}
    return hw, drawn


def test_the_class_got_both_families_of_the_pool(pooled_class):
    _, drawn = pooled_class
    assert set(Counter(d[0] for d in drawn.values())) == set(POOL)  # the case this file is about


def test_a_pooled_question_is_named_by_its_pool_and_each_answer_by_its_family(pooled_class):
    hw, drawn = pooled_class
    report = build_report(load_class(hw, hw / "graded"))
    assert [q.family for q in report.questions] == [
        "pool: sleeping_top, steady_precession", "inertia_tensor"]
    key = json.loads((hw / "key.json").read_text())
    asked_by = {}
    for sid in drawn:
        for variable, _ in student_answers(key, sid).items():
            question = int(variable[1:variable.index("_")])
            asked_by.setdefault(variable, set()).add(drawn[sid][question - 1])
    for stats in report.answers:
        assert stats.family == ", ".join(asked_by[stats.label]), stats.label
        assert len(asked_by[stats.label]) == 1  # the two families ask different answers


def test_the_page_and_the_csv_carry_the_pool(pooled_class):
    hw, _ = pooled_class
    report = build_report(load_class(hw, hw / "graded"))
    rows = list(csv.DictReader(io.StringIO(items_csv(report))))
    assert next(r for r in rows if r["item"] == "q1")["family"] == \
        "pool: sleeping_top, steady_precession"
    assert "<td>pool: sleeping_top, steady_precession</td>" in items_section(report)
