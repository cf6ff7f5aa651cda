"""Gradebook, feedback pages and summary: derived from records, escaped, one student each."""

from __future__ import annotations

import csv
import io
import json
import re
from pathlib import Path

import pytest

from grader.compare import compare, key_answers
from grader.discover import Problem
from grader.gradebook import feedback_html, gradebook_csv, gradebook_rows, number, summary_table
from grader.results import StudentResult
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
    assert table[0] == ["id", "name", "email", "q1", "q2", "total", "maximum", "status"]
    n1 = len(key["students"]["alice"]["questions"][0]["answers"])
    n2 = len(key["students"]["alice"]["questions"][1]["answers"])
    assert table[1] == ["alice", "Alice, \"Al\" Ng", "a@x", number(n1 - 1), number(n2),
                        number(n1 + n2 - 1), number(n1 + n2), "graded"]
    assert table[2] == ["bob", "Bob", "b@x", "", "", "", "", "not graded yet"]
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
    assert re.match(r"bob\s+missing\s+0\s+\d+$", lines[3])
    assert "1 graded, 1 missing, 0 failed of 2 students" in text
    assert "  eve.ipynb: not on roster" in lines
