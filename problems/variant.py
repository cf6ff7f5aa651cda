"""One student's instance of one question: displayed parameters, statement and answers.

A family (:class:`problems.family.Family`) returns a :class:`Variant`. The generator turns it
into the student's notebook cells, the key's entries, and the *public* answer spec (names,
kinds, units, shapes — never values, never mistakes) that goes into the manifest and the
notebook metadata.
The answer variable of answer ``name`` in question ``k`` (1-based) is ``q{k}_{name}``.
"""

from __future__ import annotations

import keyword
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from problems.answers import WRITTEN, Answer


def variable_name(question: int, answer_name: str) -> str:
    """The notebook variable holding answer ``answer_name`` of question ``question`` (1-based).

    Examples
    --------
    >>> variable_name(3, "beta1")
    'q3_beta1'
    """
    return f"q{question}_{answer_name}"


def plain_number_tree(value: Any, what: str) -> float | list:
    """``value`` as plain JSON numbers: a finite float or (nested) lists of them.

    numpy scalars and arrays are converted; bools, strings, NaN and infinities are refused with
    a ``ValueError`` naming ``what`` (a template bug, reported before anything is written).
    """
    if type(value) is float and math.isfinite(value):  # the common case, first
        return value
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, list | tuple):
        return [plain_number_tree(v, what) for v in value]
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.number):
        raise ValueError(f"{what}: expected a number or a list of numbers, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{what}: must be finite, got {number!r}")
    return number


def _plain_parameter(value: Any, where: str, name: str) -> float | list:
    """:func:`plain_number_tree` of parameter ``name`` of ``where`` (the message only built
    for a value that is not already a finite float)."""
    if type(value) is float and math.isfinite(value):
        return value
    return plain_number_tree(value, f"{where}, parameter {name!r}")


def _python_name(name: str) -> bool:
    return isinstance(name, str) and name.isidentifier() and not keyword.iskeyword(name)


@dataclass(frozen=True)
class Variant:
    """One student's instance of one problem family.

    Attributes
    ----------
    family : str
        The template's ``NAME``.
    title : str
        The question's title (one line).
    params : dict of str to float
        The *displayed* (rounded) parameter values, SI units, by the Python name they get in the
        student's parameter cell (``"I1"``, ``"omega3"``, ``"β0"``). A value may also be a list
        of numbers (a position vector); numpy values are converted to plain floats.
    param_units : dict of str to str
        Unit of each parameter (``"kg m^2"``, ``"rad/s"``; absent or ``""``: dimensionless).
    statement : str
        Markdown with LaTeX; refers to the parameters by symbol.
    answers : tuple of Answer
        In the order the question asks for them; names unique within the question.
    parameters : dict of str to float, list or str
        Every parameter the family drew (:class:`problems.family.Family`): those of the cell,
        labels (a scene, a body) and numbers written only into the statement. The family
        recomputes ``statement`` and ``answers`` from them alone. Empty for a variant built
        without a family.

    Raises
    ------
    ValueError
        A parameter or answer name that is not a Python identifier, a duplicate answer name,
        a unit for an unknown parameter, a non-finite or non-numeric parameter.
    """

    family: str
    title: str
    params: dict[str, float]
    param_units: dict[str, str]
    statement: str
    answers: tuple[Answer, ...]
    parameters: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = f"variant of {self.family!r}"
        bad = [n for n in self.params if not _python_name(n)]
        if bad:
            raise ValueError(f"{where}: parameter names must be Python identifiers: {bad}")
        unknown = sorted(set(self.param_units) - set(self.params))
        if unknown:
            raise ValueError(f"{where}: units given for unknown parameters {unknown}")
        params = self.params.items()
        plain = {k: _plain_parameter(v, where, k) for k, v in params}
        object.__setattr__(self, "params", plain)
        object.__setattr__(self, "param_units", dict(self.param_units))
        object.__setattr__(self, "answers", tuple(self.answers))
        object.__setattr__(self, "parameters", {
            k: v if isinstance(v, str) else _plain_parameter(v, where, k)
            for k, v in self.parameters.items()})
        names = [a.name for a in self.answers]
        if not names:
            raise ValueError(f"{where}: no answers")
        bad = [n for n in names if not _python_name(variable_name(1, n))]
        if bad:
            raise ValueError(f"{where}: answer names must fit in a Python identifier: {bad}")
        if len(set(names)) != len(names):
            raise ValueError(f"{where}: duplicate answer names {names}")

    def answer(self, name: str) -> Answer:
        """The answer called ``name`` (``KeyError`` if there is none)."""
        for a in self.answers:
            if a.name == name:
                return a
        raise KeyError(f"{self.family}: no answer {name!r}")

    def to_dict(self) -> dict:
        """Plain JSON; ``Variant.from_dict(v.to_dict()) == v``."""
        return {
            "family": self.family,
            "title": self.title,
            "params": dict(self.params),
            "param_units": dict(self.param_units),
            "statement": self.statement,
            "answers": [a.to_dict() for a in self.answers],
            **({"parameters": dict(self.parameters)} if self.parameters else {}),
        }

    @classmethod
    def from_dict(cls, d: dict) -> Variant:
        """Inverse of :meth:`to_dict`."""
        return cls(
            family=d["family"],
            title=d["title"],
            params=dict(d["params"]),
            param_units=dict(d["param_units"]),
            statement=d["statement"],
            answers=tuple(Answer.from_dict(a) for a in d["answers"]),
            parameters=dict(d.get("parameters", {})),
        )

    def public_dict(self, question: int) -> dict:
        """What the student may see: everything but the answers' values and known mistakes.

        This is the manifest's record of the question and the notebook metadata's answer spec
        (``eulertop check`` validates the form of answers against it without the key).
        """
        return {
            "question": question,
            "family": self.family,
            "title": self.title,
            "params": dict(self.params),
            "param_units": dict(self.param_units),
            "statement": self.statement,
            "answers": [answer_spec(a, question) for a in self.answers],
            **({"parameters": dict(self.parameters)} if self.parameters else {}),
        }


def answer_spec(answer: Answer, question: int) -> dict:
    """The public description of one answer: how it must look, never what it is.

    Keys: ``variable``, ``name``, ``kind``, ``unit``, ``length`` (number of components of a
    vector answer, else None), ``options`` (choice), ``symbols`` (expression), ``period``
    (angle compared modulo it, else None), ``points``, ``description``; and for a written
    answer its ``prompt`` (its rubric stays in the key).
    """
    spec = {
        "variable": variable_name(question, answer.name),
        "name": answer.name,
        "kind": answer.kind,
        "unit": answer.unit,
        "length": len(answer.value) if answer.kind == "vector" else None,
        "options": list(answer.options),
        "symbols": list(answer.symbols),
        "period": answer.period,
        "points": answer.points,
        "description": answer.description,
    }
    if answer.kind == WRITTEN:
        spec["prompt"] = answer.value
    return spec
