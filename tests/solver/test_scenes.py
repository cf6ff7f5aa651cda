"""The dispatcher: which model per scene, and that it agrees with a high-accuracy integration."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from solver.methods import solve
from solver.parameters import ParameterError
from solver.scenes import (
    MODEL_FOR_KIND,
    FreeBody,
    HeavyBody,
    choose_model,
    fast_top_error,
    fast_top_parameter,
    solve_scene,
)

SCENES = {
    "free_symmetric": (FreeBody(1.0, 1.0, 1.7, (0.4, 0.1, 3.0)), "R8"),
    "free_asymmetric": (FreeBody(1.0, 2.0, 2.5, (0.2, 1.0, 0.3)), "R10"),
    "free_symmetric_about_axis_1": (FreeBody(1.6, 1.0, 1.0, (2.0, 0.3, 0.1)), "R10"),
    "heavy_symmetric": (HeavyBody(1.0, 1.0, 0.6, 1.0, 0.8, 0.2, 0.5, 3.0), "R20"),
    "sleeping": (HeavyBody(1.0, 1.0, 0.6, 1.0, 0.0, 0.0, 0.0, 8.0), "sleeping"),
    "sleeping_but_kicked": (HeavyBody(1.0, 1.0, 0.6, 1.0, 0.0, 0.0, 0.3, 8.0), "R20"),
    "torqued_asymmetric": (HeavyBody(1.0, 1.2, 0.6, 1.0, 0.8, 0.2, 0.5, 3.0), "DOP853"),
}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_model_choice(name):
    scene, model = SCENES[name]
    assert choose_model(scene) == model
    times = np.linspace(0.0, 6.0, 5)
    solution = solve_scene(scene, times)
    assert solution.model == model and solution.trajectory.success
    assert (solution.trajectory.nfev == 0) == (model != "DOP853")  # only one scene integrates


@pytest.mark.parametrize("name", sorted(SCENES))
def test_chosen_model_matches_a_tight_integration(name):
    """Against Radau at rtol 1e-12 (a different integrator from the dispatcher's DOP853)."""
    scene, _ = SCENES[name]
    times = np.linspace(0.0, 6.0, 5)
    chosen = solve_scene(scene, times).trajectory
    tight = solve(scene, times, "Radau", 1e-12)
    assert np.max(np.abs(chosen.y - tight.y)) < 2e-9


def test_torqued_asymmetric_body_conserves_its_invariants():
    """No closed form: check the integration against energy and p_α = L·ẑ, computed in mpmath
    from the initial state (the body's only two invariants with I1 ≠ I2)."""
    scene, _ = SCENES["torqued_asymmetric"]
    from solver.integrators import heavy_body_rhs, heavy_body_state, integrate_adaptive

    y0 = heavy_body_state(scene.beta0, scene.alpha_dot0, scene.beta_dot0, scene.gamma_dot0)
    rhs = heavy_body_rhs(scene.I1, scene.I2, scene.I3, scene.Mgl)
    result = integrate_adaptive(rhs, y0, [0.0, 20.0], "DOP853", 1e-12, 1e-12)
    moments = np.array([scene.I1, scene.I2, scene.I3])

    def energy_and_pz(y):
        q, w = y[:4] / np.linalg.norm(y[:4]), y[4:]
        qw, qx, qy, qz = q
        up = np.array([2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx**2 + qy**2)])
        return 0.5 * np.sum(moments * w**2) + scene.Mgl * up[2], np.dot(moments * w, up)

    with mp.workdps(40):  # initial invariants from R12/R15 with exact inputs
        b, ad, bd, gd = (mp.mpf(x) for x in (scene.beta0, scene.alpha_dot0, scene.beta_dot0,
                                               scene.gamma_dot0))
        w = [-ad * mp.sin(b), bd, ad * mp.cos(b) + gd]
        kinetic = sum(mp.mpf(i) * x**2 for i, x in zip(moments, w, strict=True)) / 2
        E0 = kinetic + scene.Mgl * mp.cos(b)
        pz0 = -scene.I1 * w[0] * mp.sin(b) + scene.I3 * w[2] * mp.cos(b)
    E, pz = energy_and_pz(result.y[-1])
    assert abs(E - float(E0)) < 1e-10 and abs(pz - float(pz0)) < 1e-10


@pytest.mark.parametrize("beta0", [0.0, 0.5, 1.2, 2.5])
@pytest.mark.parametrize("omega3", [5.0, 30.0, 300.0])
def test_fast_top_error_against_mpmath(beta0, omega3):
    I1, I3, Mgl = 2e-4, 1e-4, 0.02
    pg = I3 * omega3
    slow_err, fast_err = fast_top_error(I1, I3, Mgl, beta0, pg)
    with mp.workdps(40):
        c = mp.cos(mp.mpf(beta0))
        disc = mp.mpf(pg) ** 2 - 4 * mp.mpf(I1) * Mgl * c
        if disc < 0:
            assert np.isnan(slow_err) and np.isnan(fast_err)
            return
        slow = (pg - mp.sqrt(disc)) / (2 * I1 * c) if c != 0 else mp.mpf(Mgl) / pg
        ref_slow = float((mp.mpf(Mgl) / pg) / slow - 1)
        ref_fast = float((pg / (I1 * c)) / ((pg + mp.sqrt(disc)) / (2 * I1 * c)) - 1) if c else None
    assert slow_err == pytest.approx(ref_slow, rel=1e-8, abs=1e-15)
    if ref_fast is not None:
        assert fast_err == pytest.approx(ref_fast, rel=1e-8, abs=1e-15)
    eps = float(fast_top_parameter(I1, I3, Mgl, omega3))
    if eps < 1e-3:  # first order: ∓ ε cos β0 / 2
        assert slow_err == pytest.approx(-eps * np.cos(beta0) / 2, rel=2 * eps, abs=1e-15)


def test_every_kind_has_a_model_and_bad_scenes_are_named():
    assert set(MODEL_FOR_KIND) == {"free_symmetric", "free_asymmetric", "heavy_symmetric",
                                   "sleeping", "torqued_asymmetric"}
    with pytest.raises(ParameterError, match="I3"):
        FreeBody(1.0, 1.0, 3.0, (0.0, 0.0, 1.0))
    with pytest.raises(ParameterError, match="omega0"):
        FreeBody(1.0, 1.0, 1.0, (0.0, 1.0))
    with pytest.raises(ParameterError, match="Mgl"):
        HeavyBody(1.0, 1.0, 0.6, 0.0, 0.5, 0.0, 0.0, 1.0)
    with pytest.raises(ParameterError, match="beta0"):
        HeavyBody(1.0, 1.0, 0.6, 1.0, -0.5, 0.0, 0.0, 1.0)
