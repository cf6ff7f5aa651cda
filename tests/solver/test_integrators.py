"""The integrators' building blocks against closed forms and conservation laws."""

from __future__ import annotations

import numpy as np
import pytest

from solver.euler_angles import rotation_matrix
from solver.heavy_top import constants_of_motion
from solver.integrators import (
    fixed_step,
    free_body_rhs,
    heavy_body_rhs,
    heavy_body_state,
    heavy_top_euler_rhs,
    integrate_adaptive,
    lie_poisson_step,
    quaternion_cos_beta,
    rk4_step,
)
from solver.torque_free import euler_rhs

RNG = np.random.default_rng(7)


@pytest.mark.parametrize("moments", [(1.0, 2.0, 3.0), (2.0, 2.0, 1.0), (3.0, 1.5, 2.0)])
def test_free_body_rhs_is_euler_rhs(moments):
    w = RNG.normal(size=3)
    assert np.allclose(free_body_rhs(*moments)(0.0, w), euler_rhs(0.0, w, *moments), rtol=1e-15)


@pytest.mark.parametrize("beta", [0.0, 0.4, 1.3, 2.9])
def test_initial_quaternion_is_r11(beta):
    """ẑ' = q* ẑ q must equal the third column of R = R_γ R_β R_α (R11) with α = γ = 0."""
    y = heavy_body_state(beta, 0.3, -0.2, 5.0)
    w, x, yq, z = y[:4]
    up = [2 * (x * z - w * yq), 2 * (yq * z + w * x), 1 - 2 * (x * x + yq * yq)]
    assert np.allclose(up, rotation_matrix(0.0, beta, 0.0)[:, 2], atol=1e-15)
    assert quaternion_cos_beta(y) == pytest.approx(np.cos(beta), abs=1e-15)


@pytest.mark.parametrize("moments", [(1.0, 1.0, 0.6), (1.0, 1.3, 0.6)])
def test_heavy_body_conserves_energy(moments):
    """E = ½ ω·Iω + Mgl cos β (conservation law; torque sign and kinematics both matter)."""
    rhs = heavy_body_rhs(*moments, 1.0)
    y0 = heavy_body_state(0.8, 0.2, 0.5, 3.0)
    res = integrate_adaptive(rhs, y0, [0.0, 10.0], "DOP853", 1e-12, 1e-12)

    def energy(y):
        return 0.5 * np.sum(np.array(moments) * y[4:] ** 2) + quaternion_cos_beta(y)

    assert res.success and abs(energy(res.y[-1]) - energy(y0)) < 1e-10


def test_euler_angle_equations_conserve_p_alpha_p_gamma_and_energy():
    state = (1.0, 0.6, 1.0, 0.8, 0.2, 0.5, 3.0)
    rhs = heavy_top_euler_rhs(*state[:3])
    res = integrate_adaptive(rhs, [0.0, 0.8, 0.0, 0.2, 0.5, 3.0], [0.0, 7.0], "DOP853",
                             1e-12, 1e-12)
    _, b, _, ad, bd, gd = res.y[-1]
    got = constants_of_motion(*state[:3], b, ad, bd, gd)
    want = constants_of_motion(*state)
    assert np.allclose(got, want, rtol=1e-10)


def test_lie_poisson_step_keeps_L2_exactly_and_is_vectorised():
    moments = np.array([1.0, 2.0, 3.0])
    L = RNG.normal(size=(5, 3))
    out = L
    for _ in range(1000):
        out = lie_poisson_step(out, 0.05, moments)
    assert np.allclose(np.sum(out**2, -1), np.sum(L**2, -1), rtol=1e-13)
    single = L[2]
    for _ in range(1000):
        single = lie_poisson_step(single, 0.05, moments)
    assert np.array_equal(single, out[2])


def test_rk4_is_exact_for_a_cubic_in_time():
    """Classical RK4 integrates y' = 4t³ exactly (a quadrature of degree ≤ 3 + Simpson)."""
    res = fixed_step(lambda t, y, h: rk4_step(lambda s, _: 4 * s**3, t, y, h), [0.0],
                     [0.5, 2.0], 0.3, 4)
    assert np.allclose(res.y[:, 0], [0.5**4, 2.0**4], rtol=1e-14)
    assert res.nsteps == 2 + 5 and res.nfev == 4 * res.nsteps


def test_adaptive_counts_steps_and_hits_output_times():
    rhs = free_body_rhs(1.0, 2.0, 3.0)
    res = integrate_adaptive(rhs, [0.5, 0.0, 1.0], [0.0, 1.0, 2.5, 2.5, 10.0], "RK45",
                             1e-8, 1e-10)
    assert res.success and res.y.shape == (5, 3) and res.nsteps > 0 and res.nfev > res.nsteps
    assert np.array_equal(res.y[2], res.y[3])


def test_adaptive_failure_is_reported():
    rhs = heavy_top_euler_rhs(1.0, 0.6, 1.0)
    res = integrate_adaptive(rhs, [0.0, 0.0, 0.0, 0.0, 0.0, 5.0], [0.0, 1.0], "DOP853",
                             1e-8, 1e-8)
    assert not res.success and "non-finite" in res.message
