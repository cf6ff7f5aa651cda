"""A student's notebook is short: conventions once at the top, each question readable in a
minute, and nothing typed into a statement that the notebook derives (issue 13).

Measured on a notebook of all the families (one question each), in words (whitespace-separated
tokens, LaTeX included), for several students. Before issue 13 such a notebook's Markdown was
about 4,200 words, with the heavy-top conventions paragraph repeated in four questions and the
answers listed twice (a table at the top, and the answer cells).
"""

from __future__ import annotations

import json

import pytest

from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

STUDENTS = tuple(f"s{i}" for i in range(8))
MAX_QUESTION_WORDS = 270
"""A question's Markdown cell (heading, statement, comparison line): a minute's reading."""
MAX_MARKDOWN_WORDS = 3600
"""All Markdown cells of a notebook with one question of every family."""


@pytest.fixture(scope="module")
def notebooks(tmp_path_factory) -> dict[str, dict]:
    out = tmp_path_factory.mktemp("length") / "HW"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in STUDENTS)), out, FAMILIES,
                        seed=13)
    return {s: json.loads((out / "release" / f"{s}.ipynb").read_text()) for s in STUDENTS}


def _words(cell: dict) -> int:
    return len("".join(cell["source"]).split())


def _markdown(nb: dict) -> list[dict]:
    return [c for c in nb["cells"] if c["cell_type"] == "markdown"]


def test_each_question_reads_in_a_minute(notebooks):
    for nb in notebooks.values():
        questions = [c for c in nb["cells"] if c["id"].endswith("-statement")]
        assert len(questions) == len(FAMILIES)
        longest = max(questions, key=_words)
        assert _words(longest) <= MAX_QUESTION_WORDS, longest["id"]


def test_the_whole_notebook_is_bounded(notebooks):
    for nb in notebooks.values():
        assert sum(_words(c) for c in _markdown(nb)) <= MAX_MARKDOWN_WORDS


def test_conventions_are_stated_once_at_the_top(notebooks):
    for nb in notebooks.values():
        cells = _markdown(nb)
        text = ["".join(c["source"]) for c in cells]
        top, questions = text[1], text[2:]
        for heading in ("**Conventions for every question**", "**Euler angles**",
                        "**Heavy symmetric top.**", "**Inertia tensor.**", "**Free rigid body.**"):
            assert top.count(heading) == 1
        assert all("Conventions" not in q and "R_\\gamma R_\\beta R_\\alpha" not in q
                   for q in questions)


def test_every_question_states_how_its_answers_are_compared_and_no_statement_types_it(
        notebooks):
    for nb in notebooks.values():
        meta = nb["metadata"]["eulertop"]["questions"]
        for q, spec in zip(
                [c for c in nb["cells"] if c["id"].endswith("-statement")], meta, strict=True):
            text = "".join(q["source"])
            statement, compared = text.rsplit("\n\n", 1)
            assert "tolerance" not in statement.lower()  # only the derived line says it
            assert compared.startswith("*Compared:* ")
            for answer in spec["answers"]:  # every answer is named in the comparison line
                assert f"`{answer['variable']}`" in compared
            angles = [a for a in spec["answers"] if a["kind"] == "angle"]
            if angles:
                assert "in radians" in compared and "modulo 2π" in compared
