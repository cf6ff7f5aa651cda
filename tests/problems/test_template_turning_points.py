"""Independent checks of the turning_points template's answers (R15–R17).

The template's numbers come from ``solver.heavy_top`` (the nutation cubic of R17, solved about
``cos β0``). Here, from the *shown* parameters only, with R2's moments and R15/R16 typed in:

- ``V_eff(beta)`` from R16 evaluated by mpmath at 40 digits;
- ``β1, β2`` as the roots of ``V_eff(β) = E'`` found by ``scipy.optimize.brentq`` on either side
  of the minimum of ``V_eff`` (``minimize_scalar``) — no cubic, no ``cos β`` substitution;
- the scene's physical limits on those roots (the toy top's disc clear of the table, the hanging
  disc below its joint, the poles avoided, the nutation not degenerate);
- the known mistakes' turning points from the same root finding with the mistaken physics
  (``E`` for ``E'``, ``I1`` about the centre of mass).
"""

from __future__ import annotations

import math
from dataclasses import replace

import mpmath
import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from problems.answers import grade
from problems.templates import FAMILIES
from problems.templates import turning_points as template
from problems.templates.heavy_top_constants import MARGIN

SEEDS = range(30)
EDGE = 1e-9  # brackets stop this far from the poles, where V_eff is infinite


def _mistaken(variant, name, mistake_name):
    """The listed mistake's value, or None if the answer does not list it in this variant."""
    found = variant.answer(name).mistake(mistake_name)
    return None if found is None else found.value


@pytest.fixture(scope="module")
def variants():
    return [FAMILIES[template.NAME].generate(np.random.default_rng(seed)) for seed in SEEDS]


def top(p: dict) -> tuple[float, float, float, float | None]:
    """``(I1 about the tip, I3, Mgl, I1 about the CM or None)`` from R2, typed in."""
    Mgl = p["M"] * p["g"] * p["l"]
    if "I1" in p:
        return p["I1"], p["I3"], Mgl, None
    M, R, arm = p["M"], p["R"], p["l"]
    return M * R**2 / 4 + M * arm**2, M * R**2 / 2, Mgl, M * R**2 / 4


def constants(I1, I3, Mgl, p, beta_dot=None):
    """R15/R16: ``(p_α, p_γ, E')`` of the shown state (``beta_dot`` overrides ``β̇0``)."""
    b, ad, gd = p["beta0"], p["alpha_dot0"], p["gamma_dot0"]
    bd = p["beta_dot0"] if beta_dot is None else beta_dot
    p_gamma = I3 * (ad * math.cos(b) + gd)
    p_alpha = I1 * ad * math.sin(b) ** 2 + p_gamma * math.cos(b)
    e_prime = I1 * bd**2 / 2 + I1 * (ad * math.sin(b)) ** 2 / 2 + Mgl * math.cos(b)
    return p_alpha, p_gamma, e_prime


def v_eff(beta, I1, Mgl, p_alpha, p_gamma):
    """R16, typed in."""
    return ((p_alpha - p_gamma * math.cos(beta)) ** 2 / (2 * I1 * math.sin(beta) ** 2)
            + Mgl * math.cos(beta))


def roots(I1, Mgl, p_alpha, p_gamma, e_prime):
    """``β1 ≤ β2`` with ``V_eff = E'``, bracketed by the minimum of ``V_eff`` and the poles."""
    def f(b):
        return v_eff(b, I1, Mgl, p_alpha, p_gamma) - e_prime

    low = minimize_scalar(f, bounds=(EDGE, math.pi - EDGE), method="bounded",
                          options={"xatol": 1e-12}).x
    return (brentq(f, EDGE, low, xtol=1e-15, rtol=1e-14),
            brentq(f, low, math.pi - EDGE, xtol=1e-15, rtol=1e-14))


def test_every_scene_and_both_kinds_of_start_are_drawn(variants):
    assert len({v.title.split(":")[0] for v in variants}) == 3
    released = [v.params["alpha_dot0"] == 0 and v.params["beta_dot0"] == 0 for v in variants]
    assert any(released) and not all(released)


def test_V_eff_matches_R16_at_40_digits(variants):
    for v in variants:
        p = v.params
        I1, I3, Mgl, _ = top(p)
        with mpmath.workdps(40):
            b0, ad, gd, beta = (mpmath.mpf(p[k]) for k in ("beta0", "alpha_dot0", "gamma_dot0",
                                                            "beta"))
            p_gamma = I3 * (ad * mpmath.cos(b0) + gd)
            p_alpha = I1 * ad * mpmath.sin(b0) ** 2 + p_gamma * mpmath.cos(b0)
            reference = ((p_alpha - p_gamma * mpmath.cos(beta)) ** 2
                         / (2 * I1 * mpmath.sin(beta) ** 2) + Mgl * mpmath.cos(beta))
            spin = p_gamma**2 / (2 * I3)
        assert v.answer("V_eff").value == pytest.approx(float(reference), rel=1e-12)
        assert _mistaken(v, "V_eff", "spin_energy_included") == pytest.approx(
            float(reference + spin), rel=1e-12)


def test_turning_points_are_the_roots_of_V_eff_minus_E_prime(variants):
    for v in variants:
        p = v.params
        I1, I3, Mgl, _ = top(p)
        p_alpha, p_gamma, e_prime = constants(I1, I3, Mgl, p)
        beta1, beta2 = roots(I1, Mgl, p_alpha, p_gamma, e_prime)
        assert v.answer("beta1").value == pytest.approx(beta1, rel=1e-9)
        assert v.answer("beta2").value == pytest.approx(beta2, rel=1e-9)
        assert beta1 <= p["beta0"] + 1e-12 and p["beta0"] <= beta2 + 1e-12


def test_motion_stays_within_the_scene(variants):
    for v in variants:
        p = v.params
        beta1, beta2 = v.answer("beta1").value, v.answer("beta2").value
        assert 0.05 <= beta1 and beta2 <= math.pi - 0.05
        assert beta2 - beta1 >= 0.02  # not nearly steady precession
        if v.title.startswith("A toy top on a table"):
            assert beta2 < math.atan2(p["l"], p["R"])  # the rim stays off the table
        if v.title.startswith("A spinning disc"):
            assert beta1 >= math.pi / 2  # it hangs below the joint


def test_turning_point_mistakes_are_the_mistaken_physics(variants):
    cm_seen = 0
    for v in variants:
        p = v.params
        I1, I3, Mgl, I1_cm = top(p)
        p_alpha, p_gamma, e_prime = constants(I1, I3, Mgl, p)
        with_E = roots(I1, Mgl, p_alpha, p_gamma, e_prime + p_gamma**2 / (2 * I3))
        for name, index in (("beta1", 0), ("beta2", 1)):
            key = v.answer(name).value
            assert _mistaken(v, name, "degrees") == pytest.approx(key * 180 / math.pi, rel=1e-12)
            other = v.answer(("beta2", "beta1")[index]).value
            assert _mistaken(v, name, "turning_points_exchanged") == other
            value = _mistaken(v, name, "E_not_E_prime")
            assert value is None or value == pytest.approx(with_E[index], rel=1e-8)
        if I1_cm is not None:
            wrong = roots(I1_cm, Mgl, *constants(I1_cm, I3, Mgl, p))
            for name, index in (("beta1", 0), ("beta2", 1)):
                value = _mistaken(v, name, "I1_about_cm")
                if value is not None:
                    cm_seen += 1
                    assert value == pytest.approx(wrong[index], rel=1e-8)
    assert cm_seen > 0


def test_mistakes_are_named_even_with_tolerances_widened_margin_times(variants):
    # select_mistakes keeps mistakes MARGIN tolerances from the key and from each other (and
    # replace() re-validates: it refuses a mistake within the widened tolerance of the key)
    for v in variants:
        for a in v.answers:
            wide = replace(a, rtol=MARGIN * a.rtol, atol=MARGIN * a.atol)
            for m in wide.mistakes:
                assert grade(wide, m.value).mistake == m.name, (a.name, m.name)
