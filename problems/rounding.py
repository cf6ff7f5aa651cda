"""Rounding parameters to the significant figures a student sees, and printing them.

The rule of a family (``problems/API.md``, "A family"): parameters are rounded to the digits
shown in the statement, and answers are computed from the rounded values. So the rounded *value*
and the displayed *string* must be the same number: :func:`round_sig` returns ``float(s)`` where
``s`` is the decimal string with ``sig`` significant digits, and :func:`format_sig` prints
exactly that number, so ``float(format_sig(x, sig)) == round_sig(x, sig)`` for every finite
``x``.

Rounding is Python's correctly rounded decimal conversion (``f"{x:.{sig-1}e}"``): it rounds the
exact binary value of ``x``, ties to even. A number that looks like a tie in decimal usually is
not one in binary: ``2.675`` is stored as ``2.67499999…`` and rounds to ``2.67``.
"""

from __future__ import annotations

import math
import numbers
from decimal import Decimal, getcontext
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.parameters import ParameterError, as_real

__all__ = ["PLAIN_RANGE", "format_sig", "latex_sig", "round_sig"]

PLAIN_RANGE = (1e-3, 1e5)
"""Rounded magnitudes in ``[low, high)`` print positionally (``0.00123``, ``12300``); others, in
scientific notation (``1.23e-4``, ``1.23e5``). Zero prints as ``0``."""


_FLOATS = frozenset({float, np.float64})
"""Types of one number whose ``float`` is its value (no ``__float__`` of a subclass)."""


def _check_sig(sig: int) -> int:
    if type(sig) is int and sig >= 1:
        return sig
    if isinstance(sig, bool) or not isinstance(sig, numbers.Integral) or sig < 1:
        raise ParameterError("sig", f"must be an integer ≥ 1, got {sig!r}")
    return int(sig)


def _digits(x: float, sig: int) -> str:
    """``x`` correctly rounded to ``sig`` significant digits, as ``d.ddde±XX``."""
    return f"{x:.{sig - 1}e}"


def round_sig(x: ArrayLike, sig: int) -> float | NDArray[np.float64]:
    """Round to ``sig`` significant figures, exactly as :func:`format_sig` displays the value.

    Parameters
    ----------
    x : array_like
        Finite real numbers (any shape).
    sig : int
        Significant figures, ≥ 1.

    Returns
    -------
    float or ndarray
        A float for scalar input, else an array of ``x``'s shape.

    Raises
    ------
    solver.parameters.ParameterError
        ``x`` not finite or not real; ``sig`` not a positive integer.

    Examples
    --------
    >>> round_sig(1234.5678, 3)
    1230.0
    >>> round_sig([0.000123456, -9.996], 3).tolist()
    [0.000123, -10.0]
    """
    sig = _check_sig(sig)
    if type(x) in _FLOATS and math.isfinite(x):  # as_real's array holds float(x)
        return float(_digits(float(x), sig))
    if isinstance(x, float):  # one number, the common case: what the array path gives for it
        return float(_digits(float(as_real("x", x)), sig))
    values = as_real("x", x)
    rounded = np.array([float(_digits(v, sig)) for v in values.ravel().tolist()], dtype=float)
    rounded = rounded.reshape(values.shape)
    return float(rounded) if rounded.ndim == 0 else rounded


def _parts(x: ArrayLike, sig: int, trailing_zeros: bool) -> tuple[str, int | None]:
    """(mantissa or positional digits, decimal exponent or None for positional notation)."""
    sig = _check_sig(sig)
    if type(x) is not float or not math.isfinite(x):  # else x is what as_real would give
        value = as_real("x", x)
        if value.ndim:
            raise ParameterError("x", f"must be a single number, got shape {value.shape}")
        x = float(value)
    trailing_zeros = bool(trailing_zeros)
    if trailing_zeros or sig <= getcontext().prec:  # then a pure function of its arguments
        return _exact_parts(x, sig, trailing_zeros)
    return _float_parts(x, sig, trailing_zeros)


def _float_parts(x: float, sig: int, trailing_zeros: bool) -> tuple[str, int | None]:
    """:func:`_parts` of a finite float."""
    text = _digits(x, sig)
    mantissa, exponent = text.split("e")
    magnitude = abs(float(text))
    if magnitude == 0:
        return "0", None
    if PLAIN_RANGE[0] <= magnitude < PLAIN_RANGE[1]:
        if trailing_zeros or sig <= getcontext().prec:  # normalize() would round nothing
            return _positional(mantissa, int(exponent), trailing_zeros), None
        number = Decimal(text).normalize()  # rounded to the context's precision
        return f"{number:f}", None
    if not trailing_zeros and "." in mantissa:
        mantissa = mantissa.rstrip("0").rstrip(".")
    return mantissa, int(exponent)


_exact_parts = lru_cache(maxsize=4096)(_float_parts)
""":func:`_float_parts` where no Decimal context rounds, remembered: a class's statements
print the same rounded parameters again and again (0 and −0, the one pair of equal floats that
differ, both print ``0``)."""


def _positional(mantissa: str, exponent: int, trailing_zeros: bool) -> str:
    """``f"{Decimal(f'{mantissa}e{exponent}'):f}"`` of a nonzero mantissa (``-1.230``), its
    trailing zeros first dropped unless ``trailing_zeros`` (as ``normalize()`` drops them when
    it rounds nothing): the digits, and the point ``exponent + 1`` places after the first."""
    sign = "-" if mantissa[0] == "-" else ""
    digits = mantissa.lstrip("-").replace(".", "")
    if not trailing_zeros:
        digits = digits.rstrip("0")  # not empty: the first digit of a nonzero number is not 0
    point = exponent + 1  # digits before the decimal point
    if point <= 0:
        return f"{sign}0.{'0' * -point}{digits}"
    if point >= len(digits):
        return f"{sign}{digits}{'0' * (point - len(digits))}"
    return f"{sign}{digits[:point]}.{digits[point:]}"


def format_sig(x: float, sig: int, *, trailing_zeros: bool = False) -> str:
    """``x`` rounded to ``sig`` significant figures, as plain text for a statement or code.

    Positional in :data:`PLAIN_RANGE`, else ``1.23e5`` (a valid Python literal). Without
    ``trailing_zeros`` no zero ends the fraction (``2.5``, not ``2.50``); with it, the string
    shows all ``sig`` digits. Always ``float(format_sig(x, sig)) == round_sig(x, sig)``.

    Examples
    --------
    >>> format_sig(0.1 + 0.2, 3), format_sig(2.5, 3, trailing_zeros=True)
    ('0.3', '2.50')
    >>> format_sig(1234.5678, 3), format_sig(6.02214076e23, 4), format_sig(-1.6e-19, 2)
    ('1230', '6.022e23', '-1.6e-19')
    """
    digits, exponent = _parts(x, sig, trailing_zeros)
    return digits if exponent is None else f"{digits}e{exponent}"


def latex_sig(x: float, sig: int, *, trailing_zeros: bool = False) -> str:
    r"""As :func:`format_sig`, for LaTeX: ``1.23 \times 10^{5}`` instead of ``1.23e5``.

    Examples
    --------
    >>> latex_sig(6.02214076e23, 3), latex_sig(1e-7, 2), latex_sig(-0.25, 2)
    ('6.02 \\times 10^{23}', '10^{-7}', '-0.25')
    """
    digits, exponent = _parts(x, sig, trailing_zeros)
    if exponent is None:
        return digits
    if digits in ("1", "-1"):  # 1 × 10^{-7} reads better as 10^{-7}
        return f"{digits[:-1]}10^{{{exponent}}}"
    return rf"{digits} \times 10^{{{exponent}}}"
