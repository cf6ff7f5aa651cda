"""Reading a class's key (``load_assignment`` then ``expected``): a key file edited by hand is
refused where it would mis-grade, naming the file, the student and the answer; one that keeps
within what grading needs is read as written (issue 34: the generator's own margin between a
key and its known mistakes is a rule of generation, not of reading)."""

from __future__ import annotations

import json

import pytest

from grader.assignment import UsageError, load_assignment
from problems.answers import grade
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    hw = tmp_path_factory.mktemp("key") / "HW"
    roster = Roster(("id", "name"), ({"id": "ada", "name": "Ada"}, {"id": "bo", "name": "Bo"}))
    generate_assignment(roster, hw, FAMILIES, problems=["symmetric_free_top"], seed=3)
    return hw, (hw / "key.json").read_text()


def _edited(generated, edit) -> object:
    """The assignment with ``edit(first scalar answer of bo's key)`` written to key.json."""
    hw, text = generated
    key = json.loads(text)
    answer = next(a for a in key["students"]["bo"]["questions"][0]["answers"]
                  if a["kind"] == "scalar" and a["mistakes"])
    edit(answer)
    (hw / "key.json").write_text(json.dumps(key))
    return load_assignment(hw), answer


def test_the_generated_key_reads_back_as_written(generated):
    a, _ = _edited(generated, lambda answer: None)
    for sid in ("ada", "bo"):
        assert [k.answer.to_dict() for k in a.expected(sid)] == \
            [x for q in a.key["students"][sid]["questions"] for x in q["answers"]]


@pytest.mark.parametrize(("edit", "fragment"), [
    (lambda a: a["mistakes"][0].update(value="12.5"), "the string '12.5', not a number"),
    (lambda a: a["mistakes"][0].update(value=a["value"]), "indistinguishable from the key"),
    (lambda a: a.update(accepted=[[1.0, 2.0]]), "a single number is expected"),
    (lambda a: a.update(rtol=-0.1), "must be finite and ≥ 0"),
    (lambda a: a.update(unexpected=1), "unknown keys ['unexpected']"),
])
def test_a_hand_edit_that_would_misgrade_is_refused_by_name(generated, edit, fragment):
    a, _ = _edited(generated, edit)
    a.expected("ada")  # the other student's entry is untouched
    with pytest.raises(UsageError) as refused:
        a.check_key()
    message = str(refused.value)
    assert message.startswith(f"{generated[0] / 'key.json'}: bo's entry cannot be read")
    assert fragment in message


def test_a_mistake_nearer_than_the_generators_margin_is_graded_as_written(generated):
    """3 tolerances from the key: a template would have drawn again (5), a key file is read."""
    def nearer(answer):
        answer["mistakes"][0]["value"] = answer["value"] * (1 + 3 * answer["rtol"])

    a, answer = _edited(generated, nearer)
    a.check_key()
    read = next(k.answer for k in a.expected("bo") if k.answer.name == answer["name"])
    assert grade(read, answer["mistakes"][0]["value"]).mistake == answer["mistakes"][0]["name"]
    assert grade(read, answer["value"]).status == "correct"
