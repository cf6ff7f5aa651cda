"""Independent checks of the euler_kinetic_energy template's answers (R12, R13).

The template's number comes from ``solver.euler_angles.kinetic_energy_euler`` (numpy, R12 then
R13). Here, from the displayed parameters only:

- ``T`` from the motion itself: ω's body components by a central difference of scipy
  rotations (the angles advancing at their rates), then R3's ``T = ½ Σ I_i ω_i²``;
- ``T`` from the sympy derivation ``solver.symbolic.kinetic_energy_euler_expr`` (R11 → R12 →
  R13, derived, not typed in), evaluated by mpmath at 30 digits;
- ``T_expr`` against the textbook symmetric-top formula of R13 (``docs/physics/``), typed in
  here: symbolically (the difference simplifies to 0) and through the grader.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.spatial.transform import Rotation

from problems.answers import grade
from problems.expressions import parse_expression
from problems.templates import FAMILIES, euler_kinetic_energy
from solver.symbolic import SYMBOLS, kinetic_energy_euler_expr

SEEDS = range(40)
TEXTBOOK = (
    "I1*(alpha_dot**2*sin(beta)**2 + beta_dot**2)/2 + I3*(alpha_dot*cos(beta) + gamma_dot)**2/2"
)


@pytest.fixture(scope="module")
def variants():
    family = FAMILIES[euler_kinetic_energy.NAME]
    return [family.generate(np.random.default_rng(seed)) for seed in SEEDS]


def _answer(variant, name):
    return next(a for a in variant.answers if a.name == name)


def _moments(p):
    return np.array([p["I1"], p.get("I2", p["I1"]), p["I3"]])  # toy top: I2 = I1


def _omega_by_motion(p, h=1e-6):
    def rot(t):
        alpha = t * p["alpha_dot"]  # α itself does not enter T; start it at 0
        return Rotation.from_euler(
            "ZYZ", [alpha, p["beta"] + t * p["beta_dot"], p["gamma"] + t * p["gamma_dot"]]
        )

    return (rot(-h).inv() * rot(h)).as_rotvec() / (2 * h)


def test_both_scenes_are_drawn(variants):
    assert {"I2" in v.params for v in variants} == {True, False}


def test_T_matches_R3_with_omega_from_the_motion(variants):
    for v in variants:
        p = v.params
        T = 0.5 * np.sum(_moments(p) * _omega_by_motion(p) ** 2)
        assert _answer(v, "T").value == pytest.approx(T, rel=1e-8)


def test_T_matches_the_sympy_derivation_at_30_digits(variants):
    expr = kinetic_energy_euler_expr()
    for v in variants:
        p = v.params
        I1, I2, I3 = _moments(p)
        subs = {SYMBOLS[n]: sp.Float(p[n], 30)
                for n in ("beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot")}
        subs |= {SYMBOLS["I1"]: I1, SYMBOLS["I2"]: I2, SYMBOLS["I3"]: I3}
        reference = float(expr.evalf(30, subs=subs))
        assert _answer(v, "T").value == pytest.approx(reference, rel=1e-13)


def test_expression_is_the_textbook_formula(variants):
    answer = _answer(variants[0], "T_expr")
    symbols = answer.symbols
    difference = parse_expression(answer.value, symbols) - parse_expression(TEXTBOOK, symbols)
    assert sp.simplify(difference) == 0
    assert grade(answer, TEXTBOOK).status == "correct"
    assert grade(answer, sp.sympify(TEXTBOOK, locals=dict(SYMBOLS))).status == "correct"
    assert {_answer(v, "T_expr") for v in variants} == {answer}  # the same for every student


def test_symmetric_top_number_agrees_with_the_expression(variants):
    # The toy top's number is the textbook formula evaluated at its parameters (γ drops out).
    for v in variants:
        p = v.params
        if "I2" in p:
            continue
        values = {n: sp.Float(p[n], 30) for n in SYMBOLS if n in p}
        reference = float(sp.sympify(TEXTBOOK, locals=dict(SYMBOLS)).evalf(
            30, subs={SYMBOLS[n]: x for n, x in values.items()}))
        assert _answer(v, "T").value == pytest.approx(reference, rel=1e-13)
