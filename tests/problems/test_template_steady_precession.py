"""Independent checks of the steady-precession template (R2, R15, R16, R21).

References, none of which calls the solver: ``I1 = Icm + M l²`` (parallel axes, R2) and
``p_γ = I3 ω3`` typed here; R21's quadratic ``I1 cos β0 α̇² − p_γ α̇ + Mgl = 0`` solved by
``numpy.roots`` (fine for these moderate parameters); steady precession as a stationary point of
``V_eff`` (R16 typed here; ``∂V_eff/∂β = 0`` at ``β0`` with ``p_α = I1 α̇ sin²β0 + p_γ cos β0``,
differentiated by ``mpmath.diff`` at 40 digits); and the fast-top formulas of R21 typed here.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from problems.templates import FAMILIES
from problems.templates import steady_precession as template

SEEDS = range(20)


@pytest.fixture(params=SEEDS, ids=[f"seed{s}" for s in SEEDS])
def variant(request):
    return FAMILIES[template.NAME].generate(np.random.default_rng(request.param))


def top(p: dict) -> tuple[float, float, float]:
    """(I1 about the pivot, p_γ, M g l)."""
    return p["Icm"] + p["M"] * p["l"] ** 2, p["I3"] * p["omega3"], p["M"] * p["g"] * p["l"]


def test_rates_are_the_roots_of_the_quadratic(variant):
    p = variant.params
    I1, p_gamma, Mgl = top(p)
    roots = np.roots([I1 * math.cos(p["beta0"]), -p_gamma, Mgl])
    assert np.all(np.isreal(roots))
    slow, fast = sorted(np.real(roots), key=abs)
    assert math.isclose(variant.answer("slow").value, slow, rel_tol=1e-10)
    assert math.isclose(variant.answer("fast").value, fast, rel_tol=1e-10)


def _v_eff_slope(I1: float, Mgl: float, p_gamma: float, beta0: float, rate: float) -> float:
    """``∂V_eff/∂β`` at ``β0`` for the top precessing at ``rate`` there (R15, R16), relative to
    the size of its terms."""
    with mpmath.workdps(40):
        b0 = mpmath.mpf(beta0)
        p_alpha = I1 * mpmath.mpf(rate) * mpmath.sin(b0) ** 2 + p_gamma * mpmath.cos(b0)

        def v(beta):
            return ((p_alpha - p_gamma * mpmath.cos(beta)) ** 2 / (2 * I1 * mpmath.sin(beta) ** 2)
                    + Mgl * mpmath.cos(beta))

        scale = Mgl + I1 * rate**2 + abs(p_gamma * rate)
        return float(mpmath.diff(v, b0) / scale)


def test_rates_make_v_eff_stationary(variant):
    p = variant.params
    I1, p_gamma, Mgl = top(p)
    for which in ("slow", "fast"):
        rate = variant.answer(which).value
        assert abs(_v_eff_slope(I1, Mgl, p_gamma, p["beta0"], rate)) < 1e-12, which
        # and a rate 0.1 % off is not stationary: the test can tell
        assert abs(_v_eff_slope(I1, Mgl, p_gamma, p["beta0"], rate * 1.001)) > 1e-6, which


def test_fast_top_approximations_and_error(variant):
    p = variant.params
    I1, p_gamma, Mgl = top(p)
    slow_approx, fast_approx = Mgl / p_gamma, p_gamma / (I1 * math.cos(p["beta0"]))
    assert math.isclose(variant.answer("slow_approx").value, slow_approx, rel_tol=1e-13)
    assert math.isclose(variant.answer("fast_approx").value, fast_approx, rel_tol=1e-13)
    slow = variant.answer("slow").value
    error = variant.answer("slow_error").value
    assert math.isclose(error, (slow_approx - slow) / slow, rel_tol=1e-9)
    assert error < 0  # Mgl/p_γ underestimates the slow rate above the horizontal


def test_mistaken_moment_about_the_centre_of_mass(variant):
    p = variant.params
    _, p_gamma, Mgl = top(p)
    roots = np.roots([p["Icm"] * math.cos(p["beta0"]), -p_gamma, Mgl])
    wrong = next(m.value for m in variant.answer("fast").mistakes if m.name == "I1_about_cm")
    assert math.isclose(wrong, max(np.real(roots), key=abs), rel_tol=1e-10)


def test_draws_have_real_rates_with_margin():
    for seed in range(60):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        p = v.params
        I1, p_gamma, Mgl = top(p)
        stiffness = p_gamma**2 / (4 * I1 * Mgl * math.cos(p["beta0"]))
        assert template.STIFFNESS[0] <= stiffness <= template.STIFFNESS[1]
        assert 0.2 < p["beta0"] < 1.4  # above the horizontal, away from cos β0 = 0
        # the fast-top approximation is off by more than the tolerance
        assert abs(v.answer("slow_error").value) > 5 * template.RTOL
