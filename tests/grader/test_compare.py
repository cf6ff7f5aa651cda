"""Comparison in the grader process: the problems' own verdicts, failing closed."""

from __future__ import annotations

import pytest

from grader import compare as compare_module
from grader.compare import NOT_EXTRACTED, compare, key_answers, variable_names
from problems.answers import Answer, Mistake
from problems.generate import student_answers

OMEGA = Answer("omega", "scalar", 2.5, unit="rad/s", rtol=1e-2, points=2.0,
               mistakes=(Mistake("rpm", 23.87, "rad/s, not rpm"),))
AXIS = Answer("axis", "vector", [0.0, 0.6, 0.8], atol=1e-6)
LOOPS = Answer("shape", "choice", "loops", options=("loops", "cusps", "waves"))
KEY = {"students": {"alice": {"hash": "sha256:0", "questions": [
    {"question": 1, "family": "f", "answers": [OMEGA.to_dict(), AXIS.to_dict()]},
    {"question": 2, "family": "g", "answers": [LOOPS.to_dict()]},
]}}}


@pytest.fixture
def expected():
    return key_answers(KEY, "alice")


def test_key_answers_agree_with_the_generators_mapping(expected):
    assert {k.variable: k.answer for k in expected} == student_answers(KEY, "alice")
    assert [(k.variable, k.question) for k in expected] == [
        ("q1_omega", 1), ("q1_axis", 1), ("q2_shape", 2)]


def test_only_names_go_to_the_execution(expected):
    names = variable_names(expected)
    assert names == ("q1_omega", "q1_axis", "q2_shape")
    assert all(isinstance(n, str) for n in names)


@pytest.mark.parametrize(("submitted", "status", "points", "mistake"), [
    ({"q1_omega": 2.51, "q1_axis": [0, 0.6, 0.8], "q2_shape": " Loops "},
     ("correct", "correct", "correct"), (2.0, 1.0, 1.0), (None, None, None)),
    ({"q1_omega": 23.9, "q1_axis": [0.6, 0.8, 0.0], "q2_shape": "cusps"},
     ("wrong", "wrong", "wrong"), (0.0, 0.0, 0.0), ("rpm", None, None)),
    ({"q1_omega": "2.5", "q1_axis": [0.6, 0.8], "q2_shape": None},
     ("invalid", "invalid", "missing"), (0.0, 0.0, 0.0), (None, None, None)),
])
def test_verdicts_per_answer(expected, submitted, status, points, mistake):
    results = compare(expected, submitted)
    assert tuple(r.verdict.status for r in results) == status
    assert tuple(r.verdict.points for r in results) == points
    assert tuple(r.verdict.mistake for r in results) == mistake
    assert [r.submitted for r in results] == [submitted[k.variable] for k in expected]


@pytest.mark.parametrize("extracted", [None, {}])
def test_nothing_extracted_gives_nothing(expected, extracted):
    results = compare(expected, extracted)
    assert all(r.verdict.status == "missing" and r.verdict.points == 0 for r in results)
    assert all(r.verdict.message == NOT_EXTRACTED for r in results)
    assert [r.verdict.max_points for r in results] == [2.0, 1.0, 1.0]


def test_a_variable_absent_from_the_extraction_is_missing(expected):
    results = compare(expected, {"q1_omega": 2.5})
    assert [r.verdict.status for r in results] == ["correct", "missing", "missing"]


def test_a_comparison_that_crashes_gives_no_credit(expected, monkeypatch):
    def boom(answer, submitted):
        raise RuntimeError("comparison bug")

    monkeypatch.setattr(compare_module, "grade", boom)
    results = compare(expected, {"q1_omega": 2.5, "q1_axis": [0, 0.6, 0.8], "q2_shape": "loops"})
    assert {r.verdict.status for r in results} == {"invalid"}
    assert sum(r.verdict.points for r in results) == 0
    assert "could not be compared (RuntimeError)" in results[0].verdict.message


def test_an_unconvertible_kernel_value_is_invalid_and_says_what_it_was(expected):
    results = compare(expected, {"q1_omega": {"__invalid__": "a complex number"},
                                 "q1_axis": [0, 0.6, 0.8], "q2_shape": "loops"})
    assert results[0].verdict.status == "invalid"
    assert results[0].verdict.message == (
        "a complex number, which cannot be read as a scalar answer")
    assert [r.verdict.points for r in results] == [0.0, 1.0, 1.0]
