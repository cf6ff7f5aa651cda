"""Tests of solver/euler_angles.py (R11–R13).

References, none of them the code under test:
- R11: ``scipy.spatial.transform.Rotation`` with intrinsic z-y'-z'' angles ("ZYZ"), whose active
  matrix ``A = R_z(α) R_y(β) R_z(γ)`` has the body axes as columns, so ``R = Aᵀ``;
- R12: the angular velocity read off ``Ṙ`` (``[ω']× = −Ṙ Rᵀ``), ``R(t)`` built and differentiated
  in mpmath at 40 digits (``mp.diff``);
- R13: ``T = ½ ω·I·ω`` evaluated in the *inertial* frame, with ``ω = α̇ ẑ + β̇ ê'2 + γ̇ ê3`` and
  the axes taken from scipy's rotation; the symmetric-top form checked with sympy;
- gimbal lock: the condition number of the inverse map, measured with ``numpy.linalg.cond``,
  against its closed form ``cot(β/2)`` (singular values of R12's matrix: ``√(1 ± cos β)``, 1).
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from scipy.spatial.transform import Rotation

from solver.euler_angles import (
    GIMBAL_LOCK_SIN_BETA,
    euler_rates,
    kinetic_energy_euler,
    omega_body,
    rotation_matrix,
    solve_euler_angles,
    to_body,
    to_inertial,
)
from solver.parameters import ParameterError

RTOL = 1e-12


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(11121314)


@pytest.fixture
def angles(rng):
    """200 random orientations: α, γ ∈ [−π, π), β ∈ (0, π)."""
    n = 200
    return rng.uniform(-np.pi, np.pi, n), rng.uniform(1e-3, np.pi - 1e-3, n), rng.uniform(
        -np.pi, np.pi, n
    )


@pytest.fixture
def rates(rng):
    return tuple(rng.normal(scale=3.0, size=200) for _ in range(3))


def _scipy_active(alpha, beta, gamma):
    """Body axes as columns (active rotation), by scipy's intrinsic z-y'-z'' Euler angles."""
    return Rotation.from_euler("ZYZ", np.stack((alpha, beta, gamma), axis=-1)).as_matrix()


# --- R11 rotation matrix --------------------------------------------------------------------------

def test_rotation_matrix_is_a_rotation(angles):
    r = rotation_matrix(*angles)
    assert r.shape == (200, 3, 3)
    np.testing.assert_allclose(r @ np.swapaxes(r, -1, -2), np.broadcast_to(np.eye(3), r.shape),
                               atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, rtol=1e-15)


def test_rotation_matrix_is_transpose_of_scipy_intrinsic_zyz(angles):
    np.testing.assert_allclose(rotation_matrix(*angles),
                               np.swapaxes(_scipy_active(*angles), -1, -2), atol=1e-15)


def test_scipy_recovers_the_angles(angles):
    """The inverse direction: scipy reads (α, β, γ) back off R for β ∈ (0, π)."""
    recovered = Rotation.from_matrix(np.swapaxes(rotation_matrix(*angles), -1, -2)).as_euler("ZYZ")
    np.testing.assert_allclose(recovered, np.stack(angles, axis=-1), atol=1e-12)


def test_vertical_in_body_components(angles):
    """ẑ = −sin β cos γ ê1 + sin β sin γ ê2 + cos β ê3 (R12's note), and ê3 = (sβcα, sβsα, cβ)."""
    alpha, beta, gamma = angles
    r = rotation_matrix(alpha, beta, gamma)
    expected = np.stack((-np.sin(beta) * np.cos(gamma), np.sin(beta) * np.sin(gamma),
                         np.cos(beta)), axis=-1)
    np.testing.assert_allclose(to_body(r, [0.0, 0.0, 1.0]), expected, atol=1e-15)
    symmetry_axis = np.stack((np.sin(beta) * np.cos(alpha), np.sin(beta) * np.sin(alpha),
                              np.cos(beta)), axis=-1)
    np.testing.assert_allclose(to_inertial(r, [0.0, 0.0, 1.0]), symmetry_axis, atol=1e-15)


def test_to_body_and_to_inertial(angles, rng):
    r = rotation_matrix(*angles)
    v = rng.normal(size=(200, 3))
    body = to_body(r, v)
    # scipy's active rotation takes body components to inertial ones.
    np.testing.assert_allclose(Rotation.from_matrix(_scipy_active(*angles)).apply(body), v,
                               atol=1e-14)
    np.testing.assert_allclose(to_inertial(r, body), v, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(body, axis=-1), np.linalg.norm(v, axis=-1),
                               rtol=1e-14)


def test_rotation_matrix_vectorised_equals_loop(rng):
    alpha, beta, gamma = rng.uniform(0, 3, (4, 1)), rng.uniform(0, 3, (1, 5)), 0.7
    stacked = rotation_matrix(alpha, beta, gamma)
    assert stacked.shape == (4, 5, 3, 3)
    for i in range(4):
        for j in range(5):
            np.testing.assert_array_equal(stacked[i, j],
                                          rotation_matrix(alpha[i, 0], beta[0, j], gamma))


@pytest.mark.parametrize(
    ("matrix", "vector"),
    [
        (np.diag([1.0, 1.0, 2.0]), [1.0, 0.0, 0.0]),  # not orthogonal
        (np.diag([1.0, 1.0, -1.0]), [1.0, 0.0, 0.0]),  # a reflection
        (np.eye(3), [1.0, 0.0]),  # not a 3-vector
    ],
)
def test_to_body_rejects_non_rotations(matrix, vector):
    with pytest.raises(ParameterError) as info:
        to_body(matrix, vector)
    assert info.value.parameter == ("R" if len(vector) == 3 else "V")


def test_bad_angle_is_named():
    with pytest.raises(ParameterError) as info:
        rotation_matrix(0.0, float("nan"), 0.0)
    assert info.value.parameter == "beta"


# --- R12 angular velocity -------------------------------------------------------------------------

def _mp_rotation(alpha, beta, gamma):
    """R = R_γ R_β R_α in mpmath, from the elementary passive rotations of R11."""
    def about_z(a):
        return mp.matrix([[mp.cos(a), mp.sin(a), 0], [-mp.sin(a), mp.cos(a), 0], [0, 0, 1]])

    about_y = mp.matrix([[mp.cos(beta), 0, -mp.sin(beta)], [0, 1, 0],
                         [mp.sin(beta), 0, mp.cos(beta)]])
    return about_z(gamma) * about_y * about_z(alpha)


def _omega_from_rdot(angles, rates):
    """Body ω from the skew matrix −Ṙ Rᵀ, R(t) at uniform rates differentiated at t = 0."""
    with mp.workdps(40):
        angles, rates = [mp.mpf(a) for a in angles], [mp.mpf(r) for r in rates]

        def entry(i, j):
            def value(t):
                return _mp_rotation(*(a + r * t for a, r in zip(angles, rates, strict=True)))[i, j]

            return value

        rdot = mp.matrix(3, 3)
        for i in range(3):
            for j in range(3):
                rdot[i, j] = mp.diff(entry(i, j), 0)
        skew = -rdot * _mp_rotation(*angles).T
        return np.array([float(skew[2, 1]), float(skew[0, 2]), float(skew[1, 0])])


@pytest.mark.parametrize(
    ("angles", "rates"),
    [
        ((0.3, 1.1, -0.4), (0.7, -1.3, 2.9)),
        ((-2.0, 2.8, 1.7), (5.0, 0.2, -0.6)),
        ((1.0, 1e-6, 0.5), (1.5, 0.3, 10.0)),  # near the vertical, away from β = 0 exactly
        ((0.0, np.pi / 2, np.pi), (0.0, 0.0, 1.0)),  # pure spin
        ((4.0, 0.9, -3.0), (-1e-3, 2e-3, 0.0)),
    ],
)
def test_omega_body_matches_derivative_of_rotation(angles, rates):
    reference = _omega_from_rdot(angles, rates)
    np.testing.assert_allclose(omega_body(*angles[1:], *rates), reference, rtol=RTOL,
                               atol=RTOL * np.max(np.abs(reference)))


def test_omega_body_vectorised_equals_loop(angles, rates):
    _, beta, gamma = angles
    stacked = omega_body(beta, gamma, *rates)
    assert stacked.shape == (200, 3)
    for k in range(0, 200, 17):
        np.testing.assert_array_equal(
            stacked[k], omega_body(beta[k], gamma[k], *(r[k] for r in rates))
        )


def test_euler_rates_inverts_omega_body(angles, rates):
    _, beta, gamma = angles
    recovered = euler_rates(beta, gamma, omega_body(beta, gamma, *rates))
    # Rounding in ω is amplified by the condition number cot(β/2) ≤ 2/β (β ≥ 1e-3 here).
    for got, want in zip(recovered, rates, strict=True):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-11)


def test_omega_body_inverts_euler_rates(angles, rng):
    _, beta, gamma = angles
    omega = rng.normal(size=(200, 3))
    np.testing.assert_allclose(omega_body(beta, gamma, *euler_rates(beta, gamma, omega)), omega,
                               atol=1e-13)


def _inverse_jacobian(beta, gamma):
    """The (linear) map ω → (α̇, β̇, γ̇) as a matrix, column k = image of the unit vector ê_k."""
    columns = euler_rates(np.asarray(beta)[..., None], np.asarray(gamma)[..., None], np.eye(3))
    return np.stack(columns, axis=-2)


@pytest.mark.parametrize("gamma", [0.0, 0.9, -2.3])
def test_gimbal_lock_conditioning_grows_like_one_over_sin_beta(gamma):
    beta = np.logspace(-1, -7, 7)
    condition = np.linalg.cond(_inverse_jacobian(beta, gamma))
    # Closed form: R12's matrix has singular values √(1 + cos β), 1, √(1 − cos β).
    np.testing.assert_allclose(condition, 1 / np.tan(beta / 2), rtol=1e-6)
    # Measured growth: log-log slope −1 against sin β, and κ sin β → 2.
    slope = np.polyfit(np.log(np.sin(beta)), np.log(condition), 1)[0]
    np.testing.assert_allclose(slope, -1.0, atol=1e-3)
    np.testing.assert_allclose(condition[-1] * np.sin(beta[-1]), 2.0, rtol=1e-6)


@pytest.mark.parametrize("beta", [0.0, np.pi, 1e-10, -1e-9, np.pi - 1e-10, 2 * np.pi])
def test_gimbal_lock_raises_naming_beta(beta):
    with pytest.raises(ParameterError, match="gimbal lock") as info:
        euler_rates(beta, 0.3, [0.1, 0.2, 0.3])
    assert info.value.parameter == "beta"


def test_gimbal_lock_raises_when_any_element_is_locked():
    with pytest.raises(ParameterError) as info:
        euler_rates([0.5, 1.0, 0.0], 0.3, [0.1, 0.2, 0.3])
    assert info.value.parameter == "beta"


def test_just_outside_gimbal_lock_still_inverts():
    beta = 10 * GIMBAL_LOCK_SIN_BETA
    rates = (0.4, -0.2, 1.3)
    recovered = euler_rates(beta, 0.3, omega_body(beta, 0.3, *rates))
    # Error bound: ε |ω| cot(β/2) ≈ 2ε|ω|/β, here ~1e-8.
    np.testing.assert_allclose(recovered, rates, atol=4 * np.finfo(float).eps * 2 * 1.5 / beta)


# --- R13 kinetic energy ---------------------------------------------------------------------------

def test_kinetic_energy_in_the_inertial_frame(angles, rates, rng):
    """T = ½ ω·I·ω with ω = α̇ ẑ + β̇ ê'2 + γ̇ ê3 and I = A diag(I) Aᵀ, all in inertial axes."""
    alpha, beta, gamma = angles
    alpha_dot, beta_dot, gamma_dot = rates
    moments = np.sort(rng.uniform(1.0, 2.0, size=(200, 3)), axis=-1)
    axes = _scipy_active(alpha, beta, gamma)  # columns ê1, ê2, ê3
    line_of_nodes = Rotation.from_euler("Z", alpha[:, None]).apply([0.0, 1.0, 0.0])  # ê'2
    omega = (alpha_dot[:, None] * [0.0, 0.0, 1.0] + beta_dot[:, None] * line_of_nodes
             + gamma_dot[:, None] * axes[..., 2])
    tensor = np.einsum("nik,nk,njk->nij", axes, moments, axes)
    reference = 0.5 * np.einsum("ni,nij,nj->n", omega, tensor, omega)
    got = kinetic_energy_euler(*moments.T, beta, gamma, *rates)
    np.testing.assert_allclose(got, reference, rtol=1e-12)


def test_kinetic_energy_symmetric_top_form(angles, rates):
    """For I1 = I2: T = ½ I1 (α̇² sin²β + β̇²) + ½ I3 (α̇ cos β + γ̇)², independent of γ."""
    _, beta, gamma = angles
    alpha_dot, beta_dot, gamma_dot = rates
    i1, i3 = 1.7, 0.6
    symmetric = (0.5 * i1 * (alpha_dot**2 * np.sin(beta) ** 2 + beta_dot**2)
                 + 0.5 * i3 * (alpha_dot * np.cos(beta) + gamma_dot) ** 2)
    np.testing.assert_allclose(kinetic_energy_euler(i1, i1, i3, beta, gamma, *rates), symmetric,
                               rtol=1e-12)


def test_symmetric_reduction_of_r13_with_sympy():
    """R13's general form with I2 = I1 simplifies to its symmetric form exactly."""
    i1, i3, b, g, ad, bd, gd = sp.symbols("I1 I3 beta gamma alpha_dot beta_dot gamma_dot")
    general = (i1 * (-ad * sp.sin(b) * sp.cos(g) + bd * sp.sin(g)) ** 2
               + i1 * (ad * sp.sin(b) * sp.sin(g) + bd * sp.cos(g)) ** 2
               + i3 * (ad * sp.cos(b) + gd) ** 2) / 2
    symmetric = i1 * (ad**2 * sp.sin(b) ** 2 + bd**2) / 2 + i3 * (ad * sp.cos(b) + gd) ** 2 / 2
    assert sp.simplify(general - symmetric) == 0
    # ... and the solver evaluates that expression at a random point to 1e-13.
    point = {i1: 1.3, i3: 0.4, b: 0.8, g: -2.1, ad: 0.9, bd: 1.7, gd: -3.2}
    expected = float(symmetric.subs(point))
    got = kinetic_energy_euler(1.3, 1.3, 0.4, 0.8, -2.1, 0.9, 1.7, -3.2)
    np.testing.assert_allclose(got, expected, rtol=1e-13)


def test_kinetic_energy_rejects_impossible_moments():
    with pytest.raises(ParameterError) as info:
        kinetic_energy_euler(1.0, 1.0, 3.0, 0.5, 0.1, 1.0, 1.0, 1.0)
    assert info.value.parameter == "I3"


# --- solve_euler_angles ---------------------------------------------------------------------------

@pytest.fixture
def state():
    return {"alpha": 0.4, "beta": 1.2, "gamma": -0.7, "alpha_dot": 1.5, "beta_dot": -0.3,
            "gamma_dot": 8.0}


def test_solve_without_moments_has_no_energy(state):
    result = solve_euler_angles(**state)
    assert set(result) == {"R", "omega_body"}
    np.testing.assert_allclose(
        result["R"], _scipy_active(state["alpha"], state["beta"], state["gamma"]).T, atol=1e-15
    )


def test_solve_with_moments_has_energy(state):
    result = solve_euler_angles(**state, I1=2.0, I2=3.0, I3=4.0)
    assert set(result) == {"R", "omega_body", "T"}
    omega = _omega_from_rdot((state["alpha"], state["beta"], state["gamma"]),
                             (state["alpha_dot"], state["beta_dot"], state["gamma_dot"]))
    np.testing.assert_allclose(result["omega_body"], omega, rtol=RTOL)
    np.testing.assert_allclose(result["T"], 0.5 * np.dot([2.0, 3.0, 4.0], omega**2), rtol=RTOL)


@pytest.mark.parametrize(
    ("moments", "culprit"),
    [({"I1": 1.0}, "I2"), ({"I1": 1.0, "I2": 1.0}, "I3"), ({"I3": 1.0}, "I1")],
)
def test_solve_with_some_moments_names_a_missing_one(state, moments, culprit):
    with pytest.raises(ParameterError) as info:
        solve_euler_angles(**state, **moments)
    assert info.value.parameter == culprit
