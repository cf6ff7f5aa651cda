"""Independent checks of the torque-free symmetric top template (R8).

References: Euler's equations (R7) written out here and integrated with scipy's DOP853 at
rtol 1e-12 — for ω(t), for Ω read off the turning of (ω1, ω2), and, together with the rotation
matrix (Ṙ = −[ω]ₓ R, R taking inertial to body components), for the precession of the symmetry
axis about the fixed L in space and the cone angle. None of this calls the solver.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from problems.templates import FAMILIES
from problems.templates import symmetric_free_top as template

SEEDS = range(12)


def euler(moments: np.ndarray, w: np.ndarray) -> np.ndarray:
    """R7, component by component."""
    I1, I2, I3 = moments
    return np.array([(I2 - I3) * w[1] * w[2] / I1,
                     (I3 - I1) * w[2] * w[0] / I2,
                     (I1 - I2) * w[0] * w[1] / I3])


def hat(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def integrate(variant, t_end: float, with_rotation: bool = False, n: int = 400):
    """ω(t) (and R(t), R(0) = identity) on ``n`` times in [0, t_end], DOP853 at rtol 1e-12."""
    I1, I3 = variant.params["I1"], variant.params["I3"]
    moments = np.array([I1, I1, I3])
    w0 = np.array(variant.params["omega0"])

    def rhs(t, y):
        w = y[:3]
        if not with_rotation:
            return euler(moments, w)
        R = y[3:].reshape(3, 3)
        return np.concatenate([euler(moments, w), (-hat(w) @ R).ravel()])

    y0 = np.concatenate([w0, np.eye(3).ravel()]) if with_rotation else w0
    times = np.linspace(0.0, t_end, n)
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", t_eval=times, rtol=1e-12,
                    atol=1e-12 * np.abs(y0).max())
    assert sol.success
    return times, sol.y.T


@pytest.fixture(params=SEEDS, ids=[f"seed{s}" for s in SEEDS])
def variant(request):
    return FAMILIES[template.NAME].generate(np.random.default_rng(request.param))


def test_omega_at_t_matches_integrated_euler_equations(variant):
    t = variant.params["t"]
    _, y = integrate(variant, t, n=2)
    assert_allclose(variant.answer("omega_t").value, y[-1], rtol=1e-9)


def test_body_rate_and_period_from_the_turning_of_omega_perp(variant):
    period = variant.answer("T_body").value
    times, y = integrate(variant, 1.5 * period)
    phase = np.unwrap(np.arctan2(y[:, 1], y[:, 0]))  # Ω > 0: from ê1 towards ê2
    slope = np.polyfit(times, phase, 1)[0]
    assert_allclose(variant.answer("Omega").value, slope, rtol=1e-8)
    _, back = integrate(variant, period, n=2)  # ω is back where it started after one period
    assert_allclose(back[-1], variant.params["omega0"], rtol=1e-9, atol=0)


def test_space_precession_and_cone_angle_from_the_orientation(variant):
    """ê3 seen from the inertial frame turns about the fixed L at L/I1, at the angle θ."""
    I1, I3 = variant.params["I1"], variant.params["I3"]
    w0 = np.array(variant.params["omega0"])
    L = np.array([I1, I1, I3]) * w0  # inertial = body components at t = 0 (R(0) = 1)
    alpha_dot = variant.answer("alpha_dot").value
    times, y = integrate(variant, 1.3 * 2 * math.pi / alpha_dot, with_rotation=True)
    e3 = y[:, 3:].reshape(-1, 3, 3)[:, 2, :]  # row 3 of R: ê3 in inertial components
    n = L / np.linalg.norm(L)
    u = np.cross(n, [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    phase = np.unwrap(np.arctan2(e3 @ v, e3 @ u))
    assert_allclose(np.polyfit(times, phase, 1)[0], alpha_dot, rtol=1e-8)
    assert_allclose(np.arccos(e3 @ n), variant.answer("theta").value, rtol=1e-8)


def test_oblate_and_prolate_bodies_are_both_drawn():
    shapes = set()
    for seed in range(40):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        oblate = v.params["I3"] > v.params["I1"]
        assert (v.answer("Omega").value > 0) == oblate  # ω3 > 0 in every draw
        # ω3 > 0 in every draw, so "oblate" would tell the sign of Ω: the shape is not named
        assert "oblate" not in v.statement and "prolate" not in v.statement
        shapes.add(oblate)
    assert shapes == {True, False}


@pytest.mark.parametrize("body", template.BODIES, ids=lambda b: b.noun)
def test_every_body_is_a_rigid_body_with_a_visible_wobble(body):
    """The catalogue's ranges give moments obeying I3 ≤ 2 I1 and the tilt stays in range."""
    seen = False
    for seed in range(60):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        if body.noun[1:] not in v.statement:
            continue
        seen = True
        I1, I3 = v.params["I1"], v.params["I3"]
        assert I3 <= 2 * I1
        w1, w2, w3 = v.params["omega0"]
        tilt = math.atan2(math.hypot(w1, w2), w3)
        assert 0.9 * template.TILT[0] < tilt < 1.1 * template.TILT[1]
    assert seen, f"{body.noun} never drawn in 60 seeds"
