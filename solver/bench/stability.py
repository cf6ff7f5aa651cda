"""The stability battery, measured: where a naive method fails and the project's does not.

Each stage returns rows ``{"case", "parameter", "method", "error", "nfev", "note"}`` (``error``
NaN and ``note`` the reason where a method fails outright); ``eulertop bench`` writes them to
``stability.csv`` and the site's table is rendered from it. References are independent of the
code under test: mpmath at 40 digits (the cubic's roots, ``2K/λ``, ``4K/√(B(u3 − u1))``, R20),
or a closed form (a sleeping top keeps ``u ≡ 1``). ``tests/solver/test_stability.py`` asserts
the same phenomena (it fails; it loses more than N digits), not these measured margins.
"""

from __future__ import annotations

import math
import warnings

import mpmath as mp
import numpy as np

from solver.asymmetric_top import asymmetric_top_period, flip_time
from solver.bench.work_precision import heavy_reference, mp_cubic_roots
from solver.heavy_top import (
    constants_of_motion,
    cubic_roots,
    nutation_period,
    steady_precession_rates,
    turning_points,
)
from solver.methods import solve
from solver.scenes import FreeBody, HeavyBody
from solver.torque_free import invariants

__all__ = [
    "double_root_rows",
    "energy_drift_rows",
    "flip_time_rows",
    "near_vertical_rows",
    "quadrature_rows",
    "stability_battery",
]

I1, I3, MGL = 1.0, 0.6, 1.0
VERTICAL_RTOL = 1e-10


def _row(case: str, parameter: str, method: str, error: float, nfev: int | None = None,
         note: str = "", value: float | None = None) -> dict:
    """One measurement; ``parameter`` names the case's variable and ``value`` is its value
    (``None`` where ``parameter`` is a description)."""
    return {"case": case, "parameter": parameter, "value": value, "method": method,
            "error": error, "nfev": nfev, "note": note}


def _through_vertical(eta: float) -> HeavyBody:
    """Stable spin (ω3 = 10 > ω_c); α̇0 puts ``p_α = p_γ (1 + η)``: for η = 0 the axis passes
    through the vertical, otherwise within β1 = O(η) of it."""
    b0, w3 = 0.3, 10.0
    ad0 = I3 * w3 * (1 - math.cos(b0)) / (I1 * math.sin(b0) ** 2) * (1 + eta)
    return HeavyBody(I1, I1, I3, MGL, b0, ad0, 0.0, w3 - ad0 * math.cos(b0))


def near_vertical_rows() -> list[dict]:
    """Euler angles (R14, ÷ sin β) against quaternions, both DOP853 at rtol ``VERTICAL_RTOL``
    over 3 nutation periods (7 times), for an axis passing within β1 of the vertical and for a
    sleeping top (reference ``u ≡ 1``)."""
    rows = []
    case = f"axis near the vertical (DOP853, rtol {VERTICAL_RTOL:g}, 3 nutation periods)"
    for eta in (1e-1, 1e-8, 0.0):
        scene = _through_vertical(eta)
        state = scene.heavy_top_state()
        beta1 = float(turning_points(*state)[0])
        times = np.linspace(0.0, 3 * float(nutation_period(*state)), 7)
        reference = np.array([heavy_reference(scene, float(t)) for t in times])
        label, value = ("through the vertical", None) if eta == 0 else ("β1", beta1)
        for method, name in (("EulerAngles", "Euler angles"), ("DOP853", "quaternions")):
            traj = solve(scene, times, method, VERTICAL_RTOL)
            error = float(np.max(np.abs(traj.y - reference))) if traj.success else math.nan
            rows.append(_row(case, label, name, error, traj.nfev,
                             "" if traj.success else traj.message, value))
    sleeping = HeavyBody(I1, I1, I3, MGL, 0.0, 0.0, 0.0, 10.0)
    times = np.linspace(0.0, 5.0, 6)
    for method, name in (("EulerAngles", "Euler angles"), ("DOP853", "quaternions")):
        traj = solve(sleeping, times, method, VERTICAL_RTOL)
        error = float(np.max(np.abs(traj.y - 1.0))) if traj.success else math.nan
        rows.append(_row(case, "sleeping top", name, error, traj.nfev,
                         "" if traj.success else traj.message))
    return rows


def _steady_state(beta_dot0: float) -> tuple[float, ...]:
    slow = float(steady_precession_rates(I1, I3, MGL, 0.8, I3 * 60.0)[0])
    return (I1, I3, MGL, 0.8, slow, beta_dot0, 60.0 - slow * math.cos(0.8))


def double_root_rows() -> list[dict]:
    """Max error of u1, u2 near a double root (β̇0 → 0 at steady precession): ``np.roots`` on the
    expanded cubic against ``cubic_roots``, both against mpmath."""
    rows = []
    case = "near-double root (β̇0 → 0 at steady precession), max error of u1, u2"
    for beta_dot0 in (1e-2, 1e-4, 1e-6, 1e-8):
        state = _steady_state(beta_dot0)
        with mp.workdps(40):
            u1, u2, _ = mp_cubic_roots(state)
            ref = (float(u1), float(u2))
        pa, pg, e = constants_of_motion(*state)
        a, b, A, B = pg / I1, pa / I1, 2 * e / I1, 2 * MGL / I1
        naive = np.sort(np.roots([B, -A - a * a, 2 * a * b - B, A - b * b]).real)
        ours = cubic_roots(*state)
        for name, roots in (("np.roots", naive), ("cubic_roots", ours)):
            error = max(abs(float(roots[0]) - ref[0]), abs(float(roots[1]) - ref[1]))
            rows.append(_row(case, "β̇0", name, error, value=beta_dot0))
    return rows


def flip_time_rows() -> list[dict]:
    """Relative error of the flip time (2K/λ) at ``ω0 = (δ, 1, δ)``, ``I = (1, 2, 3)``: an
    integration (DOP853, rtol 1e-10, time between zero crossings of ω2) against ``flip_time``,
    both against mpmath."""
    from scipy.integrate import solve_ivp

    from solver.integrators import free_body_rhs

    rows = []
    case = "flip time near the separatrix, ω0 = (δ, 1, δ), relative error"
    moments = (1.0, 2.0, 3.0)
    for delta in (1e-4, 1e-6, 1e-8):
        w0 = np.array([delta, 1.0, delta])
        with mp.workdps(40):
            m1, m2, m3 = (mp.mpf(x) for x in moments)
            w = [mp.mpf(x) for x in w0]
            two_T = m1 * w[0] ** 2 + m2 * w[1] ** 2 + m3 * w[2] ** 2
            L2 = m1**2 * w[0] ** 2 + m2**2 * w[1] ** 2 + m3**2 * w[2] ** 2
            lam = mp.sqrt((m3 - m2) * (L2 - two_T * m1) / (m1 * m2 * m3))
            m = (m2 - m1) * (two_T * m3 - L2) / ((m3 - m2) * (L2 - two_T * m1))
            reference = float(2 * mp.ellipk(m) / lam)
        ours = float(flip_time(*moments, w0))

        def crossing(t, y):
            return y[1]

        sol = solve_ivp(free_body_rhs(*moments), (0, 2.2 * ours), w0, method="DOP853",
                        rtol=1e-10, atol=1e-12, events=crossing)
        first, second = sol.t_events[0][:2]
        rows.append(_row(case, "δ", "DOP853, rtol 1e-10",
                         float(abs((second - first) / reference - 1)), sol.nfev, value=delta))
        rows.append(_row(case, "δ", "flip_time", abs(ours / reference - 1), value=delta))
    return rows


def quadrature_rows() -> list[dict]:
    """Relative error of the nutation period ``2 ∫ du/√f``: scipy ``quad`` on the raw integrand,
    ``quad`` as its documentation recommends for end singularities (``weight='alg'``,
    ``wvar=(-½, -½)``), and ``nutation_period`` (Carlson R_F), against mpmath's
    ``4K(k)/√(B(u3 − u1))``."""
    from scipy.integrate import IntegrationWarning, quad

    rows = []
    case = "nutation period, relative error"
    for label, state in (("fast top", (I1, I3, MGL, 0.8, 0.0, 0.1, 200.0)),
                         ("near steady", _steady_state(1e-4))):
        with mp.workdps(40):
            u1, u2, u3 = mp_cubic_roots(state)
            B = 2 * mp.mpf(MGL) / mp.mpf(I1)
            reference = float(4 * mp.ellipk((u2 - u1) / (u3 - u1)) / mp.sqrt(B * (u3 - u1)))
        pa, pg, e = constants_of_motion(*state)
        a, b, A, Bf = pg / I1, pa / I1, 2 * e / I1, 2 * MGL / I1

        def integrand(u, a=a, b=b, A=A, Bf=Bf):
            f = (1 - u * u) * (A - Bf * u) - (b - a * u) ** 2
            return 2.0 / np.sqrt(f) if f > 0 else 0.0

        r1, r2, r3 = (float(x) for x in cubic_roots(*state))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IntegrationWarning)
            naive = quad(integrand, r1, r2)[0]
        documented = quad(lambda u, r3=r3, Bf=Bf: 2.0 / np.sqrt(Bf * (r3 - u)), r1, r2,
                          weight="alg", wvar=(-0.5, -0.5))[0]
        for name, value in (("quad, raw integrand", naive),
                            ("quad, weight='alg'", documented),
                            ("Carlson R_F", float(nutation_period(*state)))):
            rows.append(_row(case, label, name, abs(value / reference - 1)))
    return rows


def energy_drift_rows() -> list[dict]:
    """Relative energy error, max over the first and over the last 100 of 1000 periods, RK4
    against the Lie–Poisson splitting at the same step (period/20); and the splitting's |L|²
    error over the whole run. Reference: the initial invariants (conservation laws)."""
    scene = FreeBody(1.0, 2.0, 3.0, (0.5, 0.0, 1.0))
    period = float(asymmetric_top_period(1.0, 2.0, 3.0, scene.omega0))
    cycles = np.linspace(0.25, 1000.0, 4000)
    early, late = cycles <= 100.0, cycles >= 900.0
    T0, L20 = invariants(1.0, 2.0, 3.0, scene.omega0)
    rows = []
    case = "free top over 1000 periods, step period/20, relative error of the invariant"
    for method in ("RK4", "LiePoisson2"):
        traj = solve(scene, period * cycles, method, period / 20)
        T, L2 = invariants(1.0, 2.0, 3.0, traj.y)
        dT, dL = np.abs(T / T0 - 1), np.abs(L2 / L20 - 1)
        rows.append(_row(case, "energy, first 100 periods", method, float(dT[early].max()),
                         traj.nfev))
        rows.append(_row(case, "energy, last 100 periods", method, float(dT[late].max()),
                         traj.nfev))
        rows.append(_row(case, "|L|², all 1000 periods", method, float(dL.max()), traj.nfev))
    return rows


def stability_battery() -> list[dict]:
    """All the stages' rows, in the table's order."""
    return [*near_vertical_rows(), *double_root_rows(), *flip_time_rows(), *quadrature_rows(),
            *energy_drift_rows()]
