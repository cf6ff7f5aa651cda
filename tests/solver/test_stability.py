"""The stability battery: where the naive method fails and ours does not.

Each test measures both methods against an independent reference (mpmath at 40 digits, or a
closed form). Each library routine is used as its documentation recommends for the case (``quad``
with ``weight='alg'`` for the end singularities), and the tests assert the phenomenon — it fails,
it loses more than N digits, its error grows towards the singular case — not a library's exact
failure margins, which change between versions (those measured once are quoted in docstrings).
Already shown elsewhere, and not repeated here:

* near-double roots of the cubic, np.roots vs ours on fixed hard cases —
  ``test_nutation.py::test_np_roots_is_not_good_enough`` (here: the sweep towards the double root);
* the logarithmic growth of the period at the separatrix, ``(2/λ) ln(16/(1 − k²))`` —
  ``test_asymmetric_top.py::test_period_grows_logarithmically_at_the_separatrix``;
* scipy's ``ellipj`` near ``m = 1`` —
  ``test_jacobi.py::test_scipy_ellipj_fails_where_landen_does_not``;
* a loose RK45 drifting in energy where R10 does not —
  ``test_asymmetric_top.py::test_loose_explicit_integrator_drifts_exact_solution_does_not``.
"""

from __future__ import annotations

import warnings

import mpmath as mp
import numpy as np
import pytest
from scipy.integrate import IntegrationWarning, quad

from solver.asymmetric_top import asymmetric_top_period
from solver.bench.stability import flip_time_rows
from solver.heavy_top import (
    constants_of_motion,
    cos_beta,
    cubic_roots,
    nutation_period,
    steady_precession_rates,
)
from solver.methods import solve
from solver.scenes import FreeBody, HeavyBody
from solver.torque_free import invariants

I1, I3, MGL = 1.0, 0.6, 1.0


def _mp_roots(state):
    """Roots of R17's cubic from the exact binary state, mpmath 40 digits (independent)."""
    with mp.workdps(40):
        i1, i3, mgl, b0, ad, bd, gd = (mp.mpf(x) for x in state)
        c, s = mp.cos(b0), mp.sin(b0)
        pg = i3 * (ad * c + gd)
        pa = i1 * ad * s**2 + pg * c
        E = i1 * (bd**2 + ad**2 * s**2) / 2 + mgl * c
        a, b, A, B = pg / i1, pa / i1, 2 * E / i1, 2 * mgl / i1
        roots = mp.polyroots([B, -(A + a * a), 2 * a * b - B, A - b * b], maxsteps=400,
                             extraprec=400)
        return sorted(mp.re(r) for r in roots), B


# --- Euler angles against quaternions near the vertical --------------------------------------


def _through_vertical(eta: float) -> HeavyBody:
    """Stable spin (ω3 = 10 > ω_c = 3.3); α̇0 puts p_α = p_γ (1 + O(η)): for η = 0 the axis
    passes exactly through the vertical, otherwise within β1 ≈ 0.31 η of it."""
    b0, w3 = 0.3, 10.0
    ad0 = I3 * w3 * (1 - np.cos(b0)) / (I1 * np.sin(b0) ** 2) * (1 + eta)
    return HeavyBody(I1, I1, I3, MGL, b0, ad0, 0.0, w3 - ad0 * np.cos(b0))


def _near_vertical_run(scene, method):
    state = scene.heavy_top_state()
    times = np.linspace(0.0, 3 * float(nutation_period(*state)), 7)
    traj = solve(scene, times, method, 1e-10)
    return traj, np.max(np.abs(traj.y - cos_beta(times, *state)))


def test_euler_angles_cost_and_error_blow_up_near_the_vertical():
    """Measured (DOP853, rtol 1e-10, 3 nutation periods, error vs R20): Euler angles need 2657
    evaluations at β1 = 3e-2, 13193 at 3e-9 and lose 1e-10 (7e-8) when the axis passes through
    the vertical; quaternions need 545 throughout, error 1.4e-10 (the tolerance's)."""
    far, near, through = (_through_vertical(eta) for eta in (1e-1, 1e-8, 0.0))
    euler = [_near_vertical_run(s, "EulerAngles") for s in (far, near, through)]
    quat = [_near_vertical_run(s, "DOP853") for s in (far, near, through)]
    assert euler[1][0].nfev > 4 * euler[0][0].nfev  # cost grows like log(1/β1)
    assert euler[2][1] > 1e-8  # through the vertical: accuracy lost
    assert len({q.nfev for q, _ in quat}) == 1  # quaternions do not see the vertical
    assert max(err for _, err in quat) < 5e-10
    assert euler[2][0].nfev > 20 * quat[2][0].nfev


def test_sleeping_top_euler_angles_fail_quaternions_exact():
    """β0 = β̇0 = 0: the Euler-angle equations divide 0 by sin 0; quaternions keep u = 1."""
    scene = HeavyBody(I1, I1, I3, MGL, 0.0, 0.0, 0.0, 10.0)
    times = np.linspace(0.0, 5.0, 6)
    naive = solve(scene, times, "EulerAngles", 1e-10)
    assert not naive.success and "non-finite" in naive.message
    ours = solve(scene, times, "DOP853", 1e-10)
    assert ours.success and np.max(np.abs(ours.y - 1.0)) < 1e-15


# --- near-double roots: the sweep ------------------------------------------------------------


@pytest.mark.parametrize("beta_dot0", [1e-2, 1e-4, 1e-6, 1e-8])
def test_near_double_root_sweep(beta_dot0):
    """Approach steady precession (u2 − u1 ∝ β̇0²): np.roots on the expanded cubic loses about
    √ε·(scale) — measured error of u1, u2 above 1e-10 once β̇0 ≤ 1e-4 (u2 − u1 ≲ 1e-8) — ours
    stays at rounding (< 4e-16) along the whole sweep."""
    slow, _ = steady_precession_rates(I1, I3, MGL, 0.8, I3 * 60.0)
    state = (I1, I3, MGL, 0.8, float(slow), beta_dot0, 60.0 - float(slow) * np.cos(0.8))
    (u1, u2, _), _ = _mp_roots(state)
    pa, pg, e = constants_of_motion(*state)
    a, b, A, B = pg / I1, pa / I1, 2 * e / I1, 2 * MGL / I1
    naive = np.sort(np.roots([B, -A - a * a, 2 * a * b - B, A - b * b]).real)
    ours = cubic_roots(*state)
    naive_err = max(abs(naive[0] - float(u1)), abs(naive[1] - float(u2)))
    ours_err = max(abs(ours[0] - float(u1)), abs(ours[1] - float(u2)))
    assert ours_err < 4e-16
    if beta_dot0 <= 1e-4:
        assert naive_err > 1e-10


# --- the separatrix: flip time ---------------------------------------------------------------


def test_flip_time_near_the_separatrix():
    """ω0 = (δ, 1, δ) about the intermediate axis of (1, 2, 3): 1 − k² ≈ 2δ². The flip time
    (half period, 2K/λ) from an integration (DOP853, rtol 1e-10: time between zero crossings of
    ω2) against mpmath's 2K/λ loses accuracy as the separatrix nears (sensitivity ∝ 1/√(1 − k²):
    each factor 100 closer costs the integration at least a factor 10), while ``flip_time``
    stays at rounding. The bench's battery makes the measurement (``flip_time_rows``, the
    reference computed there with mpmath, not by ``flip_time``); its numbers are in
    ``docs/bench/summary.md``."""
    rows = flip_time_rows()  # the bench's own measurement, in the order δ = 1e-4, 1e-6, 1e-8
    assert [r["value"] for r in rows if r["method"] == "flip_time"] == [1e-4, 1e-6, 1e-8]
    ours = [r["error"] for r in rows if r["method"] == "flip_time"]
    integrated = [r["error"] for r in rows if r["method"].startswith("DOP853")]
    assert max(ours) < 1e-15
    assert integrated[1] > 10 * integrated[0] and integrated[2] > 10 * integrated[1]
    assert integrated[2] > 1e-6  # the integration has lost more than ten of its digits


# --- the nutation period: quadrature used naively and as documented, against Carlson -------


@pytest.mark.parametrize(
    "name", ["fast top", "near steady"],
)
def test_nutation_period_quadrature_against_carlson(name):
    """``T = 2 ∫ du/√f`` has inverse-square-root end singularities. scipy's ``quad`` documents
    ``weight='alg'`` for exactly that (``(u − u1)^−½ (u2 − u)^−½`` handled by the rule): used so,
    it meets the 1e-10 target against mpmath's ``4K(k)/√(B(u3 − u1))`` (measured 1e-15 fast,
    4e-12 near steady, where the interval is narrow), as ``nutation_period`` (Carlson R_F) does
    to rounding. Called naively on ``2/√f`` (f from the expanded cubic) it loses digits — the
    phenomenon asserted, not scipy's exact margin (which changes between versions)."""
    if name == "near steady":
        slow = float(steady_precession_rates(I1, I3, MGL, 0.8, I3 * 60.0)[0])
        state = (I1, I3, MGL, 0.8, slow, 1e-4, 60.0 - slow * np.cos(0.8))
    else:
        state = (I1, I3, MGL, 0.8, 0.0, 0.1, 200.0)
    (u1, u2, u3), B = _mp_roots(state)
    with mp.workdps(40):
        reference = float(4 * mp.ellipk((u2 - u1) / (u3 - u1)) / mp.sqrt(B * (u3 - u1)))
    pa, pg, e = constants_of_motion(*state)
    a, b, A, Bf = pg / I1, pa / I1, 2 * e / I1, 2 * MGL / I1

    def integrand(u):
        f = (1 - u * u) * (A - Bf * u) - (b - a * u) ** 2
        return 2.0 / np.sqrt(f) if f > 0 else 0.0

    r1, r2, r3 = (float(x) for x in cubic_roots(*state))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IntegrationWarning)
        naive = quad(integrand, r1, r2)[0]
    documented = quad(lambda u: 2.0 / np.sqrt(Bf * (r3 - u)), r1, r2, weight="alg",
                      wvar=(-0.5, -0.5))[0]
    assert abs(documented / reference - 1) < 1e-10  # the project's accuracy target
    assert abs(naive / reference - 1) > 100 * abs(documented / reference - 1)
    assert abs(float(nutation_period(*state)) / reference - 1) < 1e-15


# --- explicit Runge–Kutta drift against the Lie–Poisson splitting ----------------------------


def test_rk4_energy_drifts_lie_poisson_error_stays_bounded():
    """Same step (period/20), sampled 4 times a period-ish over 1000 periods: RK4's energy error
    grows linearly (max over the last 100 periods ≈ 10 × the max over the first 100), the
    Lie–Poisson splitting's oscillates within a fixed bound (its modified energy is conserved)
    and it keeps |L|² to rounding."""
    scene = FreeBody(1.0, 2.0, 3.0, (0.5, 0.0, 1.0))
    period = float(asymmetric_top_period(1.0, 2.0, 3.0, scene.omega0))
    cycles = np.linspace(0.25, 1000.0, 4000)
    early, late = cycles <= 100.0, cycles >= 900.0
    times = period * cycles
    T0, L20 = invariants(1.0, 2.0, 3.0, scene.omega0)
    errors = {}
    for method in ("RK4", "LiePoisson2"):
        traj = solve(scene, times, method, period / 20)
        T, L2 = invariants(1.0, 2.0, 3.0, traj.y)
        errors[method] = np.abs(T / T0 - 1), np.abs(L2 / L20 - 1)
    rk4_T, _ = errors["RK4"]
    lp_T, lp_L2 = errors["LiePoisson2"]
    assert rk4_T[late].max() > 8 * rk4_T[early].max()
    assert lp_T[late].max() < 1.1 * lp_T[early].max()
    assert np.all(lp_L2 < 1e-13)
