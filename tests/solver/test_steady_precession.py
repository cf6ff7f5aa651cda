"""Sleeping top (R19) and steady precession (R21) against mpmath at 40 digits."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from solver.parameters import ParameterError
from solver.steady_precession import (
    critical_spin,
    fast_top_rates,
    sleeping_top_stable,
    steady_precession_rates,
)

mp.mp.dps = 40
I1, I3, MGL = 2.0e-4, 1.0e-4, 0.02


def _mp_rates(beta0, p_gamma):
    """R21 as printed, ``[p_γ ± √(p_γ² − 4 I1 Mgl cos β0)]/(2 I1 cos β0)``, in mpmath."""
    i1, mgl, pg, c = mp.mpf(I1), mp.mpf(MGL), mp.mpf(p_gamma), mp.cos(mp.mpf(beta0))
    root = mp.sqrt(pg**2 - 4 * i1 * mgl * c)
    lo, hi = (pg - root) / (2 * i1 * c), (pg + root) / (2 * i1 * c)
    return sorted((lo, hi), key=abs)


@pytest.mark.parametrize("beta0", [0.0, 0.5, 1.3, 2.0, 3.0])
@pytest.mark.parametrize("omega3", [60.0, 150.0, 5000.0, -150.0])
def test_steady_rates_against_mpmath(beta0, omega3):
    slow, fast = steady_precession_rates(I1, I3, MGL, beta0, I3 * omega3)
    want_slow, want_fast = _mp_rates(beta0, I3 * omega3)
    assert abs(slow / float(want_slow) - 1) < 1e-13
    assert abs(fast / float(want_fast) - 1) < 1e-13
    # both satisfy the steady-precession condition I1 cos β0 α̇² − p_γ α̇ + Mgl = 0 (R21)
    for rate in (slow, fast):
        residual = I1 * np.cos(beta0) * rate**2 - I3 * omega3 * rate + MGL
        assert abs(residual) < 1e-12 * (abs(I3 * omega3 * rate) + MGL)


def test_slow_rate_of_a_fast_top_does_not_cancel():
    """ω3 = 5e5 rad/s: the textbook (p_γ − √…)/(2 I1 cos β0) loses ~8 digits; ours none."""
    beta0, pg = 0.5, I3 * 5.0e5
    want = float(_mp_rates(beta0, pg)[0])
    textbook = (pg - np.sqrt(pg**2 - 4 * I1 * MGL * np.cos(beta0))) / (2 * I1 * np.cos(beta0))
    assert abs(textbook / want - 1) > 1e-10
    assert abs(steady_precession_rates(I1, I3, MGL, beta0, pg)[0] / want - 1) < 1e-15


def test_horizontal_axis_and_no_real_rates():
    slow, fast = steady_precession_rates(I1, I3, MGL, np.pi / 2, I3 * 150.0)
    # cos(fl(π/2)) = 6e-17 ≠ 0: the fast rate is huge, not infinite
    assert slow == pytest.approx(MGL / (I3 * 150.0), rel=1e-14) and abs(fast) > 1e15
    slow, fast = steady_precession_rates(I1, I3, MGL, 1.0, I3 * 20.0)  # p_γ² < 4 I1 Mgl cos β0
    assert np.isnan(slow) and np.isnan(fast)
    slow, fast = steady_precession_rates(I1, I3, MGL, [0.5, 1.0], I3 * np.array([150.0, 20.0]))
    assert np.isfinite(slow[0]) and np.isnan(slow[1])


def test_fast_top_rates_approach_the_exact_ones():
    """Relative error of the fast-top limits is O(I1 Mgl cos β0 / p_γ²) (R21)."""
    for omega3 in (1e3, 1e4, 1e5):
        pg = I3 * omega3
        slow, fast = fast_top_rates(I1, I3, MGL, 0.5, pg)
        exact = steady_precession_rates(I1, I3, MGL, 0.5, pg)
        small = I1 * MGL * np.cos(0.5) / pg**2
        assert abs(slow / exact[0] - 1) < 3 * small and abs(fast / exact[1] - 1) < 3 * small
    with pytest.raises(ParameterError) as err:
        fast_top_rates(I1, I3, MGL, 0.5, 0.0)
    assert err.value.parameter == "p_gamma"


def test_critical_spin_and_sleeping_stability():
    """R19: ω3 = 2√(Mgl I1)/I3; stable iff the β² coefficient p_γ²/(8 I1) − Mgl/2 ≥ 0."""
    crit = critical_spin(I1, I3, MGL)
    assert abs(crit - float(2 * mp.sqrt(mp.mpf(MGL) * I1) / I3)) < 1e-14 * crit
    omega = crit * np.array([1 - 1e-9, 1 + 1e-9, -(1 + 1e-9), 3.0])
    stable = sleeping_top_stable(I1, I3, MGL, omega)
    coeff = [(mp.mpf(I3) * w) ** 2 / (8 * mp.mpf(I1)) - mp.mpf(MGL) / 2 for w in omega]
    assert list(stable) == [c >= 0 for c in coeff]
    assert sleeping_top_stable(5.0, 1.0, 20.0, 20.0)  # exactly critical: p_γ² = 4 Mgl I1


@pytest.mark.parametrize(("call", "name"), [
    (lambda: steady_precession_rates(I1, I3, MGL, 4.0, 0.01), "beta0"),
    (lambda: steady_precession_rates(I1, I3, -MGL, 0.5, 0.01), "Mgl"),
    (lambda: critical_spin(0.0, I3, MGL), "I1"),
    (lambda: sleeping_top_stable(I1, I3, MGL, np.nan), "omega3"),
])
def test_bad_input(call, name):
    with pytest.raises(ParameterError) as err:
        call()
    assert err.value.parameter == name
