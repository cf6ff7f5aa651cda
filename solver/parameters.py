"""Checking physical parameters before any formula sees them.

Every public solver function validates its inputs through these checks, so that bad input is
reported as a :class:`ParameterError` naming the parameter at fault (the CLI turns it into
``{"error": "..."}``), never as a NaN or a numpy warning further down.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

# defined below the solver, and so shipped by the student package too, which has no solver
from eulertop_base import ParameterError


def as_real(
    name: str, value: ArrayLike, *, shape_tail: tuple[int, ...] = ()
) -> NDArray[np.float64]:
    """Return ``value`` as a finite float array, or raise :class:`ParameterError` naming ``name``.

    ``shape_tail`` demands trailing dimensions, e.g. ``(3,)`` for a vector or ``(3, 3)`` for a
    tensor; leading dimensions are free (vectorised input).
    """
    if isinstance(value, float):  # a plain number, the common case: no numpy reductions
        if not math.isfinite(value):
            raise ParameterError(name, "must be finite (got NaN or infinity)")
        if shape_tail:
            raise ParameterError(name, f"must have shape (..., {'×'.join(map(str, shape_tail))})"
                                 ", got shape ()")
        return np.asarray(value, dtype=float)
    if isinstance(value, (str, bytes)) or value is None:
        raise ParameterError(name, f"must be a number, got {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be a number, got {value!r}") from None
    if shape_tail and arr.shape[arr.ndim - len(shape_tail):] != shape_tail:
        want = "×".join(map(str, shape_tail))
        raise ParameterError(name, f"must have shape (..., {want}), got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ParameterError(name, "must be finite (got NaN or infinity)")
    return arr


def positive(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """`as_real`, and every element > 0 (masses, moments of inertia, lengths)."""
    if isinstance(value, float) and 0 < value < math.inf:  # NaN fails both: as_real refuses it
        return np.asarray(value, dtype=float)  # what as_real gives, and it is > 0
    arr = as_real(name, value)
    if any_true(arr <= 0):
        raise ParameterError(name, f"must be positive, got {_worst(arr, arr <= 0)}")
    return arr


def nonnegative(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """`as_real`, and every element >= 0 (e.g. M g l of a top balanced on its tip)."""
    arr = as_real(name, value)
    if any_true(arr < 0):
        raise ParameterError(name, f"must be non-negative, got {_worst(arr, arr < 0)}")
    return arr


def principal_moments(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, *, rtol: float = 1e-12
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Validate principal moments: positive, and each at most the sum of the other two (R4).

    A rigid body's principal moments obey the triangle inequality ``I_i + I_j >= I_k``
    (equality only for a lamina); ``rtol`` forgives the rounding of displayed parameters.
    """
    a, b, c = positive("I1", I1), positive("I2", I2), positive("I3", I3)
    if not a.shape == b.shape == c.shape:  # (broadcast_arrays returns equal shapes as they are)
        a, b, c = np.broadcast_arrays(a, b, c)
    for name, big, s1, s2 in (("I1", a, b, c), ("I2", b, c, a), ("I3", c, a, b)):
        bad = big > (s1 + s2) * (1 + rtol)
        if any_true(bad):
            raise ParameterError(
                name,
                f"violates the triangle inequality of principal moments ({name} = "
                f"{_worst(big, bad)} exceeds the sum of the other two); no rigid body has these",
            )
    return a, b, c


def any_true(mask: NDArray[np.bool_] | np.bool_) -> bool:
    """``mask.any()``, without numpy's reduction machinery for a single value (a 0-d mask)."""
    return bool(mask) if mask.ndim == 0 else bool(mask.any())


def _worst(arr: NDArray[np.float64], bad: NDArray[np.bool_]) -> str:
    return f"{np.asarray(arr)[np.asarray(bad)].ravel()[0]:.6g}"
