"""The class report when variants of one family ask for different answers (``euler_rotation``
asks some students for ``F_body``, others for ``r_lab``): every answer is an item, judged only
over the students asked it."""

from __future__ import annotations

import json
from collections import Counter

import numpy as np
import pytest

from grader.pipeline import grade_assignment
from grader.report import build_report, load_class
from problems.generate import generate_assignment, student_answers
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute, student_notebook

N = 16


@pytest.fixture(scope="module")
def variant_class(tmp_path_factory):
    """``N`` students, all right but each third student wrong (×2) on question 1's first
    answer; graded by the real pipeline (whose last step writes the report)."""
    folder = tmp_path_factory.mktemp("variants")
    ids = tuple(f"s{i:02d}" for i in range(N))
    hw = folder / "HW"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in ids)), hw, FAMILIES,
                        problems=["euler_rotation"], seed=2024)
    key = json.loads((hw / "key.json").read_text())
    keys = {s: {v: a.value for v, a in student_answers(key, s).items()} for s in ids}
    subs = folder / "subs"
    subs.mkdir()
    rng = np.random.default_rng(1)
    wrong = set(ids[::3])
    for sid in ids:
        values = dict(keys[sid])
        first = next(iter(values))
        if sid in wrong:
            values[first] = (np.asarray(values[first]) * 2).tolist()
        release = json.loads((hw / "release" / f"{sid}.ipynb").read_text())
        (subs / f"{sid}.ipynb").write_text(json.dumps(student_notebook(release, values, rng)))
    grade_assignment(hw, subs, limits="literal", execute=LiteralExecute(), jobs=2)
    return hw, keys, wrong, first


def test_the_variants_do_ask_for_different_answers(variant_class):
    _, keys, _, _ = variant_class
    asked = Counter(v for k in keys.values() for v in k)
    assert len({frozenset(k) for k in keys.values()}) > 1  # the case this file is about
    assert min(asked.values()) < N


def test_every_answer_asked_of_anyone_is_an_item_judged_over_those_asked(variant_class):
    hw, keys, wrong, first = variant_class
    data = load_class(hw, hw / "graded")
    asked = Counter(v for k in keys.values() for v in k)
    assert {i.variable for i in data.items} == set(asked)
    report = build_report(data)
    for stats in report.answers:
        assert sum(stats.counts.values()) == asked[stats.label]
        students = [s for s in keys if stats.label in keys[s]]
        right = sum(1 for s in students if not (s in wrong and stats.label == first))
        assert stats.facility == pytest.approx(right / len(students))


def test_grading_writes_the_report(variant_class):
    """It used to fail with a KeyError on the answer the first student was not asked, and
    the grading run wrote no report at all."""
    hw, *_ = variant_class
    assert (hw / "graded" / "report.html").is_file()
    assert (hw / "graded" / "report_items.csv").is_file()
