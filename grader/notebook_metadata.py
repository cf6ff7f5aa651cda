"""What a notebook says it is: the ``metadata["eulertop"]`` the generator writes into every
notebook it makes — the student it was made for, and its public answer list (names, kinds,
units, never values).

One reading of it, shared by ``eulertop check`` (:mod:`grader.check`, which refuses a notebook
without an answer list) and grading (:func:`grader.grade_one.record`, which grades such a
notebook all the same and says it is not this assignment's, or another student's). Only ever
*reported*: the metadata is in the student's hands; the grader takes the student from the file
name and the answers from the key.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any


class NoAnswerList(ValueError):
    """The notebook has no eulertop answer list, or a damaged one: not a notebook the generator
    made. The message says which, as what the notebook does (``has no eulertop answer list in
    its metadata``)."""


def answer_list(metadata: Any) -> tuple[dict, ...]:
    """The public answer specs of a notebook's ``metadata`` (its top-level metadata dict), in
    question order.

    Raises
    ------
    NoAnswerList
        No ``eulertop`` entry, or one without a well-formed answer list.
    """
    eulertop = metadata.get("eulertop") if isinstance(metadata, Mapping) else None
    if eulertop is None:
        raise NoAnswerList("has no eulertop answer list in its metadata")
    try:
        specs = tuple(dict(a) for q in eulertop["questions"] for a in q["answers"])
        if not specs or not all(_valid_spec(s) for s in specs):
            raise ValueError
    except (KeyError, TypeError, ValueError):
        raise NoAnswerList("has eulertop metadata that is damaged") from None
    return specs


def named_student(metadata: Any) -> str | None:
    """The student id a notebook's ``metadata`` names (``eulertop.student``; ``student_id``
    accepted too), or None."""
    try:
        eulertop = metadata["eulertop"]
        claim = eulertop.get("student", eulertop.get("student_id"))
    except (KeyError, TypeError, AttributeError):
        return None
    return claim if isinstance(claim, str) else None


@dataclass(frozen=True)
class Identity:
    """What a submitted notebook's metadata says it is (:func:`identity`)."""

    student: str | None  # the student it names, if any
    no_answer_list: str = ""  # why it is no notebook of the generator's; "" when it is one

    def not_for(self, student_id: str) -> str:
        """Why this is not ``student_id``'s notebook of this assignment, for their record;
        ``""`` when nothing says so."""
        if self.no_answer_list:
            return f"not this assignment's notebook: it {self.no_answer_list}"
        if self.student is not None and self.student != student_id:
            return f"another student's notebook: its metadata names student {self.student!r}"
        return ""


def identity(data: bytes) -> Identity | None:
    """The :class:`Identity` of a submitted notebook's bytes; None when they cannot be parsed
    as a notebook at all (within the limits of :func:`grader.notebook_load.notebook_json`):
    the execution stage reports that."""
    from grader.notebook_load import notebook_json

    try:
        metadata = notebook_json(data).get("metadata")
    except Exception:
        return None
    return identity_of(metadata)


def identity_of(metadata: Any) -> Identity:
    """The :class:`Identity` a notebook's (parsed) ``metadata`` gives: what the execution
    stage reads from the notebook it has parsed already (a large notebook is not parsed a
    second time to tell whose it is)."""
    try:
        answer_list(metadata)
        why = ""
    except NoAnswerList as e:
        why = str(e)
    return Identity(named_student(metadata), why)


def _valid_spec(spec: Mapping[str, Any]) -> bool:
    from problems.answers import ANSWER_KINDS

    variable = spec.get("variable")
    return (isinstance(variable, str) and variable.isidentifier()
            and spec.get("kind") in ANSWER_KINDS and isinstance(spec.get("name"), str))
