"""Parameter checks: a plain float takes a short path that must behave like the array path."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from solver.parameters import (
    ParameterError,
    any_true,
    as_real,
    nonnegative,
    positive,
    principal_moments,
)


@pytest.mark.parametrize("value", [0.5, -3.0, 0.0, 1e300, np.float64(2.5), 7, np.array(1.5)])
def test_a_number_becomes_a_0d_float_array(value):
    arr = as_real("x", value)
    assert isinstance(arr, np.ndarray) and arr.shape == () and arr.dtype == np.float64
    assert arr.item() == float(value)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, np.float64("nan")])
@pytest.mark.parametrize("as_array", [False, True])
def test_nan_and_infinity_are_refused_alike_as_float_and_as_array(bad, as_array):
    with pytest.raises(ParameterError, match=r"^I1: must be finite \(got NaN or infinity\)$"):
        as_real("I1", np.array([bad]) if as_array else bad)


def test_a_number_where_a_vector_is_due_names_the_shape():
    for value in (1.0, np.array(1.0)):
        with pytest.raises(ParameterError, match=r"must have shape \(\.\.\., 3\), got shape \(\)"):
            as_real("omega", value, shape_tail=(3,))


def test_signs_and_the_triangle_inequality():
    assert positive("M", 2.0).item() == 2.0
    assert nonnegative("Mgl", 0.0).item() == 0.0
    with pytest.raises(ParameterError, match=r"^M: must be positive, got -1$"):
        positive("M", -1.0)
    with pytest.raises(ParameterError, match=r"^Mgl: must be non-negative, got -0\.5$"):
        nonnegative("Mgl", -0.5)
    a, b, c = principal_moments(1.0, 2.0, 3.0)
    assert (a.item(), b.item(), c.item()) == (1.0, 2.0, 3.0)
    with pytest.raises(ParameterError, match=r"^I3: violates the triangle inequality"):
        principal_moments(1.0, 1.0, 2.5)
    with pytest.raises(ParameterError, match=r"^I2: must be a number"):
        principal_moments(1.0, "2", 2.5)


def test_any_true_of_a_single_value_and_of_arrays():
    assert any_true(np.asarray(1.0) > 0) is True and any_true(np.asarray(1.0) < 0) is False
    assert any_true(np.array([1.0, -1.0]) < 0) is True
    assert any_true(np.zeros((2, 3)) > 0) is False and any_true(np.zeros(0) > 0) is False


def test_principal_moments_broadcast_as_before():
    a, b, c = principal_moments([1.0, 2.0], 2.0, 2.5)
    assert a.shape == b.shape == c.shape == (2,)
    np.testing.assert_array_equal(b, [2.0, 2.0])
    with pytest.raises(ParameterError, match=r"^I3: violates .*\(I3 = 3\.5 exceeds"):
        principal_moments([1.5, 1.0], 2.0, [2.5, 3.5])


@pytest.mark.parametrize("value", [2.5, 5e-324, 1.7e308, np.float64(3.0), 0.0, -0.0, -2.0,
                                   math.nan, math.inf, -math.inf, np.float64("nan"), 2,
                                   np.array(1.5), [1.0, 2.0]])
def test_positive_of_a_float_is_as_real_then_the_sign(value):
    """positive's short path for a float > 0 gives what the checks give, and refuses the rest
    with their messages."""
    try:
        arr = as_real("M", value)
        expected = None if not (arr <= 0).any() else \
            f"M: must be positive, got {np.asarray(arr)[arr <= 0].ravel()[0]:.6g}"
    except ParameterError as err:
        expected = str(err)
    if expected is not None:
        with pytest.raises(ParameterError, match=f"^{re.escape(expected)}$"):
            positive("M", value)
        return
    got = positive("M", value)
    assert type(got) is np.ndarray and got.dtype == arr.dtype and got.shape == arr.shape
    assert got.tobytes() == arr.tobytes()
