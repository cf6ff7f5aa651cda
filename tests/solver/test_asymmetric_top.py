"""Tests of the exact asymmetric-top solution (R10) against independent references.

References: a Taylor-series integration of Euler's equations (R7) with ``mpmath.odefun`` at
30 digits; mpmath's ``ellipfun``/``ellipk`` at 40 digits; the conservation of T and L²; the
symmetric-top closed form (R8); the linearised equations (R9) through ``scipy.linalg.expm``.
"""

from __future__ import annotations

import functools
import itertools

import mpmath as mp
import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import minimize_scalar

from solver.asymmetric_top import (
    asymmetric_top_omega,
    asymmetric_top_period,
    flip_time,
    solve_free_top,
)
from solver.parameters import ParameterError
from solver.torque_free import euler_rhs, invariants, near_axis_stability, symmetric_top_omega

# Moments (3, 4, 6) and ω = (2, ·, 1) lie exactly on the separatrix L² = 2T I2 in binary
# floating point: L² − 2T I2 = I1 (I1 − I2) ω1² + I3 (I3 − I2) ω3² = −12 + 12 = 0.
SEPARATRIX_MOMENTS = (3.0, 4.0, 6.0)
SEPARATRIX_OMEGA = (2.0, 0.7, 1.0)
# ω3 = 1 ± 5.5e-7 puts the motion at 1 − k² ≈ 1e-6 above (+) or below (−) the separatrix.
NEAR_ABOVE = (2.0, 0.7, 1.0 + 5.5e-7)
NEAR_BELOW = (2.0, 0.7, 1.0 - 5.5e-7)


@functools.cache
def _mp_solution(moments: tuple, omega0: tuple):
    """mpmath Taylor integrator of R7 from the exact binary values of the inputs, 30 digits."""
    with mp.workdps(30):
        I1, I2, I3 = (mp.mpf(x) for x in moments)

        def rhs(_t, w):
            return [
                (I2 - I3) * w[1] * w[2] / I1,
                (I3 - I1) * w[2] * w[0] / I2,
                (I1 - I2) * w[0] * w[1] / I3,
            ]

        # tol 1e-20, degree 30: agrees with mpmath's defaults to ~1e-25, three times faster
        return mp.odefun(rhs, 0, [mp.mpf(x) for x in omega0], tol=mp.mpf("1e-20"), degree=30)


def ode_reference(moments, omega0, times) -> np.ndarray:
    solution = _mp_solution(tuple(map(float, moments)), tuple(map(float, omega0)))
    with mp.workdps(30):
        return np.array([[float(c) for c in solution(mp.mpf(float(t)))] for t in times])


def permuted(perm, moments, omega0):
    return tuple(moments[i] for i in perm), tuple(omega0[i] for i in perm)


def relative_error(value, reference, omega0) -> float:
    return float(np.max(np.abs(np.asarray(value) - reference)) / np.linalg.norm(omega0))


# --- against the ODE ----------------------------------------------------------------------

GENERIC_ABOVE = ((1.0, 2.0, 2.5), (0.4, 0.5, 0.9))  # L² > 2T I2: ω circles the I = 2.5 axis
GENERIC_BELOW = ((1.0, 2.0, 2.5), (0.9, 0.5, 0.3))  # L² < 2T I2: ω circles the I = 1 axis


@pytest.mark.parametrize("perm", list(itertools.permutations(range(3))))
@pytest.mark.parametrize("case", [GENERIC_ABOVE, GENERIC_BELOW], ids=["above", "below"])
def test_all_moment_orders_match_ode(perm, case):
    moments, omega0 = permuted(perm, *case)
    invariant_T, L2 = invariants(*case[0], case[1])
    assert (L2 > 2 * invariant_T * 2.0) == (case is GENERIC_ABOVE)
    times = np.linspace(0.0, 3.0, 4)
    exact = asymmetric_top_omega(*moments, omega0, times)
    assert relative_error(exact, ode_reference(moments, omega0, times), omega0) < 1e-12


@pytest.mark.parametrize(
    ("perm", "omega0"),
    [((0, 1, 2), NEAR_ABOVE), ((1, 0, 2), NEAR_BELOW)],
    ids=["above-even", "below-odd"],
)
def test_near_separatrix_matches_ode_over_a_period(perm, omega0):
    moments, w0 = permuted(perm, SEPARATRIX_MOMENTS, omega0)
    period = float(asymmetric_top_period(*moments, w0))
    times = np.append(np.linspace(0.0, 1.15 * period, 12), period)
    reference = ode_reference(moments, w0, times)
    exact = asymmetric_top_omega(*moments, w0, times)
    assert relative_error(exact, reference, w0) < 1e-10
    # the ODE itself returns to ω(0) after the computed period (a check on 4K/λ)
    assert relative_error(reference[-1], np.array(w0), w0) < 1e-10
    # and ω really flips in between: ω2 changes sign
    assert np.min(reference[:, perm.index(1)]) < -0.5 < 0.5 < np.max(reference[:, perm.index(1)])


@pytest.mark.parametrize("perm", [(0, 1, 2), (2, 1, 0)], ids=["even", "odd"])
def test_on_separatrix_matches_ode(perm):
    moments, w0 = permuted(perm, SEPARATRIX_MOMENTS, SEPARATRIX_OMEGA)
    times = np.linspace(0.0, 20.0, 5)
    exact = asymmetric_top_omega(*moments, w0, times)
    assert relative_error(exact, ode_reference(moments, w0, times), w0) < 1e-10
    assert asymmetric_top_period(*moments, w0) == np.inf


def test_separatrix_approaches_saddle():
    """On the separatrix ω tends to the intermediate-axis rotation ±(0, ω2∞, 0) as t → ±∞."""
    I1, I2, I3 = SEPARATRIX_MOMENTS
    T, _ = invariants(I1, I2, I3, SEPARATRIX_OMEGA)
    late = asymmetric_top_omega(I1, I2, I3, SEPARATRIX_OMEGA, [-200.0, 200.0])
    assert_allclose(np.abs(late[:, 1]), np.sqrt(2 * T / I2), rtol=1e-12)
    assert np.all(np.abs(late[:, [0, 2]]) < 1e-12)


# --- the period -----------------------------------------------------------------------------


def _mp_period(moments, omega0) -> float:
    """4K(k)/λ of R10 in mpmath at 40 digits, sorted moments, both sides of the separatrix."""
    with mp.workdps(40):
        order = np.argsort(moments)
        J = [mp.mpf(moments[i]) for i in order]
        w = [mp.mpf(omega0[i]) for i in order]
        two_T = sum(j * x**2 for j, x in zip(J, w, strict=True))
        L2 = sum(j**2 * x**2 for j, x in zip(J, w, strict=True))
        if L2 < two_T * J[1]:  # roles of 1 and 3 exchanged
            J = J[::-1]
        k2 = (J[1] - J[0]) * (two_T * J[2] - L2) / ((J[2] - J[1]) * (L2 - two_T * J[0]))
        lam = mp.sqrt((J[2] - J[1]) * (L2 - two_T * J[0]) / (J[0] * J[1] * J[2]))
        return float(4 * mp.ellipk(k2) / lam)


PERIOD_CASES = [
    GENERIC_ABOVE,
    GENERIC_BELOW,
    ((2.5, 1.0, 2.0), (0.9, 0.4, 0.5)),
    (SEPARATRIX_MOMENTS, NEAR_ABOVE),
    ((6.0, 3.0, 4.0), (1.0 - 5.5e-7, 2.0, 0.7)),
    (SEPARATRIX_MOMENTS, (2.0, 0.7, 1.0 + 2**-40)),
]


@pytest.mark.parametrize(("moments", "omega0"), PERIOD_CASES)
def test_period_against_mpmath(moments, omega0):
    period = asymmetric_top_period(*moments, omega0)
    assert_allclose(period, _mp_period(moments, omega0), rtol=1e-12)
    # ω(t + period) = ω(t) at a few unrelated times
    t = np.array([0.0, 0.37, 5.1])
    assert relative_error(
        asymmetric_top_omega(*moments, omega0, t + period),
        asymmetric_top_omega(*moments, omega0, t),
        omega0,
    ) < 1e-10
    assert_allclose(flip_time(*moments, omega0), period / 2, rtol=1e-15)


def test_period_grows_logarithmically_at_the_separatrix():
    """Period → (2/λ) ln(16/(1 − k²)) as k → 1: each factor 128 in 1 − k² adds (2/λ) ln 128."""
    I1, I2, I3 = SEPARATRIX_MOMENTS
    # 1 + 2⁻ⁿ is exact in binary, so 1 − k² ∝ (1 + δ)² − 1 drops by 128 (1 + O(δ)) per step
    omega0 = [(2.0, 0.7, 1.0 + delta) for delta in 2.0 ** -np.arange(20, 49, 7)]
    periods = asymmetric_top_period(I1, I2, I3, np.array(omega0))
    with mp.workdps(40):  # λ and 1 − k² of R10 from the exact binary inputs
        lam, m1 = [], []
        for w in omega0:
            w1, w2, w3 = (mp.mpf(x) for x in w)
            two_T = I1 * w1**2 + I2 * w2**2 + I3 * w3**2
            L2 = I1**2 * w1**2 + I2**2 * w2**2 + I3**2 * w3**2
            lam.append(float(mp.sqrt((I3 - I2) * (L2 - two_T * I1) / (I1 * I2 * I3))))
            m1.append(float((I3 - I1) * (L2 - two_T * I2) / ((I3 - I2) * (L2 - two_T * I1))))
    lam, m1 = np.array(lam), np.array(m1)
    assert_allclose(periods, 2 / lam * np.log(16 / m1), rtol=1e-6)
    assert_allclose(np.diff(periods * lam / 2), np.log(128.0), rtol=1e-5)


# --- invariants, symmetric and spherical tops, steady rotation ------------------------------


@pytest.mark.parametrize(
    ("moments", "omega0"),
    [*PERIOD_CASES, (SEPARATRIX_MOMENTS, SEPARATRIX_OMEGA), ((1.0, 1.0, 1.5), (0.3, 0.2, 1.1))],
)
def test_invariants_conserved_along_exact_solution(moments, omega0):
    times = np.linspace(0.0, 1.0e4, 2001)
    T0, L20 = invariants(*moments, omega0)
    T, L2 = invariants(*moments, asymmetric_top_omega(*moments, omega0, times))
    assert_allclose(T, T0, rtol=1e-12)
    assert_allclose(L2, L20, rtol=1e-12)


@pytest.mark.parametrize("symmetric_axis", [0, 1, 2])
@pytest.mark.parametrize("moments_pair", [(2.0, 3.0), (3.0, 2.0)], ids=["oblate", "prolate"])
def test_symmetric_top_is_r8(symmetric_axis, moments_pair):
    transverse, axial = moments_pair
    moments = [transverse] * 3
    moments[symmetric_axis] = axial
    omega0 = np.roll([0.4, -0.7, 1.3], symmetric_axis - 2)
    times = np.linspace(0.0, 20.0, 41)
    exact = asymmetric_top_omega(*moments, omega0, times)
    # cyclic relabelling puts the symmetry axis last, where R8 is written
    shift = 2 - symmetric_axis
    r8 = np.roll(symmetric_top_omega(transverse, axial, np.roll(omega0, shift), times), -shift, -1)
    assert relative_error(exact, r8, omega0) < 1e-13
    rate = abs(omega0[symmetric_axis] * (axial - transverse) / transverse)
    assert_allclose(asymmetric_top_period(*moments, omega0), 2 * np.pi / rate, rtol=1e-14)


def test_nearly_symmetric_top_tends_to_r8():
    """With I2 = I1 (1 + ε) the exact motion differs from R8 by O(ε) over a fixed time."""
    omega0 = np.array([0.4, -0.7, 1.3])
    times = np.linspace(0.0, 5.0, 11)
    r8 = symmetric_top_omega(2.0, 3.0, omega0, times)
    errors = [
        relative_error(asymmetric_top_omega(2.0, 2.0 * (1 + eps), 3.0, omega0, times), r8, omega0)
        for eps in (1e-4, 1e-6)
    ]
    assert errors[1] < 1e-5 and 50 < errors[0] / errors[1] < 200


@pytest.mark.parametrize(
    ("moments", "omega0"),
    [
        ((1.0, 2.0, 3.0), (0.0, 0.0, 2.0)),
        ((1.0, 2.0, 3.0), (0.0, -1.5, 0.0)),  # intermediate axis: the saddle itself
        ((1.0, 2.0, 3.0), (0.7, 0.0, 0.0)),
        ((1.5, 1.5, 1.5), (0.3, -0.2, 0.9)),  # spherical
        ((2.0, 2.0, 3.0), (0.3, -0.2, 0.0)),  # in the degenerate plane of a symmetric top
        ((2.0, 3.0, 4.0), (0.0, 0.0, 0.0)),  # at rest
    ],
)
def test_steady_rotation(moments, omega0):
    times = np.array([0.0, 1.0, 1e3])
    assert_allclose(asymmetric_top_omega(*moments, omega0, times), np.tile(omega0, (3, 1)))
    assert asymmetric_top_period(*moments, omega0) == np.inf
    assert np.all(euler_rhs(0.0, omega0, *moments) == 0)  # independent: it is an equilibrium


# --- R9 as the small-amplitude limit ----------------------------------------------------------


@pytest.mark.parametrize("axis", [1, 3])
def test_small_amplitude_period_is_r9(axis):
    moments = (1.0, 2.0, 3.0)
    stability = near_axis_stability(*moments, 1.7, axis=axis)
    assert stability["stable"]
    deviations = []
    for amplitude in (1e-3, 1e-5):
        omega0 = np.array([amplitude, 2 * amplitude, 1.7])  # unequal: see R9's O(a²) term
        omega0 = omega0[[0, 1, 2] if axis == 3 else [2, 0, 1]]
        period = asymmetric_top_period(*moments, omega0)
        deviations.append(abs(period * stability["rate"] / (2 * np.pi) - 1))
    assert deviations[1] < 1e-9 and deviations[0] > 1e3 * deviations[1]  # O(amplitude²)


def test_intermediate_axis_growth_matches_linearised_ode():
    """Exact R10 near the intermediate axis follows R9's linear ODE, growing at its rate."""
    moments, spin, eps = (1.0, 2.0, 3.0), 1.3, 1e-9
    r9 = near_axis_stability(*moments, spin, axis=2)
    assert not r9["stable"]
    # axis 2: transverse components in cyclic order (ω3, ω1); ω̇3 = −Ω1 ω1, ω̇1 = Ω2 ω3
    A = np.array([[0.0, -r9["Omega1"]], [r9["Omega2"], 0.0]])
    perturbation = np.array([eps, 0.4 * eps])  # (ω3, ω1)
    times = np.linspace(0.0, 12.0, 7)
    exact = asymmetric_top_omega(*moments, [0.4 * eps, spin, eps], times)[:, [2, 0]]
    linear = np.array([expm(A * t) @ perturbation for t in times])
    assert_allclose(exact, linear, rtol=1e-5, atol=1e-20)
    growth = np.log(np.linalg.norm(linear[-1]) / np.linalg.norm(linear[-2])) / 2.0
    assert_allclose(growth, r9["rate"], rtol=1e-3)


# --- the flip -------------------------------------------------------------------------------


def test_flip_time_is_max_to_min_of_intermediate_component():
    moments, omega0 = SEPARATRIX_MOMENTS, NEAR_ABOVE
    period = float(asymmetric_top_period(*moments, omega0))
    grid = np.linspace(0.0, period, 4001)
    w2 = asymmetric_top_omega(*moments, omega0, grid)[:, 1]

    def extremum(sign):
        t0 = grid[np.argmax(sign * w2)]
        fit = minimize_scalar(
            lambda t: -sign * asymmetric_top_omega(*moments, omega0, t)[1],
            bracket=(t0 - period / 4000, t0, t0 + period / 4000),
            options={"xtol": 1e-12},
        )
        return fit.x

    assert_allclose((extremum(-1) - extremum(+1)) % period, flip_time(*moments, omega0), rtol=1e-6)


# --- numerical drift ------------------------------------------------------------------------


def test_loose_explicit_integrator_drifts_exact_solution_does_not():
    moments, omega0 = (1.0, 2.0, 3.0), np.array([1.0, 0.3, 0.5])
    times = np.array([100.0, 1000.0, 3000.0])
    T0, _ = invariants(*moments, omega0)
    rhs = functools.partial(euler_rhs, I1=moments[0], I2=moments[1], I3=moments[2])
    rk45 = solve_ivp(rhs, (0, times[-1]), omega0, rtol=1e-3, atol=1e-6, t_eval=times)
    drift = np.abs(invariants(*moments, rk45.y.T)[0] / T0 - 1)
    assert np.all(np.diff(drift) > 0) and drift[-1] > 1e-2 and drift[-1] > 5 * drift[0]
    exact = asymmetric_top_omega(*moments, omega0, times)
    exact_drift = np.abs(invariants(*moments, exact)[0] / T0 - 1)
    assert np.all(exact_drift < 1e-13)


# --- interface ------------------------------------------------------------------------------


def test_vectorised_matches_loop():
    moments = np.array([[1.0, 2.0, 2.5], [3.0, 4.0, 6.0], [2.0, 2.0, 3.0]])
    omegas = np.array([[0.4, 0.5, 0.9], list(NEAR_BELOW), [0.1, 0.2, 0.3]])
    times = np.linspace(0.0, 3.0, 4)[:, None]
    batch = asymmetric_top_omega(moments[:, 0], moments[:, 1], moments[:, 2], omegas, times)
    assert batch.shape == (4, 3, 3)
    for i in range(3):
        single = asymmetric_top_omega(*moments[i], omegas[i], times[:, 0])
        assert_allclose(batch[:, i], single, rtol=0, atol=0)


def test_solve_free_top():
    result = solve_free_top(1.0, 2.0, 3.0, [1.0, 0.3, 0.5], t=[0.0, 1.0])
    assert result["omega"].shape == (2, 3)
    assert_allclose(result["omega"][0], [1.0, 0.3, 0.5], rtol=1e-14)
    assert_allclose(result["T"], 0.5 * (1.0 + 2 * 0.09 + 3 * 0.25))
    assert_allclose(result["L"], np.sqrt(1.0 + 4 * 0.09 + 9 * 0.25))
    assert_allclose(result["period"], _mp_period((1.0, 2.0, 3.0), (1.0, 0.3, 0.5)), rtol=1e-12)
    assert result["stability"].tolist() == [True, False, True]
    assert solve_free_top(2.0, 2.0, 2.0, [1.0, 2.0, 3.0])["period"] == np.inf


def test_hairer_lubich_wanner_free_rigid_body():
    """The free rigid body test problem of Hairer, Lubich & Wanner (Geometric Numerical
    Integration, ch. IV–VII): ``I = (2, 1, 2/3)``, angular momentum ``y0 = (cos 1.1, 0,
    sin 1.1)`` (as quoted, with the attribution "DK16/HXW14/HLW", in public
    geometric-integration code). Its moments violate the triangle inequality 2 > 1 + 2/3, so
    the rigid-body solver refuses it, naming I1; as Euler's equations taken as an ODE
    (``rigid_body=False``) the exact solution must match an independent 30-digit Taylor
    integration and return to ``ω0`` after its period."""
    moments = (2.0, 1.0, 2.0 / 3.0)
    omega0 = np.array([np.cos(1.1), 0.0, np.sin(1.1)]) / moments
    with pytest.raises(ParameterError) as error:
        asymmetric_top_omega(*moments, omega0, 1.0)
    assert error.value.parameter == "I1"
    times = np.array([0.5, 3.0, 10.0])
    exact = asymmetric_top_omega(*moments, omega0, times, rigid_body=False)
    assert relative_error(exact, ode_reference(moments, omega0, times), omega0) < 1e-10
    period = asymmetric_top_period(*moments, omega0, rigid_body=False)
    back = asymmetric_top_omega(*moments, omega0, [period, 3 * period], rigid_body=False)
    assert relative_error(back, np.array([omega0, omega0]), omega0) < 1e-12


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        ({"I1": -1.0}, "I1"),
        ({"I3": 5.0}, "I3"),
        ({"omega0": [1.0, 2.0]}, "omega0"),
        ({"omega0": [1.0, np.nan, 0.0]}, "omega0"),
        ({"t": np.inf}, "t"),
    ],
)
def test_bad_input_is_named(kwargs, parameter):
    arguments = {"I1": 1.0, "I2": 2.0, "I3": 2.5, "omega0": [0.1, 0.2, 0.3], "t": 1.0} | kwargs
    with pytest.raises(ParameterError) as error:
        asymmetric_top_omega(**arguments)
    assert error.value.parameter == parameter
