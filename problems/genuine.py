"""Whether a student's earlier answers are ground for follow-through credit (issue 30): the
default degenerate cases every family gets, beside a family's own ``degenerate``.

Follow-through credit (:mod:`grader.follow_through`) judges a later answer ``L`` against what
the student's own earlier answers give, whenever those differ from the key's. A marker gives
that credit only where the earlier error does not make the later work easier: a later answer
that follows trivially from a degenerate value has shown nothing. An earlier answer that
differs from the key's value is *degenerate* when

zero
    it is zero (its size at most :data:`SAME` of the key's) where the key's is not;
identity
    it has 9 entries (a 3×3 matrix row by row) and is the identity where the key's is not;
far
    its size (a vector's norm; an expression's at its sample points) is more than a factor
    :data:`FAR` from the key's;
copied
    it is a number of the statement (a parameter, to :data:`SAME`; a vector up to the order of
    its components) where the key's is not;

and the later answer ``L`` recomputed from the student's values is *trivial* when it is zero
(to :data:`SAME` of the key's size), or a number of the statement or another of the student's
answers of that question, in ``L``'s unit (to :data:`COPY_RTOL`; a vector up to order), where
the key's ``L`` is not. ``far`` and ``copied``
spare a value the answer's own comparison recognises — right within its tolerance, an accepted
value, or one of its known mistakes (a named mistake is a genuine attempt: degrees for radians,
a factor 2).

Every threshold here is fixed, not an answer's tolerance, except the recognition that spares:
so widening a tolerance can only spare more, never take follow-through credit away.

A reason is one line for the student; it names answers and parameters as ``{name}``, which the
grader writes as the notebook's variable (``q2_I_offdiag``): :func:`named`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from problems.answers import Answer, grade, numbers_of, read_value

SAME = 1e-12
"""Relative difference within which two values are the same number (a copy, the key's own)."""
FAR = 10.0
"""Factor by which an earlier value's size may differ from the key's and still be an attempt."""
COPY_RTOL = 1e-3
"""Relative difference within which a recomputed later answer is a copy of a number."""
IDENTITY = np.eye(3).ravel()


class Given(NamedTuple):
    """One answer of a question: the key's record of it, and the student's value (plain JSON)."""

    answer: Answer
    value: Any


def same_as_key(given: Given) -> bool:
    """Whether the student's value is the key's own (the same number to :data:`SAME`; a
    boolean, a choice or an expression's text exactly)."""
    answer = given.answer
    if answer.kind in ("boolean", "choice"):
        return read_value(answer, given.value) == read_value(answer, answer.value)
    mine = numbers_of(answer, given.value)
    return mine is not None and _same(mine, numbers_of(answer, answer.value), SAME)


def default_reason(later: Answer, earlier: Sequence[Given], followed: Any,
                   params: Mapping[str, Any], others: Sequence[Given],
                   units: Mapping[str, str] | None = None) -> str | None:
    """Why the student's earlier values ``earlier`` give no follow-through credit to ``later``
    (module docstring), or None. ``followed``: ``later`` recomputed from them; ``others``: the
    student's other answers of the question; ``params``: the question's parameters, and
    ``units`` their units (a later answer is a copy only of a number in its own unit)."""
    given = list(_given_numbers(params))
    for e in earlier:
        if not same_as_key(e):
            reason = _earlier_reason(e, later, given)
            if reason is not None:
                return reason
    units = units or {}
    alike = [(label, v) for label, v in given
             if units.get(label.removeprefix("an entry of ").strip("{}")) == later.unit]
    return _trivial_reason(later, followed, alike,
                           [o for o in others if o.answer.unit == later.unit])


def statement_number(value: Any, params: Mapping[str, Any], key: Any = None) -> str | None:
    """The parameter ``value`` is a copy of — a number of the statement, to :data:`SAME` (a
    vector up to the order of its components) — unless ``key``, the key's value where a family
    knows it, is a copy of it too; or None. For a family's own ``degenerate``.

    Examples
    --------
    >>> statement_number(160.0, {"M": 0.0586, "omega3": 160.0})
    'omega3'
    >>> statement_number([0.0, 1.0, 2.0], {"r": [2.0, 0.0, 1.0]}) is None  # up to order
    False
    """
    mine = np.atleast_1d(np.asarray(value, dtype=float))
    key = np.full(mine.shape, np.nan) if key is None else np.atleast_1d(np.asarray(key, float))
    copied = _copy_of(mine, key, list(_given_numbers(params)), SAME)
    return None if copied is None else copied.removeprefix("an entry of ").strip("{}")


def named(reason: str, question: int, names: Iterable[str]) -> str:
    """``reason`` with each ``{name}`` of ``names`` written as its variable ``q{question}_name``.

    Examples
    --------
    >>> named("your {R} is the identity", 2, ["R", "r_lab"])
    'your q2_R is the identity'
    """
    for name in names:
        reason = reason.replace(f"{{{name}}}", f"q{question}_{name}")
    return reason


# -- the earlier answers


def _earlier_reason(e: Given, later: Answer,
                    given: Sequence[tuple[str, NDArray]]) -> str | None:
    mine, key = numbers_of(e.answer, e.value), numbers_of(e.answer, e.answer.value)
    if mine is None or mine.shape != key.shape:
        return None
    yours, nothing = f"your {_ref(e.answer.name)}", \
        f"which leaves nothing to work out for {_ref(later.name)}"
    size, key_size = _size(mine), _size(key)
    if key_size > 0 and size <= SAME * key_size:
        return f"{yours} is zero, {nothing}"
    if mine.size == 9 and _same(mine, IDENTITY, SAME) and not _same(key, IDENTITY, SAME):
        return f"{yours} is the identity matrix, {nothing}"
    if _recognised(e):
        return None
    if key_size > 0 and not key_size / FAR <= size <= FAR * key_size:
        return (f"{yours} is more than a factor of {FAR:g} from any value this problem can "
                f"have: no ground for {_ref(later.name)}")
    copied = _copy_of(mine, key, given, SAME)
    if copied is not None:
        return f"{yours} is {copied}, copied from the statement, not worked out"
    return None


def _recognised(e: Given) -> bool:
    """Right (the key or an accepted value, within tolerance) or a known mistake."""
    verdict = grade(e.answer, e.value)
    return verdict.status == "correct" or verdict.mistake is not None


# -- the later answer


def _trivial_reason(later: Answer, followed: Any, given: Sequence[tuple[str, NDArray]],
                    others: Sequence[Given]) -> str | None:
    mine, key = numbers_of(later, followed), numbers_of(later, later.value)
    if mine is None or mine.shape != key.shape or not np.all(np.isfinite(mine)):
        return None
    from_yours = f"{_ref(later.name)} from your values is"
    key_size = _size(key)
    if key_size > 0 and _size(mine) <= SAME * key_size:
        return f"{from_yours} zero: nothing is left to work out"
    copied = _copy_of(mine, key, given, COPY_RTOL)
    if copied is not None:
        return f"{from_yours} {copied} of the statement: a copy, not worked out"
    answers = [(_ref(o.answer.name), numbers_of(o.answer, o.value)) for o in others
               if o.answer.name != later.name]
    copied = _copy_of(mine, key, [(n, v) for n, v in answers if v is not None], COPY_RTOL)
    if copied is not None:
        return f"{from_yours} your {copied}: a copy, not worked out"
    return None


def _ref(name: str) -> str:
    """``{name}``: an answer or parameter, written as its variable by :func:`named`."""
    return "{" + name + "}"


# -- numbers


def _given_numbers(params: Mapping[str, Any]) -> Iterable[tuple[str, NDArray]]:
    """The statement's numbers, each with how a reason names it: each numeric parameter
    (``{name}``), whole and (for an array) each entry (``an entry of {name}``)."""
    for name, value in params.items():
        try:
            numbers = np.asarray(value, dtype=float).ravel()
        except (TypeError, ValueError):
            continue  # a label
        if numbers.size == 0 or not np.all(np.isfinite(numbers)):
            continue
        yield _ref(name), numbers
        if numbers.size > 1:
            yield from ((f"an entry of {_ref(name)}", numbers[i:i + 1])
                        for i in range(numbers.size))


def _copy_of(mine: NDArray, key: NDArray, candidates: Sequence[tuple[str, NDArray]],
             rtol: float) -> str | None:
    """How a reason names the first candidate ``mine`` is a copy of (to ``rtol``; up to
    order) and ``key`` is not."""
    for name, value in candidates:
        if value.shape == mine.shape and _size(value) > 0 and \
                _same(np.sort(mine), np.sort(value), rtol) and \
                not _same(np.sort(key), np.sort(value), rtol):
            return name
    return None


def _same(x: NDArray, v: NDArray, rtol: float) -> bool:
    """``‖x − v‖ ≤ rtol ‖v‖`` over the entries finite in both (an expression's sample points)."""
    finite = np.isfinite(x) & np.isfinite(v)
    if not np.any(finite):
        return False
    x, v = x[finite], v[finite]
    return bool(np.linalg.norm(x - v) <= rtol * np.linalg.norm(v))


def _size(x: NDArray) -> float:
    return float(np.linalg.norm(x[np.isfinite(x)]))
