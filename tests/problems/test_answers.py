"""Answer kinds: reading (missing / invalid) kept apart from judging (correct / wrong).

Every kind is exercised over the same grid of cases: the key itself, a value just inside and
just outside the tolerance (built from the definition ``atol + rtol·|v|``, not from the code),
a plainly wrong value, each known mistake, each malformed form, and a missing value. Messages
are checked for what a student needs (the offending value, the expected shape or options) and
for what they must not see (the key).
"""

from __future__ import annotations

import builtins
import json
import math
import os
import re

import numpy as np
import pytest
import sympy as sp

from problems.answers import (
    KINDS,
    STATUSES,
    Answer,
    Mistake,
    Verdict,
    check_form,
    check_spec,
    comparison_rule,
    grade,
)
from problems.rounding import round_sig
from problems.variant import answer_spec
from solver.parameters import ParameterError
from solver.symbolic import SYMBOLS

TAU = 2 * math.pi
KEY_TEXT = "I1*sin(beta)**2/2 + I3*cos(beta)**2/2"  # R12-like: T of a symmetric top, ω = 1

ANSWERS = {
    "scalar": Answer(
        "omega3", "scalar", 2.71828, unit="rad/s", rtol=1e-3, points=2.0,
        mistakes=(Mistake("rpm", 2.71828 * 60 / TAU, "you gave rev/min; the unit is rad/s"),),
    ),
    "angle": Answer(
        "beta1", "angle", 0.73189, unit="rad", rtol=1e-3, period=TAU,
        mistakes=(Mistake("degrees", math.degrees(0.73189), "that is in degrees; use radians"),),
    ),
    "vector": Answer(
        "omega", "vector", [1.31415, 0.0, -2.71828], unit="rad/s", rtol=1e-3,
        mistakes=(Mistake("sign", [-1.31415, 0.0, 2.71828], "check the sense of rotation"),),
    ),
    "boolean": Answer("loops", "boolean", True),
    "choice": Answer(
        "motion", "choice", "loops", options=("loops", "cusps", "waves"),
        mistakes=(Mistake("cusps", "cusps", "cusps need the top released at rest"),),
    ),
    "expression": Answer(
        "T", "expression", KEY_TEXT, unit="J", rtol=1e-6, symbols=("I1", "I3", "beta"),
        mistakes=(Mistake("no_half", "I1*sin(beta)**2 + I3*cos(beta)**2", "T = ½ ω·Iω"),),
    ),
}

# (kind, submission) -> expected status; mistakes expected by name.
CORRECT = [
    ("scalar", 2.71828),
    ("scalar", 2.71828 * (1 + 0.9e-3)),  # just inside rtol
    ("scalar", 2.71828 * (1 - 0.9e-3)),
    ("scalar", np.float64(2.7183)),
    ("scalar", np.float32(2.71828)),
    ("scalar", np.array(2.71828)),
    ("scalar", sp.Float(2.71828)),
    ("scalar", sp.Rational(271828, 100000)),
    ("angle", 0.73189),
    ("angle", 0.73189 + TAU),  # modulo the period
    ("angle", 0.73189 - 2 * TAU),
    ("angle", 0.73189 * (1 + 0.9e-3) + TAU),
    ("vector", [1.31415, 0.0, -2.71828]),
    ("vector", [1.31415, 1e-12, -2.71828]),  # a zero component needs no exact zero (norm-based)
    ("vector", (1.31415, 0, -2.71828)),
    ("vector", np.array([1.31415, 0.0, -2.71828])),
    ("vector", sp.Matrix([1.31415, 0, -2.71828])),  # column
    ("vector", sp.Matrix([[1.31415, 0, -2.71828]])),  # row
    ("boolean", True),
    ("boolean", np.bool_(True)),
    ("boolean", sp.true),
    ("choice", "loops"),
    ("choice", "  LOOPS "),
    ("expression", KEY_TEXT),
    ("expression", "(I1*(1 - cos(beta)**2) + I3*(1 - sin(beta)**2))/2"),  # same, other form
    ("expression", "0.5*(I1*sin(beta)^2 + I3*cos(beta)^2)"),
    ("expression", f"(1 + 0.9e-6)*({KEY_TEXT})"),  # just inside rtol
    (
        "expression",
        SYMBOLS["I1"] * sp.sin(SYMBOLS["beta"]) ** 2 / 2
        + SYMBOLS["I3"] * sp.cos(SYMBOLS["beta"]) ** 2 / 2,
    ),
]
WRONG = [
    ("scalar", 2.71828 * (1 + 1.1e-3)),  # just outside rtol
    ("scalar", 2.71828 * (1 - 1.1e-3)),
    ("scalar", -2.71828),
    ("scalar", 3),
    ("angle", 0.73189 * (1 + 1.1e-3)),
    ("angle", 0.73189 + math.pi),  # half a period away
    ("angle", -0.73189),
    ("vector", [1.31415 + 1.1e-3 * math.hypot(1.31415, 2.71828), 0.0, -2.71828]),
    ("vector", [2.71828, 0.0, -1.31415]),
    ("boolean", False),
    ("boolean", np.bool_(False)),
    ("choice", "waves"),
    ("expression", f"(1 + 1.1e-6)*({KEY_TEXT})"),  # just outside rtol
    ("expression", "I1*cos(beta)**2/2 + I3*sin(beta)**2/2"),
    ("expression", "3"),
    ("expression", 3.0),
    ("expression", "I1*sqrt(cos(beta))"),  # undefined at some sample points only: wrong
]
MISTAKES = [
    ("scalar", 2.71828 * 60 / TAU, "rpm"),
    ("angle", math.degrees(0.73189) * (1 + 1e-4), "degrees"),
    ("vector", [-1.31415, 0.0, 2.71828], "sign"),
    ("vector", np.array([-1.3142, 0.0, 2.7183]), "sign"),
    ("choice", "Cusps", "cusps"),
    ("expression", "I3*cos(beta)**2 + I1*(1 - cos(beta)**2)", "no_half"),
]
# (kind, submission, fragment the message must contain)
INVALID = [
    ("scalar", "2.71828", "remove the quotes"),
    ("scalar", "e", "not a number"),
    ("scalar", True, "boolean"),
    ("scalar", np.bool_(False), "boolean"),
    ("scalar", float("nan"), "NaN"),
    ("scalar", float("inf"), "infinite"),
    ("scalar", -math.inf, "infinite"),
    ("scalar", np.float64("nan"), "NaN"),
    ("scalar", [2.71828], "single number"),
    ("scalar", np.array([2.71828]), "single number"),
    ("scalar", 2.7 + 0.1j, "real number"),
    ("scalar", {"value": 2.7}, "of type dict"),
    ("scalar", sp.Symbol("x") + 1, "expression in x"),
    ("scalar", 10**400, "too large"),
    ("angle", "0.73", "remove the quotes"),
    ("angle", sp.nan, "NaN"),
    ("vector", [1.0, 2.0], "3 numbers"),
    ("vector", [1.0, 2.0, 3.0, 4.0], "3 numbers"),
    ("vector", [[1.0, 0.0, -2.7]], "flat list"),
    ("vector", np.zeros((3, 1)), "flat list"),
    ("vector", [1.0, "0", -2.7], "component 2"),
    ("vector", [1.0, math.nan, -2.7], "component 2 is NaN"),
    ("vector", [1.0, 0.0, True], "component 3"),
    ("vector", 1.0, "3 numbers"),
    ("vector", [], "3 numbers"),
    ("vector", "[1, 0, 2]", "3 numbers"),
    ("boolean", 1, "True or False"),
    ("boolean", 0, "True or False"),
    ("boolean", "True", "without quotes"),
    ("boolean", "yes", "True or False"),
    ("boolean", [True], "True or False"),
    ("choice", "spiral", "'loops', 'cusps', 'waves'"),
    ("choice", 1, "'loops', 'cusps', 'waves'"),
    ("choice", ["loops"], "'loops', 'cusps', 'waves'"),
    ("expression", "theta*I1", "unknown symbol 'theta' — allowed symbols: I1, I3, beta"),
    ("expression", "I1*", "not a valid expression"),
    ("expression", "1/(beta - beta)", "cannot be evaluated"),
    ("expression", "I1**I1**I1**I1**1000", "cannot be evaluated"),  # overflows everywhere
    ("expression", True, "boolean"),
    ("expression", [1.0], "expression"),
    ("expression", "x" * 3000, "too long"),
]

CASES = (
    [pytest.param(k, v, "correct", None, id=f"{k}-correct-{i}") for i, (k, v) in enumerate(CORRECT)]
    + [pytest.param(k, v, "wrong", None, id=f"{k}-wrong-{i}") for i, (k, v) in enumerate(WRONG)]
    + [pytest.param(k, v, "wrong", m, id=f"{k}-mistake-{m}") for k, v, m in MISTAKES]
    + [pytest.param(k, v, "invalid", None, id=f"{k}-invalid-{i}")
       for i, (k, v, _) in enumerate(INVALID)]
    + [pytest.param(k, None, "missing", None, id=f"{k}-missing") for k in KINDS]
)


def test_every_kind_has_cases() -> None:
    for table in (CORRECT, WRONG, INVALID):
        assert {k for k, *_ in table} == set(KINDS)
    assert {k for k, *_ in MISTAKES} == {k for k, a in ANSWERS.items() if a.mistakes}


@pytest.mark.parametrize(("kind", "submitted", "status", "mistake"), CASES)
def test_grade(kind: str, submitted: object, status: str, mistake: str | None) -> None:
    answer = ANSWERS[kind]
    verdict = grade(answer, submitted)
    assert verdict.status == status, verdict.message
    assert verdict.mistake == mistake
    assert verdict.points == (answer.points if status == "correct" else 0.0)
    assert verdict.max_points == answer.points
    assert verdict.message
    if mistake:
        assert verdict.message == next(m.feedback for m in answer.mistakes if m.name == mistake)


@pytest.mark.parametrize(("kind", "submitted", "fragment"), [i[:3] for i in INVALID])
def test_invalid_messages_say_why(kind: str, submitted: object, fragment: str) -> None:
    verdict = grade(ANSWERS[kind], submitted)
    assert verdict.status == "invalid"
    assert fragment in verdict.message


@pytest.mark.parametrize(("kind", "submitted", "status", "mistake"), CASES)
def test_messages_never_show_the_key(
    kind: str, submitted: object, status: str, mistake: str | None
) -> None:
    if status == "correct" or mistake:
        return  # the echo of a correct value is the student's own; feedback is the template's
    message = grade(ANSWERS[kind], submitted).message
    for leak in ("2.718", "0.7318", "1.314", KEY_TEXT, "I1*sin(beta)**2/2"):
        if leak not in str(submitted):
            assert leak not in message


@pytest.mark.parametrize(("kind", "submitted", "status", "mistake"), CASES)
def test_check_form_reads_but_never_judges(
    kind: str, submitted: object, status: str, mistake: str | None
) -> None:
    answer = ANSWERS[kind]
    checked = check_form(answer, submitted)
    assert checked.points == 0.0
    if status in ("missing", "invalid"):
        assert checked == grade(answer, submitted)  # the same reading step, the same message
    else:
        assert checked.status == "correct"  # well formed, right or wrong
        assert checked.mistake is None
        assert checked.message.startswith("well formed")
    # eulertop check has only the public spec (no key, no mistakes): same outcome.
    spec = answer_spec(answer, 1)
    assert "value" not in spec and "mistakes" not in spec
    assert check_spec(spec, submitted).status == checked.status


def test_angle_without_period_is_not_modular() -> None:
    answer = Answer("beta", "angle", 0.73189)
    assert grade(answer, 0.73189 + TAU).status == "wrong"
    assert grade(answer, 0.73189).status == "correct"


@pytest.mark.parametrize(
    ("submitted", "status"),
    [
        (0.005, "correct"),
        (TAU - 0.005, "correct"),  # wraps across 0: difference −0.005 modulo 2π
        (-0.005 + 3 * TAU, "correct"),
        (TAU - 0.02, "wrong"),
        (math.pi, "wrong"),
    ],
)
def test_angle_wraps_across_zero(submitted: float, status: str) -> None:
    answer = Answer("alpha", "angle", 0.0, atol=0.01, period=TAU)
    assert grade(answer, submitted).status == status


def test_absolute_tolerance_for_a_zero_key() -> None:
    answer = Answer("omega2", "scalar", 0.0, atol=1e-6)
    assert grade(answer, 9e-7).status == "correct"
    assert grade(answer, -1.1e-6).status == "wrong"


def test_sympy_number_for_an_angle() -> None:
    answer = Answer("beta", "angle", math.pi / 3, period=TAU)
    assert grade(answer, sp.pi / 3).status == "correct"
    assert grade(answer, sp.pi / 3 + 2 * sp.pi).status == "correct"


def test_grading_is_deterministic() -> None:
    answer = ANSWERS["expression"]
    submitted = f"(1 + 0.99e-6)*({KEY_TEXT})"
    assert grade(answer, submitted) == grade(answer, submitted)
    assert Answer.from_dict(answer.to_dict()) == answer


# ---------------------------------------------------------------- injections through grade


@pytest.fixture
def sentinel(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    calls: list[str] = []

    def recorder(name, original):
        def wrapped(*args, **kwargs):
            if any(isinstance(a, str) and "PWNED" in a for a in args):
                calls.append(name)
            return original(*args, **kwargs)

        return wrapped

    for name in ("exec", "eval", "open", "__import__"):
        monkeypatch.setattr(builtins, name, recorder(name, getattr(builtins, name)))
    monkeypatch.setattr(os, "system", recorder("os.system", os.system))
    return calls


@pytest.mark.parametrize(
    "payload",
    [
        "__import__('os').system('PWNED')",
        "().__class__.__base__.__subclasses__()",
        "lambda: 1",
        "exec('PWNED')",
        "open('PWNED')",
        "I1.conjugate()",
        "[1]",
        "'PWNED'",
        "9**9**9**9",
        "1e999999",
        "b" * 5000,
    ],
)
def test_injections_are_invalid_and_never_run(payload: str, sentinel: list[str]) -> None:
    verdict = grade(ANSWERS["expression"], payload)
    assert verdict.status == "invalid"
    assert verdict.message
    assert sentinel == []


# ---------------------------------------------------------------- records and JSON


@pytest.mark.parametrize("kind", KINDS)
def test_answer_round_trips_through_json(kind: str) -> None:
    answer = ANSWERS[kind]
    again = Answer.from_dict(json.loads(json.dumps(answer.to_dict())))
    assert again == answer
    assert grade(again, None) == grade(answer, None)


def test_numpy_and_sympy_keys_are_stored_as_plain_json() -> None:
    vector = Answer("L", "vector", np.array([1.0, 2.0, 3.0]), mistakes=(
        Mistake("neg", np.array([-1.0, -2.0, -3.0]), "sign"),))
    scalar = Answer("E", "scalar", np.float32(1.5))
    expression = Answer("T", "expression", SYMBOLS["I1"] * SYMBOLS["beta"] ** 2, symbols=(
        "I1", "beta"))
    assert vector.value == [1.0, 2.0, 3.0] and vector.mistakes[0].value == [-1.0, -2.0, -3.0]
    assert type(scalar.value) is float
    assert expression.value == "I1*beta**2"
    for answer in (vector, scalar, expression):
        assert Answer.from_dict(json.loads(json.dumps(answer.to_dict()))) == answer


@pytest.mark.parametrize(
    "verdict",
    [
        Verdict("correct", 2.0, 2.0, "correct"),
        Verdict("wrong", 0.0, 1.0, "that is in degrees", mistake="degrees"),
        Verdict("invalid", 0, 1, "the string '3.2', not a number — remove the quotes"),
        Verdict("missing", 0.0, 0.5, "no answer"),
    ],
)
def test_verdict_round_trips_through_json(verdict: Verdict) -> None:
    assert Verdict.from_dict(json.loads(json.dumps(verdict.to_dict()))) == verdict
    assert verdict.status in STATUSES


@pytest.mark.parametrize(
    "fields",
    [
        {"status": "partial", "points": 0.0, "max_points": 1.0, "message": ""},
        {"status": "correct", "points": 2.0, "max_points": 1.0, "message": ""},
        {"status": "wrong", "points": -1.0, "max_points": 1.0, "message": ""},
        {"status": "wrong", "points": 0.0, "max_points": 1.0, "message": None},
        {"status": "wrong", "points": 0.0, "max_points": 1.0, "message": "", "extra": 1},
    ],
)
def test_bad_verdicts_are_refused(fields: dict) -> None:
    with pytest.raises(ParameterError):
        Verdict.from_dict(fields)


# ---------------------------------------------------------------- validation of Answer records


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        ({"kind": "matrix", "value": 1.0}, "kind"),
        ({"kind": "scalar", "value": 1.0, "rtol": -1e-3}, "rtol"),
        ({"kind": "scalar", "value": 1.0, "rtol": math.nan}, "rtol"),
        ({"kind": "scalar", "value": 1.0, "atol": True}, "atol"),
        ({"kind": "scalar", "value": 1.0, "points": -1}, "points"),
        ({"kind": "scalar", "value": "1.0"}, "value"),
        ({"kind": "scalar", "value": math.nan}, "value"),
        ({"kind": "scalar", "value": None}, "value"),
        ({"kind": "scalar", "value": 0.0}, "atol"),  # a zero key needs atol
        ({"kind": "angle", "value": -0.0}, "atol"),
        ({"kind": "scalar", "value": 1.0, "rtol": math.inf}, "rtol"),
        ({"kind": "scalar", "value": 1.0, "rtol": np.float64(math.nan)}, "rtol"),
        ({"kind": "vector", "value": [0.0, 0.0]}, "atol"),
        ({"kind": "vector", "value": []}, "value"),
        ({"kind": "vector", "value": [[1.0, 2.0]]}, "value"),
        ({"kind": "angle", "value": 1.0, "period": 0.0}, "period"),
        ({"kind": "scalar", "value": 1.0, "period": TAU}, "period"),
        ({"kind": "scalar", "value": 1.0, "options": ("a",)}, "options"),
        ({"kind": "boolean", "value": 1}, "value"),
        ({"kind": "choice", "value": "a"}, "options"),
        ({"kind": "choice", "value": "d", "options": ("a", "b")}, "value"),
        ({"kind": "choice", "value": "a", "options": ("a", " A")}, "options"),
        ({"kind": "choice", "value": "a", "options": ("a", "")}, "options"),
        ({"kind": "expression", "value": "I1"}, "symbols"),
        ({"kind": "expression", "value": "I1", "symbols": ("__class__",)}, "symbols"),
        ({"kind": "expression", "value": "theta", "symbols": ("I1",)}, "value"),
        ({"kind": "expression", "value": "sqrt(-I1)", "symbols": ("I1",)}, "value"),
        ({"kind": "expression", "value": "I1 - I1", "symbols": ("I1",)}, "atol"),
        # defined at too few sample points (u = cos β in (−0.9, 0.9)), whatever atol is
        ({"kind": "expression", "value": "sqrt(u - 0.85)", "symbols": ("u",), "atol": 1.0},
         "value"),
        ({"kind": "scalar", "value": 1.0, "mistakes": (Mistake("same", 1.0004, "x"),)},
         "mistakes"),
        ({"kind": "scalar", "value": 1.0, "mistakes": (Mistake("bad", "2", "x"),)}, "mistakes"),
        ({"kind": "scalar", "value": 1.0,
          "mistakes": (Mistake("a", 2.0, "x"), Mistake("a", 3.0, "y"))}, "mistakes"),
        ({"kind": "scalar", "value": 1.0, "mistakes": ("degrees",)}, "mistakes"),
        ({"kind": "angle", "value": 0.5, "period": TAU,
          "mistakes": (Mistake("turn", 0.5 + TAU, "x"),)}, "mistakes"),
        ({"kind": "expression", "value": "sin(b)**2", "symbols": ("b",),
          "mistakes": (Mistake("same", "1 - cos(b)**2", "x"),)}, "mistakes"),
    ],
)
def test_bad_answers_are_refused(kwargs: dict, parameter: str) -> None:
    with pytest.raises(ParameterError) as err:
        Answer("x", **kwargs)
    assert err.value.parameter == parameter


@pytest.mark.parametrize(
    ("fields", "parameter"),
    [
        ({"name": "x", "kind": "scalar", "value": 1.0, "tolerance": 0.1}, "answer"),
        ({"name": "x", "kind": "scalar", "value": 1.0,
          "mistakes": [{"name": "m", "value": 2.0, "feedback": "f", "hint": ""}]}, "mistake"),
        ({"name": "x", "kind": "scalar", "value": 1.0,
          "mistakes": [{"name": "", "value": 2.0, "feedback": "f"}]}, "mistakes"),
        ({"name": "x", "kind": "scalar", "value": 1.0,
          "mistakes": [{"name": "m", "value": 2.0, "feedback": ""}]}, "mistakes"),
        ({"name": "not an identifier", "kind": "scalar", "value": 1.0}, "name"),
    ],
)
def test_bad_key_records_are_refused(fields: dict, parameter: str) -> None:
    with pytest.raises(ParameterError) as err:
        Answer.from_dict(fields)
    assert err.value.parameter == parameter


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize(
    "oddity", [object(), b"2.7", {1, 2}, range(3), np.array(["a", "b", "c"]), sp.zoo, sp.I],
    ids=["object", "bytes", "set", "range", "str-array", "zoo", "I"],
)
def test_unforeseen_values_are_invalid_not_a_crash(kind: str, oddity: object) -> None:
    verdict = grade(ANSWERS[kind], oddity)
    assert verdict.status == "invalid" and verdict.message and verdict.points == 0.0


# --- how an answer is compared, in words (issue 13) ------------------------------------------


@pytest.mark.parametrize(("answer", "words"), [
    (Answer("T", "scalar", 2.0, unit="J"), ["within 0.1 %"]),
    (Answer("w", "scalar", 2.0, unit="rad/s", rtol=1e-2, atol=0.00654),
     ["within 1 % + 0.00654 rad/s"]),
    (Answer("k", "scalar", 2.0, rtol=0.0, atol=0.01), ["within 0.01 (absolute)"]),
    (Answer("L", "vector", [1.0, 2.0, 2.0], rtol=2e-3), ["within 0.2 % of its length"]),
    (Answer("b", "angle", 1.0, unit="rad"), ["in radians", "within 0.1 %", "not modulo 2π"]),
    (Answer("b", "angle", 1.0, unit="rad", period=2 * math.pi), ["in radians", "modulo 2π"]),
    (Answer("s", "boolean", True), ["True or False"]),
    (Answer("c", "choice", "a", options=("a", "b")), ["one of the options"]),
    (Answer("e", "expression", "x**2", symbols=("x",), rtol=1e-6),
     ["random values of its symbols", "within 0.0001 %"]),
])
def test_comparison_rule_is_derived_from_the_answer(answer, words):
    rule = comparison_rule(answer)
    assert all(w in rule for w in words), rule
    assert "modulo" not in rule or answer.period is not None or "not modulo" in rule


def test_comparison_rule_follows_the_tolerance_that_grades():
    """The words and the comparison agree: a value just inside the stated tolerance is correct,
    just outside is not."""
    answer = Answer("w", "scalar", 2.0, unit="rad/s", rtol=1e-2, atol=0.005)
    assert "within 1 % + 0.005 rad/s" in comparison_rule(answer)
    edge = 2.0 * 1.01 + 0.005
    assert grade(answer, edge * (1 - 1e-9)).status == "correct"
    assert grade(answer, edge * (1 + 1e-6)).status == "wrong"


# --- an answer rounded to too few figures (issue 13) ------------------------------------------


@pytest.mark.parametrize(("key", "submitted", "figures"), [
    (0.0123456, 0.012, "2 significant figures"),
    (0.0123456, 0.0123, "3 significant figures"),
    (-5432.1, -5400.0, "2 significant figures"),
    (9.87654, 9.8, "2 significant figures"),       # cut, not rounded (9.9)
    (2.71828e-5, 2.7e-5, "2 significant figures"),
])
def test_a_scalar_rounded_too_far_is_told_so(key, submitted, figures):
    answer = Answer("x", "scalar", key, unit="J")
    verdict = grade(answer, submitted)
    assert (verdict.status, verdict.mistake) == ("wrong", "too_few_figures")
    assert f"rounded to {figures}" in verdict.message
    # the advice: keeping N figures is safe with a figure to spare, and not excessive
    keep = int(re.search(r"keep at least (\d+) figures", verdict.message).group(1))
    assert grade(answer, round_sig(key, keep)).status == "correct"
    assert grade(answer, round_sig(key, keep - 1)).status == "correct"
    assert keep <= 5  # 0.1 % never needs more than four figures for rounding
    assert repr(key) not in verdict.message and f"{key:.4g}" not in verdict.message


def test_a_vector_rounded_to_few_decimals_is_told_so():
    answer = Answer("L", "vector", [1.23456, -0.0234567, 5.4321], unit="kg m^2/s")
    verdict = grade(answer, [1.2, 0.0, 5.4])
    assert verdict.mistake == "too_few_figures" and "1 decimal" in verdict.message


@pytest.mark.parametrize("submitted", [
    3.0,        # one figure: any small integer would "match"; just wrong
    2.7185,     # five figures, but not the key's: a wrong computation
    2.8,        # two figures, but not the key rounded (2.7) nor cut
    -2.7,       # the sign is wrong
])
def test_a_wrong_value_that_is_not_the_key_rounded_is_just_wrong(submitted):
    verdict = grade(Answer("e", "scalar", 2.71828, rtol=1e-5), submitted)
    assert verdict.status == "wrong" and verdict.mistake is None
    assert "not within the tolerance" in verdict.message


def test_a_known_mistake_is_named_before_rounding_is_considered():
    answer = Answer("w", "scalar", 2.5, mistakes=(Mistake("rpm", 24.0, "rad/s, not rpm"),))
    assert grade(answer, 24.0).mistake == "rpm"


@pytest.mark.parametrize("build", [
    lambda feedback: Answer("T", "expression", "I1*w**2/2 + I3*v**2/2",
                            symbols=("I1", "I3", "w", "v"),
                            mistakes=(Mistake("half", "I1*w**2 + I3*v**2", feedback),)),
    lambda feedback: Answer("stable", "boolean", True, mistakes=(Mistake("no", False, feedback),)),
    lambda feedback: Answer("motion", "choice", "loops", options=("loops", "cusps", "waves"),
                            mistakes=(Mistake("cusp", "cusps", feedback),)),
])
def test_an_answer_whose_checks_are_kept_is_the_one_checked_afresh(build):
    """Expression, boolean and choice answers keep the outcome of their checks by what decides
    it (problems.answers._CHECKED): built again, from what was kept, an answer is the one the
    checks make with nothing kept, and each keeps its own mistakes' feedback."""
    from problems import answers

    answers._CHECKED.clear()
    fresh = build("first")
    assert answers._CHECKED  # the outcome was kept
    again = build("other words")
    answers._CHECKED.clear()
    assert again.to_dict() == build("other words").to_dict()
    assert again.to_dict() != fresh.to_dict()
    assert [m.feedback for m in again.mistakes] == ["other words"]


def test_a_value_equal_to_a_checked_one_but_of_another_type_is_checked_again():
    """1 == True (and hashes the same), but 1 is no boolean answer: the kept outcome of True
    does not let it through."""
    Answer("stable", "boolean", True)
    with pytest.raises(ParameterError, match="value"):
        Answer("stable", "boolean", 1)
