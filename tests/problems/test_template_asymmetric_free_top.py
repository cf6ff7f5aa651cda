"""Independent checks of the exact asymmetric top template (R10).

Reference: Euler's equations (R7) written out here and integrated with scipy's DOP853 at
rtol 1e-12 from the displayed ω(0). The extrema of ω2 are the zeros of ω̇2 ∝ ω3 ω1, located as
integration events: consecutive ones are a maximum and a minimum, so their spacing is the flip
time, every second one the period, and ω must come back to ω(0) after one period. The circled
axis is the one whose component never changes sign along the integrated orbit. None of this
calls the solver.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from problems.templates import FAMILIES
from problems.templates import asymmetric_free_top as template

SEEDS = range(16)


def euler(moments: tuple[float, float, float], w: np.ndarray) -> np.ndarray:
    """R7, component by component."""
    I1, I2, I3 = moments
    return np.array([(I2 - I3) * w[1] * w[2] / I1,
                     (I3 - I1) * w[2] * w[0] / I2,
                     (I1 - I2) * w[0] * w[1] / I3])


@pytest.fixture(params=SEEDS, ids=[f"seed{s}" for s in SEEDS])
def orbit(request):
    """The variant, and its orbit integrated over 2.3 key periods with ω2's extrema."""
    variant = FAMILIES[template.NAME].generate(np.random.default_rng(request.param))
    moments = tuple(variant.params[k] for k in ("I1", "I2", "I3"))
    w0 = np.array(variant.params["omega0"])

    def omega2_extremum(t, w):
        return w[0] * w[2]

    t_end = 2.3 * variant.answer("period").value
    sol = solve_ivp(lambda t, w: euler(moments, w), (0.0, t_end), w0, method="DOP853",
                    rtol=1e-12, atol=1e-13 * np.abs(w0).max(), events=omega2_extremum,
                    dense_output=True)
    assert sol.success
    return variant, sol


def test_flip_time_is_the_spacing_of_omega2_max_and_min(orbit):
    variant, sol = orbit
    times, states = sol.t_events[0], sol.y_events[0]
    assert len(times) >= 4
    assert np.all(np.diff(np.sign(states[:, 1])) != 0)  # maxima and minima alternate
    assert_allclose(np.diff(times), variant.answer("t_flip").value, rtol=1e-8)


def test_period_brings_omega_back(orbit):
    variant, sol = orbit
    period = variant.answer("period").value
    times = sol.t_events[0]
    assert_allclose(times[2:] - times[:-2], period, rtol=1e-8)
    w0 = np.array(variant.params["omega0"])
    assert_allclose(sol.sol(period), w0, rtol=0, atol=1e-8 * np.abs(w0).max())
    half = sol.sol(period / 2)
    assert np.abs(half - w0).max() > 1e-3 * np.abs(w0).max()  # the period is the least one


def test_circled_axis_keeps_the_sign_of_its_component(orbit):
    variant, sol = orbit
    w = sol.sol(np.linspace(0.0, sol.t[-1], 2000))
    keeps_sign = [bool(np.all(np.sign(c) == np.sign(c[0]))) for c in w]
    assert keeps_sign == [str(k + 1) == variant.answer("circled_axis").value for k in range(3)]


def test_draws_are_ordered_off_the_separatrix_and_varied():
    kinds = set()
    for seed in range(60):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        m = np.array([v.params[k] for k in ("I1", "I2", "I3")])
        w = np.array(v.params["omega0"])
        assert np.all(np.diff(m) >= template.MIN_GAP * m[2])
        L2, two_T = np.sum((m * w) ** 2), np.sum(m * w**2)
        assert abs(L2 - two_T * m[1]) >= template.SEPARATRIX_GAP * L2
        kinds.add((int(np.argmax(np.abs(w))) + 1, v.answer("circled_axis").value))
    # flips near ê2 on both sides of the separatrix, wobbles about ê1 and ê3
    assert {(2, "1"), (2, "3"), (1, "1"), (3, "3")} <= kinds
