"""Significant-figure rounding and printing, checked against Python's decimal arithmetic.

The reference rounds ``Decimal(x)`` — the exact value of the binary float — to ``sig`` digits
with ROUND_HALF_EVEN, an independent path from the formatted-string rounding under test.
"""

from __future__ import annotations

import math
import re
from decimal import ROUND_HALF_EVEN, Decimal

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from problems.rounding import PLAIN_RANGE, _parts, format_sig, latex_sig, round_sig
from solver.parameters import ParameterError


def decimal_round(x: float, sig: int) -> float:
    """``x`` rounded to ``sig`` significant digits in exact decimal arithmetic."""
    exact = Decimal(x)
    if exact == 0:
        return 0.0
    quantum = Decimal(1).scaleb(exact.adjusted() - sig + 1)
    return float(exact.quantize(quantum, rounding=ROUND_HALF_EVEN))


def latex_to_float(text: str) -> float:
    text = re.sub(r"^(-?)10\^\{(-?\d+)\}$", r"\g<1>1e\2", text)
    return float(re.sub(r" \\times 10\^\{(-?\d+)\}$", r"e\1", text))


@pytest.fixture(scope="module")
def samples() -> np.ndarray:
    """Numbers over 40 decades, both signs, plus decimal-looking values near ties."""
    rng = np.random.default_rng(20240611)
    spread = rng.uniform(1, 10, 400) * 10.0 ** rng.integers(-20, 20, 400)
    signs = rng.choice([-1.0, 1.0], 400)
    near_ties = np.round(rng.uniform(0, 100, 100), 3) + 0.0005  # e.g. 12.3455: looks like a tie
    return np.concatenate([spread * signs, near_ties, [0.0, 9.9995, 99999.5, 0.00099995]])


@pytest.mark.parametrize("sig", [1, 2, 3, 4, 6, 9])
def test_round_sig_matches_exact_decimal_rounding(samples: np.ndarray, sig: int) -> None:
    expected = [decimal_round(x, sig) for x in samples.tolist()]
    np.testing.assert_array_equal(round_sig(samples, sig), expected)


@pytest.mark.parametrize("sig", [1, 2, 3, 4, 6, 9])
def test_one_number_at_a_time_matches_exact_decimal_rounding(samples: np.ndarray,
                                                              sig: int) -> None:
    """A float (or numpy float) takes a shorter path than an array: the same rounding."""
    for x in samples.tolist():
        for value in (x, np.float64(x)):
            r = round_sig(value, sig)
            assert type(r) is float and r == decimal_round(x, sig), (x, sig)
    assert math.copysign(1.0, round_sig(-0.0, sig)) == -1.0


@pytest.mark.parametrize("sig", [1, 2, 3, 4, 6, 9])
@pytest.mark.parametrize("trailing_zeros", [False, True])
def test_displayed_string_is_the_rounded_value(
    samples: np.ndarray, sig: int, trailing_zeros: bool
) -> None:
    for x in samples.tolist():
        r = round_sig(x, sig)
        assert float(format_sig(x, sig, trailing_zeros=trailing_zeros)) == r, x
        assert latex_to_float(latex_sig(x, sig, trailing_zeros=trailing_zeros)) == r, x


@pytest.mark.parametrize(
    ("x", "sig", "expected"),
    [
        (0.125, 2, 0.12),  # an exact binary tie: half to even
        (0.375, 2, 0.38),
        (2.675, 3, 2.67),  # 2.675 is stored as 2.67499999…
        (9.996, 3, 10.0),  # carries into a new decade
        (-1234.5678, 2, -1200.0),
        (6.02214076e23, 3, 6.02e23),
    ],
)
def test_round_sig_known_values(x: float, sig: int, expected: float) -> None:
    assert round_sig(x, sig) == expected


def test_round_sig_shapes() -> None:
    assert isinstance(round_sig(3.14159, 3), float)
    grid = np.full((2, 3), math.pi)
    out = round_sig(grid, 3)
    assert out.shape == (2, 3)
    np.testing.assert_array_equal(out, 3.14)


@pytest.mark.parametrize(
    ("x", "sig", "plain", "latex"),
    [
        (0.1 + 0.2, 3, "0.3", "0.3"),  # no floating-point noise digits
        (1234.5678, 3, "1230", "1230"),
        (2.0, 3, "2", "2"),
        (-0.25, 2, "-0.25", "-0.25"),
        (0.0, 3, "0", "0"),
        (-0.0, 3, "0", "0"),
        (PLAIN_RANGE[0], 3, "0.001", "0.001"),
        (0.000999, 3, "9.99e-4", r"9.99 \times 10^{-4}"),
        (99999.7, 3, "1e5", "10^{5}"),  # the rounded value decides the notation
        (6.02214076e23, 4, "6.022e23", r"6.022 \times 10^{23}"),
        (-1.602176634e-19, 2, "-1.6e-19", r"-1.6 \times 10^{-19}"),
        (1e-7, 2, "1e-7", "10^{-7}"),
    ],
)
def test_format_sig_examples(x: float, sig: int, plain: str, latex: str) -> None:
    assert format_sig(x, sig) == plain
    assert latex_sig(x, sig) == latex


@pytest.mark.parametrize(
    ("x", "sig", "expected"),
    [(2.5, 3, "2.50"), (1.0, 2, "1.0"), (1.0e5, 3, "1.00e5"), (0.00123, 4, "0.001230")],
)
def test_format_sig_trailing_zeros(x: float, sig: int, expected: str) -> None:
    assert format_sig(x, sig, trailing_zeros=True) == expected


@pytest.mark.parametrize(
    ("x", "sig", "parameter"),
    [
        (float("nan"), 3, "x"),
        (float("inf"), 3, "x"),
        ("1.5", 3, "x"),
        (1.5, 0, "sig"),
        (1.5, 2.5, "sig"),
        (1.5, True, "sig"),
    ],
)
def test_bad_input_is_refused(x: object, sig: object, parameter: str) -> None:
    with pytest.raises(ParameterError) as err:
        round_sig(x, sig)
    assert err.value.parameter == parameter
    with pytest.raises(ParameterError):
        format_sig(x, sig)


def test_format_sig_wants_one_number() -> None:
    with pytest.raises(ParameterError, match="single number"):
        format_sig([1.0, 2.0], 3)


def _decimal_parts(x: float, sig: int, trailing_zeros: bool) -> tuple[str, int | None]:
    """:func:`problems.rounding._parts` as written before issue 34: positional notation by
    ``Decimal`` (normalized, without trailing zeros, unless ``trailing_zeros``)."""
    text = f"{x:.{sig - 1}e}"
    mantissa, exponent = text.split("e")
    magnitude = abs(float(text))
    if magnitude == 0 or PLAIN_RANGE[0] <= magnitude < PLAIN_RANGE[1]:
        number = Decimal(text) if trailing_zeros else Decimal(text).normalize()
        return ("0" if float(text) == 0 else f"{number:f}"), None
    if not trailing_zeros and "." in mantissa:
        mantissa = mantissa.rstrip("0").rstrip(".")
    return mantissa, int(exponent)


_DECADES = st.builds(lambda m, e: m * 10.0 ** e, st.floats(-10, 10), st.integers(-6, 7))


@settings(max_examples=1000, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False) | _DECADES, st.integers(1, 32),
       st.booleans())
def test_positional_digits_are_the_decimal_modules(x: float, sig: int,
                                                   trailing_zeros: bool) -> None:
    """The digits and point placed by string work, as ``Decimal`` places them (past 28
    figures, the context's precision, ``normalize`` rounds: the Decimal path is kept there)."""
    assert _parts(x, sig, trailing_zeros) == _decimal_parts(x, sig, trailing_zeros)


@pytest.mark.parametrize("sig", [1, 3, 17, 29])
def test_one_number_is_rounded_as_an_array_of_it(sig: int) -> None:
    """A plain float's shortest path, a numpy float's and an array's give the same float."""
    for x in (2.675, -0.0, 1.5e-310, -1e300, 9.9995):
        array = round_sig(np.array([x]), sig)
        for value in (x, np.float64(x)):
            r = round_sig(value, sig)
            assert type(r) is float and r == array[0]
            assert math.copysign(1.0, r) == math.copysign(1.0, array[0])
