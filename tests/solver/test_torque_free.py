"""Tests of Euler's equations, their invariants, the symmetric top and R9 stability (R7–R9).

References: R7 written out component by component; a Taylor-series integration of R7 with
``mpmath.odefun`` at 30 digits; closed forms; eigenvalues of the Jacobian of the right-hand
side at a steady spin (an independent route to R9's frequencies).
"""

from __future__ import annotations

import functools
import itertools

import mpmath as mp
import numpy as np
import pytest
from numpy.testing import assert_allclose

from solver.parameters import ParameterError
from solver.torque_free import (
    body_precession_rate,
    euler_rhs,
    invariants,
    near_axis_stability,
    space_precession_rate,
    symmetric_top_omega,
)


@pytest.fixture
def rng():
    return np.random.default_rng(20240524)


def test_euler_rhs_is_r7_componentwise(rng):
    I1, I2, I3 = 1.0, 1.7, 2.2
    w = rng.normal(size=(5, 3))
    torque = rng.normal(size=(5, 3))
    w1, w2, w3 = w.T
    expected = np.stack(
        [
            (torque[:, 0] - w2 * w3 * (I3 - I2)) / I1,
            (torque[:, 1] - w3 * w1 * (I1 - I3)) / I2,
            (torque[:, 2] - w1 * w2 * (I2 - I1)) / I3,
        ],
        axis=-1,
    )
    assert_allclose(euler_rhs(0.0, w, I1, I2, I3, torque=torque), expected, rtol=1e-14)
    assert_allclose(euler_rhs(0.0, w, I1, I2, I3), expected - torque / [I1, I2, I3], rtol=1e-13)


def test_euler_rhs_conserves_invariants_to_first_order(rng):
    """dT/dt = Σ I ω ω̇ = 0 and dL²/dt = 2 Σ I² ω ω̇ = 0 for the torque-free motion."""
    moments = np.array([1.0, 1.7, 2.2])
    w = rng.normal(size=(10, 3))
    dw = euler_rhs(0.0, w, *moments)
    assert_allclose(np.sum(moments * w * dw, axis=-1), 0, atol=1e-14)
    assert_allclose(np.sum(moments**2 * w * dw, axis=-1), 0, atol=1e-14)


def test_invariants_closed_form():
    T, L2 = invariants(1.0, 2.0, 3.0, [1.0, -2.0, 0.5])
    assert T == 0.5 * (1.0 + 8.0 + 0.75)
    assert L2 == 1.0 + 16.0 + 2.25


@pytest.mark.parametrize(
    ("transverse", "axial", "omega0"),
    [(2.0, 3.0, (0.4, -0.7, 1.3)), (3.0, 1.5, (1.1, 0.2, -0.8)), (1.0, 1.0, (0.3, 0.4, 0.5))],
    ids=["oblate", "prolate", "spherical"],
)
def test_symmetric_top_matches_mpmath_ode(transverse, axial, omega0):
    times = np.linspace(0.0, 4.0, 5)
    with mp.workdps(30):
        a, c = mp.mpf(transverse), mp.mpf(axial)

        def rhs(_t, w):
            return [(a - c) * w[1] * w[2] / a, (c - a) * w[2] * w[0] / a, 0]

        solution = mp.odefun(rhs, 0, [mp.mpf(x) for x in omega0], tol=mp.mpf("1e-20"), degree=30)
        reference = np.array([[float(x) for x in solution(mp.mpf(t))] for t in times])
    exact = symmetric_top_omega(transverse, axial, omega0, times)
    assert_allclose(exact, reference, rtol=0, atol=1e-13 * np.linalg.norm(omega0))
    # precession rate and sense: ω̇1 = −Ω ω2 at t = 0 (R8), from the independent R7 code path
    rate = body_precession_rate(transverse, axial, omega0[2])
    assert_allclose(euler_rhs(0.0, omega0, transverse, transverse, axial)[0], -rate * omega0[1])


def test_space_precession_rate_closed_form():
    # L = (I1 ω1, I1 ω2, I3 ω3) = (2, 0, 3): |L| = √13, α̇ = √13/2
    assert_allclose(space_precession_rate(2.0, 3.0, [1.0, 0.0, 1.0]), np.sqrt(13.0) / 2)


def _jacobian_eigenvalues(moments, omega):
    """Eigenvalues of ∂(dω/dt)/∂ω; central differences are exact for a quadratic field."""
    h = 1e-3
    columns = [
        (euler_rhs(0.0, omega + h * e, *moments) - euler_rhs(0.0, omega - h * e, *moments))
        / (2 * h)
        for e in np.eye(3)
    ]
    return np.linalg.eigvals(np.stack(columns, axis=-1))


@pytest.mark.parametrize("perm", list(itertools.permutations(range(3))))
@pytest.mark.parametrize("axis", [1, 2, 3])
def test_near_axis_stability_against_jacobian(perm, axis):
    moments = np.array([1.0, 1.6, 2.3])[list(perm)]
    spin = -1.7
    result = near_axis_stability(*moments, spin, axis=axis)
    omega = np.zeros(3)
    omega[axis - 1] = spin
    eigenvalues = _jacobian_eigenvalues(moments, omega)
    is_extreme = moments[axis - 1] in (moments.min(), moments.max())
    assert bool(result["stable"]) == is_extreme
    if is_extreme:  # ±i rate, 0
        assert_allclose(np.sort(np.abs(eigenvalues.imag))[1:], result["rate"], rtol=1e-12)
        assert_allclose(eigenvalues.real, 0, atol=1e-12)
    else:  # ±rate, 0
        assert_allclose(np.sort(eigenvalues.real)[[0, 2]], [-result["rate"], result["rate"]])
    # the axis-3 formulas are R9's verbatim
    if axis == 3:
        I1, I2, I3 = moments
        assert_allclose(result["Omega1"], spin * (I3 - I2) / I1, rtol=1e-15)
        assert_allclose(result["Omega2"], spin * (I3 - I1) / I2, rtol=1e-15)


@pytest.mark.parametrize(
    ("moments", "axis", "stable"),
    [
        ((2.0, 2.0, 3.0), 3, True),  # symmetry axis of a symmetric top
        ((2.0, 2.0, 3.0), 1, False),  # a transverse axis: ω wanders round ê3
        ((2.0, 3.0, 3.0), 2, False),
        ((2.0, 2.0, 2.0), 2, True),  # spherical: every ω is steady
    ],
)
def test_near_axis_stability_equal_moments(moments, axis, stable):
    result = near_axis_stability(*moments, 1.3, axis=axis)
    assert bool(result["stable"]) == stable
    if stable and moments[0] == moments[2]:
        assert result["rate"] == 0


def test_near_axis_stability_vectorised():
    result = near_axis_stability([1.0, 3.0], 2.0, [3.0, 1.0], [1.0, 2.0], axis=2)
    assert result["stable"].tolist() == [False, False]
    assert result["rate"].shape == (2,)


@pytest.mark.parametrize(
    ("call", "parameter"),
    [
        (functools.partial(euler_rhs, 0.0, [1.0, 2.0, 3.0], 1.0, 1.0, 3.0), "I3"),
        (functools.partial(euler_rhs, 0.0, [1.0, 2.0], 1.0, 1.0, 1.0), "omega"),
        (functools.partial(invariants, 0.0, 1.0, 1.0, [1.0, 2.0, 3.0]), "I1"),
        (functools.partial(symmetric_top_omega, 1.0, 2.5, [1.0, 0.0, 0.0], 1.0), "I3"),
        (functools.partial(near_axis_stability, 1.0, 2.0, 2.5, 1.0, axis=4), "axis"),
        (functools.partial(near_axis_stability, 1.0, 2.0, 2.5, np.nan), "omega_spin"),
        (functools.partial(body_precession_rate, 1.0, 1.5, "fast"), "omega3"),
    ],
)
def test_bad_input_is_named(call, parameter):
    with pytest.raises(ParameterError) as error:
        call()
    assert error.value.parameter == parameter
