"""Safe reading of expressions: accepted forms, refused injections, bounded evaluation.

References: sympy expressions built directly from the solver's symbols (for what is parsed) and
mpmath evaluation of those at 40 digits (for the float evaluator). Injection attempts are checked
with sentinels: the builtins and ``os.system`` a payload would call are replaced by recorders,
and ``parse_expr`` by a spy, so the test fails if anything in a payload ever runs — or even
reaches sympy.
"""

from __future__ import annotations

import builtins
import os
import time

import mpmath
import numpy as np
import pytest
import sympy as sp

import problems.expressions as expressions
from problems.expressions import (
    MAX_DEPTH,
    MAX_LENGTH,
    ExpressionError,
    check_symbol_names,
    evaluate_expression,
    parse_expression,
    sample_points,
    symbol_table,
)
from solver.symbolic import SYMBOLS

S = SYMBOLS
NAMES = ("I1", "I3", "beta", "b", "alpha_dot", "p_gamma")
MARK = "PWNED"


@pytest.fixture
def points() -> dict[str, np.ndarray]:
    return sample_points(NAMES, "test", 6)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("I1*beta^2", S["I1"] * S["beta"] ** 2),
        ("I1*beta**2/2", S["I1"] * S["beta"] ** 2 / 2),
        ("  (I3 - I1) * alpha_dot  ", (S["I3"] - S["I1"]) * S["alpha_dot"]),
        ("p_gamma**2/(2*I3)", S["p_gamma"] ** 2 / (2 * S["I3"])),
        ("sqrt(I1*I3)*cos(beta)", sp.sqrt(S["I1"] * S["I3"]) * sp.cos(S["beta"])),
        ("-b + 1.5e-3", -S["b"] + sp.Float("1.5e-3")),
        ("2*pi*E", 2 * sp.pi * sp.E),
        ("log(I1, 2) + ln(I3)", sp.log(S["I1"], 2) + sp.log(S["I3"])),
        ("Abs(sin(beta)) + sign(b)", sp.Abs(sp.sin(S["beta"])) + sp.sign(S["b"])),
        (".5*b", S["b"] / 2),
        ("3", sp.Integer(3)),
    ],
)
def test_accepted_expressions_parse_to_the_expected_sympy(text: str, expected: sp.Expr) -> None:
    parsed = parse_expression(text, NAMES)
    assert isinstance(parsed, sp.Expr)
    assert sp.simplify(parsed - expected) == 0


def test_parsed_symbols_are_the_solvers_own() -> None:
    # Same objects, same assumptions: I1 is positive in solver.symbolic.
    assert parse_expression("I1 + beta", NAMES).free_symbols == {S["I1"], S["beta"]}
    assert symbol_table(["I1", "zeta"])["zeta"] == sp.Symbol("zeta", real=True)


@pytest.mark.parametrize(
    "text",
    [
        "sin(b)**2 + cos(b)**2",
        "I1*sin(beta)**2/2 + I3*cos(beta)**2",
        "log(I1, 2) - ln(I3)/3",
        "cot(beta) + sec(b) + csc(beta) + coth(b) + acot(b - 1)",
        "asin(beta/4) + acos(b/3) + atan(b) + asinh(b) + acosh(1 + b) + atanh(b/3)",
        "cbrt(I1) * exp(-b) * tanh(p_gamma) * sinh(b) * cosh(b)",
        "Abs(b - 1) * sign(b - 1) + 2^-b",
        "p_gamma**2/(2*I3) - alpha_dot**(1/2)",
    ],
)
def test_evaluation_matches_mpmath(text: str, points: dict[str, np.ndarray]) -> None:
    got = evaluate_expression(text, NAMES, points)
    expr = parse_expression(text, NAMES)
    mpmath.mp.dps = 40
    for k in range(len(got)):
        subs = {S.get(n, sp.Symbol(n, real=True)): sp.Float(points[n][k], 40) for n in NAMES}
        reference = complex(mpmath.mpmathify(sp.N(expr.subs(subs), 40)))
        assert reference.imag == 0
        assert got[k] == pytest.approx(reference.real, rel=1e-12, abs=1e-14)


def test_equivalent_forms_evaluate_equal(points: dict[str, np.ndarray]) -> None:
    a = evaluate_expression("sin(b)**2", NAMES, points)
    b = evaluate_expression("1 - cos(b)**2", NAMES, points)
    np.testing.assert_allclose(a, b, rtol=1e-12)


def test_undefined_values_come_back_non_finite() -> None:
    pts = {"b": np.array([-1.0, 0.0, 4.0])}
    values = evaluate_expression("sqrt(b)/b", ["b"], pts)
    assert np.isnan(values[0]) and not np.isfinite(values[1]) and values[2] == 0.5


@pytest.fixture
def sentinels(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Record any call a payload could make; record any text that reaches sympy."""
    calls: list[str] = []

    def recorder(name, original):
        def wrapped(*args, **kwargs):
            if any(isinstance(a, str) and MARK in a for a in args):
                calls.append(name)
            return original(*args, **kwargs)

        return wrapped

    for name in ("exec", "eval", "open", "compile", "__import__", "getattr"):
        monkeypatch.setattr(builtins, name, recorder(name, getattr(builtins, name)))
    monkeypatch.setattr(os, "system", recorder("os.system", os.system))

    def spy(text, *args, **kwargs):
        calls.append(f"parse_expr({text!r})")
        raise AssertionError("rejected text reached sympy")

    monkeypatch.setattr(expressions, "parse_expr", spy)
    expressions._checked_tree.cache_clear()
    expressions._sympy_expression.cache_clear()
    return calls


INJECTIONS = [
    f"__import__('os').system('{MARK}')",
    "().__class__.__bases__[0].__subclasses__()",
    "().__class__",
    f"lambda: {MARK}",
    "lambda: 1",
    "I1.b",
    "a.b",
    f"exec('{MARK}')",
    f"eval('{MARK}')",
    f"open('{MARK}')",
    "exec",
    "open",
    f"getattr(I1, '{MARK}')",
    "[1]",
    "I1[0]",
    "{1: 2}",
    '"s"',
    f"'{MARK}'",
    f"I1  # {MARK}",
    "I1; import os",
    "I1 if b else b",
    "(b := 3)",
    "Symbol('x')",  # a sympy name that is in parse_expr's namespace, not in the whitelist
    "Integer",
    "__builtins__",
    "_",
    "I1 @ b",
    "I1 // b",
    "I1 % b",
    "I1 < b",
    "not b",
    "b and I1",
    "2 b",
    "1j*b",
    "0x1F",
    "1_000*b",
    "1e999999",
    "9" * 400,  # a literal too large for a float
    "9**9**9**9",  # a numeric power tower: exact evaluation would never finish
    "exp(-9**9**9)",
    "1/0 + b",
    "sqrt(-1)",
    "theta",
    "β",
    "sin",
    "sin()",
    "sin(b, b)",
    "sin(x=b)",
    "sin(*b)",
    "I1(b)",
    "(b, I1)",
    "b\nI1",
    "b\\",
    "$b",
    "`b`",
    "b!",
    "",
    "   ",
    "sin(" * 250 + "b" + ")" * 250,  # nested too deeply
    "-" * 500 + "b",
    "b + " * (MAX_LENGTH // 4) + "b",  # too long
]


@pytest.mark.parametrize("text", INJECTIONS, ids=lambda t: repr(t)[:40])
def test_injections_are_refused_before_sympy(text: str, sentinels: list[str]) -> None:
    with pytest.raises(ExpressionError) as err:
        parse_expression(text, NAMES)
    assert str(err.value)
    with pytest.raises(ExpressionError):
        evaluate_expression(text, NAMES, sample_points(NAMES, "x", 3))
    assert sentinels == []


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("theta*I1", "unknown symbol 'theta' — allowed symbols: I1, I3, beta"),
        ("I1.real", "'.' is not allowed"),
        ("lambda: 1", "'lambda' is not allowed"),
        ("__import__('os')", "'__import__' is not allowed"),
        ("[1]", "'[' is not allowed"),
        ("1e999999", "too large"),
        ("9**9**9", "not a finite number"),
        ("x" * (MAX_LENGTH + 1), "too long"),
        ("2 b", "write products with *"),
        ("sin(b, b)", "sin takes 1 argument"),
    ],
)
def test_messages_name_the_offending_token(text: str, fragment: str) -> None:
    with pytest.raises(ExpressionError, match=None) as err:
        parse_expression(text, NAMES)
    assert fragment in str(err.value)


@pytest.mark.parametrize(
    "text",
    [
        "I1**I1**I1**I1**1000",
        "exp(exp(exp(exp(b*1000))))",
        "+".join(["I1**I1**I1**I1**I1**I1**I1"] * 70),  # ~2000 characters of towers
        "*".join(["sin(cos(tan(exp(b))))"] * 90),
    ],
)
def test_resource_bombs_evaluate_quickly(text: str) -> None:
    assert len(text) <= MAX_LENGTH
    pts = sample_points(["I1", "b"], "bomb", 32)
    start = time.perf_counter()
    parse_expression(text, ["I1", "b"])  # unevaluated: nothing is computed exactly
    values = evaluate_expression(text, ["I1", "b"], pts)
    assert time.perf_counter() - start < 1.0
    assert values.shape == (32,)


@pytest.mark.parametrize(
    ("head", "tail"), [("b+", ""), ("-", ""), ("b**", ""), ("sin(", ")"), ("sin(-", ")")]
)
def test_deepest_accepted_nesting_parses_and_evaluates(head: str, tail: str) -> None:
    # Find the deepest nesting of this pattern the depth gate lets through; sympy's parser and
    # the recursive evaluator must both cope with it (no RecursionError).
    for n in range(MAX_DEPTH, 0, -1):
        text = head * n + "b" + tail * n
        try:
            expr = parse_expression(text, ["b"])
        except ExpressionError as err:
            assert "nested too deeply" in str(err)
            continue
        break
    assert n > MAX_DEPTH // 3
    assert isinstance(expr, sp.Expr)
    assert evaluate_expression(text, ["b"], {"b": np.array([0.7])}).shape == (1,)


def test_tower_overflows_instead_of_hanging() -> None:
    pts = sample_points(["I1"], "tower", 8)  # I1 in (1, 2)
    assert np.all(np.isinf(evaluate_expression("I1**I1**I1**I1**1000", ["I1"], pts)))


def test_sample_points_are_reproducible_and_in_range() -> None:
    names = ("I1", "I2", "I3", "beta", "theta0", "gamma", "u", "alpha_dot", "Mgl")
    first, again = sample_points(names, "q1", 200), sample_points(names, "q1", 200)
    other = sample_points(names, "q2", 200)
    for n in names:
        np.testing.assert_array_equal(first[n], again[n])
        assert not np.array_equal(first[n], other[n])
        assert not first[n].flags.writeable
    bounds = {"I1": (1, 2), "beta": (0, np.pi), "theta0": (0, np.pi), "gamma": (0, 2 * np.pi),
              "u": (-1, 1), "alpha_dot": (0, np.inf), "Mgl": (0, np.inf)}
    for n, (low, high) in bounds.items():
        assert np.all((low < first[n]) & (first[n] < high)), n
    i1, i2, i3 = first["I1"], first["I2"], first["I3"]  # R4 triangle inequality at every draw
    assert np.all((i1 + i2 > i3) & (i2 + i3 > i1) & (i3 + i1 > i2))


@pytest.mark.parametrize(
    "symbols",
    [["__class__"], ["_x"], ["sin"], ["pi"], ["lambda"], ["1a"], ["a.b"], ["b", "b"], [3]],
)
def test_bad_symbol_names_are_refused(symbols: list) -> None:
    with pytest.raises(ValueError):
        check_symbol_names(symbols)


def test_non_text_is_refused() -> None:
    with pytest.raises(ExpressionError, match="as text"):
        parse_expression(3.5, NAMES)
