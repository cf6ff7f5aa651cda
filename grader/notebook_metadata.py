"""What a notebook says it is: the ``metadata["eulertop"]`` the generator writes into every
notebook it makes — the student it was made for, and its public answer list (names, kinds,
units, never values) — and the values its parameters cell holds (whose variant it is).

One reading of it, shared by ``eulertop check`` (:mod:`grader.check`, which refuses a notebook
without an answer list) and grading (:func:`grader.grade_one.record`, which grades such a
notebook all the same and says it is not this assignment's, another student's, or another
variant's). Only ever
*reported*: the metadata is in the student's hands; the grader takes the student from the file
name and the answers from the key.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

PARAMETERS_CELL = "parameters"
"""The id (and ``metadata["eulertop"]["role"]``) of the code cell holding a student's
parameters, ``q2_M = 1.5  # kg`` a line (:mod:`problems.notebook`)."""

MAX_PARAMETERS_SOURCE = 100_000
"""Longest parameters cell read, in characters (a generated one is a few kB): a longer one is
not parsed, and its notebook's parameters are not told."""

SHOWN_PARAMETERS = 3
"""Most parameters whose values :meth:`Identity.not_for` names; it counts the rest."""

SHOWN_CHARACTERS = 40
"""Longest value it shows, as its literal (longer ones are cut, ``…``)."""


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
    parameters: Mapping[str, Any] | None = None  # its parameters cell's values, if it has one

    def not_for(self, student_id: str, own: Mapping[str, Any] | None = None) -> str:
        """Why this is not ``student_id``'s notebook of this assignment, for their record;
        ``""`` when nothing says so. ``own``: the student's parameters by notebook variable
        (``q2_M``), as the manifest records them; given, a notebook whose parameters cell
        holds other values is named as another variant's."""
        if self.no_answer_list:
            return f"not this assignment's notebook: it {self.no_answer_list}"
        if self.student is not None and self.student != student_id:
            return f"another student's notebook: its metadata names student {self.student!r}"
        if own and self.parameters is not None:
            return other_variant(self.parameters, own)
        return ""


def other_variant(found: Mapping[str, Any], own: Mapping[str, Any]) -> str:
    """Why a notebook whose parameters cell holds ``found`` is not of the variant whose
    parameters are ``own`` (both by notebook variable); ``""`` when every one of ``own`` it
    holds has the same value and it holds at least one. Values are compared exactly: the
    generator writes each as the literal that reads back as the recorded value."""
    shared = [name for name in own if name in found]
    if not shared:
        if not found:
            return ""  # an emptied cell says nothing of whose it was
        return ("another variant's notebook: its parameters cell holds none of this "
                f"student's parameters ({', '.join(list(found)[:SHOWN_PARAMETERS])}"
                f"{', …' if len(found) > SHOWN_PARAMETERS else ''} instead)")
    differ = [name for name in shared if not _same(found[name], own[name])]
    if not differ:
        return ""
    named = "; ".join(f"{name} = {_shown(found[name])} where theirs is {_shown(own[name])}"
                      for name in differ[:SHOWN_PARAMETERS])
    more = len(differ) - SHOWN_PARAMETERS
    return (f"another variant's notebook: its parameters are not this student's ({named}"
            f"{f'; {more} more differ' if more > 0 else ''})")


def _shown(value: Any) -> str:
    """A value as its literal, cut to :data:`SHOWN_CHARACTERS` (a cell is the student's to
    fill with a long one)."""
    text = repr(value)
    return text if len(text) <= SHOWN_CHARACTERS else text[:SHOWN_CHARACTERS - 1] + "…"


def _same(a: Any, b: Any) -> bool:
    """Equal as the same JSON value: a bool is no number, a list holds the same in order."""
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    return a == b


def notebook_parameters(cells: Any) -> dict[str, Any] | None:
    """The values a notebook's parameters cell assigns (``q2_M = 1.5  # kg`` gives
    ``{"q2_M": 1.5}``): each top-level assignment of a literal to one name in the code cell
    the generator made (id, or metadata role, :data:`PARAMETERS_CELL`). None when the
    notebook has no such cell, or its source is too long or cannot be parsed; a line that
    computes its value is left out (only ever read, never run)."""
    if not isinstance(cells, list):
        return None
    for cell in cells:
        if isinstance(cell, Mapping) and cell.get("cell_type") == "code" and \
                (cell.get("id") == PARAMETERS_CELL or _role(cell) == PARAMETERS_CELL):
            return _assigned(cell.get("source"))
    return None


def _role(cell: Mapping) -> Any:
    metadata = cell.get("metadata")
    eulertop = metadata.get("eulertop") if isinstance(metadata, Mapping) else None
    return eulertop.get("role") if isinstance(eulertop, Mapping) else None


def _assigned(source: Any) -> dict[str, Any] | None:
    if isinstance(source, list) and all(isinstance(line, str) for line in source):
        source = "".join(source)
    if not isinstance(source, str) or len(source) > MAX_PARAMETERS_SOURCE:
        return None
    try:
        tree = ast.parse(source)
    except Exception:  # the student's text: whatever parsing it raises, it tells nothing
        return None
    found = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and \
                isinstance(node.targets[0], ast.Name):
            try:
                found[node.targets[0].id] = ast.literal_eval(node.value)
            except Exception:
                found.pop(node.targets[0].id, None)  # computed: its value is not read
    return found


def identity(data: bytes) -> Identity | None:
    """The :class:`Identity` of a submitted notebook's bytes; None when they cannot be parsed
    as a notebook at all (within the limits of :func:`grader.notebook_load.notebook_json`):
    the execution stage reports that."""
    from grader.notebook_load import notebook_json

    try:
        notebook = notebook_json(data)
        metadata, cells = notebook.get("metadata"), notebook.get("cells")
    except Exception:
        return None
    return identity_of(metadata, cells)


def identity_of(metadata: Any, cells: Any = None) -> Identity:
    """The :class:`Identity` a notebook's (parsed) ``metadata`` and ``cells`` give: what the
    execution stage reads from the notebook it has parsed already (a large notebook is not
    parsed a second time to tell whose it is)."""
    try:
        answer_list(metadata)
        why = ""
    except NoAnswerList as e:
        why = str(e)
    return Identity(named_student(metadata), why, notebook_parameters(cells))


def _valid_spec(spec: Mapping[str, Any]) -> bool:
    from problems.answers import ANSWER_KINDS

    variable = spec.get("variable")
    return (isinstance(variable, str) and variable.isidentifier()
            and spec.get("kind") in ANSWER_KINDS and isinstance(spec.get("name"), str))
