"""Independent checks of the sleeping-top template (R2, R19).

References, none of which calls the solver: the moments of a disc, a solid cylinder and a solid
cone about the tip typed from the textbook formulas (R2 plus the parallel-axis theorem); the
critical spin from the sign change of the β² coefficient of ``V_eff`` (R16 typed here, expanded
by sympy about β = 0 at ``p_α = p_γ``); and that sign change seen directly in ``V_eff(β) −
V_eff(0)`` evaluated by mpmath at 40 digits just above and just below the key.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import sympy as sp

from problems.templates import FAMILIES
from problems.templates import sleeping_top as template

SEEDS = range(20)

_I1, _Mgl, _p, _beta = sp.symbols("I1 Mgl p beta", positive=True)
# R16 with p_alpha = p_gamma = p (a top whose axis passes through the vertical)
_V = (_p - _p * sp.cos(_beta)) ** 2 / (2 * _I1 * sp.sin(_beta) ** 2) + _Mgl * sp.cos(_beta)
_C2 = sp.series(_V, _beta, 0, 4).removeO().coeff(_beta, 2)
# the positive p at which the β² coefficient changes sign
(_P_CRITICAL,) = [r for r in sp.solve(sp.Eq(_C2, 0), _p) if r.is_positive]
P_CRITICAL = sp.lambdify((_I1, _Mgl), _P_CRITICAL)


@pytest.fixture(params=SEEDS, ids=[f"seed{s}" for s in SEEDS])
def variant(request):
    return FAMILIES[template.NAME].generate(np.random.default_rng(request.param))


def moments(p: dict) -> tuple[float, float, float, float]:
    """(I1 about the tip, I3, I about the centre of mass, M g l), typed from R2."""
    M, R, g = p["M"], p["R"], p["g"]
    if "h" not in p:  # thin disc on an axle
        i_cm, i3, arm = M * R**2 / 4, M * R**2 / 2, p["l"]
    elif "l" in p:  # solid cylinder on an axle
        i_cm, i3, arm = M * (3 * R**2 + p["h"] ** 2) / 12, M * R**2 / 2, p["l"]
    else:  # solid cone on its apex: centre of mass 3h/4 from the apex
        h = p["h"]
        i_cm, i3, arm = 3 * M * R**2 / 20 + 3 * M * h**2 / 80, 3 * M * R**2 / 10, 3 * h / 4
    return i_cm + M * arm**2, i3, i_cm, M * g * arm


def test_c2_is_the_textbook_coefficient():
    assert sp.simplify(_C2 - (_p**2 / (8 * _I1) - _Mgl / 2)) == 0


def test_critical_spin_from_the_expansion_of_v_eff(variant):
    I1, I3, _, Mgl = moments(variant.params)
    expected = P_CRITICAL(I1, Mgl) / I3
    assert math.isclose(variant.answer("omega3_c").value, expected, rel_tol=1e-12)


def _v_rise(I1: float, Mgl: float, p: float, beta: float = 1e-4) -> mpmath.mpf:
    """``V_eff(β) − V_eff(0)`` at ``p_α = p_γ = p`` (R16), at 40 digits."""
    with mpmath.workdps(40):
        b = mpmath.mpf(beta)
        v = (p - p * mpmath.cos(b)) ** 2 / (2 * I1 * mpmath.sin(b) ** 2) + Mgl * mpmath.cos(b)
        return v - Mgl


def test_v_eff_changes_curvature_at_the_key(variant):
    I1, I3, _, Mgl = moments(variant.params)
    w = variant.answer("omega3_c").value
    assert _v_rise(I1, Mgl, I3 * w * (1 + 1e-6)) > 0  # a minimum: stable
    assert _v_rise(I1, Mgl, I3 * w * (1 - 1e-6)) < 0  # a maximum: unstable


def test_stability_at_the_given_spin(variant):
    I1, I3, _, Mgl = moments(variant.params)
    w = variant.params["omega3"]
    assert variant.answer("stable").value == bool(_v_rise(I1, Mgl, I3 * w) > 0)
    critical = variant.answer("omega3_c").value
    assert abs(w / critical - 1) >= template.THRESHOLD_MARGIN


def test_mistake_values_follow_the_mistaken_physics(variant):
    I1, I3, i_cm, Mgl = moments(variant.params)
    mistakes = {m.name: m.value for m in variant.answer("omega3_c").mistakes}
    expected = {
        "I1_about_cm": 2 * math.sqrt(Mgl * i_cm) / I3,
        "I1_I3_swapped": 2 * math.sqrt(Mgl * I3) / I1,
        "missing_factor_2": math.sqrt(Mgl * I1) / I3,
        "hz": 2 * math.sqrt(Mgl * I1) / I3 / (2 * math.pi),
    }
    assert mistakes.keys() == expected.keys()
    for name, value in expected.items():
        assert math.isclose(mistakes[name], value, rel_tol=1e-12), name


def test_draws_are_real_tops_and_both_outcomes_occur():
    outcomes, kinds = set(), set()
    for seed in range(60):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        p = v.params
        assert 0.03 <= p["M"] <= 0.5 and 0.02 <= p["R"] <= 0.05
        I1, I3, _, Mgl = moments(p)
        assert 0.02 <= Mgl / (p["M"] * p["g"]) <= 0.06  # centre of mass 2–6 cm from the tip
        assert I3 <= 2 * I1
        outcomes.add(v.answer("stable").value)
        kinds.add(("h" in p, "l" in p))
    assert outcomes == {True, False}
    assert len(kinds) == 3
