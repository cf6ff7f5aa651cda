"""What an assignment spec changes in one question: parameters, points and tolerances.

A :class:`QuestionSettings` is applied by :meth:`problems.family.Family.generate` to every draw:
:meth:`~QuestionSettings.adjust_parameters` after the family's ``draw`` (a fixed value replaces
the drawn one, a range redraws it, a choice narrowed to some labels rejects the others), then
the family's ``answers`` on the adjusted parameters — which still reject an ill-posed result —
and :meth:`~QuestionSettings.adjust_answers` on the key (points, tolerances). The settings are
read from the spec by :mod:`problems.spec`, which checks them against the family first.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from problems.answers import Answer, Mistake, grade

if TYPE_CHECKING:
    from problems.family import Family


@dataclass(frozen=True)
class ParameterSetting:
    """One parameter as a spec sets it: a fixed ``value``, a range ``(low, high)`` to draw it
    in, or the ``choices`` (labels) it may take."""

    value: Any = None
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        """Plain JSON, for the manifest."""
        if self.value is not None:
            return {"value": self.value}
        if self.choices:
            return {"choices": list(self.choices)}
        return {"range": [self.low, self.high]}


@dataclass(frozen=True)
class AnswerSetting:
    """One answer's points and tolerances as a spec sets them (None: the family's)."""

    points: float | None = None
    rtol: float | None = None
    atol: float | None = None

    def to_dict(self) -> dict:
        return {k: v for k, v in (("points", self.points), ("rtol", self.rtol),
                                  ("atol", self.atol)) if v is not None}


@dataclass(frozen=True)
class QuestionSettings:
    """A question's total ``points`` (spread over its answers by their own weights), settings
    by answer name and by parameter name, and the family's written parts it asks for
    (``written``: True all, a tuple of their names, or none: :mod:`problems.written`)."""

    points: float | None = None
    answers: Mapping[str, AnswerSetting] = field(default_factory=dict)
    parameters: Mapping[str, ParameterSetting] = field(default_factory=dict)
    written: bool | tuple[str, ...] = False

    def to_dict(self) -> dict:
        """Plain JSON, for the manifest (:meth:`from_dict` reads it back); ``written`` only
        when set, so that a spec without it records what it did before."""
        d = {"points": self.points,
             "answers": {k: s.to_dict() for k, s in self.answers.items()},
             "parameters": {k: s.to_dict() for k, s in self.parameters.items()}}
        if self.written:
            d["written"] = True if self.written is True else list(self.written)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> QuestionSettings:
        """Inverse of :meth:`to_dict`."""
        parameters = {}
        for name, p in d.get("parameters", {}).items():
            low, high = p.get("range", (None, None))
            parameters[name] = ParameterSetting(p.get("value"), low, high,
                                                tuple(p.get("choices", ())))
        answers = {name: AnswerSetting(**a) for name, a in d.get("answers", {}).items()}
        written = d.get("written", False)
        return cls(d.get("points"), answers, parameters,
                   written if isinstance(written, bool) else tuple(written))

    def adjust_parameters(self, params: Mapping[str, Any], family: Family,
                          rng: np.random.Generator) -> dict[str, Any] | None:
        """``params`` with the set parameters applied; None when a label is not allowed.

        Settings apply in the family's declaration order. A number this draw does not have (a
        thickness, for a thin disc) is left out; a draw without a label the spec narrows (no
        ``box``, for point masses) is rejected, like one with another label.
        """
        declared = family.parameters
        params = dict(params)
        for name in (n for n in declared if n in self.parameters):
            setting, parameter = self.parameters[name], declared[name]
            if parameter.is_choice:
                allowed = (setting.value,) if setting.value is not None else setting.choices
                if params.get(name) not in allowed:
                    return None
            elif name not in params:
                continue
            elif setting.value is not None:
                params[name] = setting.value
            else:
                params[name] = parameter.draw(rng, setting.low, setting.high)
        return params

    def adjust_answers(self, answers: tuple[Answer, ...]) -> tuple[Answer, ...]:
        """The answers with their set tolerances and points, then the question's total spread
        over the answers whose points were not set, in proportion to their own."""
        answers = tuple(self._answer(a) for a in answers)
        if self.points is None:
            return answers
        fixed = {a.name for a in answers if self._setting(a.name).points is not None}
        weight = sum(a.points for a in answers if a.name not in fixed)
        rest = self.points - sum(a.points for a in answers if a.name in fixed)
        if weight <= 0:
            return answers
        return tuple(a if a.name in fixed else a.with_points(a.points * rest / weight)
                     for a in answers)

    def _setting(self, name: str) -> AnswerSetting:
        return self.answers.get(name, AnswerSetting())

    def _answer(self, answer: Answer) -> Answer:
        setting = self._setting(answer.name)
        if setting == AnswerSetting():
            return answer
        if setting.points is not None:  # a written answer's rubric scaled with them
            answer = answer.with_points(setting.points)
        changes = {k: v for k, v in (("rtol", setting.rtol), ("atol", setting.atol))
                   if v is not None}
        bare = replace(answer, mistakes=(), **changes)
        return replace(bare, mistakes=still_wrong(bare, answer.mistakes))


def still_wrong(answer: Answer, mistakes: tuple[Mistake, ...]) -> tuple[Mistake, ...]:
    """The ``mistakes`` whose values ``answer`` (with its tolerances) grades wrong: a widened
    tolerance turns a close mistake into a right answer, and its feedback would never show."""
    return tuple(m for m in mistakes if grade(answer, m.value).status == "wrong")
