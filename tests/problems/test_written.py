"""Written parts in families and specs (issue 31): the ``Written`` record and its rubric, a
family's ``written(params)``, a spec asking for them or adding a question of its own, and one
message naming the file, line and key for each bad entry, with nothing written."""

from __future__ import annotations

import json
import math

import pytest

from eulertop.cli import main
from eulertop.family import Written
from problems.answers import Answer, check_form, grade
from problems.generate import recorded_variants
from problems.settings import AnswerSetting, QuestionSettings
from problems.spec import SpecError, read_spec
from problems.templates import FAMILIES
from solver.parameters import ParameterError

OFFERING = ("turning_points", "near_axis_stability", "symmetric_free_top", "sleeping_top")


def test_written_checks_its_rubric():
    w = Written("why", "Explain why.", 3, [("first", 1), {"item": "second", "points": 2}])
    assert [r.points for r in w.answer().rubric] == [1.0, 2.0]
    assert Written("why", "Explain.", None, [("a", 0.5), ("b", 0.25)]).points == 0.75
    with pytest.raises(ParameterError, match="add up to 2, not to the answer's 3"):
        Written("why", "Explain why.", 3, [("first", 1), ("second", 1)])
    with pytest.raises(ParameterError, match="its prompt"):
        Written("why", " ", 1, [("a", 1)])
    with pytest.raises(ParameterError, match="points must be a number ≥ 0"):
        Written("why", "Explain.", 1, [("a", -1), ("b", 2)])
    with pytest.raises(ParameterError, match="1 to 9 items"):
        Written("why", "Explain.", 10, [(f"item {i}", 1) for i in range(10)])
    with pytest.raises(ParameterError, match="only for, written"):
        Answer("x", "scalar", 1.0, rubric=(("a", 1),))


def test_a_written_answer_is_pending_when_written_and_never_judged():
    answer = Written("why", "Explain why.", 2, [("a", 1), ("b", 1)]).answer()
    assert grade(answer, {"text": "Because $x > 0$."}).status == "pending"
    assert grade(answer, {"text": "", "attachments": {"p.png": {}}}).status == "pending"
    assert grade(answer, {"text": "  \n"}).status == "missing"
    assert grade(answer, None).status == "missing"
    assert check_form(answer, "Because.").message == "well formed: 8 characters"
    assert Answer.from_dict(json.loads(json.dumps(answer.to_dict()))) == answer


@pytest.mark.parametrize("name", OFFERING)
def test_four_built_in_families_offer_a_written_part_citing_the_lecture(name):
    family = FAMILIES[name]
    (part,) = family.written({})
    assert part.kind == "written" and 2 <= len(part.rubric) <= 4
    assert math.isclose(sum(r.points for r in part.rubric), part.points)
    assert any(r in part.description for r in family.results)  # cites the R-ids it derives
    rng = __import__("numpy").random.default_rng(0)
    plain = family.generate(rng)
    assert all(a.kind != "written" for a in plain.answers)  # only when a spec asks
    asked = family.generate(__import__("numpy").random.default_rng(0),
                            QuestionSettings(written=True))
    assert [a.name for a in asked.answers] == [*(a.name for a in plain.answers), part.name]


def test_the_questions_points_spread_over_a_written_part_scale_its_rubric():
    answers = FAMILIES["sleeping_top"].written({})
    settings = QuestionSettings(points=6.0, answers={"sleeping_condition": AnswerSetting(4.5)})
    (scaled,) = settings.adjust_answers(answers)
    assert scaled.points == 4.5
    assert [r.points for r in scaled.rubric] == [1.5, 1.5, 1.5]


SPEC = """\
title = "W"
seed = 1
roster = "roster.csv"

[[questions]]
family = "sleeping_top"
written = ["sleeping_condition"]

[[questions]]
written = "Explain the tennis racket."
name = "racket"
points = 2
rubric = [
  { item = "linearised", points = 1 },
  { item = "sign of Ω₁Ω₂", points = 1 },
]
"""


@pytest.fixture
def course(tmp_path):
    (tmp_path / "roster.csv").write_text("id\nada\nbob\n")
    return tmp_path


def test_a_spec_asks_for_written_parts_and_adds_a_question_of_its_own(course):
    (course / "a.toml").write_text(SPEC)
    assert main(["generate", "--spec", str(course / "a.toml"), "--out",
                 str(course / "HW")]) == 0
    manifest = json.loads((course / "HW" / "assignment.json").read_text())
    key = json.loads((course / "HW" / "key.json").read_text())
    assert manifest["problems"] == ["sleeping_top", "written:racket"]
    q1, q2 = key["students"]["ada"]["questions"]
    assert q1["answers"][-1]["name"] == "sleeping_condition"
    assert q2["family"] == "written" and q2["answers"][0]["rubric"][1]["item"] == "sign of Ω₁Ω₂"
    variants = recorded_variants(manifest, FAMILIES, "ada")  # what rekey recomputes
    assert [a.to_dict() for v in variants for a in v.answers] == \
        [a for q in (q1, q2) for a in q["answers"]]
    assert main(["generate", "--reroll", "bob", "--out", str(course / "HW")]) == 0
    again = json.loads((course / "HW" / "key.json").read_text())["students"]["bob"]
    assert again["questions"][1]["answers"] == q2["answers"]


@pytest.mark.parametrize(("entry", "line", "key", "why"), [
    ('written = "Explain."\nname = "x"\npoints = 3\nrubric = [{ item = "a", points = 1 }]',
     7, "questions[1].rubric", "add up to 1, not to the answer's 3"),
    ('written = "Explain."\nname = "not a name"\nrubric = [{ item = "a", points = 1 }]',
     5, "questions[1].name", "a name that can end a Python variable"),
    ('written = "Explain."\nname = "x"', 3, "questions[1].rubric", "give the rubric"),
    ('written = "Explain."\nname = "x"\nrubric = [{ item = "a", points = 1, why = 2 }]',
     6, "questions[1].rubric[1].why", "unknown key"),
    ('family = "sleeping_top"\nwritten = ["nope"]', 5, "questions[1].written",
     "sleeping_top has no written part nope; its written parts: sleeping_condition"),
    ('family = "inertia_tensor"\nwritten = true', 5, "questions[1].written",
     "inertia_tensor has no written part"),
    ('family = "sleeping_top"\nwritten = 3', 5, "questions[1].written", "must be true"),
    ('family = "sleeping_top"\nwritten = true\n[questions.answers.sleeping_condition]\n'
     'rtol = 0.1', 6, "questions[1].answers.sleeping_condition", "has no tolerance"),
])
def test_a_bad_written_entry_is_one_line_naming_the_key(course, capsys, entry, line, key,
                                                        why):
    (course / "a.toml").write_text(f'roster = "roster.csv"\n\n[[questions]]\n{entry}\n')
    assert main(["generate", "--spec", str(course / "a.toml"), "--out",
                 str(course / "HW")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"a.toml:{line}: {key}: " in err and why in err
    assert not (course / "HW").exists()


def test_the_issues_own_example_reads(course):
    (course / "a.toml").write_text('''
[[questions]]
written = "Show that V_eff(β) has exactly one minimum between β = 0 and β = π when |p_α| ≠ |p_γ|."
name = "veff_minimum"
points = 3
rubric = [
  { item = "V_eff in terms of p_α, p_γ, I1 and Mgl", points = 1 },
  { item = "V_eff → +∞ at both ends argued", points = 1 },
  { item = "one stationary point shown", points = 1 },
]
''')
    (question,) = read_spec(course / "a.toml").questions
    assert question.written.points == 3 and len(question.written.rubric) == 3
    assert question.label == "written:veff_minimum" and question.pool == ()
    (course / "b.toml").write_text('[[questions]]\nwritten = "x"\nname = "y"\nrubric = 3\n')
    with pytest.raises(SpecError, match=r"b.toml:4: questions\[1\].rubric: give the rubric"):
        read_spec(course / "b.toml")
