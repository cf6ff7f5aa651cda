"""A student's notebook is short: conventions once at the top, each question readable in a
minute, and nothing typed into a statement that the notebook derives (issues 13 and 25).

Measured on a notebook of all the families (one question each), in words (whitespace-separated
tokens, LaTeX included), for several students and seeds. Before issue 13 such a notebook's
Markdown was about 4,200 words, with the heavy-top conventions paragraph repeated in four
questions and the answers listed twice; before issue 25, about 3,300 (3,437 at most over 40
students of seed 13): under 2,500 is a notebook a student reads in minutes.
"""

from __future__ import annotations

import json

import pytest

from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

STUDENTS = tuple(f"s{i}" for i in range(12))
SEEDS = (13, 2024)
MAX_QUESTION_WORDS = 200
"""A question's Markdown cell (heading, statement, comparison line): a minute's reading."""
MAX_MARKDOWN_WORDS = 2500
"""All Markdown cells of a notebook with one question of every family: fewer words than this."""
LONG_PARAGRAPH = 40
"""Paragraphs of this many words or more are never repeated within a notebook."""


@pytest.fixture(scope="module")
def notebooks(tmp_path_factory) -> dict[str, dict]:
    found = {}
    for seed in SEEDS:
        out = tmp_path_factory.mktemp("length") / "HW"
        generate_assignment(Roster(("id",), tuple({"id": s} for s in STUDENTS)), out,
                            FAMILIES, seed=seed)
        found |= {f"{seed}/{s}": json.loads((out / "release" / f"{s}.ipynb").read_text())
                  for s in STUDENTS}
    return found


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


def test_the_whole_notebook_is_under_2500_words(notebooks):
    for name, nb in notebooks.items():
        assert sum(_words(c) for c in _markdown(nb)) < MAX_MARKDOWN_WORDS, name


def _paragraphs(nb: dict) -> list[str]:
    return [p.strip() for c in _markdown(nb) for p in "".join(c["source"]).split("\n\n")]


def test_no_long_paragraph_is_repeated(notebooks):
    for name, nb in notebooks.items():
        long = [p for p in _paragraphs(nb) if len(p.split()) >= LONG_PARAGRAPH]
        assert long and len(set(long)) == len(long), name


def test_a_repeated_long_paragraph_would_be_caught():
    """The check above on a notebook that states a tool paragraph twice (as one did before
    issue 13, once per question)."""
    text = " ".join(["word"] * LONG_PARAGRAPH)
    cell = {"cell_type": "markdown", "source": [f"intro\n\n{text}"]}
    nb = {"cells": [cell, dict(cell)]}
    long = [p for p in _paragraphs(nb) if len(p.split()) >= LONG_PARAGRAPH]
    assert len(long) == 2 and len(set(long)) == 1


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
