"""Independent checks of the heavy_top_constants template's answers (R14–R16).

The template's numbers come from ``solver.heavy_top.constants_of_motion`` (numpy). Here, from
the *shown* parameters only, with the moments typed in from R2 (thin disc: ``I1 = M R²/4 +
M l²`` about the tip, ``I3 = M R²/2``; the gyroscope's are given):

- ``p_α``, ``p_γ`` and ``E'`` derived by sympy from the Lagrangian R14 typed in here
  (``p = ∂L/∂q̇``, ``E = Σ p q̇ − L``), evaluated at 30 digits;
- ``E'`` from R15's energy in its textbook form (with ``(p_α − p_γ cos β)²/(2 I1 sin²β)``),
  evaluated by mpmath at 40 digits, minus ``p_γ²/(2 I3)`` (R16);
- the known mistakes' values from the same formulas with the mistaken input (``I1`` about the
  centre of mass, ``I1`` and ``I3`` swapped, ``ω3 = γ̇``, ``p_α`` without ``p_γ cos β``, ``E``).
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import cache

import mpmath
import numpy as np
import pytest
import sympy as sp

from problems.answers import grade
from problems.templates import FAMILIES
from problems.templates import heavy_top_constants as template

SEEDS = range(30)
ANSWERS = ("p_gamma", "p_alpha", "E_prime")


def _mistaken(variant, name, mistake_name):
    """The listed mistake's value, or None if the answer does not list it in this variant."""
    found = variant.answer(name).mistake(mistake_name)
    return None if found is None else found.value


@pytest.fixture(scope="module")
def variants():
    return [FAMILIES[template.NAME].generate(np.random.default_rng(seed)) for seed in SEEDS]


def moments(p: dict) -> tuple[float, float, float]:
    """``(I1 about the tip, I3, I1 about the centre of mass or None)`` from R2, typed in."""
    if "I1" in p:
        return p["I1"], p["I3"], None
    M, R, arm = p["M"], p["R"], p["l"]
    return M * R**2 / 4 + M * arm**2, M * R**2 / 2, M * R**2 / 4


@cache
def lagrangian_constants():
    """``(p_α, p_γ, E')`` as functions of the state, derived by sympy from R14."""
    I1, I3, Mgl, beta, ad, bd, gd = sp.symbols("I1 I3 Mgl beta alpha_dot beta_dot gamma_dot")
    L = (I1 / 2 * (ad**2 * sp.sin(beta) ** 2 + bd**2)
         + I3 / 2 * (ad * sp.cos(beta) + gd) ** 2 - Mgl * sp.cos(beta))
    p_alpha, p_beta, p_gamma = (sp.diff(L, v) for v in (ad, bd, gd))
    E = ad * p_alpha + bd * p_beta + gd * p_gamma - L
    symbols = (I1, I3, Mgl, beta, ad, bd, gd)
    return symbols, (p_alpha, p_gamma, sp.expand(E - p_gamma**2 / (2 * I3)))


def state(p):
    return (p["beta0"], p["alpha_dot0"], p["beta_dot0"], p["gamma_dot0"])


def textbook_energy(I1, I3, Mgl, beta, ad, bd, gd):
    """R15's ``p_α, p_γ`` and ``E' = E − p_γ²/(2 I3)`` with E in its textbook form, mpmath."""
    with mpmath.workdps(40):
        I1, I3, Mgl, beta, ad, bd, gd = map(mpmath.mpf, (I1, I3, Mgl, beta, ad, bd, gd))
        p_gamma = I3 * (ad * mpmath.cos(beta) + gd)
        p_alpha = I1 * ad * mpmath.sin(beta) ** 2 + p_gamma * mpmath.cos(beta)
        E = (I1 * bd**2 / 2 + p_gamma**2 / (2 * I3)
             + (p_alpha - p_gamma * mpmath.cos(beta)) ** 2 / (2 * I1 * mpmath.sin(beta) ** 2)
             + Mgl * mpmath.cos(beta))
        return float(p_alpha), float(p_gamma), float(E - p_gamma**2 / (2 * I3)), float(E)


def test_every_scene_is_drawn(variants):
    assert {v.title.split(":")[0] for v in variants} == {
        "A toy top on a table", "A gyroscope on a post", "A spinning disc hanging from a ball joint"
    }
    for v in variants:
        assert v.params["g"] == 9.81
        if v.title.startswith("A spinning disc"):
            assert v.params["beta0"] > math.pi / 2  # hangs below its joint
        if v.title.startswith("A toy top on a table"):
            assert v.params["beta0"] < math.atan2(v.params["l"], v.params["R"])  # rim clear


def test_constants_match_the_lagrangian_at_30_digits(variants):
    symbols, exprs = lagrangian_constants()
    for v in variants:
        p = v.params
        I1, I3, _ = moments(p)
        values = (I1, I3, p["M"] * p["g"] * p["l"], *state(p))
        subs = {s: sp.Float(x, 30) for s, x in zip(symbols, values, strict=True)}
        p_alpha, p_gamma, e_prime = (float(e.evalf(30, subs=subs)) for e in exprs)
        assert v.answer("p_alpha").value == pytest.approx(p_alpha, rel=1e-12)
        assert v.answer("p_gamma").value == pytest.approx(p_gamma, rel=1e-12)
        assert v.answer("E_prime").value == pytest.approx(e_prime, rel=1e-12)


def test_E_prime_matches_the_textbook_energy_minus_spin_energy(variants):
    for v in variants:
        p = v.params
        I1, I3, _ = moments(p)
        _, _, e_prime, E = textbook_energy(I1, I3, p["M"] * p["g"] * p["l"], *state(p))
        assert v.answer("E_prime").value == pytest.approx(e_prime, rel=1e-12)
        assert _mistaken(v, "E_prime", "E_not_E_prime") == pytest.approx(E, rel=1e-12)


def test_mistakes_are_the_mistaken_physics(variants):
    cm_seen = 0
    for v in variants:
        p = v.params
        I1, I3, I1_cm = moments(p)
        Mgl = p["M"] * p["g"] * p["l"]
        beta, ad, _, gd = state(p)
        assert _mistaken(v, "p_gamma", "omega3_is_gamma_dot") == pytest.approx(I3 * gd, rel=1e-12)
        assert _mistaken(v, "p_alpha", "missing_p_gamma_term") == pytest.approx(
            I1 * ad * math.sin(beta) ** 2, rel=1e-12)
        swapped = textbook_energy(I3, I1, Mgl, *state(p))
        for name, reference in zip(("p_alpha", "p_gamma", "E_prime"), swapped, strict=False):
            value = _mistaken(v, name, "I1_I3_swapped")
            assert value is None or value == pytest.approx(reference, rel=1e-12)
        if I1_cm is not None:
            wrong = textbook_energy(I1_cm, I3, Mgl, *state(p))
            for name, reference in (("p_alpha", wrong[0]), ("E_prime", wrong[2])):
                value = _mistaken(v, name, "I1_about_cm")
                if value is not None:
                    cm_seen += 1
                    assert value == pytest.approx(reference, rel=1e-12)
        degrees = textbook_energy(I1, I3, Mgl, math.radians(beta), *state(p)[1:])
        value = _mistaken(v, "p_alpha", "degree_mode")
        assert value is None or value == pytest.approx(degrees[0], rel=1e-12)
    assert cm_seen > 0


def test_answers_are_well_conditioned(variants):
    # |p_α| and |E'| are not a small difference of large terms (template's MIN_CONDITION).
    for v in variants:
        p = v.params
        I1 = moments(p)[0]
        beta, ad, bd, _ = state(p)
        pg = v.answer("p_gamma").value
        terms_pa = abs(I1 * ad * math.sin(beta) ** 2) + abs(pg * math.cos(beta))
        terms_e = (I1 * (bd**2 + (ad * math.sin(beta)) ** 2) / 2
                   + abs(p["M"] * p["g"] * p["l"] * math.cos(beta)))
        assert abs(v.answer("p_alpha").value) >= 0.19 * terms_pa
        assert abs(v.answer("E_prime").value) >= 0.19 * terms_e


def test_primary_mistakes_always_listed(variants):
    for v in variants:
        assert _mistaken(v, "p_gamma", "omega3_is_gamma_dot") is not None
        assert _mistaken(v, "p_alpha", "missing_p_gamma_term") is not None
        assert _mistaken(v, "E_prime", "E_not_E_prime") is not None


def test_mistakes_are_named_even_with_tolerances_widened_margin_times(variants):
    # select_mistakes keeps mistakes MARGIN tolerances from the key and from each other (and
    # replace() re-validates: it refuses a mistake within the widened tolerance of the key)
    for v in variants:
        for a in v.answers:
            wide = replace(a, rtol=template.MARGIN * a.rtol, atol=template.MARGIN * a.atol)
            for m in wide.mistakes:
                assert grade(wide, m.value).mistake == m.name, (a.name, m.name)
