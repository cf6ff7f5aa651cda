"""Independent checks of the symbolic-derivation template (R14–R16, R18, R19).

References: the results as ``docs/physics/`` states them, typed here in numpy — R15's momenta
(``p_α`` in its R15 form ``I1 α̇ sin²β + p_γ cos β``), R16's ``E' = ½ I1 β̇² + V_eff`` with the
momenta of R15, R18's ``α̇`` — compared with the key expressions (derived by
:mod:`solver.symbolic`, a different route) at random points; the sleeping top's ``c2`` as the
limit ``(V_eff(β) − V_eff(0))/β²`` of R16 at ``p_α = p_γ``, by mpmath at 40 digits. A
student's textbook form of each result, as a string, is graded correct by the answer's own
comparison, and the numeric answers equal the typed formulas at the displayed state.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import sympy as sp

from problems.answers import grade
from problems.templates import FAMILIES
from problems.templates import symbolic_derivation as template
from solver.symbolic import SYMBOLS


def _p_gamma(I1, I3, beta, alpha_dot, gamma_dot):
    return I3 * (alpha_dot * np.cos(beta) + gamma_dot)  # R15


def _p_alpha(I1, I3, beta, alpha_dot, gamma_dot):
    p_gamma = _p_gamma(I1, I3, beta, alpha_dot, gamma_dot)
    return I1 * alpha_dot * np.sin(beta) ** 2 + p_gamma * np.cos(beta)  # R15


def _v_eff(I1, Mgl, beta, p_alpha, p_gamma):
    return (p_alpha - p_gamma * np.cos(beta)) ** 2 / (2 * I1 * np.sin(beta) ** 2) \
        + Mgl * np.cos(beta)  # R16


def _e_prime(I1, I3, Mgl, beta, alpha_dot, beta_dot, gamma_dot):
    p_alpha = _p_alpha(I1, I3, beta, alpha_dot, gamma_dot)
    p_gamma = _p_gamma(I1, I3, beta, alpha_dot, gamma_dot)
    return 0.5 * I1 * beta_dot**2 + _v_eff(I1, Mgl, beta, p_alpha, p_gamma)  # R16


def _alpha_dot(I1, beta, p_alpha, p_gamma):
    return (p_alpha - p_gamma * np.cos(beta)) / (I1 * np.sin(beta) ** 2)  # R18


def _c2(I1, Mgl, p_gamma):
    """lim (V_eff(β) − V_eff(0))/β² at p_α = p_γ (R16), numerically at 40 digits."""
    with mpmath.workdps(40):
        b = mpmath.mpf("1e-12")
        v = (p_gamma - p_gamma * mpmath.cos(b)) ** 2 / (2 * I1 * mpmath.sin(b) ** 2) \
            + Mgl * mpmath.cos(b)
        return float((v - Mgl) / b**2)


REFERENCES = {
    "p_alpha": _p_alpha, "p_gamma": _p_gamma, "E_prime": _e_prime, "V_eff": _v_eff,
    "alpha_dot": _alpha_dot, "c2": _c2,
}
# How a student would write each result from docs/physics/ (a different form from the key's).
TEXTBOOK = {
    "p_alpha": "I1*alpha_dot*sin(beta)^2 + I3*(alpha_dot*cos(beta) + gamma_dot)*cos(beta)",
    "p_gamma": "I3*alpha_dot*cos(beta) + I3*gamma_dot",
    "E_prime": "I1*beta_dot**2/2 + I1*alpha_dot**2*(1 - cos(beta)**2)/2 + Mgl*cos(beta)",
    "V_eff": "(p_alpha - p_gamma*cos(beta))**2/(2*I1*(1 - cos(beta)**2)) + Mgl*cos(beta)",
    "alpha_dot": "(p_alpha/I1 - p_gamma*cos(beta)/I1)/sin(beta)**2",
    "c2": "(p_gamma**2 - 4*Mgl*I1)/(8*I1)",
}
INDICES = range(len(template.QUANTITIES))
IDS = [q.name for q in template.QUANTITIES]


@pytest.fixture(params=INDICES, ids=IDS)
def quantity(request):
    return template.QUANTITIES[request.param], template._compiled(request.param).expression


def test_key_expression_matches_physics_md(quantity):
    q, expression = quantity
    key = sp.parse_expr(expression.value, local_dict=dict(SYMBOLS))
    f = sp.lambdify([SYMBOLS[n] for n in q.symbols], key, "numpy")
    rng = np.random.default_rng(1)
    args = [rng.uniform(0.2, 2.9, 50) if n == "beta" else rng.uniform(0.5, 2.0, 50)
            for n in q.symbols]
    reference = REFERENCES[q.name]
    expected = np.vectorize(reference)(*args) if q.name == "c2" else reference(*args)
    np.testing.assert_allclose(f(*args), expected, rtol=1e-11)


def test_textbook_form_is_graded_correct(quantity):
    q, expression = quantity
    verdict = grade(expression, TEXTBOOK[q.name])
    assert verdict.status == "correct", verdict


def test_mistaken_expressions_are_graded_as_their_mistake(quantity):
    _, expression = quantity
    for mistake in expression.mistakes:
        assert grade(expression, mistake.value).mistake == mistake.name


@pytest.mark.parametrize("seed", range(24))
def test_numeric_answer_is_the_formula_at_the_displayed_state(seed):
    v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
    number = next(a for a in v.answers if not a.name.endswith("_expr"))
    expected = REFERENCES[number.name](**v.params)
    assert math.isclose(number.value, float(expected), rel_tol=1e-11)


def test_every_quantity_is_asked():
    family = FAMILIES[template.NAME]
    asked = {next(a.name for a in family.generate(np.random.default_rng(s)).answers)
             for s in range(60)}
    assert asked == {f"{q.name}_expr" for q in template.QUANTITIES}
