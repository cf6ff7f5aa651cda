"""A family of an instructor's own with a follow-through chain, for the tests of issue 30:
``a = 2x``, then ``t = a²`` from the student's own ``a``; its own degenerate case (a negative
arm) beside the defaults. :func:`lever_assignment` generates an assignment with it."""

from __future__ import annotations

import json
from pathlib import Path

import nbformat

from problems.family_files import catalogue
from problems.generate import generate_assignment
from problems.roster import Roster

LEVER = '''"""A lever arm and its square: a = 2x, then t = a^2 from your own a."""

from eulertop.family import Answer, Mistake, Parameter, follows_from

NAME = "lever"
TITLE = "A lever arm and its square"
SUMMARY = "a = 2x, then t = a^2 from your a"
PARAMETERS = {"x": Parameter(unit="m", low=1.0, high=2.0, figures=3)}


def answers(params):
    a = 2 * params["x"]
    half = Mistake("half", a / 4, "The arm is 2x, not x/2.")
    return (Answer("a", "scalar", a, unit="m", mistakes=(half,)),
            follows_from(Answer("t", "scalar", a * a, unit="m^2"), "a"))


def statement(params):
    return "Compute the arm $a = 2x$, then $t = a^2$ from your $a$."


def follow(name, params, earlier):
    return earlier["a"] ** 2


def degenerate(name, params, earlier):
    if earlier["a"] < 0:
        return "your {a} is negative: no arm is, so {t} from it shows nothing"
    return None
'''


def lever_assignment(root: Path, students: tuple[str, ...], problems=("lever",),
                     seed: int = 30) -> Path:
    """``root/HW`` generated for ``students`` with ``root/mine/lever.py`` among its families."""
    (root / "mine").mkdir(parents=True, exist_ok=True)
    (root / "mine" / "lever.py").write_text(LEVER)
    roster = Roster(("id", "name"), tuple({"id": s, "name": s} for s in students))
    generate_assignment(roster, root / "HW", catalogue([root / "mine"], entry_points=False),
                        problems=list(problems), seed=seed)
    return root / "HW"


def key_values(hw: Path, sid: str) -> dict[str, object]:
    """``sid``'s key values by variable."""
    key = json.loads((hw / "key.json").read_text())
    return {f"q{q['question']}_{a['name']}": a["value"]
            for q in key["students"][sid]["questions"] for a in q["answers"]}


def notebook(answers: dict) -> str:
    """A submission assigning each answer variable a literal (what ``LiteralExecute``
    reads)."""
    code = "\n".join(f"{name} = {value!r}" for name, value in answers.items())
    return nbformat.writes(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)]))
