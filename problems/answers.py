"""Answer kinds, and how a submitted value is compared with the key.

This is the contract between the generator (which writes :class:`Answer` records into
``key.json``), the grader (which extracts each answer variable from the executed notebook as
plain JSON and asks :func:`grade`) and ``eulertop check`` (which asks :func:`check_form`, or
:func:`check_spec` when it only has the public answer spec of the notebook's metadata).

As in PrairieLearn, reading a value is kept apart from judging it: a value that is missing or
malformed (a string where a number is due, NaN, a list of the wrong length, an unknown symbol)
is ``"missing"`` or ``"invalid"`` with a message saying what is wrong with its *form*; only a
well-formed value is compared with the key, and is then ``"correct"`` or ``"wrong"``. A wrong
value is compared with each known :class:`Mistake`; when one matches, the student gets that
mistake's feedback. Messages never contain the key's value.

Kinds and their comparison (``v`` the key, ``x`` the submission)
-----------------------------------------------------------------
``scalar``
    A real number (int, float, numpy or sympy number; *not* a bool, *not* a string).
    Correct when ``|x − v| ≤ atol + rtol·|v|``.
``angle``
    A real number, in radians; as ``scalar`` but, when ``period`` is set, the difference is
    first wrapped into ``(−period/2, period/2]`` (so 2π − 0.001 matches 0.001 modulo 2π).
``vector``
    A flat list (tuple, numpy array, sympy row or column matrix) of exactly ``len(v)`` real
    numbers. Norm-based: correct when ``‖x − v‖₂ ≤ atol + rtol·‖v‖₂``. Chosen over a
    component-wise test so that a component that is zero in the key (a body axis at rest)
    does not demand an exact zero from a student's floating-point computation.
``boolean``
    ``True`` or ``False`` (also numpy and sympy booleans). The numbers 0 and 1 and the strings
    ``"True"``/``"False"`` are *invalid*: the question asks for a boolean, and accepting ``1``
    would make a numerical answer typed into the wrong variable look like a yes.
``choice``
    One of ``options``, compared case-insensitively with surrounding spaces removed.
    Anything else is invalid, and the message lists the options.
``written``
    A derivation or an explanation the student writes in a Markdown cell of the notebook
    (issue 31), graded by a person against the answer's ``rubric``: the key's ``value`` is the
    prompt (Markdown), the submission the cell's text (``{"text": …}``, as the grader reads it
    from the notebook file, or the text itself). :func:`grade` never judges it: an answer with
    text is ``pending`` (0 of its points) until a review gives it points (``reviewed``,
    :mod:`grader.reviews`); an empty cell is ``missing``.
``expression``
    A formula in the answer's ``symbols``: a string, or in-process a sympy expression (graded
    through its ``str``). Read safely by :mod:`problems.expressions` (never executed). Graded by
    evaluating both expressions at sample points drawn reproducibly from the answer's name and
    symbols (:func:`problems.expressions.sample_points`), keeping the points where the key is
    defined: correct when ``|x − v| ≤ atol + rtol·|v|`` at every point. An expression that is
    undefined (division by zero, overflow, complex value) at every point is invalid.

A key of exactly zero (norm zero, or an expression zero at every sample point) needs
``atol > 0``: with a relative tolerance alone only an exact zero would match, which a student's
floating-point computation rarely produces. :class:`Answer` refuses such a record.
"""

from __future__ import annotations

import math
import numbers
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import asdict, dataclass, fields, replace
from functools import cache, lru_cache, partial
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from eulertop_base import ParameterError
from problems.expressions import (
    ExpressionError,
    check_symbol_names,
    evaluate_expression,
    parse_expression,
    sample_points,
)

if TYPE_CHECKING:
    import sympy

__all__ = [
    "ANSWER_KINDS",
    "KINDS",
    "STATUSES",
    "WRITTEN",
    "Answer",
    "Mistake",
    "RubricItem",
    "Verdict",
    "check_form",
    "check_spec",
    "comparison_rule",
    "grade",
    "kind_hint",
    "numbers_of",
    "read_value",
]

KINDS = ("scalar", "vector", "angle", "boolean", "choice", "expression")
"""The kinds compared with a key."""
STATUSES = ("correct", "follows", "wrong", "invalid", "missing", "pending", "reviewed")
"""``follows``: wrong against the key, right against what the student's own earlier answers
give (follow-through credit, :mod:`grader.follow_through`); the grader sets it, never
:func:`grade`. ``pending``: a written answer not reviewed yet (0 of its points); ``reviewed``:
one a person scored by its rubric (:mod:`grader.reviews`)."""

WRITTEN = "written"
"""The kind of an answer written in Markdown and scored by a person against a rubric."""

ANSWER_KINDS = (*KINDS, WRITTEN)
"""Every kind an :class:`Answer` may have."""

MAX_RUBRIC_ITEMS = 9
"""Items a rubric holds at most (one per key 1–9 of the review desk)."""

POINTS_SUM_TOLERANCE = 1e-9
"""Relative difference allowed between a written answer's points and its rubric's sum (what
scaling the points by a spec's settings leaves)."""

N_SAMPLE_CANDIDATES = 32
"""Sample points drawn for an expression answer (those where the key is undefined are dropped)."""

MIN_SAMPLE_POINTS = 8
"""Fewest sample points at which an expression key must be defined."""


@dataclass(frozen=True)
class Mistake:
    """A known mistake the grader recognises.

    Attributes
    ----------
    name : str
        Short id, e.g. ``"degrees"``, ``"I1_I3_swapped"``, ``"missing_factor_2"``; it is
        recorded in the verdict's ``mistake``.
    value : Any
        The value a student making this mistake gets, of the answer's kind (normalised to plain
        JSON by the :class:`Answer` that holds it).
    feedback : str
        What the student is told when their value matches this one.
    """

    name: str
    value: Any
    feedback: str

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ParameterError("mistakes", f"a mistake needs a non-empty name, got {self.name!r}")
        if not isinstance(self.feedback, str) or not self.feedback.strip():
            raise ParameterError("mistakes", f"mistake {self.name!r} needs a feedback text")


@dataclass(frozen=True)
class RubricItem:
    """One item of a written answer's rubric: what earns it, and its points (≥ 0)."""

    item: str
    points: float

    def __post_init__(self) -> None:
        if not isinstance(self.item, str) or not self.item.strip():
            raise ParameterError("rubric", f"an item needs its text, got {self.item!r}")
        points = self.points
        if isinstance(points, bool) or not isinstance(points, numbers.Real) \
                or not math.isfinite(points) or points < 0:
            raise ParameterError("rubric", f"item {self.item!r}: points must be a number ≥ 0, "
                                 f"got {points!r}")
        object.__setattr__(self, "points", float(points))

    def to_dict(self) -> dict:
        return {"item": self.item, "points": self.points}


def rubric_items(items: Any) -> tuple[RubricItem, ...]:
    """``items`` — RubricItems, ``{"item", "points"}`` dicts or ``(item, points)`` pairs — as
    RubricItems; ParameterError naming the one that is none of these."""
    read = []
    for item in items:
        if isinstance(item, RubricItem):
            read.append(item)
        elif isinstance(item, Mapping) and set(item) == {"item", "points"}:
            read.append(RubricItem(item["item"], item["points"]))
        elif isinstance(item, tuple | list) and len(item) == 2:
            read.append(RubricItem(*item))
        else:
            raise ParameterError("rubric", f"an item is {{'item': text, 'points': number}}, "
                                 f"got {item!r}")
    return tuple(read)


@dataclass(frozen=True)
class Answer:
    """One answer of a question: the key value, its kind, and how it is compared.

    Attributes
    ----------
    name : str
        Variable suffix: the notebook variable is ``f"q{question}_{name}"``.
    kind : str
        One of :data:`KINDS` (see the module docstring for each kind's comparison).
    value : Any
        The key, normalised to plain JSON: ``float`` (scalar, angle), ``list[float]`` (vector),
        ``bool`` (boolean), ``str`` (choice: the option as spelled in ``options``; expression:
        its text). numpy and sympy values are converted on construction.
    unit : str
        SI unit, e.g. ``"rad"``, ``"rad/s"``, ``"kg m^2"``; ``""`` if dimensionless.
    rtol, atol : float
        Relative and absolute tolerance (≥ 0; ``atol`` in ``unit``).
    points : float
        Points for a correct answer (≥ 0).
    mistakes : tuple of Mistake
        Known mistakes; each value must be of the answer's kind and *distinguishable* from the
        key (not within tolerance of it).
    options : tuple of str
        ``choice`` only: the allowed strings (distinct ignoring case and surrounding spaces).
    symbols : tuple of str
        ``expression`` only: the symbol names the expression may use.
    period : float or None
        ``angle`` only: compare modulo this (e.g. 2π) when set.
    description : str
        One line shown next to the answer variable.
    accepted : tuple
        Other values accepted as correct, compared under the same rule (an instructor's key
        change, ``eulertop key set --accept``: another sign convention, say); of the answer's
        kind and form, as ``value``.
    depends_on : tuple of str
        Names of earlier answers of the same question this one is computed from (the statement
        asks for it from them): a wrong value that follows from the student's own earlier
        answers earns follow-through credit (:mod:`grader.follow_through`).
    rubric : tuple of RubricItem
        ``written`` only (and required there): what a reviewer gives points for, at most
        :data:`MAX_RUBRIC_ITEMS` items, whose points add up to ``points``.

    ``accepted``, ``depends_on`` and ``rubric`` are written to the key file only when set, so a
    key without them reads, and hashes, as before.

    Raises
    ------
    eulertop_base.ParameterError
        A ``ValueError`` naming the field at fault: unknown kind, negative tolerance, a value not
        of the kind's form, a zero key without ``atol``, options or symbols missing or given to
        the wrong kind, a mistake indistinguishable from the key.
    """

    name: str
    kind: str
    value: Any
    unit: str = ""
    rtol: float = 1e-3
    atol: float = 0.0
    points: float = 1.0
    mistakes: tuple[Mistake, ...] = ()
    options: tuple[str, ...] = ()
    symbols: tuple[str, ...] = ()
    period: float | None = None
    description: str = ""
    accepted: tuple[Any, ...] = ()
    depends_on: tuple[str, ...] = ()
    rubric: tuple[RubricItem, ...] = ()

    def __post_init__(self) -> None:
        _validate_fields(self)
        if self.kind == WRITTEN:
            _validate_written(self)
            return
        decided_by = _decided_by(self) if self.kind in _COMPARED_AS_VALUES else None
        checked = _CHECKED.get(decided_by) if decided_by is not None else None
        if checked is not None:
            _take_checked(self, checked)
            return
        self._check_and_normalise()
        if decided_by is not None:
            _keep(_CHECKED, decided_by,
                  (self.value, self.accepted, tuple(m.value for m in self.mistakes)))

    def _check_and_normalise(self) -> None:
        """Every value read and checked (the key gradable, each mistake apart from it), and
        kept as plain JSON."""
        form = _Form.of(self, reading_key=True)
        key = _read_key(form, self.value, "value")
        object.__setattr__(self, "value", _to_json(key))
        _require_gradable_key(self)
        if self.kind in ("vector", "expression"):  # the graded form knows the key: its length,
            form = _Form.of(self)  # the points where it is defined
        if type(self.accepted) is not tuple or self.accepted:  # () as it is: most answers
            object.__setattr__(self, "accepted", tuple(
                _to_json(_read_key(form, v, "accepted")) for v in self.accepted))
        _check_depends_on(self)
        # each mistake read in the graded form, against the key read once
        near_key = _near(self, key)
        mistakes = tuple(_checked_mistake(self, m, form, near_key) for m in self.mistakes)
        object.__setattr__(self, "mistakes", mistakes)
        _check_mistake_names(self)

    def mistake(self, name: str) -> Mistake | None:
        """The known mistake called ``name``, or None if this answer does not list it."""
        return next((m for m in self.mistakes if m.name == name), None)

    def to_dict(self, *, copy: bool = True) -> dict:
        """Plain JSON (lists for tuples); ``Answer.from_dict(a.to_dict()) == a``.

        ``copy=False`` leaves the values (key, mistakes', accepted) the answer's own, for a
        caller that only encodes the dict at once (the generator's key entries)."""
        # field by field in their order (the key file's bytes and hashes follow it), not
        # asdict, which deep-copies through every dataclass; values are plain JSON already,
        # lists copied so that the dict shares none with the answer
        own = _json_copy if copy else _same
        d = {"name": self.name, "kind": self.kind, "value": own(self.value),
             "unit": self.unit, "rtol": self.rtol, "atol": self.atol, "points": self.points,
             "mistakes": [{"name": m.name, "value": own(m.value), "feedback": m.feedback}
                          for m in self.mistakes],
             "options": list(self.options), "symbols": list(self.symbols),
             "period": self.period, "description": self.description}
        if self.accepted:  # the last three only when set: older keys hash as before
            d["accepted"] = [own(v) for v in self.accepted]
        if self.depends_on:
            d["depends_on"] = list(self.depends_on)
        if self.rubric:
            d["rubric"] = [r.to_dict() for r in self.rubric]
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Answer:
        """Inverse of :meth:`to_dict`; unknown keys are an error (a key file from elsewhere)."""
        d = _known_keys(cls, d, "answer")
        d["mistakes"] = tuple(Mistake(**_known_keys(Mistake, m, "mistake"))
                              for m in d.get("mistakes", ()))
        d["rubric"] = rubric_items(d.get("rubric", ()))
        return cls(**d)

    def following(self, *names: str) -> Answer:
        """This answer declared as computed from the earlier answers ``names``
        (``depends_on``). Only the names are checked again: the rest of a valid answer stays
        valid (``replace`` would read and regrade every value)."""
        copy = _unchecked(self, depends_on=names)
        _check_depends_on(copy)
        return copy

    def with_points(self, points: float) -> Answer:
        """This answer worth ``points``: a written one's rubric scaled to add up to them."""
        if self.kind != WRITTEN or self.points == points:
            return replace(self, points=points)
        scale = points / self.points if self.points else 0.0
        rubric = tuple(RubricItem(r.item, r.points * scale) for r in self.rubric)
        return replace(self, points=points, rubric=rubric)


def _same(value: Any) -> Any:
    """``value`` itself (:meth:`Answer.to_dict` without copies)."""
    return value


def _json_copy(value: Any) -> Any:
    """A copy of plain JSON ``value`` sharing no list or dict with it (tuples stay tuples)."""
    if isinstance(value, list):
        return [v if type(v) is float else _json_copy(v) for v in value]
    if isinstance(value, tuple):
        return tuple(_json_copy(v) for v in value)
    if isinstance(value, dict):
        return {k: _json_copy(v) for k, v in value.items()}
    return value


@dataclass(frozen=True)
class Verdict:
    """The outcome of reading (and grading) one submitted answer.

    Attributes
    ----------
    status : str
        One of :data:`STATUSES`. From :func:`check_form`, ``"correct"`` means *well formed*.
    points : float
        Points awarded (``max_points`` when correct, else 0; always 0 from :func:`check_form`).
    max_points : float
        The answer's points.
    message : str
        For the student: what was read, or what is wrong with its form. Never the key.
    mistake : str or None
        :attr:`Mistake.name` when a known mistake was recognised.
    """

    status: str
    points: float
    max_points: float
    message: str
    mistake: str | None = None

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ParameterError("status", f"must be one of {STATUSES}, got {self.status!r}")
        for field in ("points", "max_points"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise ParameterError(field, f"must be a number, got {value!r}")
            object.__setattr__(self, field, float(value))
        if not 0.0 <= self.points <= self.max_points:
            raise ParameterError("points", f"must lie in [0, {self.max_points}], got {self.points}")
        if not isinstance(self.message, str):
            raise ParameterError("message", f"must be a string, got {self.message!r}")
        if self.mistake is not None and not isinstance(self.mistake, str):
            raise ParameterError("mistake", f"must be a string or None, got {self.mistake!r}")

    def to_dict(self) -> dict:
        """Plain JSON; ``Verdict.from_dict(v.to_dict()) == v``."""
        return asdict(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Verdict:
        """Inverse of :meth:`to_dict`."""
        return cls(**_known_keys(cls, d, "verdict"))


# --------------------------------------------------------------------------------------------
# The public entry points


def check_form(answer: Answer, submitted: Any) -> Verdict:
    """Is ``submitted`` present and well formed for ``answer``? Never says right or wrong.

    Parameters
    ----------
    answer : Answer
        The answer the value is for (only its form is used: kind, length, options, symbols).
    submitted : Any
        The extracted value; ``None`` when the variable is missing or still ``None``.

    Returns
    -------
    Verdict
        ``"missing"``, ``"invalid"`` (the message says why), or ``"correct"`` meaning *well
        formed* (the message echoes what was read). ``points`` is always 0: nothing is graded.

    Examples
    --------
    >>> a = Answer("beta1", "angle", 0.7, unit="rad")
    >>> check_form(a, "0.7").message
    "the string '0.7', not a number — remove the quotes"
    >>> check_form(a, 12.0).status      # well formed, even though wrong
    'correct'
    """
    return _check(_Form.of(answer), submitted)


def check_spec(spec: Mapping[str, Any], submitted: Any) -> Verdict:
    """:func:`check_form` from the *public* answer spec, for ``eulertop check`` without the key.

    ``spec`` is :func:`problems.variant.answer_spec`'s dict: ``name``, ``kind``, ``unit``,
    ``length`` (vectors), ``options``, ``symbols``, ``points``. Expressions are tried at sample
    points drawn from the name and symbols alone, so one defined at none of them is invalid.
    """
    return _check(_Form.of_spec(spec), submitted)


_KIND_HINTS = {
    "scalar": "a number",
    "angle": "an angle (a number)",
    "boolean": "True or False",
    WRITTEN: "Markdown in its answer cell",
}

def kind_hint(spec: Mapping[str, Any]) -> str:
    """How an answer must look, in words, from its public spec (``a list of 3 numbers``): the
    generated answer lines and ``eulertop check`` say it alike."""
    kind = spec["kind"]
    if kind == "vector":
        return f"a list of {spec['length']} numbers"
    if kind == "choice":
        return "one of " + ", ".join(f'"{o}"' for o in spec["options"])
    if kind == "expression":
        return "an expression in " + ", ".join(spec["symbols"])
    return _KIND_HINTS.get(kind, kind)


def grade(answer: Answer, submitted: Any) -> Verdict:
    """Grade ``submitted`` against ``answer``: missing, invalid, correct, or wrong.

    A missing or malformed value is reported exactly as by :func:`check_form`. A well-formed
    value is compared with the key under the kind's rule (module docstring); if it is not
    within tolerance, each known mistake is tried with the same rule, and the first that matches
    gives the feedback and ``mistake``.

    Examples
    --------
    >>> a = Answer("omega", "scalar", 2.5, unit="rad/s", rtol=1e-2,
    ...            mistakes=(Mistake("rpm", 23.87, "rad/s, not rpm"),))
    >>> grade(a, 2.51).status, grade(a, 2.51).points
    ('correct', 1.0)
    >>> grade(a, 23.9).mistake
    'rpm'
    >>> grade(a, None).status
    'missing'
    """
    form = _Form.of(answer)
    value, unreadable = _reading(form, submitted)
    if unreadable:
        return unreadable
    if answer.kind == WRITTEN:  # a person scores it (grader.reviews)
        return _verdict(form, "pending", PENDING)
    for key in (answer.value, *answer.accepted):
        if _matches(answer, value, _read_key(form, key, "value")):
            return Verdict("correct", answer.points, answer.points,
                           f"correct: {_show(form, value)}")
    for mistake in answer.mistakes:
        if _matches(answer, value, _read_key(form, mistake.value, "mistakes")):
            return _verdict(form, "wrong", mistake.feedback, mistake=mistake.name)
    rounded = rounded_too_far(answer, value)
    if rounded is not None:
        return _verdict(form, "wrong", f"{_show(form, value)}: {rounded}", mistake=TOO_FEW_FIGURES)
    return _verdict(form, "wrong", f"{_show(form, value)}: {_not_within(answer)}")


PENDING = "not reviewed yet: a person scores it by its rubric"
"""The message of a written answer's ``pending`` verdict."""


def read_value(answer: Answer, value: Any) -> Any:
    """``value`` in ``answer``'s normal form — a float (scalar, angle), a numpy array
    (vector), a bool, the option as ``options`` spells it, the expression's text — or None
    when it is not well formed for ``answer`` (:func:`check_form` says why)."""
    read, unreadable = _reading(_Form.of(answer), value)
    return None if unreadable else read


def numbers_of(answer: Answer, value: Any) -> NDArray[np.float64] | None:
    """``value`` as the numbers ``answer``'s comparison looks at: a scalar or an angle as one
    number, a vector as its components, an expression as its values at the answer's sample
    points (those where the key is defined; NaN where the value is not). None for a boolean,
    a choice, or a value not well formed.

    Examples
    --------
    >>> numbers_of(Answer("L", "vector", [1.0, 2.0, 2.0]), (0, 0, 3)).tolist()
    [0.0, 0.0, 3.0]
    >>> numbers_of(Answer("up", "boolean", True), True) is None
    True
    """
    if answer.kind in ("boolean", "choice", WRITTEN):
        return None
    form = _Form.of(answer)
    read, unreadable = _reading(form, value)
    if unreadable:
        return None
    if answer.kind != "expression":
        return np.atleast_1d(np.asarray(read, dtype=float))
    return np.array(_values(read, form.symbols, form.where))


TOO_FEW_FIGURES = "too_few_figures"
"""The ``mistake`` of a verdict on a value that is the key rounded to too few figures."""

MAX_ROUNDED_FIGURES = 6
"""Most significant figures (or decimals + 1) tried when recognising a rounded answer."""


def rounded_too_far(answer: Answer, value: Any) -> str | None:
    """Feedback when a wrong ``value`` is the key rounded (or cut) to too few figures, else None.

    Recognised for scalars, angles and vectors when every number of ``value`` has at most ``n``
    significant figures, ``n ≥ 2`` (or, for a vector, ``d ≥ 1`` decimals), and is what
    rounding the key to them gives (within half a unit of the last figure) or cutting it
    (towards zero, within one unit). The message says so, and how many
    figures the tolerance needs (from the key's magnitude and the tolerance only).
    """
    if answer.kind not in ("scalar", "angle", "vector"):
        return None
    x = np.atleast_1d(np.asarray(value, dtype=float))
    v = np.atleast_1d(np.asarray(answer.value, dtype=float))
    if x.shape != v.shape or not np.all(np.isfinite(x)):
        return None
    need = _figures_needed(answer, v) + 1  # one more than rounding alone needs: working errs too
    for n in range(2, MAX_ROUNDED_FIGURES + 1):  # one figure: any small integer would match
        if _all_rounded(x, v, partial(_sig_unit, n=n)):
            return (f"not correct: it looks rounded to {_count(n, 'significant figure')}, too "
                    f"few for the tolerance ({comparison_rule(answer)}); keep at least {need} "
                    "figures — round only the value you write, never the working")
    for d in range(1, MAX_ROUNDED_FIGURES):
        if x.size > 1 and _all_rounded(x, v, partial(_decimal_unit, d=d)):
            return (f"not correct: its components look rounded to {_count(d, 'decimal')}, too "
                    f"few for the tolerance ({comparison_rule(answer)}); keep at least {need} "
                    "significant figures")
    return None


def _sig_unit(c: float, n: int) -> float:
    """One unit in the ``n``-th significant figure of ``c`` (0 for ``c == 0``)."""
    return 0.0 if c == 0 else 10.0 ** (math.floor(math.log10(abs(c))) - n + 1)


def _decimal_unit(c: float, d: int) -> float:
    """One unit in the ``d``-th decimal (whatever ``c``)."""
    return 10.0 ** -d


def _all_rounded(x: NDArray, v: NDArray, unit: Callable[[float], float]) -> bool:
    """Every ``x_i`` is a multiple of ``unit(v_i)`` within one such unit of ``v_i``."""
    for xi, vi in zip(x, v, strict=True):
        u = unit(vi)
        if u == 0.0:
            if xi != 0.0:
                return False
            continue
        steps = xi / u
        if abs(steps - round(steps)) > 1e-6:
            return False  # more figures than that
        rounded = abs(xi - vi) <= 0.5 * u * (1 + 1e-6)
        cut = abs(xi) <= abs(vi) and xi * vi >= 0 and abs(xi - vi) < u
        if not (rounded or cut):
            return False
    return True


def _figures_needed(answer: Answer, v: NDArray) -> int:
    """Fewest significant figures whose rounding error (half a unit) fits the tolerance."""
    scale = float(np.linalg.norm(v)) if answer.kind == "vector" else float(abs(v[0]))
    tolerance = answer.atol + answer.rtol * scale
    biggest = float(np.max(np.abs(v)))
    for n in range(1, 17):
        if 0.5 * _sig_unit(biggest, n) * (math.sqrt(v.size)) <= tolerance:
            return n
    return 17


def comparison_rule(answer: Answer) -> str:
    """How ``answer`` is compared, in words for the student, from its own kind and tolerances.

    Nothing of the key is in it (only ``rtol``, ``atol``, ``unit``, ``period`` and the kind).
    A percentage is relative (the notebook's conventions say so once), an amount with a unit
    absolute.

    Examples
    --------
    >>> comparison_rule(Answer("T", "scalar", 2.0, unit="J"))
    'within 0.1 %'
    >>> comparison_rule(Answer("w", "scalar", 2.0, unit="rad/s", atol=0.005))
    'within 0.1 % + 0.005 rad/s'
    >>> comparison_rule(Answer("L", "vector", [1.0, 2.0]))
    'within 0.1 % of its length'
    >>> comparison_rule(Answer("b", "angle", 1.0, unit="rad"))
    'in radians, within 0.1 %, not modulo 2π'
    >>> comparison_rule(Answer("b", "angle", 1.0, unit="rad", period=2 * math.pi))
    'in radians, within 0.1 %, modulo 2π'
    """
    kind = answer.kind
    if kind == WRITTEN:
        return "by a person, against a rubric"
    if kind == "boolean":
        return "True or False, exactly"
    if kind == "choice":
        return "one of the options, exactly"
    relative = _percent(answer.rtol) if answer.rtol else ""
    absolute = ""
    if answer.atol:
        unit = f" {answer.unit}" if answer.unit else " (absolute)"
        absolute = f"{answer.atol:.3g}{unit}"
    within = "within " + " + ".join(part for part in (relative, absolute) if part)
    if kind == "vector":
        return within.replace(" %", " % of its length", 1) if relative else f"{within} in length"
    if kind == "expression":
        return f"at random values of its symbols, {within}"
    if kind == "angle":
        if answer.period is None:
            return f"in radians, {within}, not modulo 2π"
        period = "2π" if math.isclose(answer.period, 2 * math.pi) else f"{answer.period:.6g}"
        return f"in radians, {within}, modulo {period}"
    return within


def _percent(rtol: float) -> str:
    """``0.001`` → ``'0.1 %'``; ``1e-6`` → ``'0.0001 %'``."""
    return f"{rtol * 100:.3g} %"


# --------------------------------------------------------------------------------------------
# The form of an answer: everything needed to read a value, nothing of the key


class _Form(NamedTuple):
    name: str
    kind: str
    unit: str
    points: float
    length: int | None  # vector
    options: tuple[str, ...]  # choice
    symbols: tuple[str, ...]  # expression
    where: tuple | None  # expression: where to try it (_sample)

    @classmethod
    def of(cls, answer: Answer, reading_key: bool = False) -> _Form:
        """The form of ``answer``; ``reading_key`` while its key is not read yet (no length, and
        expressions tried at every candidate point, not only where the key is defined)."""
        length = len(answer.value) if answer.kind == "vector" and not reading_key else None
        where = None
        if answer.kind == "expression":
            where = (answer.name,) if reading_key else _at_key(answer)
        return cls(answer.name, answer.kind, answer.unit, answer.points, length,
                   answer.options, answer.symbols, where)

    @classmethod
    def of_spec(cls, spec: Mapping[str, Any]) -> _Form:
        kind, name = spec.get("kind"), spec.get("name", "")
        if kind not in ANSWER_KINDS:
            raise ParameterError("kind", f"must be one of {ANSWER_KINDS}, got {kind!r}")
        symbols = tuple(spec.get("symbols") or ())
        where = (name,) if kind == "expression" else None
        return cls(name, kind, spec.get("unit", ""), float(spec.get("points", 1.0)),
                   spec.get("length"), tuple(spec.get("options") or ()), symbols, where)


class _Missing(Exception):
    """No value was submitted."""


class _Invalid(Exception):
    """The submitted value is malformed; the message says why, for the student."""


_MISSING = "no answer: the variable is missing or still None"


def _reading(form: _Form, submitted: Any) -> tuple[Any, Verdict | None]:
    """(value in normal form, None), or (None, the missing/invalid verdict)."""
    try:
        return _read(form, submitted), None
    except _Missing:
        return None, _verdict(form, "missing", _EMPTY_CELL if form.kind == WRITTEN else _MISSING)
    except _Invalid as err:
        return None, _verdict(form, "invalid", str(err))


def _check(form: _Form, submitted: Any) -> Verdict:
    value, unreadable = _reading(form, submitted)
    return unreadable or _verdict(form, "correct", f"well formed: {_show(form, value)}")


def _verdict(form: _Form, status: str, message: str, mistake: str | None = None) -> Verdict:
    return Verdict(status, 0.0, form.points, message, mistake)


def _read(form: _Form, submitted: Any) -> Any:
    """The submitted value in the kind's normal form, or raise _Missing / _Invalid."""
    if submitted is None:
        raise _Missing
    try:
        return _READERS[form.kind](_plain(submitted), form)
    except (_Invalid, _Missing):
        raise
    except Exception as err:  # fail closed: a value nobody foresaw is invalid, not a crash
        raise _Invalid(f"the value could not be read ({type(err).__name__})") from None


def _read_key(form: _Form, value: Any, field: str) -> Any:
    """Read a value written by the template (key or mistake): malformed is a template bug."""
    if type(value) is float and form.kind in _NUMBER_KINDS and math.isfinite(value):
        return value  # what _read gives, without its calls: most of a key
    if form.kind == "vector" and _finite_floats(value, form.length):
        return np.array(value)  # what _read gives (_read_vector), without its calls
    try:
        return _read(form, value)
    except (_Missing, _Invalid) as err:
        message = str(err) or "no value (None)"
        raise ParameterError(field, f"answer {form.name!r}: {message}") from None


# --------------------------------------------------------------------------------------------
# Readers: plain value -> normal form of the kind


_PLAIN = frozenset({float, int, bool, str, list, dict})
"""Types :func:`_plain` gives back as they are (no numpy or sympy object is one of them)."""


def _plain(x: Any) -> Any:
    """numpy and sympy objects as plain Python, one level deep (elements are read one by one)."""
    if type(x) in _PLAIN:  # the common cases first
        return x
    if isinstance(x, np.ndarray):
        return x.tolist() if x.ndim else x.item()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, tuple):
        return list(x)
    sympy = sys.modules.get("sympy")
    if sympy is None:
        return x
    if isinstance(x, sympy.MatrixBase):
        return list(x) if 1 in x.shape else x.tolist()  # a row or column vector is flat
    if isinstance(x, sympy.logic.boolalg.BooleanAtom):
        return bool(x)
    if isinstance(x, sympy.Expr) and x.is_number:
        return _sympy_number(x)
    return x


def _sympy_class(name: str) -> type | tuple[()]:
    """``sympy.<name>`` if sympy is loaded, else ``()`` (``isinstance(x, ())`` is False).

    A value can only be a sympy object once sympy has been imported, so reading and judging
    values never imports it: ``eulertop check`` of a notebook of numbers does without sympy's
    start-up (most of a second). Expressions import it where they are parsed
    (:mod:`problems.expressions`).
    """
    sympy = sys.modules.get("sympy")
    return () if sympy is None else getattr(sympy, name)


def _sympy_number(x: sympy.Expr) -> float | complex | sympy.Expr:
    try:
        return float(x)
    except (TypeError, ValueError):
        try:
            return complex(x)
        except (TypeError, ValueError):
            return x


def _quote(text: str, limit: int = 30) -> str:
    return repr(text if len(text) <= limit else text[: limit - 1] + "…")


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"


def _describe(x: Any) -> str:
    """A short, student-facing description of a value that is not of the expected form."""
    if isinstance(x, bool):
        return f"{x}, a boolean"
    if isinstance(x, str):
        return f"the string {_quote(x)}"
    if isinstance(x, numbers.Integral) and abs(x) > 10**15:
        return "a very large integer"
    if isinstance(x, numbers.Real):
        return f"the number {float(x):.6g}"
    if isinstance(x, complex):
        return f"the complex number {x:.4g}"
    if isinstance(x, list):
        nested = any(isinstance(_plain(e), list) for e in x)
        return f"a {'nested ' if nested else ''}list of {_count(len(x), 'element')}"
    if isinstance(x, _sympy_class("Basic")):
        return f"the sympy object {_quote(str(x))}"
    return f"a value of type {type(x).__name__}"


def _number(x: Any, what: str = "", unit: str = "") -> float:
    """A finite real number, or _Invalid with a message about ``what`` ("component 2"; empty
    for the value itself, so that the message starts with the description of the value)."""
    x = _plain(x)
    subject = f"{what} is " if what else ""
    if type(x) is float and math.isfinite(x):  # the common case, without the checks below
        return x
    if isinstance(x, numbers.Real) and not isinstance(x, bool):
        try:
            value = float(x)
        except OverflowError:
            raise _Invalid(f"{subject}a number too large for a float") from None
        if math.isnan(value):
            raise _Invalid(f"{subject}NaN (not a number); check the computation")
        if math.isinf(value):
            raise _Invalid(f"{subject}infinite; check the computation")
        return value
    in_unit = f" (in {unit})" if unit else ""
    if isinstance(x, str) and _numeric_string(x):
        raise _Invalid(f"{subject}{_describe(x)}, not a number — remove the quotes")
    if isinstance(x, _sympy_class("Expr")) and x.free_symbols:
        names = ", ".join(sorted(map(str, x.free_symbols)))
        raise _Invalid(f"{subject}an expression in {names}; a number{in_unit} is expected")
    if isinstance(x, complex):
        raise _Invalid(f"{subject}{_describe(x)}; a real number{in_unit} is expected")
    raise _Invalid(f"{subject}{_describe(x)}, not a number{in_unit}")


def _numeric_string(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_scalar(x: Any, form: _Form) -> float:
    if isinstance(x, list):
        raise _Invalid(f"{_describe(x)}; a single number is expected")
    return _number(x, unit=form.unit)


def _finite_floats(x: Any, length: int | None) -> bool:
    """Whether ``x`` is a non-empty list of finite floats, of ``length`` if given: a vector
    that :func:`_read_vector` reads as ``np.array(x)``."""
    return type(x) is list and bool(x) and (length is None or len(x) == length) \
        and all(type(e) is float and math.isfinite(e) for e in x)


def _read_vector(x: Any, form: _Form) -> NDArray[np.float64]:
    if _finite_floats(x, form.length):
        return np.array(x)  # what the checks below give a list of finite floats
    expected = f"a list of {form.length} numbers" if form.length else "a list of numbers"
    if not isinstance(x, list):
        raise _Invalid(f"{_describe(x)}; {expected} is expected")
    if any(isinstance(_plain(e), list) for e in x):
        raise _Invalid(f"{_describe(x)}; a flat list ({expected}) is expected")
    if (form.length is not None and len(x) != form.length) or not x:
        raise _Invalid(f"a list of {_count(len(x), 'number')}; {expected} is expected")
    return np.array([_number(e, f"component {i}", form.unit) for i, e in enumerate(x, 1)])


def _read_boolean(x: Any, form: _Form) -> bool:
    if isinstance(x, bool):
        return x
    if isinstance(x, str) and x.strip().lower() in ("true", "false"):
        raise _Invalid(f"{_describe(x)}; write True or False without quotes")
    raise _Invalid(f"{_describe(x)}; True or False is expected")


def _fold(option: str) -> str:
    return option.strip().casefold()


def _read_choice(x: Any, form: _Form) -> str:
    listed = ", ".join(repr(o) for o in form.options)
    if isinstance(x, str):
        for option in form.options:
            if _fold(option) == _fold(x):
                return option
        raise _Invalid(f"{_describe(x)} is not one of the options: {listed}")
    raise _Invalid(f"{_describe(x)}; one of the strings {listed} is expected")


def _read_expression(x: Any, form: _Form) -> str:
    if isinstance(x, _sympy_class("Basic")):
        x = str(x)
    elif isinstance(x, numbers.Real) and not isinstance(x, bool):
        x = repr(_number(x))  # a constant is a (probably wrong) expression
    if not isinstance(x, str):
        expected = "an expression (sympy, or a string) in " + ", ".join(form.symbols)
        raise _Invalid(f"{_describe(x)}; {expected} is expected")
    problem = _expression_problem(x, form.symbols, form.where)
    if problem:
        raise _Invalid(problem)
    return x.strip()


@lru_cache(maxsize=4096)
def _expression_problem(x: str, symbols: tuple[str, ...], where: tuple) -> str | None:
    """Why the text ``x`` is no expression in ``symbols`` to grade at the points ``where``
    names (:func:`_sample`), or None: cached, as a key's texts recur in every student's key."""
    try:
        parse_expression(x, symbols)
        values = _values(x, symbols, where)
    except ExpressionError as err:
        return f"expression {_quote(x.strip())}: {err}"
    if not np.any(np.isfinite(values)):
        return (f"expression {_quote(x.strip())} cannot be evaluated at any test point "
                "(division by zero, overflow, or the root or logarithm of a negative number)")
    return None


PLACEHOLDER = ("*Write your answer here, in Markdown: formulas between `$…$` (or `$$…$$` on a "
               "line of their own). Double-click the cell to edit it.*")
"""The text of a written answer cell in the release notebook (:mod:`problems.notebook`); a cell
still holding it is unanswered (:mod:`grader.written`)."""

MAX_WRITTEN_CHARS = 20_000
"""Characters of a written answer's text kept (the grader cuts it there and says so)."""

_EMPTY_CELL = "no answer: the answer cell is empty or missing"


def _read_written(x: Any, form: _Form) -> str:
    """The text of a written answer: ``{"text": …}`` as the grader records it, or the text."""
    text = x.get("text") if isinstance(x, Mapping) else x
    if not isinstance(text, str):
        raise _Invalid(f"{_describe(text)}; Markdown text is expected")
    pictures = isinstance(x, Mapping) and bool(x.get("attachments") or x.get("dropped"))
    if not text.strip() and not pictures:  # a photo of handwritten work alone is an answer
        raise _Missing
    return text


_NUMBER_KINDS = frozenset({"scalar", "angle"})
"""Kinds whose normal form is one float (:func:`_read_scalar`)."""

_READERS = {
    "scalar": _read_scalar,
    "angle": _read_scalar,
    "vector": _read_vector,
    "boolean": _read_boolean,
    "choice": _read_choice,
    "expression": _read_expression,
    WRITTEN: _read_written,
}


# --------------------------------------------------------------------------------------------
# Comparison of two values in normal form


def _within(x: NDArray | float, v: NDArray | float, answer: Answer) -> bool:
    if type(x) is float and type(v) is float:  # the same IEEE operations, without numpy's calls
        return abs(x - v) <= answer.atol + answer.rtol * abs(v)
    return bool(np.all(np.abs(np.subtract(x, v)) <= answer.atol + answer.rtol * np.abs(v)))


def _same_angle(x: float, v: float, answer: Answer) -> bool:
    if answer.period is None:
        return _within(x, v, answer)
    half = answer.period / 2
    wrapped = half - np.remainder(half - (x - v), answer.period)  # x − v wrapped to (−P/2, P/2]
    return bool(abs(wrapped) <= answer.atol + answer.rtol * abs(v))


def _same_vector(x: NDArray, v: NDArray, answer: Answer) -> bool:
    return _norm(x - v) <= answer.atol + answer.rtol * _norm(v)


def _norm(x: NDArray) -> float:
    """``np.linalg.norm(x)`` of a 1-d float array, which is ``sqrt(x.dot(x))`` (numpy's own
    path for it), without its checks of shape, type and arguments; both square roots are
    correctly rounded, so the result is the same float."""
    return math.sqrt(x.dot(x))


def _same_expression(x: str, v: str, answer: Answer) -> bool:
    where = _at_key(answer)
    xs, vs = _values(x, answer.symbols, where), _values(v, answer.symbols, where)
    with np.errstate(all="ignore"):
        return bool(np.all(np.isfinite(xs))) and _within(xs, vs, answer)


_COMPARATORS = {
    "scalar": _within,
    "angle": _same_angle,
    "vector": _same_vector,
    "boolean": lambda x, v, answer: x is v,
    "choice": lambda x, v, answer: x == v,
    "expression": _same_expression,
}


def _matches(answer: Answer, x: Any, v: Any) -> bool:
    return _COMPARATORS[answer.kind](x, v, answer)


def _near(answer: Answer, v: Any) -> Callable[[Any], bool]:
    """``x ↦ _matches(answer, x, v)`` for values read (a scalar's are floats, a vector's float
    arrays), with what depends on ``v`` alone (its tolerance, :func:`_size`) worked out once:
    the key compared with each mistake."""
    size = _size(answer)
    if size is None:
        return lambda x: _matches(answer, x, v)
    tolerance = answer.atol + answer.rtol * size(v)
    return lambda x: size(x - v) <= tolerance


def _show(form: _Form, value: Any) -> str:
    """What was read, for messages: ``1.234 rad``, ``[1, 2, 3] rad/s``, ``'loops'``."""
    unit = f" {form.unit}" if form.unit else ""
    if form.kind in ("scalar", "angle"):
        return f"{value:.6g}{unit}"
    if form.kind == "vector":
        return "[" + ", ".join(f"{c:.6g}" for c in value) + "]" + unit
    if form.kind in ("choice", "expression"):
        return _quote(value, 60)
    if form.kind == WRITTEN:
        return _count(len(value.strip()), "character")
    return str(value)


def _not_within(answer: Answer) -> str:
    if answer.kind in ("boolean", "choice"):
        return "not correct"
    parts = [f"relative {answer.rtol:.2g}"] if answer.rtol else []
    parts += [f"absolute {answer.atol:.2g}{' ' + answer.unit if answer.unit else ''}"] \
        if answer.atol else []
    modulo = f", modulo {answer.period:.6g}" if answer.period else ""
    return f"not correct (not within the tolerance: {' + '.join(parts)}{modulo})"


# --------------------------------------------------------------------------------------------
# Expression sample points (cached: pure functions of immutable arguments)


@lru_cache(maxsize=256)
def _candidates(name: str, symbols: tuple[str, ...]) -> Mapping[str, NDArray]:
    return sample_points(symbols, name, N_SAMPLE_CANDIDATES)


def _at_key(answer: Answer) -> tuple[str, str]:
    """Where ``answer``'s expressions are compared (:func:`_sample`): its key points."""
    return answer.name, answer.value


def _sample(where: tuple, symbols: tuple[str, ...]) -> Mapping[str, NDArray]:
    """The points ``where`` names: ``(name,)`` the candidates of an answer called ``name``,
    ``(name, key)`` those at which its key is defined (:func:`_key_points`)."""
    if len(where) == 1:
        return _candidates(where[0], symbols)
    return _key_points(where[0], symbols, where[1])


@lru_cache(maxsize=4096)
def _values(text: str, symbols: tuple[str, ...], where: tuple) -> NDArray:
    """``text`` evaluated at the points ``where`` names (:func:`_sample`), read-only: a key's
    expressions, the same text for a whole class, are read and compared once, not once per
    student and mistake (:class:`~problems.expressions.ExpressionError` is not cached)."""
    values = evaluate_expression(text, symbols, _sample(where, symbols))
    values.flags.writeable = False
    return values


@lru_cache(maxsize=1024)
def _key_points(name: str, symbols: tuple[str, ...], key: str) -> Mapping[str, NDArray]:
    """The candidate points at which the key expression is defined."""
    candidates = _candidates(name, symbols)
    keep = np.isfinite(_values(key, symbols, (name,)))
    if np.count_nonzero(keep) < MIN_SAMPLE_POINTS:
        raise ParameterError(
            "value",
            f"answer {name!r}: the key expression is defined at only {np.count_nonzero(keep)} "
            f"of {N_SAMPLE_CANDIDATES} sample points (need {MIN_SAMPLE_POINTS})",
        )
    points = {}
    for symbol, column in candidates.items():
        points[symbol] = column[keep]
        points[symbol].flags.writeable = False
    return points


# --------------------------------------------------------------------------------------------
# Validation of an Answer record (template bugs, reported at construction)


def _validate_fields(answer: Answer) -> None:
    name = answer.name
    if not isinstance(name, str) or not name.isidentifier():
        raise ParameterError("name", f"must be a Python identifier, got {name!r}")
    if answer.kind not in ANSWER_KINDS:
        raise ParameterError("kind", f"answer {name!r}: one of {ANSWER_KINDS}, not "
                             f"{answer.kind!r}")
    for field in ("rtol", "atol", "points"):
        value = getattr(answer, field)
        if type(value) is float and 0 <= value < math.inf:
            continue  # finite and ≥ 0 (NaN fails both), and float(value) is value
        real = type(value) is float or (
            not isinstance(value, bool) and isinstance(value, numbers.Real))
        if not real or not math.isfinite(value) or value < 0:
            raise ParameterError(field, f"answer {name!r}: must be finite and ≥ 0, got {value!r}")
        object.__setattr__(answer, field, float(value))
    for field in ("unit", "description"):
        if not isinstance(getattr(answer, field), str):
            raise ParameterError(field, f"answer {name!r}: must be a string")
    for field in ("mistakes", "options", "symbols"):
        value = getattr(answer, field)
        if type(value) is not tuple:  # tuple(value) would be value itself
            object.__setattr__(answer, field, tuple(value))
    _validate_kind_fields(answer)


def _validate_kind_fields(answer: Answer) -> None:
    name, kind = answer.name, answer.kind
    if bool(answer.rubric) != (kind == WRITTEN):
        raise ParameterError("rubric", f"answer {name!r}: required for, and only for, written")
    for field, owner in (("options", "choice"), ("symbols", "expression")):
        if bool(getattr(answer, field)) != (kind == owner):
            raise ParameterError(field, f"answer {name!r}: required for, and only for, {owner}")
    if answer.period is not None:
        if kind != "angle":
            raise ParameterError("period", f"answer {name!r}: only an angle has a period")
        period = answer.period
        if isinstance(period, bool) or not isinstance(period, numbers.Real) \
                or not math.isfinite(period) or period <= 0:
            raise ParameterError("period", f"answer {name!r}: must be > 0, got {period!r}")
        object.__setattr__(answer, "period", float(period))
    if kind == "choice":
        folded = [_fold(o) if isinstance(o, str) else None for o in answer.options]
        if None in folded or "" in folded or len(set(folded)) != len(folded):
            raise ParameterError(
                "options", f"answer {name!r}: need distinct non-empty strings, got {answer.options}"
            )
    if kind == "expression":
        try:
            check_symbol_names(answer.symbols)
        except ValueError as err:
            raise ParameterError("symbols", f"answer {name!r}: {err}") from None


def _validate_written(answer: Answer) -> None:
    """A written answer: its prompt (``value``) is Markdown text; a rubric of 1 to
    :data:`MAX_RUBRIC_ITEMS` items whose points add up to ``points``; nothing of the compared
    kinds (mistakes, accepted values, dependencies, a period)."""
    name = answer.name
    if not isinstance(answer.value, str) or not answer.value.strip():
        raise ParameterError("value", f"answer {name!r}: a written answer's value is its prompt "
                             f"(Markdown text), got {answer.value!r}")
    for field in ("mistakes", "accepted", "depends_on"):
        if getattr(answer, field):
            raise ParameterError(field, f"answer {name!r}: a written answer has no {field}")
    rubric = rubric_items(answer.rubric)
    if not 1 <= len(rubric) <= MAX_RUBRIC_ITEMS:
        raise ParameterError("rubric", f"answer {name!r}: a rubric of 1 to {MAX_RUBRIC_ITEMS} "
                             f"items, got {len(rubric)}")
    total = sum(r.points for r in rubric)
    if not math.isclose(total, answer.points, rel_tol=POINTS_SUM_TOLERANCE, abs_tol=1e-12):
        raise ParameterError("rubric", f"answer {name!r}: its items' points add up to "
                             f"{total:g}, not to the answer's {answer.points:g}")
    object.__setattr__(answer, "rubric", rubric)
    object.__setattr__(answer, "accepted", ())
    object.__setattr__(answer, "depends_on", ())


def _to_json(value: Any) -> Any:
    return value.tolist() if isinstance(value, np.ndarray) else value


def _require_gradable_key(answer: Answer) -> None:
    if answer.kind == "expression":  # defined at enough sample points; zero needs atol
        values = _values(answer.value, answer.symbols, _at_key(answer))  # finite: key points
        if answer.atol == 0 and not np.any(values):
            raise ParameterError("atol", f"answer {answer.name!r}: the key is zero everywhere; "
                                 "set atol > 0")
    elif answer.kind in ("scalar", "angle", "vector") and answer.atol == 0 \
            and _is_zero(answer.value):
        raise ParameterError(
            "atol", f"answer {answer.name!r}: the key is zero, so rtol alone accepts only an exact "
            "zero; set atol > 0"
        )


def _check_depends_on(answer: Answer) -> None:
    if type(answer.depends_on) is tuple and not answer.depends_on:
        return  # none, as most answers: nothing to check or convert
    depends = tuple(answer.depends_on)
    if not all(isinstance(n, str) and n.isidentifier() and n != answer.name for n in depends):
        raise ParameterError("depends_on", f"answer {answer.name!r}: names of other answers, "
                             f"got {depends!r}")
    object.__setattr__(answer, "depends_on", depends)


def _is_zero(value: float | list[float]) -> bool:
    """Whether a read scalar, angle or vector key (a float, a list of floats) is exactly zero:
    ``not np.any(value)``, which for floats is ``not any(value)`` (a float is true when
    nonzero, NaN included), without making an array of the list."""
    return value == 0.0 if type(value) is float else not any(value)


def _checked_mistake(answer: Answer, mistake: Any, form: _Form,
                     near_key: Callable[[Any], bool]) -> Mistake:
    """``mistake`` read in ``form``; a ParameterError if it matches the (read) key, which
    ``near_key`` tells (:func:`_near`)."""
    if not isinstance(mistake, Mistake):
        raise ParameterError("mistakes", f"answer {answer.name!r}: not a Mistake: {mistake!r}")
    value = _read_key(form, mistake.value, "mistakes")
    if near_key(value):
        raise ParameterError(
            "mistakes",
            f"answer {answer.name!r}: mistake {mistake.name!r} is indistinguishable from the key "
            "within tolerance",
        )
    if value is mistake.value:  # read as it was written (a float): already plain JSON
        return mistake
    return Mistake(mistake.name, _to_json(value), mistake.feedback)


def _known_keys(cls: type, d: Mapping[str, Any], what: str) -> dict[str, Any]:
    if type(d) is not dict and not isinstance(d, Mapping):
        raise ParameterError(what, f"expected a JSON object, got {type(d).__name__}")
    unknown = d.keys() - _field_names(cls)
    if unknown:
        raise ParameterError(what, f"unknown keys {sorted(unknown)}")
    return dict(d)


@cache
def _field_names(cls: type) -> frozenset[str]:
    return frozenset(f.name for f in fields(cls))


def mistakes_distinguishable(answer: Answer, margin: float = 5.0) -> bool:
    """Whether every known mistake lies ``margin`` tolerances from the key and from each other.

    Graded with the tolerances widened ``margin`` times, each mistake's value must still be
    recognised as that mistake (and the widened answer must still be valid — no mistake within
    the widened tolerance of the key). Templates reject draws that fail this, so the grader can
    name every listed mistake reliably even for a student whose arithmetic is slightly off.
    """
    if not answer.mistakes:
        return True
    rtol, atol = margin * answer.rtol, margin * answer.atol
    size = _size(answer)
    if size is abs:  # the floats the answer holds are read already
        return _apart((answer.value, *answer.accepted), [m.value for m in answer.mistakes],
                      rtol, atol, size)
    wide = _unchecked(answer, rtol=rtol, atol=atol)
    if size is not None:
        return _apart(*_read_values(wide), rtol, atol, size)
    decided_by = _decided_by(wide)
    if decided_by is None:
        return _compared_apart(wide)
    verdict = _VERDICTS.get(decided_by)
    return _keep(_VERDICTS, decided_by, _compared_apart(wide)) if verdict is None else verdict


def _read_values(wide: Answer) -> tuple[list, Iterator]:
    """The keys of ``wide`` (the key, the accepted values) read, and its mistakes' values,
    each read when reached."""
    form = _Form.of(wide)
    keys = [_read_key(form, v, "value") for v in (wide.value, *wide.accepted)]
    return keys, (_read_key(form, m.value, "mistakes") for m in wide.mistakes)


_VERDICTS: dict[tuple, bool] = {}
""":func:`mistakes_distinguishable` of answers compared value by value (expressions, choices,
booleans, periodic angles), by what decides it: a class's expression answers are a few
distinct ones (7 among 600 in 300 students), each costing ~0.1 ms to compare at its points."""

_MAX_KEPT = 4096
"""Most entries :data:`_VERDICTS` or :data:`_CHECKED` holds (emptied when full)."""


def _keep(kept: dict, key: tuple, value: Any) -> Any:
    """``value``, kept in ``kept`` under ``key`` (emptied first when it holds
    :data:`_MAX_KEPT`)."""
    if len(kept) >= _MAX_KEPT:
        kept.clear()
    kept[key] = value
    return value


def _compared_apart(wide: Answer) -> bool:
    """:func:`mistakes_distinguishable` by grading each mistake's value (read) against the
    keys and the mistakes before it, with the widened answer ``wide``."""
    keys, values = _read_values(wide)
    seen: list = []
    for value in values:  # what grade(wide, mistake.value) names, without its reads
        if any(_matches(wide, value, v) for v in (*keys, *seen)) \
                or not _matches(wide, value, value):
            return False
        seen.append(value)
    return True


def _size(answer: Answer) -> Callable[[Any], float] | None:
    """``abs`` for a scalar (an angle without a period), :func:`_norm` for a vector: the kinds
    whose values (read) match when ``size(x − v) ≤ atol + rtol·size(v)`` (:func:`_within` of
    two floats, :func:`_same_vector`); None for the others."""
    kind = answer.kind
    if kind == "scalar" or (kind == "angle" and answer.period is None):
        return abs
    return _norm if kind == "vector" else None


def _apart(keys: Iterable[Any], mistakes: Iterable[Any], rtol: float, atol: float,
           size: Callable[[Any], float]) -> bool:
    """:func:`mistakes_distinguishable` of values (read) compared by their ``size``
    (:func:`_size`), with tolerances ``rtol`` and ``atol``: each reference's tolerance worked
    out once. A mistake matches itself when its tolerance is ≥ 0 (``size(x − x)`` is 0: it
    is finite)."""
    known = [(v, atol + rtol * size(v)) for v in keys]
    for x in mistakes:
        for v, tolerance in known:
            if size(x - v) <= tolerance:
                return False
        tolerance = atol + rtol * size(x)
        if not 0.0 <= tolerance:
            return False
        known.append((x, tolerance))
    return True


_COMPARED_AS_VALUES = frozenset({"expression", "boolean", "choice"})
"""Kinds whose checks :data:`_CHECKED` keeps: few distinct answers in a class (an expression's
key and mistakes read and compared at its points cost ~0.05 ms, a boolean's or a choice's
~0.01 ms)."""

_CHECKED: dict[tuple, tuple] = {}
"""An answer of :data:`_COMPARED_AS_VALUES` that passed its checks, by what decides them
(:func:`_decided_by`): its value, accepted values and mistakes' values, normalised."""


def _decided_by(answer: Answer) -> tuple | None:
    """What the checks of ``answer`` (:meth:`Answer._check_and_normalise`) and the comparison
    of its values (:func:`mistakes_distinguishable`) depend on: the fields that say how values
    compare, and every value with its type (``True``, ``1`` and ``1.0`` are equal keys but not
    equally valid answers); None where a value cannot be a key (unhashable) or a mistake is
    not a :class:`Mistake` (the checks say so)."""
    if not all(type(m) is Mistake for m in answer.mistakes):
        return None
    try:
        decided_by = (answer.kind, answer.name, answer.unit, answer.rtol, answer.atol,
                      answer.options, answer.symbols, answer.period,
                      type(answer.value), answer.value,
                      tuple((type(v), v) for v in answer.accepted),
                      tuple((type(m.value), m.value) for m in answer.mistakes))
        hash(decided_by)
    except TypeError:
        return None
    return decided_by


def _take_checked(answer: Answer, checked: tuple) -> None:
    """:meth:`Answer._check_and_normalise`'s outcome for these values (``checked``, from
    :data:`_CHECKED`), without reading or comparing them again."""
    value, accepted, mistake_values = checked
    object.__setattr__(answer, "value", value)
    object.__setattr__(answer, "accepted", accepted)
    _check_depends_on(answer)
    mistakes = tuple(m if type(m.value) is type(v) and m.value == v
                     else Mistake(m.name, v, m.feedback)
                     for m, v in zip(answer.mistakes, mistake_values, strict=True))
    object.__setattr__(answer, "mistakes", mistakes)
    _check_mistake_names(answer)


def _check_mistake_names(answer: Answer) -> None:
    mistakes = answer.mistakes
    if len(mistakes) > 1 and len({m.name for m in mistakes}) != len(mistakes):
        raise ParameterError("mistakes", f"answer {answer.name!r}: duplicate names "
                             f"{[m.name for m in mistakes]}")


def _unchecked(answer: Answer, **changes: Any) -> Answer:
    """``replace(answer, **changes)`` without ``__post_init__``, for changes the caller checks
    itself: :meth:`Answer.following`'s names; :func:`mistakes_distinguishable`'s widened
    tolerances, which can make no value unreadable or the key ungradable (it checks each
    mistake against the widened key itself)."""
    copy = object.__new__(Answer)
    vars(copy).update(vars(answer), **changes)  # the fields are the instance's attributes
    return copy


def distinguishable_answers(
    build: Callable[[], tuple[Answer, ...]], margin: float = 5.0
) -> tuple[Answer, ...] | None:
    """``build()``'s answers, or None when the draw must be rejected (a template's rule).

    Rejected when a known mistake equals the key within its tolerance (``Answer`` refuses it,
    raising :class:`ParameterError` on ``mistakes``) or lies within ``margin`` tolerances of the
    key or of another mistake (:func:`mistakes_distinguishable`). Any other ``ParameterError``
    is a bug in the template, not an unlucky draw, and propagates.
    """
    try:
        answers = build()
    except ParameterError as err:
        if err.parameter != "mistakes":
            raise
        return None
    return answers if all(mistakes_distinguishable(a, margin) for a in answers) else None
