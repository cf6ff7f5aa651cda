"""Issue 34: tops swinging between near-upright and near-hanging (R17, R20).

``u2 ≈ u3 ≈ 1``: the cubic's two upper roots are a near-double root in ``w = u − cos β0``, so
their offsets are only good to ``ε |f| / |f'|`` and ``1 − u2 = (1 − u0) − w2`` lost up to 9 digits
of ``⟨α̇⟩`` and the period; the pole distances must come from the cubic re-solved in
``v = 1 − u``. Each state is judged against the independent mpmath reference with the fuzz's
acceptance (``solver.bench.fuzz``: ``error ≤ max(FLOOR, K × measured condition)``).
"""

from __future__ import annotations

import pytest

from solver.bench.fuzz import FLOOR, K, reference_row
from solver.heavy_top import nutation, solve_heavy_top_many

# (I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
SWINGS = [
    (1.0, 1.0, 1.0, 0.001, -0.001, -0.001, 0.0),  # the hypothesis failure: β1 = 2.2e-5 rad
    (1.0, 1.0, 1.0, 0.001, 0.001, 0.001, 0.0),  # its mirror image
    (1.0, 1.0, 1.0, 0.001, -1e-05, -0.001, -0.0001),  # was 1e-7 off in ⟨α̇⟩
    (1.0, 1.0, 1.0, 0.001, -1e-05, 0.001, 0.0),  # was 2e-8 off in the period
    # released at the hanging end (β̇0 = 0: the exact root deflated, u2 ≈ u3 from the quadratic)
    (1.0, 1.0, 1.0, 3.1405926537981266, -2000.0005000005, 0.0, -2000.00050000025),
]


@pytest.mark.parametrize("state", SWINGS)
def test_swing_between_the_poles_matches_the_reference(state):
    row = reference_row((0, state, 0))
    fast = nutation(*state)
    table = solve_heavy_top_many(*state)
    for key in ("nutation_period", "mean_precession_rate"):
        ref, tol = row["ref"][key], max(FLOOR, K * row["cond"][key])
        for got in (float(fast[key]), float(table[key][0])):
            assert abs(got - ref) <= tol * abs(ref), (key, got, ref)
    for key in ("beta1", "beta2"):
        ref, tol = row["ref"][key], max(FLOOR, K * row["cond"][key])
        assert abs(float(fast[key]) - ref) <= tol, (key, float(fast[key]), ref)


@pytest.mark.parametrize("spin", [1e-30, 1e-60, 1e-150])
def test_the_reference_resolves_a_turning_point_rounded_onto_the_hanging_pole(spin):
    """Upright at rest but for a spin ``γ̇0``: ``b = a = I3 γ̇0 / I1`` and the lower turning point
    ``u1 = a²/B − 1`` lies ``a²/B`` above the hanging pole — below the reference's first
    precision, where ``α̇(u1) = a/(1 + u1)`` was a division by zero (hypothesis seed 4). The
    reference raises its digits instead; ``α̇(u1) = B/a`` in closed form (R18)."""
    from solver.bench.mp_reference import reference

    I1, I3, Mgl = 1.0, 0.5, 1.0
    ref = reference((I1, I3, Mgl, 0.0, 0.0, 0.0, spin))
    a, B = I3 * spin / I1, 2 * Mgl / I1
    assert float(ref.rates[1]) == pytest.approx(B / a, rel=1e-12)
    assert float(ref.rates[0]) == pytest.approx(a / 2, rel=1e-12)
