"""Gradebook, feedback pages and summary: derived from records, escaped, one student each."""

from __future__ import annotations

import csv
import io
import json
import re
from dataclasses import replace
from pathlib import Path

import pytest

from grader.compare import compare, key_answers
from grader.gradebook import (
    answer_counts,
    answers_rows,
    feedback_html,
    gradebook_csv,
    gradebook_rows,
    number,
    reason,
    summary_table,
)
from grader.results import StudentResult
from grader.submissions import Problem
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

SCRIPT = "<script>alert('owned')</script>"


@pytest.fixture(scope="module")
def hw(tmp_path_factory) -> Path:
    roster = Roster(("id", "name", "email"), (
        {"id": "alice", "name": "Alice, \"Al\" Ng", "email": "a@x"},
        {"id": "bob", "name": "Bob", "email": "b@x"},
    ))
    out = tmp_path_factory.mktemp("report") / "HW"
    generate_assignment(roster, out, FAMILIES, problems=["inertia_tensor", "euler_rotation"],
                        seed=11, title="Week <3>")
    return out


@pytest.fixture(scope="module")
def files(hw):
    return (json.loads((hw / "assignment.json").read_text()),
            json.loads((hw / "key.json").read_text()))


def _record(key, sid, submitted, status="graded") -> StudentResult:
    answers = compare(key_answers(key, sid), submitted)
    return StudentResult(sid, status, "", answers, sum(a.verdict.points for a in answers),
                         sum(a.verdict.max_points for a in answers), "0" * 64,
                         key["students"][sid]["hash"], {}, False, "2024-01-01T00:00:00+00:00")


def _key_values(key, sid) -> dict:
    return {f"q{q['question']}_{a['name']}": a["value"]
            for q in key["students"][sid]["questions"] for a in q["answers"]}


def test_gradebook_has_roster_columns_points_per_question_and_totals(files):
    manifest, key = files
    right = _key_values(key, "alice")
    first = next(iter(right))
    alice = _record(key, "alice", {**right, first: None})  # one answer of question 1 unset
    table = gradebook_rows(manifest["roster"]["columns"], manifest["roster"]["rows"], (1, 2),
                           {"alice": alice})
    assert table[0] == ["id", "name", "email", "q1", "q2", "total", "maximum", "status",
                        "reason"]
    n1 = len(key["students"]["alice"]["questions"][0]["answers"])
    n2 = len(key["students"]["alice"]["questions"][1]["answers"])
    assert table[1] == ["alice", "Alice, \"Al\" Ng", "a@x", number(n1 - 1), number(n2),
                        number(n1 + n2 - 1), number(n1 + n2), "graded", ""]
    assert table[2] == ["bob", "Bob", "b@x", "", "", "", "", "not graded yet", ""]
    # and the CSV text reads back to the same table, commas and quotes included
    assert list(csv.reader(io.StringIO(gradebook_csv(table)))) == table


@pytest.fixture
def alice_page(files):
    manifest, key = files
    submitted = {v: SCRIPT for v in _key_values(key, "alice")}
    result = _record(key, "alice", submitted)
    result = StudentResult(**{**result.__dict__, "message": f"cell 4 raised {SCRIPT}",
                              "execution": {"cell_errors": [f"cell 4: {SCRIPT}"]}})
    return lambda reveal: feedback_html(
        manifest["title"], result, manifest["students"]["alice"]["questions"],
        _key_values(key, "alice") if reveal else None)


@pytest.mark.parametrize("reveal", [False, True])
def test_feedback_escapes_everything_the_student_wrote(alice_page, reveal):
    page = alice_page(reveal)
    assert "<script" not in page.lower()
    assert "&lt;script&gt;alert(&#x27;owned&#x27;)&lt;/script&gt;" in page
    assert "Week &lt;3&gt;" in page  # the instructor's text is escaped too


def test_feedback_shows_the_key_only_when_revealed(files, alice_page):
    _, key = files
    hidden, shown = alice_page(False), alice_page(True)
    values = [json.dumps(v) for v in _key_values(key, "alice").values()]
    assert not any(v in hidden for v in values)
    assert all(v in shown for v in values)


def test_feedback_holds_nothing_of_another_student(files, alice_page):
    manifest, key = files
    page = alice_page(True)
    bob_params = [repr(v) if not isinstance(v, list) else None
                  for q in manifest["students"]["bob"]["questions"] for v in q["params"].values()]
    bob_key = [json.dumps(v) for v in _key_values(key, "bob").values()]
    assert not any(p and p in page for p in bob_params + bob_key)
    assert "bob" not in page
    # while alice's own parameters are all there
    mine = [str(v) for q in manifest["students"]["alice"]["questions"]
            for v in q["params"].values()]
    assert all(v in page for v in mine)


def test_summary_lists_students_counts_and_strays(files):
    _, key = files
    alice = _record(key, "alice", _key_values(key, "alice"))
    bob = _record(key, "bob", None, status="missing")
    text = summary_table([alice, bob], [Problem(Path("eve.ipynb"), "eve.ipynb: not on roster")])
    lines = text.splitlines()
    assert re.match(r"alice\s+graded\s+(\d+)\s+\1$", lines[2])
    assert re.match(r"bob\s+missing\s+0\s+\d+\s+no submission$", lines[3])
    assert "1 graded, 1 missing, 0 failed of 2 students" in text
    assert "  eve.ipynb: not on roster" in lines


def _failed(key, sid, message) -> StudentResult:
    r = _record(key, sid, None, status="failed")
    return StudentResult(**{**r.__dict__, "message": message})


def test_gradebook_keeps_graded_missing_and_failed_apart_with_a_reason(files):
    _, key = files
    alice = _record(key, "alice", _key_values(key, "alice"))
    bob = StudentResult(**{**_record(key, "bob", None, status="missing").__dict__,
                           "message": "no submission"})
    roster = [{"id": "alice", "name": "A", "email": "a@x"}, {"id": "bob", "name": "B",
                                                             "email": "b@x"}]
    table = gradebook_rows(("id", "name", "email"), roster, (1, 2), {"alice": alice, "bob": bob})
    rows = {r[0]: dict(zip(table[0], r, strict=True)) for r in table[1:]}
    assert (rows["alice"]["status"], rows["alice"]["reason"]) == ("graded", "")
    assert (rows["bob"]["status"], rows["bob"]["reason"]) == ("missing", "no submission")
    bob = _failed(key, "bob", "the Python kernel died (exit signal 9)\nsecond line")
    table = gradebook_rows(("id", "name", "email"), roster, (1, 2), {"alice": alice, "bob": bob})
    failed = dict(zip(table[0], table[2], strict=True))
    assert (failed["status"], failed["reason"]) == ("failed",
                                                    "the Python kernel died (exit signal 9)")


def test_grades_csv_holds_no_control_characters(files):
    _, key = files
    nasty = "cell 2 raised ValueError: \x1b[2J\x00bell\x07\ttab\r\nnext\u2028line\x85"
    bob = _failed(key, "bob", nasty)
    text = gradebook_csv(gradebook_rows(("id", "name"), [{"id": "bob", "name": "B\tob\n"}],
                                        (1, 2), {"bob": bob}))
    body = text.replace("\r\n", "")  # the CSV record separators, and only those
    assert not re.search(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]", body)
    assert text.count("\r\n") == 2  # header and bob: nothing split a record
    row = list(csv.reader(io.StringIO(text)))[1]
    assert row[1] == "B ob" and row[-1].startswith("cell 2 raised ValueError:")


def test_summary_counts_each_answer_outcome_over_graded_submissions(files):
    _, key = files
    right = _key_values(key, "alice")
    variables = list(right)
    first = key["students"]["bob"]["questions"][0]["answers"][0]
    bob_values = _key_values(key, "bob")
    assert first["mistakes"], "the first answer of inertia_tensor lists known mistakes"
    students = [
        _record(key, "alice", right),                                    # all correct
        _record(key, "bob", {**bob_values, variables[0]: first["mistakes"][0]["value"],
                             variables[1]: "not a vector", variables[2]: None}),
        _record(key, "alice", {**right, variables[0]: [1.0, 2.0, 3.0]}),  # wrong, no mistake
        _record(key, "bob", None, status="missing"),                      # left out
    ]
    lines = answer_counts(students)
    assert lines[1] == "per answer, over 3 graded submission(s):"
    table = {line.split()[0]: [int(x) for x in line.split()[1:]] for line in lines[3:]}
    # columns: correct, wrong, known mistake, invalid, unanswered
    assert table[variables[0]] == [1, 1, 1, 0, 0]
    assert table[variables[1]] == [2, 0, 0, 1, 0]
    assert table[variables[2]] == [2, 0, 0, 0, 1]
    q1 = [v for v in variables if v.startswith("q1_")]  # question 2's answers vary by student
    assert all(sum(table[v]) == 3 for v in q1)
    assert list(table)[: len(q1)] == q1  # question order
    assert "\n".join(lines) in summary_table(students)
    assert answer_counts([students[-1]]) == []


@pytest.mark.parametrize(("points", "shown"), [
    (22 / 3, "7.333"), (14.999999999999998, "15"), (1 / 3, "0.3333"), (2.5, "2.5"), (3.0, "3"),
    (12345.6, "12350"), (0.1 + 0.2, "0.3"), (1 - 0.9 - 0.1, "0"), (-0.0, "0"),
    (1e20, "1" + "0" * 20),
])
def test_a_point_count_is_shown_to_four_significant_figures(points, shown):
    assert number(points) == shown


def test_every_view_of_a_record_shows_its_points_rounded(files):
    """Issue 30: ``14.999999999999998`` of ``22/3`` in the gradebook, answers.csv, the summary
    and the feedback page; the record keeps both floats."""
    manifest, key = files
    r = _record(key, "alice", _key_values(key, "alice"))
    answers = tuple(replace(a, verdict=replace(a.verdict, points=1 / 3, max_points=15 / 7))
                    for a in r.answers)
    r = replace(r, answers=answers, points=22 / 3, max_points=14.999999999999998)
    assert (r.points, r.max_points) == (22 / 3, 14.999999999999998)
    rows = gradebook_rows(("id",), [{"id": "alice"}], (1, 2), {"alice": r})
    assert len(key["students"]["alice"]["questions"][0]["answers"]) == 4  # inertia_tensor
    assert rows[1][1:5][0::2] == ["1.333", "7.333"] and rows[1][4] == "15"
    assert re.fullmatch(r"\d(\.\d{1,3})?", rows[1][2])  # question 2: a third per answer
    assert {tuple(row[5:7]) for row in answers_rows([{"id": "alice"}], {"alice": r})[1:]} == \
        {("0.3333", "2.143")}
    assert re.search(r"^alice\s+graded\s+7\.333\s+15$", summary_table([r]), re.M)
    page = feedback_html(manifest["title"], r, manifest["students"]["alice"]["questions"])
    assert "7.333 of 15 points" in page and "0.3333 / 2.143" in page
    assert "33333" not in page and "99999" not in page


def test_a_graded_row_names_each_cell_that_raised_or_timed_out_once(files):
    """Issue 30: a run whose cells raised or timed out left the row's reason empty. Cells its
    message already names (the one running when the notebook's time ran out) are not said
    twice."""
    _, key = files
    raised = "cell 4 (`x = 1/0`): ZeroDivisionError: division by zero"
    spun = "cell 7 (`while True:`): timed out after 30 s and was interrupted"
    ran = replace(_record(key, "alice", _key_values(key, "alice")),
                  execution={"status": "ok", "message": "ran all 9 code cells; 2 did not finish "
                             "normally", "cell_errors": [raised, spun]})
    assert reason(ran) == f"{raised}; {spun}"
    out_of_time = replace(ran, message="stopped at the time limit for the whole notebook (120 s) "
                          "while cell 7 (`while True:`) was running: it was interrupted",
                          execution={**ran.execution, "status": "timeout"})
    assert reason(out_of_time) == f"{out_of_time.message}; {raised}"
    row = gradebook_rows(("id",), [{"id": "alice"}], (1, 2), {"alice": ran})[1]
    assert row[-1] == f"{raised}; {spun}"
    assert f"{raised}; cell 7" in summary_table([ran])
