"""The self-test every problem template must pass (PrairieLearn's ``test(data)``, over many seeds).

Parametrised over ``problems.templates.FAMILIES`` × :data:`SEEDS`, so a new template is picked
up as soon as it is in the catalogue. For each variant:

- tolerances are between 1e-9 (or an atol) and 2 %, points positive; the key's answer is
  graded correct, a value just inside the tolerance too, and one ten
  tolerances away is wrong;
- every known mistake's value is graded wrong *and recognised by its own name* (so the mistakes
  of an answer are distinguishable from each other as well as from the key);
- malformed values (NaN, infinity, a string, a wrong shape, a wrong type) are invalid, with a
  message, no points, and never mistaken for a mistake;
- parameters are exactly the rounded values shown: each number is its own rounding to at most
  :data:`MAX_SIG` significant figures and appears in the statement (as ``format_sig`` or
  ``latex_sig`` prints it), and each parameter's Python name appears in the statement in
  backticks (`` `I1` ``), which is how the statement ties its symbols to the parameter cell;
- answer names make valid, unique notebook variables; the variant round-trips through JSON;
- a seed always gives the same variant, and different seeds give different variants.

Independent checks of the answers' *values* are per template, in ``test_template_<name>.py``.
"""

from __future__ import annotations

import json
import keyword
import math
import re
from functools import cache

import numpy as np
import pytest

from problems.answers import KINDS, Answer, check_form, grade
from problems.rounding import round_sig
from problems.selftest import numbers_in
from problems.templates import FAMILIES
from problems.variant import Variant, variable_name

SEEDS = range(50)
MAX_SIG = 4
FAR = 10.0  # a perturbation of this many tolerances is wrong
NEAR = 0.5  # one of this fraction of the tolerance is right

CASES = [(family, seed) for family in FAMILIES for seed in SEEDS]
CASE_IDS = [f"{family}-{seed}" for family, seed in CASES]


@cache
def variant_of(family: str, seed: int) -> Variant:
    """The variant of ``family`` for ``seed`` (cached: each is generated once per session)."""
    return FAMILIES[family].generate(np.random.default_rng(seed))


@pytest.fixture(params=CASES, ids=CASE_IDS)
def variant(request) -> Variant:
    return variant_of(*request.param)


# --------------------------------------------------------------------------------------------
# Values built from an answer: shifted by a multiple of its tolerance, and malformed


def _direction(n: int) -> np.ndarray:
    """A fixed unit vector of length ``n`` with no zero component."""
    d = np.array([(-1.0) ** k * (k + 1) for k in range(n)])
    return d / np.linalg.norm(d)


def shifted(answer: Answer, factor: float):
    """The key moved by ``factor`` tolerances (``factor`` > 1: outside; < 1: inside)."""
    v, kind = answer.value, answer.kind
    if kind in ("scalar", "angle"):
        return v + factor * (answer.atol + answer.rtol * abs(v))
    if kind == "vector":
        v = np.asarray(v)
        step = factor * (answer.atol + answer.rtol * np.linalg.norm(v))
        return (v + step * _direction(len(v))).tolist()
    if kind == "expression":
        # |x − v| = factor·(rtol |v| + atol) at every point
        return f"({v})*(1 + {factor * answer.rtol!r}) + {factor * answer.atol!r}"
    if abs(factor) < 1:
        return v
    if kind == "boolean":
        return not v
    return next(o for o in answer.options if o != v)  # choice


def malformed(answer: Answer) -> list:
    """Values of the wrong form for ``answer``: each must be graded invalid."""
    v, kind = answer.value, answer.kind
    common = [float("nan"), {"a": 1}]
    if kind in ("scalar", "angle"):
        return [*common, float("inf"), "abc", str(v), [v, v], [v], True]
    if kind == "vector":
        return [*common, "abc", [float("nan")] * len(v), v[:-1], [*v, 0.0], [v], v[0],
                [True] * len(v)]
    if kind == "boolean":
        return [*common, "True", 1, [v]]
    if kind == "choice":
        return [*common, "certainly-not-an-option", 3.0, [v]]
    if kind == "expression":
        return [*common, "no_such_symbol + 1", "__import__('os')", "1/0", [v]]
    raise AssertionError(f"unknown kind {kind}")


# --------------------------------------------------------------------------------------------
# The module's declared attributes


@pytest.mark.parametrize("family", list(FAMILIES))
def test_module_declares_name_title_summary_results(family):
    found = FAMILIES[family]
    assert found.name == family
    for text in (found.title, found.summary):
        assert isinstance(text, str) and text.strip() and "\n" not in text
    assert found.results and all(re.fullmatch(r"R([1-9]|1\d|2[01])", r) for r in found.results)


@pytest.mark.parametrize("family", list(FAMILIES))
def test_seeds_give_different_variants(family):
    texts = {json.dumps(variant_of(family, seed).to_dict(), sort_keys=True) for seed in SEEDS}
    assert len(texts) == len(SEEDS)


@pytest.mark.parametrize("family", list(FAMILIES))
def test_same_seed_same_variant(family):
    for seed in (0, 7, 49):
        again = FAMILIES[family].generate(np.random.default_rng(seed))
        assert again == variant_of(family, seed)
        assert again.to_dict() == variant_of(family, seed).to_dict()


# --------------------------------------------------------------------------------------------
# Every variant


def test_variant_is_of_its_family(variant):
    assert isinstance(variant, Variant)
    assert variant.family in FAMILIES
    assert variant.title.strip() and variant.statement.strip()
    assert all(a.kind in KINDS for a in variant.answers)


def test_answer_names_make_unique_python_variables(variant):
    names = [a.name for a in variant.answers]
    assert len(set(names)) == len(names)
    for name in names:
        var = variable_name(1, name)
        assert var.isidentifier() and not keyword.iskeyword(var)


def test_tolerances_and_points_are_sensible(variant):
    for answer in variant.answers:
        assert answer.points > 0
        if answer.kind in ("scalar", "angle", "vector", "expression"):
            # loose enough for a float computation, tight enough to tell physics apart
            assert 1e-9 <= answer.rtol <= 0.02 or answer.atol > 0, (answer.name, answer.rtol)
            assert answer.rtol <= 0.02, (answer.name, answer.rtol)


def test_key_is_correct_and_a_near_value_too(variant):
    for answer in variant.answers:
        for value in (answer.value, shifted(answer, NEAR)):
            verdict = grade(answer, value)
            assert verdict.status == "correct", (answer.name, value, verdict)
            assert verdict.points == answer.points == verdict.max_points
        assert check_form(answer, answer.value).status == "correct"


def test_far_value_is_wrong(variant):
    for answer in variant.answers:
        for sign in (1, -1) if answer.kind != "expression" else (1,):
            verdict = grade(answer, shifted(answer, sign * FAR))
            assert verdict.status == "wrong", (answer.name, verdict)
            assert verdict.points == 0


def test_every_mistake_is_recognised_by_name(variant):
    for answer in variant.answers:
        for mistake in answer.mistakes:
            verdict = grade(answer, mistake.value)
            assert (verdict.status, verdict.mistake) == ("wrong", mistake.name), \
                (answer.name, mistake.name, verdict)
            assert verdict.points == 0 and mistake.feedback in verdict.message


def test_malformed_values_are_invalid(variant):
    for answer in variant.answers:
        for value in malformed(answer):
            for verdict in (grade(answer, value), check_form(answer, value)):
                assert verdict.status == "invalid", (answer.name, value, verdict)
                assert verdict.points == 0 and verdict.message and verdict.mistake is None
        assert grade(answer, None).status == "missing"


def _leaves(value) -> list[float]:
    if isinstance(value, list):
        return [x for v in value for x in _leaves(v)]
    return [value]


def test_params_are_rounded_and_shown_in_the_statement(variant):
    shown = numbers_in(variant.statement)
    for name, value in variant.params.items():
        assert f"`{name}`" in variant.statement, f"parameter {name} not named in the statement"
        for x in _leaves(value):
            assert isinstance(x, float) and math.isfinite(x)
            assert any(round_sig(x, sig) == x for sig in range(1, MAX_SIG + 1)), (name, x)
            assert abs(x) in shown, f"{name} = {x!r} does not appear in the statement"


def test_variant_round_trips_through_json(variant):
    text = json.dumps(variant.to_dict(), allow_nan=False)
    again = Variant.from_dict(json.loads(text))
    assert again == variant
    assert json.dumps(again.to_dict(), allow_nan=False) == text


def test_numbers_in_reads_plain_scientific_and_latex():
    statement = r"$m_1 = 0.05$ kg (`r1`), $I = 1.2 \times 10^{-5}$, $10^{-7}$, 3e5, -2.5"
    assert numbers_in(statement) == {0.05, 1.2e-5, 1e-7, 3e5, 2.5}
