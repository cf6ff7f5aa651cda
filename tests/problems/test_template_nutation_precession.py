"""Independent checks of the nutation template (R15–R17, R20).

References, none of which calls the solver:

- mpmath at 40 digits: the cubic ``f(u)`` of R17 typed from the constants of motion (R15, R16),
  its roots by ``mpmath.polyroots``, and R20's integrals ``T = 2∫du/√f`` and
  ``Δα = 2∫(b − au)/((1 − u²)√f) du`` by ``mpmath.quad`` after the substitution
  ``u = u1 + (u2 − u1) sin²θ`` (smooth integrands). The solver uses Carlson's R_F and R_J.
- scipy's DOP853 (rtol 1e-11) integration of the reduced equation of motion
  ``I1 β̈ = −dV_eff/dβ`` with ``α̇ = (p_α − p_γ cos β)/(I1 sin²β)`` (R16, R18): the period is the
  time to the second turning point and the mean rate ``α(T)/T``.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from problems.templates import FAMILIES
from problems.templates import nutation_precession as template

SEEDS = range(12)
ODE_SEEDS = range(3)


@pytest.fixture(params=SEEDS, ids=[f"seed{s}" for s in SEEDS])
def variant(request):
    return FAMILIES[template.NAME].generate(np.random.default_rng(request.param))


def constants(p: dict) -> tuple[float, float, float]:
    """(p_α, p_γ, E') from the displayed state, β̇0 = 0 (R15, R16)."""
    s2, c = math.sin(p["beta0"]) ** 2, math.cos(p["beta0"])
    p_gamma = p["I3"] * p["omega3"]
    p_alpha = p["I1"] * p["alpha_dot0"] * s2 + p_gamma * c
    e_prime = 0.5 * p["I1"] * p["alpha_dot0"] ** 2 * s2 + p["Mgl"] * c
    return p_alpha, p_gamma, e_prime


def r20_reference(p: dict) -> tuple[mpmath.mpf, mpmath.mpf, list]:
    """(T_nut, mean rate, roots) of R20 at 40 digits."""
    with mpmath.workdps(40):
        p_alpha, p_gamma, e_prime = (mpmath.mpf(x) for x in constants(p))
        I1 = mpmath.mpf(p["I1"])
        a, b, A, B = p_gamma / I1, p_alpha / I1, 2 * e_prime / I1, 2 * mpmath.mpf(p["Mgl"]) / I1
        # f(u) = (1 − u²)(A − Bu) − (b − au)² = B u³ − (A + a²) u² + (2ab − B) u + A − b²
        roots = sorted(mpmath.re(r) for r in mpmath.polyroots(
            [B, -(A + a**2), 2 * a * b - B, A - b**2], maxsteps=200, extraprec=80))
        u1, u2, u3 = roots

        def u(t):
            return u1 + (u2 - u1) * mpmath.sin(t) ** 2

        # du/√f = 2 dθ / √(B (u3 − u)) under the substitution
        period = 2 * mpmath.quad(lambda t: 2 / mpmath.sqrt(B * (u3 - u(t))), [0, mpmath.pi / 2])
        angle = 2 * mpmath.quad(
            lambda t: (b - a * u(t)) / (1 - u(t) ** 2) * 2 / mpmath.sqrt(B * (u3 - u(t))),
            [0, mpmath.pi / 2])
        return period, angle / period, roots


def test_period_and_mean_rate_against_mpmath(variant):
    period, mean, _ = r20_reference(variant.params)
    assert math.isclose(variant.answer("T_nut").value, float(period), rel_tol=1e-10)
    assert math.isclose(variant.answer("mean_rate").value, float(mean), rel_tol=1e-10)


def _reduced_rhs(p: dict):
    p_alpha, p_gamma, _ = constants(p)
    I1, Mgl = p["I1"], p["Mgl"]

    def rhs(t, y):
        beta, beta_dot, _ = y
        s, c = math.sin(beta), math.cos(beta)
        n = p_alpha - p_gamma * c
        dv = n * p_gamma / (I1 * s) - n * n * c / (I1 * s**3) - Mgl * s  # dV_eff/dβ (R16)
        return [beta_dot, -dv / I1, n / (I1 * s * s)]

    return rhs


@pytest.mark.parametrize("seed", ODE_SEEDS)
def test_period_and_mean_rate_from_the_equations_of_motion(seed):
    v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
    p = v.params
    period = v.answer("T_nut").value

    def turning(t, y):
        return y[1]

    sol = solve_ivp(_reduced_rhs(p), (0.0, 1.2 * period), [p["beta0"], 0.0, 0.0],
                    method="DOP853", rtol=1e-11, atol=1e-13, events=turning, dense_output=True)
    times = [t for t in sol.t_events[0] if t > 1e-6 * period]
    assert len(times) >= 2
    assert math.isclose(times[1], period, rel_tol=1e-8)
    alpha = sol.sol(times[1])[2]
    assert math.isclose(alpha / times[1], v.answer("mean_rate").value, rel_tol=1e-7)


def test_fast_top_mistakes_are_the_fast_top_formulas(variant):
    p = variant.params
    _, p_gamma, _ = constants(p)
    t_mistakes = {m.name: m.value for m in variant.answer("T_nut").mistakes}
    r_mistakes = {m.name: m.value for m in variant.answer("mean_rate").mistakes}
    assert math.isclose(t_mistakes["small_oscillation"], 2 * math.pi * p["I1"] / p_gamma,
                        rel_tol=1e-12)
    assert math.isclose(r_mistakes["fast_top"], p["Mgl"] / p_gamma, rel_tol=1e-12)
    assert math.isclose(t_mistakes["half_period"], variant.answer("T_nut").value / 2)


def test_ellipk_mistake_uses_the_modulus(variant):
    from scipy.special import ellipk

    _, _, (u1, u2, u3) = r20_reference(variant.params)
    k2 = float((u2 - u1) / (u3 - u1))
    T = variant.answer("T_nut").value
    wrong = next(m.value for m in variant.answer("T_nut").mistakes if m.name == "ellipk_of_k")
    assert math.isclose(wrong / T, ellipk(math.sqrt(k2)) / ellipk(k2), rel_tol=1e-9)


def test_draws_are_well_posed_and_varied():
    scenes = set()
    for seed in range(40):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        _, _, (u1, u2, u3) = r20_reference(v.params)
        beta1, beta2 = math.acos(float(u2)), math.acos(float(u1))
        assert beta2 - beta1 >= template.MIN_AMPLITUDE
        assert beta2 <= template.MAX_BETA2
        assert float((u2 - u1) / (u3 - u1)) <= template.MAX_K2
        assert beta1 - 1e-12 <= v.params["beta0"] <= beta2 + 1e-12
        scenes.add(v.params["alpha_dot0"] == 0.0)
    assert scenes == {True, False}


def test_a_students_scipy_route_is_graded_correct(variant):
    """numpy.roots, scipy's ellipk and plain quad over [u1, u2] (the singular integrand as is):
    the tools the statement names land well inside the tolerance."""
    from scipy.integrate import quad
    from scipy.special import ellipk

    from problems.answers import grade

    p = variant.params
    p_alpha, p_gamma, e_prime = constants(p)
    I1 = p["I1"]
    a, b, A, B = p_gamma / I1, p_alpha / I1, 2 * e_prime / I1, 2 * p["Mgl"] / I1
    u1, u2, u3 = np.sort(np.real(np.roots([B, -(A + a**2), 2 * a * b - B, A - b**2])))
    period = 4 * ellipk((u2 - u1) / (u3 - u1)) / math.sqrt(B * (u3 - u1))

    def integrand(u):
        return (b - a * u) / ((1 - u * u) * math.sqrt(abs(B * (u - u1) * (u - u2) * (u - u3))))

    angle = 2 * quad(integrand, u1, u2, limit=200)[0]
    assert grade(variant.answer("T_nut"), period).status == "correct"
    assert grade(variant.answer("mean_rate"), angle / period).status == "correct"
