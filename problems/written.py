"""Written parts of a question (issue 31): a derivation or an explanation the student writes in
a Markdown cell, scored by a person against a rubric.

A family offers them with an optional ``written(params)`` returning :class:`Written` records
(``problems/API.md``, "A family"); an assignment spec asks for them (``written = true``, or the
names of those wanted, in a family's ``[[questions]]``), or adds a question that is only a
written part (``[[questions]] written = "…prompt…"`` with ``name``, ``points`` and
``rubric``: :func:`written_variant`). In the key each is an :class:`~problems.answers.Answer`
of kind ``written`` (the prompt as its ``value``, the rubric beside it); in the notebook a
prompt cell and a Markdown answer cell marked ``metadata["eulertop"]["written"] = <variable>``
(:mod:`problems.notebook`); in the record what the student wrote, ``pending`` until a review
scores it (:mod:`grader.written`, :mod:`grader.reviews`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from problems.answers import PLACEHOLDER as PLACEHOLDER  # the empty answer cell's text
from problems.answers import WRITTEN, Answer, RubricItem, rubric_items
from problems.variant import Variant

WRITTEN_QUESTION = "written"
"""The family name a spec's question of only a written part is recorded under (no family of
the catalogue has it)."""



@dataclass(frozen=True)
class Written:
    """A written part: its ``name`` (the notebook variable is ``q{k}_{name}``, as an answer's),
    the ``prompt`` (Markdown with LaTeX, as the student reads it), its ``points`` and its
    ``rubric`` — ``(item, points)`` pairs, ``{"item", "points"}`` tables or
    :class:`~problems.answers.RubricItem` s, 1 to 9 of them, whose points add up to
    ``points`` (``points`` None: their sum).

    Raises
    ------
    eulertop_base.ParameterError
        A ``ValueError`` naming the field at fault (no prompt, a rubric item without text or
        with negative points, items that do not add up to ``points``).

    Examples
    --------
    >>> w = Written("why_unstable", "Explain why …", 2, [("linearised", 1), ("sign", 1)])
    >>> w.answer().kind, w.answer().points
    ('written', 2.0)
    """

    name: str
    prompt: str
    points: float | None = None
    rubric: Sequence[Any] = ()
    description: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "rubric", rubric_items(self.rubric))
        if self.points is None:
            object.__setattr__(self, "points", sum(r.points for r in self.rubric))
        self.answer()  # refuses what no key could hold

    def answer(self) -> Answer:
        """The key's answer of this part (kind ``written``)."""
        return Answer(self.name, WRITTEN, self.prompt, points=self.points,
                      rubric=tuple(self.rubric), description=self.description)

    def record(self) -> dict:
        """Plain JSON, for the manifest's record of a spec's question (:meth:`from_record`)."""
        return {"name": self.name, "prompt": self.prompt, "points": self.points,
                "rubric": [r.to_dict() for r in self.rubric], "description": self.description}

    @classmethod
    def from_record(cls, d: dict) -> Written:
        return cls(d["name"], d["prompt"], d["points"],
                   tuple(RubricItem(**r) for r in d["rubric"]), d.get("description", ""))


STANDALONE_STATEMENT = ("Answer in writing, in the Markdown cell below the prompt. Your "
                        "instructor scores it against a rubric.")


def written_variant(written: Written, title: str | None = None) -> Variant:
    """The variant of a spec's question that is only ``written``: the same for every student
    (nothing is drawn), of the family :data:`WRITTEN_QUESTION`."""
    return Variant(WRITTEN_QUESTION, title or "Written answer", {}, {}, STANDALONE_STATEMENT,
                   (written.answer(),))
