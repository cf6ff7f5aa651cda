"""What an :class:`Answer` checks, wherever it is built — by a template, by ``key set``, or read
back from a ``key.json`` (``from_dict``, hand-edited or not) — and what only generation checks.

Issue 34 made these checks cheap (each value read once, a class's expression texts evaluated
once); the tests here hold them to their definitions: :func:`mistakes_distinguishable` against
the rule it states, spelled out with :func:`grade` on a widened answer (as it was computed
before), and the refusals against the fields they name.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import fields, replace
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from problems.answers import (
    Answer,
    Mistake,
    RubricItem,
    _Form,
    _Invalid,
    _is_zero,
    _Missing,
    _norm,
    _read,
    _read_key,
    _unchecked,
    distinguishable_answers,
    grade,
    mistakes_distinguishable,
    numbers_of,
    read_value,
)
from solver.parameters import ParameterError

TAU = 2 * math.pi
KEY_TEXT = "I1*sin(beta)**2/2 + I3*cos(beta)**2/2"
SYMBOLS = ("I1", "I3", "beta")


def _by_grading(answer: Answer, margin: float) -> bool:
    """The rule of :func:`mistakes_distinguishable`, spelled out: the answer with its
    tolerances widened ``margin`` times is still an answer, and grades each mistake's value as
    that mistake."""
    try:
        wide = replace(answer, rtol=margin * answer.rtol, atol=margin * answer.atol)
    except ParameterError:
        return False
    return all(grade(wide, m.value).mistake == m.name for m in wide.mistakes)


def _random_answer(rng: np.random.Generator, kind: str) -> Answer | None:
    """An answer of ``kind`` whose mistakes lie 0.5 to 12 tolerances from the key or from each
    other (so both outcomes of the rule occur); None when the constructor refuses it."""
    rtol = float(rng.choice([1e-3, 1e-2]))
    steps = rng.uniform(0.5, 12.0, size=int(rng.integers(1, 5)))
    signs = rng.choice([-1.0, 1.0], size=steps.size)
    fields: dict = {"rtol": rtol}
    if kind == "expression":
        key = KEY_TEXT
        values = [f"{float(1 + s * d * rtol)!r}*({KEY_TEXT})"
                  for s, d in zip(signs, steps, strict=True)]
        fields["symbols"] = SYMBOLS
    elif kind == "vector":
        key = rng.uniform(-2, 2, size=3).tolist()
        norm = float(np.linalg.norm(key))
        values = [(np.asarray(key) + s * d * rtol * norm * rng.normal(size=3) / math.sqrt(3)
                   ).tolist() for s, d in zip(signs, steps, strict=True)]
    else:
        key = float(rng.uniform(0.1, 3.0))
        values = [key * (1 + s * d * rtol) for s, d in zip(signs, steps, strict=True)]
        if kind == "angle" and rng.random() < 0.5:
            fields["period"] = TAU
            values = [v + TAU * int(rng.integers(-1, 2)) for v in values]
    if rng.random() < 0.3:  # a mistake near another mistake rather than near the key
        values.append(values[0] if isinstance(values[0], str) else
                      (np.asarray(values[0]) * (1 + 2 * rtol)).tolist())
    mistakes = tuple(Mistake(f"m{i}", v, "?") for i, v in enumerate(values))
    try:
        return Answer("x", kind, key, mistakes=mistakes, **fields)
    except ParameterError:
        return None


@pytest.mark.parametrize("kind", ["scalar", "angle", "vector", "expression"])
def test_mistakes_distinguishable_is_the_rule_it_states(kind):
    rng = np.random.default_rng(34)
    seen = []
    for _ in range(150):
        answer = _random_answer(rng, kind)
        if answer is None:
            continue
        margin = float(rng.choice([2.0, 5.0]))
        seen.append(mistakes_distinguishable(answer, margin))
        assert seen[-1] == _by_grading(answer, margin), answer
    assert True in seen and False in seen  # both outcomes were tried


def test_a_mistake_undefined_at_some_key_points_is_not_recognisable():
    """grade() compares an expression only where both are defined at every point: a mistake
    with NaN at some of the key's points matches nothing, not even itself."""
    root = f"sqrt(I1 - 1.5)*({KEY_TEXT})"  # I1 is sampled in (1, 2)
    answer = Answer("T", "expression", KEY_TEXT, symbols=SYMBOLS,
                    mistakes=(Mistake("root", root, "?"),))
    assert grade(answer, root).mistake is None
    assert not mistakes_distinguishable(answer, 5.0) and not _by_grading(answer, 5.0)


@pytest.mark.parametrize("kind", ["scalar", "angle", "vector"])
def test_a_mistake_exactly_at_the_widened_tolerance_is_not_told_apart(kind):
    """Powers of two make the distance and the tolerance exact: grade() counts the edge as a
    match (≤), and so must the rule."""
    key, step = ([1.0, 0.0], [2**-7, 0.0]) if kind == "vector" else (1.0, 2**-7)
    at = (np.add(key, step).tolist() if kind == "vector" else key + step)
    answer = Answer("x", kind, key, rtol=2**-8, mistakes=(Mistake("edge", at, "?"),))
    assert not _by_grading(answer, 2.0) and not mistakes_distinguishable(answer, 2.0)
    assert _by_grading(answer, 1.0) and mistakes_distinguishable(answer, 1.0)


def test_a_mistake_is_told_from_an_accepted_value_too():
    answer = Answer("x", "scalar", 1.0, accepted=(-1.0,), mistakes=(Mistake("sign", -1.001, "?"),))
    assert not mistakes_distinguishable(answer, 5.0)
    assert mistakes_distinguishable(replace(answer, accepted=(-2.0,)), 5.0)


# -- checked wherever an Answer is built, a key file read back included


def _record(**changes) -> dict:
    answer = Answer("beta1", "vector", [1.0, 2.0, 2.0], rtol=1e-3,
                    mistakes=(Mistake("sign", [-1.0, -2.0, -2.0], "check the sign"),))
    return {**json.loads(json.dumps(answer.to_dict())), **changes}


@pytest.mark.parametrize(("changes", "parameter", "fragment"), [
    ({"rtol": 2.0}, "mistakes", "'sign' is indistinguishable from the key"),
    ({"mistakes": [{"name": "sign", "value": "minus", "feedback": "?"}]}, "mistakes",
     "the string 'minus'"),
    ({"mistakes": [{"name": "sign", "value": [1.0, 2.0], "feedback": "?"}]}, "mistakes",
     "a list of 2 numbers; a list of 3 numbers is expected"),
    ({"accepted": [[1.0, 2.0]]}, "accepted", "a list of 2 numbers; a list of 3 numbers"),
    ({"mistakes": [{"name": "sign", "value": [-1.0, -2.0, -2.0], "feedback": "?"}] * 2},
     "mistakes", "duplicate names"),
    ({"value": [0.0, 0.0, 0.0], "mistakes": []}, "atol", "the key is zero"),
    ({"depends_on": ["beta1"]}, "depends_on", "names of other answers"),
])
def test_a_key_record_that_would_misgrade_is_refused_naming_the_field(changes, parameter,
                                                                      fragment):
    with pytest.raises(ParameterError) as refused:
        Answer.from_dict(_record(**changes))
    assert refused.value.parameter == parameter
    assert fragment in str(refused.value) and "'beta1'" in str(refused.value)


def test_an_accepted_value_of_the_wrong_length_could_only_fail_grading():
    """Why it is refused at construction: grade() reads accepted values in the key's form."""
    answer = Answer.from_dict(_record())
    broken = object.__new__(Answer)
    for name, value in vars(answer).items():
        object.__setattr__(broken, name, value)
    object.__setattr__(broken, "accepted", ([1.0, 2.0],))
    with pytest.raises(ParameterError, match="a list of 2 numbers"):
        grade(broken, [5.0, 5.0, 5.0])


@pytest.mark.parametrize("text", ["I1*log(-I3)", "1/(beta - beta)"])
def test_an_expression_key_defined_nowhere_is_refused_every_time(text):
    for _ in range(2):  # refusals are not remembered as answers
        with pytest.raises(ParameterError, match="cannot be evaluated at any test point"):
            Answer("T", "expression", text, symbols=SYMBOLS)


def test_an_expression_key_is_read_the_same_for_every_student():
    answer = Answer("T", "expression", KEY_TEXT, rtol=1e-6, symbols=SYMBOLS,
                    mistakes=(Mistake("half", f"({KEY_TEXT})/2", "?"),))
    again = Answer.from_dict(json.loads(json.dumps(answer.to_dict())))
    assert again == answer
    values = numbers_of(again, KEY_TEXT)
    values[:] = 0.0  # a copy: what grading compares is untouched
    assert grade(again, KEY_TEXT).status == "correct"
    assert grade(again, f"({KEY_TEXT})/2").mistake == "half"
    assert grade(again, f"({KEY_TEXT})*(1 + 1e-5)").status == "wrong"


# -- checked at generation only: the template's margin


def test_the_margin_is_a_generation_rule_and_a_key_file_is_graded_as_written():
    """A mistake 3 tolerances from the key: a template rejects the draw (5 tolerances), a key
    file holding it is read and grades the mistake as that mistake."""
    answer = Answer("t", "scalar", 1.0, rtol=1e-3, mistakes=(Mistake("near", 1.003, "?"),))
    assert distinguishable_answers(lambda: (answer,), 5.0) is None
    assert distinguishable_answers(lambda: (answer,), 2.0) == (answer,)
    read = Answer.from_dict(json.loads(json.dumps(answer.to_dict())))
    assert grade(read, 1.0005).status == "correct"
    assert grade(read, 1.003).mistake == "near"


# -- written back: every field, in order, sharing nothing


def test_a_key_record_holds_every_field_in_order_and_shares_no_list():
    names = [f.name for f in fields(Answer)]
    vector = Answer("w", "vector", [1.0, 2.0], accepted=([2.0, 1.0],), depends_on=("L",),
                    mistakes=(Mistake("m", [5.0, 5.0], "?"),), description="ω")
    prompt = Answer("why", "written", "Explain.", points=2.0,
                    rubric=(RubricItem("a", 1.0), RubricItem("b", 1.0)))
    record = vector.to_dict()
    assert list(record) == [n for n in names if n != "rubric"]
    assert list(prompt.to_dict()) == [n for n in names if n not in ("accepted", "depends_on")]
    record["value"][0] = record["accepted"][0][0] = record["mistakes"][0]["value"][0] = 9.0
    assert vector.to_dict() == {**record, "value": [1.0, 2.0], "accepted": [[2.0, 1.0]],
                                "mistakes": [{"name": "m", "value": [5.0, 5.0], "feedback": "?"}]}
    assert Answer.from_dict(prompt.to_dict()) == prompt


def test_following_checks_the_names_it_is_given_and_keeps_the_rest():
    answer = Answer("t", "scalar", 2.0, mistakes=(Mistake("half", 1.0, "?"),))
    assert answer.following("L", "T") == replace(answer, depends_on=("L", "T"))
    for names, fragment in ((("t",), "names of other answers"), (("2L",), "names of other")):
        with pytest.raises(ParameterError, match=fragment):
            answer.following(*names)


# -- the fast paths of reading and comparing (issue 34) agree with the generic ones

_FINITE = st.floats(allow_nan=False, allow_infinity=False)
_ELEMENT = st.one_of(st.floats(), st.integers(-3, 3), st.booleans(),
                     st.floats().map(np.float64), st.just([1.0]), st.just("1.0"))


def _vector_form(length: int | None) -> _Form:
    return _Form("w", "vector", "", 1.0, length, (), (), None)


@settings(max_examples=300, deadline=None)
@given(st.lists(_FINITE, min_size=1, max_size=6))
def test_the_norm_of_a_vector_is_numpys_to_the_last_bit(x):
    array = np.array(x)
    with np.errstate(over="ignore"):  # both overflow alike, to infinity
        assert _norm(array) == float(np.linalg.norm(array))


@settings(max_examples=300, deadline=None)
@given(st.lists(_ELEMENT, max_size=4) | _ELEMENT, st.sampled_from([None, 3]))
def test_a_vector_key_is_read_as_the_generic_reader_reads_it(x, length):
    """_read_key's fast path for a list of finite floats gives what _read gives, and any other
    value is refused with _read's message."""
    form = _vector_form(length)
    try:
        expected = _read(form, x)
    except (_Invalid, _Missing) as err:
        with pytest.raises(ParameterError) as refused:
            _read_key(form, x, "value")
        assert str(refused.value) == f"value: answer 'w': {str(err) or 'no value (None)'}"
        return
    read = _read_key(form, x, "value")
    assert read.dtype == expected.dtype and read.tobytes() == expected.tobytes()


@given(st.lists(st.floats(allow_infinity=False), min_size=1, max_size=4))
def test_a_zero_vector_key_is_told_as_numpy_tells_it(x):
    assert _is_zero(x) == (not np.any(x))


def _reference_match(answer: Any, x, v) -> bool:
    """The comparisons as written before issue 34 (np.linalg.norm, each tolerance anew), for
    values read (``answer``: anything with ``kind``, ``rtol`` and ``atol``)."""
    with np.errstate(invalid="ignore", over="ignore"):  # 0 × inf: NaN, never within, no warning
        if answer.kind == "vector":
            return bool(np.linalg.norm(x - v) <= answer.atol + answer.rtol * np.linalg.norm(v))
        return abs(x - v) <= answer.atol + answer.rtol * abs(v)


def _reference_distinguishable(answer: Answer, margin: float) -> bool:
    """mistakes_distinguishable as written before issue 34: every value read, each compared
    with the keys, the mistakes before it and itself."""
    wide = _unchecked(answer, rtol=margin * answer.rtol, atol=margin * answer.atol)
    keys = [read_value(wide, v) for v in (wide.value, *wide.accepted)]
    seen: list = []
    for mistake in wide.mistakes:
        value = read_value(wide, mistake.value)
        if any(_reference_match(wide, value, v) for v in (*keys, *seen)) \
                or not _reference_match(wide, value, value):
            return False
        seen.append(value)
    return True


_TOLERANCE = st.sampled_from([0.0, 2**-8, 1e-3, 0.1, 1e300])
_MARGIN = st.sampled_from([0.0, 1.0, 2.0, 5.0, -1.0, math.nan, math.inf])


@st.composite
def _near_values(draw, kind: str) -> tuple:
    """A key, mistakes around it (some exactly a power-of-two step away, at the edge of a
    tolerance of powers of two) and the tolerances."""
    n = 3 if kind == "vector" else 1
    key = np.array(draw(st.lists(st.floats(-4, 4), min_size=n, max_size=n)))
    steps = draw(st.lists(st.lists(st.sampled_from([0.0, 2**-9, -2**-8, 2**-7, 1e-3, 3.0]),
                                   min_size=n, max_size=n), min_size=1, max_size=5))
    mistakes = [key + np.array(step) for step in steps]
    as_plain = (lambda a: a.tolist()) if kind == "vector" else (lambda a: float(a[0]))
    return as_plain(key), [as_plain(m) for m in mistakes], draw(_TOLERANCE), draw(_TOLERANCE)


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(["scalar", "angle", "vector"]).flatmap(
    lambda kind: st.tuples(st.just(kind), _near_values(kind), _MARGIN)))
def test_distinguishing_mistakes_compares_as_before(case):
    """The key against each mistake (at construction: refused or not, with the same message)
    and mistakes_distinguishable, for every margin, against the comparisons spelled out."""
    kind, (key, values, rtol, atol), margin = case
    mistakes = tuple(Mistake(f"m{i}", v, "?") for i, v in enumerate(values))
    try:
        answer = Answer("x", kind, key, rtol=rtol, atol=atol, mistakes=mistakes)
    except ParameterError as err:
        if err.parameter == "atol":  # a zero key without atol: refused before any mistake
            assert atol == 0 and not np.any(key)
            return
        read = (lambda v: np.array(v)) if kind == "vector" else (lambda v: v)
        tolerances = SimpleNamespace(kind=kind, rtol=rtol, atol=atol)
        first = next(m for m in mistakes
                     if _reference_match(tolerances, read(m.value), read(key)))
        assert str(err) == (f"mistakes: answer 'x': mistake {first.name!r} is "
                            "indistinguishable from the key within tolerance")
        return
    assert mistakes_distinguishable(answer, margin) == _reference_distinguishable(answer, margin)


@pytest.mark.parametrize("value", [0.0, -0.0, 5e-324, 1e-3, 1.7e308, 1, np.float64(2e-3),
                                   math.inf, -math.inf, math.nan, -1e-300, -1, True, "0.1"])
def test_a_tolerance_is_refused_or_kept_as_before(value):
    """rtol, atol and points: kept as float(value) (the very float given) when a finite real
    number ≥ 0, else refused naming the field and the value."""
    ok = not isinstance(value, bool | str) and math.isfinite(value) and value >= 0
    for field in ("rtol", "atol", "points"):
        if not ok:
            with pytest.raises(ParameterError, match=re.escape(
                    f"{field}: answer 'x': must be finite and ≥ 0, got {value!r}")):
                Answer("x", "scalar", 1.0, **{field: value})
            continue
        kept = getattr(Answer("x", "scalar", 1.0, **{field: value}), field)
        assert type(kept) is float and kept == value
        assert math.copysign(1.0, kept) == math.copysign(1.0, value)
        if type(value) is float:
            assert kept is value
