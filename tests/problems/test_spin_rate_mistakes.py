"""γ̇ given where ω3 = γ̇ + α̇ cos β is asked, or the reverse: a known mistake with its own
feedback in every family where the two differ (issue 13).

Each check is an identity of R12 (ω3 = γ̇ + α̇ cos β) between the key and the mistake's value,
not a recomputation by the template's own code.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from problems.answers import grade
from problems.templates import FAMILIES
from solver.heavy_top import nutation

SEEDS = range(40)


def _with(family: str, answer: str, mistake: str) -> list:
    """Variants of ``family`` (over SEEDS) whose ``answer`` lists ``mistake``."""
    found = [v for v in (FAMILIES[family].generate(np.random.default_rng(s)) for s in SEEDS)
             if v.answer(answer).mistake(mistake) is not None]
    assert len(found) >= 5, f"{family}.{answer}: {mistake} in only {len(found)} variants"
    return found


def _recognised(answer, name: str) -> str:
    verdict = grade(answer, answer.mistake(name).value)
    assert (verdict.status, verdict.mistake) == ("wrong", name)
    return verdict.message


def test_euler_rotation_omega3_taken_as_gamma_dot():
    for v in _with("euler_rotation", "omega_body", "omega3_is_gamma_dot"):
        p, key = v.params, np.array(v.answer("omega_body").value)
        wrong = np.array(v.answer("omega_body").mistake("omega3_is_gamma_dot").value)
        assert_allclose(key[2], p["gamma_dot"] + p["alpha_dot"] * math.cos(p["beta"]),
                        rtol=1e-12)  # R12
        assert_allclose(wrong, [key[0], key[1], p["gamma_dot"]], rtol=1e-12)
        assert "γ̇ + α̇ cos β" in _recognised(v.answer("omega_body"), "omega3_is_gamma_dot")


def test_euler_kinetic_energy_with_omega3_taken_as_gamma_dot():
    for v in _with("euler_kinetic_energy", "T", "omega3_is_gamma_dot"):
        p = v.params
        T, wrong = v.answer("T").value, v.answer("T").mistake("omega3_is_gamma_dot").value
        omega3 = p["gamma_dot"] + p["alpha_dot"] * math.cos(p["beta"])
        # only the ê3 term of T = ½ Σ I_i ω_i² changes
        assert_allclose(T - wrong, 0.5 * p["I3"] * (omega3**2 - p["gamma_dot"] ** 2),
                        rtol=1e-9)
        assert "γ̇ + α̇ cos β" in _recognised(v.answer("T"), "omega3_is_gamma_dot")


def test_heavy_top_p_alpha_with_omega3_taken_as_gamma_dot():
    """p_α = I1 α̇ sin²β + p_γ cos β: taking ω3 = γ̇ changes p_γ by I3 α̇ cos β and p_α by that
    times cos β — whatever I1 and I3 are."""
    for v in _with("heavy_top_constants", "p_alpha", "omega3_is_gamma_dot"):
        pg, pa = v.answer("p_gamma"), v.answer("p_alpha")
        d_pg = pg.value - pg.mistake("omega3_is_gamma_dot").value
        d_pa = pa.value - pa.mistake("omega3_is_gamma_dot").value
        assert_allclose(d_pa, d_pg * math.cos(v.params["beta0"]), rtol=1e-9)
        _recognised(pa, "omega3_is_gamma_dot")


@pytest.mark.parametrize("family", ["turning_points", "motion_type"])
def test_heavy_top_turning_points_list_it_where_it_moves_the_answer(family):
    """The same p_γ = I3 γ̇ mistake, propagated; listed only where α̇0 ≠ 0."""
    listed = 0
    for s in SEEDS:
        v = FAMILIES[family].generate(np.random.default_rng(s))
        for a in v.answers:
            if a.mistake("omega3_is_gamma_dot") is not None:
                assert v.params["alpha_dot0"] != 0.0
                _recognised(a, "omega3_is_gamma_dot")
                listed += 1
    assert listed >= 5


def test_nutation_with_the_given_omega3_taken_as_gamma_dot():
    """The reverse: ω3 is given, γ̇0 = ω3 − α̇0 cos β0 is what the motion needs."""
    variants = _with("nutation_precession", "T_nut", "gamma_dot_is_omega3")
    for v in variants:
        p = v.params
        assert p["alpha_dot0"] != 0.0
        n = nutation(p["I1"], p["I3"], p["Mgl"], p["beta0"], p["alpha_dot0"], 0.0, p["omega3"])
        assert_allclose(v.answer("T_nut").mistake("gamma_dot_is_omega3").value,
                        float(n["nutation_period"]), rtol=1e-12)
        assert "γ̇ = ω3 − α̇ cos β" in _recognised(v.answer("T_nut"), "gamma_dot_is_omega3")
    for s in SEEDS:
        v = FAMILIES["nutation_precession"].generate(np.random.default_rng(s))
        if v.params["alpha_dot0"] == 0.0:  # no precession: γ̇0 = ω3 exactly, no such mistake
            assert all(a.mistake("gamma_dot_is_omega3") is None for a in v.answers)
