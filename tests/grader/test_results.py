"""Result records: exact JSON round trip, strict JSON, and atomic writing."""

from __future__ import annotations

import json
import math
import os

import pytest

from grader.results import (
    AnswerResult,
    StudentResult,
    atomic_write_text,
    plain_json,
    read_result,
    remove_stale_temporaries,
    result_json,
    write_result,
)
from problems.answers import Verdict


def _answer(q: int, name: str, submitted, status: str = "correct", points: float = 1.0):
    awarded = points if status == "correct" else 0.0
    return AnswerResult(f"q{q}_{name}", q, name, submitted,
                        Verdict(status, awarded, points, f"{status}: {submitted!r}"))


def _result(status: str = "graded", answers=(), **kw) -> StudentResult:
    fields = dict(
        student_id="alice", status=status, message="", answers=tuple(answers),
        points=sum(a.verdict.points for a in answers),
        max_points=sum(a.verdict.max_points for a in answers),
        submission_sha256="ab" * 32, key_sha256="sha256:" + "cd" * 32,
        execution={"status": "ok", "message": "", "cell_errors": ("cell 3 raised X",),
                   "duration": 1.25, "output_truncated": False},
        sandboxed=False, graded_at="2024-01-01T00:00:00+00:00",
    )
    fields.update(kw)
    return StudentResult(**fields)


RESULTS = {
    "graded, every kind of submitted value": _result(answers=(
        _answer(1, "I", 0.5), _answer(1, "v", [1.0, 2.0, 3.0]),
        _answer(2, "spin", True), _answer(2, "shape", "loops"),
        _answer(3, "expr", "m*L**2/12", "wrong"),
        _answer(3, "nan", math.nan, "invalid"), _answer(3, "inf", [1.0, -math.inf], "invalid"),
        _answer(4, "unset", None, "missing"),
        _answer(4, "marker", {"unreadable": "a <lambda>"}, "invalid"),
        _answer(4, "odd", "q\"uote\u00e9 <script>", "invalid"),
    )),
    "missing": _result("missing", answers=(_answer(1, "I", None, "missing"),),
                       message="no submission", submission_sha256=None, execution={}),
    "failed, non-finite duration": _result(
        "failed", answers=(_answer(1, "I", None, "missing"),), message="kernel died\nline 2",
        execution={"status": "kernel_died", "message": "died", "cell_errors": [],
                   "duration": math.inf, "output_truncated": True}),
}


@pytest.mark.parametrize("result", RESULTS.values(), ids=RESULTS.keys())
def test_round_trip_through_json_text_is_exact(result):
    text = result_json(result)
    assert StudentResult.from_dict(json.loads(text)) == result
    assert StudentResult.from_dict(result.to_dict()) == result


@pytest.mark.parametrize("result", RESULTS.values(), ids=RESULTS.keys())
def test_result_files_are_strict_json(result):
    # Python's json would happily write NaN/Infinity tokens, which other tools reject.
    json.loads(result_json(result), parse_constant=lambda c: pytest.fail(f"token {c}"))


def test_plain_json_names_non_finite_floats_and_flattens_tuples():
    assert plain_json({"x": (math.nan, math.inf, -math.inf, 1.5)}) == {
        "x": ["NaN", "Infinity", "-Infinity", 1.5]}


def test_question_points_sum_per_question():
    r = RESULTS["graded, every kind of submitted value"]
    assert r.question_points() == {1: 2.0, 2: 2.0, 3: 0.0, 4: 0.0}


def test_unknown_status_and_unknown_fields_are_refused():
    with pytest.raises(ValueError, match="status"):
        _result("great")
    d = _result().to_dict() | {"extra": 1}
    with pytest.raises(ValueError, match="extra"):
        StudentResult.from_dict(d)


def test_write_and_read_back(tmp_path):
    r = RESULTS["missing"]
    path = write_result(tmp_path, r)
    assert path == tmp_path / "alice.json"
    assert read_result(path) == r
    assert os.listdir(tmp_path) == ["alice.json"]  # no temporary left


@pytest.mark.parametrize("content", ["", "{", "[]", '{"student_id": "x"}'])
def test_unreadable_records_read_as_none(tmp_path, content):
    (tmp_path / "x.json").write_text(content)
    assert read_result(tmp_path / "x.json") is None
    assert read_result(tmp_path / "absent.json") is None


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    target = tmp_path / "grades.csv"
    target.write_text("old")

    def crash(src, dst):
        raise KeyboardInterrupt  # Ctrl-C between writing and renaming

    monkeypatch.setattr(os, "replace", crash)
    with pytest.raises(KeyboardInterrupt):
        atomic_write_text(target, "new")
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["grades.csv"]


def test_stale_temporaries_of_a_killed_run_are_removed(tmp_path):
    (tmp_path / ".alice.json.x1y2.tmp").write_text('{"half')
    (tmp_path / "alice.json").write_text("{}")
    removed = remove_stale_temporaries(tmp_path, tmp_path / "absent")
    assert [p.name for p in removed] == [".alice.json.x1y2.tmp"]
    assert os.listdir(tmp_path) == ["alice.json"]
