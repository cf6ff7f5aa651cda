"""The heavy symmetric top on a fixed tip (R14–R21 of the physics page, ``docs/physics/``).

Every function of the initial state takes ``I1, I3, Mgl, beta0, alpha_dot0, beta_dot0,
gamma_dot0``: ``I1`` the transverse moment about the tip and ``I3`` the axial moment (kg m²),
``Mgl`` weight × tip-to-centre-of-mass distance (J, > 0: a free top is ``solver.torque_free``'s
job), ``beta0`` the tilt from the upward vertical (rad, in [0, π]) and the Euler-angle rates
(rad/s, R11/R12 conventions). All broadcast together; results have the broadcast shape.

Which model for which case
--------------------------
=================  ===================================================================
case               how it is computed
=================  ===================================================================
turning points     roots of the cubic in ``w = u − cos β0`` (``solver.nutation``): exact
                   deflation if ``β̇0 = 0``, Newton + Vieta otherwise; never ``np.roots``;
                   near a pole re-solved in ``v = 1 ∓ u`` (full relative accuracy)
nutation period    ``4 R_F(0, u3 − u2, u3 − u1)/√B`` (Carlson); its limit if steady/sleeping
mean precession    ``Δα / T_nut``, ``Δα`` from Carlson ``R_F``/``R_J`` (third kind) in the
                   form whose terms share one sign (π split off when ``p_α``, ``p_γ``
                   differ in sign); ``α̇(β0)`` for steady precession; NaN for a sleeping top
``u(t)``           Jacobi ``sn²`` with the phase of the initial state
steady rates       closed form of R21 without cancellation (``solver.steady_precession``)
=================  ===================================================================

Motion types (R18) and their tolerance logic
--------------------------------------------
``"sleeping"``: ``β0 = 0``, ``β̇0 = 0`` and ``p_γ² ≥ 4 Mgl I1`` (R19) — exact comparisons.
``"steady"``: ``β̇0 = 0`` (``u0`` is an exact root) and ``u2 − u1`` below 32 ε times the
largest term of the coefficient ``c1`` it comes from (i.e. the rates were a steady state up to
rounding). ``"cusps"``: ``α̇ = 0`` at a turning point off the poles, i.e. ``b − a u_i = Q − a w_i``
is within 32 ε of its terms (a top released from rest has ``Q = 0`` and ``w = 0`` exactly, so
that case is exact, not tolerance luck). ``"loops"``: ``α̇`` has opposite signs at the two turning
points (it is ``(b − a u)/(1 − u²)``, monotone in sign on ``[u1, u2]``). ``"waves"``: otherwise.
``"revolves"``: the planar pendulum (``p_α = p_γ = 0`` exactly) going over the top — ``u1 = −1``
and ``u2 = 1`` are exact roots, the axis passes both poles without stopping, so ``β1 = 0`` and
``β2 = π`` are the extremes of β, not turning points (a swinging pendulum is ``"cusps"``: it stops
at ``β1``). At a pole reached by the top (``β1 = 0``) ``α̇`` is the finite limit ``(b + a)/4``.
An unstable sleeping top (``β0 = β̇0 = 0``, ``p_γ² < 4 Mgl I1``) rests on a separatrix:
``β1 = 0``, ``β2`` the other root, ``T_nut = inf``, mean precession NaN, type from the α̇ signs.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.nutation import (
    NutationCubic,
    cos_beta_of,
    nutation_cubic,
    nutation_integrals,
    nutation_period_of,
    precession_angle_of,
    precession_rate_at,
)
from solver.parameters import ParameterError, as_real, positive, principal_moments
from solver.steady_precession import (
    _tilt,
    critical_spin,
    fast_top_rates,
    sleeping_top_stable,
    steady_precession_rates,
)

__all__ = [
    "constants_of_motion",
    "cos_beta",
    "critical_spin",
    "cubic_roots",
    "effective_potential",
    "fast_top_rates",
    "mean_precession_rate",
    "motion_type",
    "nutation_period",
    "precession_rate",
    "sleeping_top_stable",
    "solve_heavy_top",
    "spin_rate",
    "steady_precession_rates",
    "turning_points",
    "undefined_reasons",
]

_EPS = np.finfo(float).eps
_STATE = ("I1", "I3", "Mgl", "beta0", "alpha_dot0", "beta_dot0", "gamma_dot0")


def _state(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0):
    """Validate and broadcast the initial state; return (shape, flat arrays)."""
    i1, _, i3 = principal_moments(I1, I1, I3)  # I3 ≤ 2 I1: true of any body about its tip
    arrays = np.broadcast_arrays(
        i1, i3, positive("Mgl", Mgl), _tilt("beta0", beta0), as_real("alpha_dot0", alpha_dot0),
        as_real("beta_dot0", beta_dot0), as_real("gamma_dot0", gamma_dot0),
    )
    return arrays[0].shape, [np.ravel(x).astype(float, copy=False) for x in arrays]


def _cubic(*state) -> tuple[tuple[int, ...], NutationCubic, list[NDArray[np.float64]]]:
    shape, flat = _state(*state)
    return shape, nutation_cubic(*flat), flat


def _out(x, shape):
    return np.reshape(x, shape)[()]


def constants_of_motion(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Conserved momenta and reduced energy of the heavy top (R15, R16).

    Returns
    -------
    p_alpha : ndarray
        ``I1 α̇ sin²β + p_γ cos β``, kg m²/s.
    p_gamma : ndarray
        ``I3 (α̇ cos β + γ̇) = I3 ω3``, kg m²/s.
    E_prime : ndarray
        ``E − p_γ²/(2 I3) = ½ I1 β̇² + ½ I1 α̇² sin²β + Mgl cos β``, J (R16 with
        ``(p_α − p_γ cos β)²/(2 I1 sin²β) = ½ I1 α̇² sin²β``, finite at the poles).

    Examples
    --------
    >>> pa, pg, e = constants_of_motion(2e-4, 1e-4, 0.02, 0.5, 0.0, 0.0, 150.0)
    >>> round(float(pg), 6), round(float(e), 6)
    (0.015, 0.017552)
    """
    shape, (i1, i3, mgl, b0, ad, bd, gd) = _state(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0,
                                                  gamma_dot0)
    u0, s2 = np.cos(b0), np.sin(b0) ** 2
    pg = i3 * (ad * u0 + gd)
    pa = i1 * ad * s2 + pg * u0
    e = 0.5 * i1 * (bd * bd + ad * ad * s2) + mgl * u0
    return _out(pa, shape), _out(pg, shape), _out(e, shape)


def precession_rate(
    beta: ArrayLike, I1: ArrayLike, p_alpha: ArrayLike, p_gamma: ArrayLike
) -> NDArray[np.float64]:
    """Precession rate ``α̇ = (p_α − p_γ cos β)/(I1 sin²β)`` (R18), rad/s.

    Evaluated as ``½[(b − a)/(2 sin²(β/2)) + (b + a)/(2 cos²(β/2))]`` (``a = p_γ/I1``,
    ``b = p_α/I1``): the textbook form loses every digit near ``β = 0`` (``b − a cos β`` and
    ``sin²β`` both vanish), this one none. A vanishing numerator counts as zero, so a top at a
    pole it can reach (``p_α = ±p_γ``) has the finite limit (``(b ± a)/4``); a pole with
    ``p_α ≠ ±p_γ`` is unreachable and gives ``±inf``.

    Parameters
    ----------
    beta : array_like
        Tilt from the upward vertical, rad, in [0, π].
    I1 : array_like
        Transverse moment about the tip, kg m².
    p_alpha, p_gamma : array_like
        Conserved momenta (R15), kg m²/s.
    """
    b = _tilt("beta", beta)
    i1 = positive("I1", I1)
    pa, pg = as_real("p_alpha", p_alpha), as_real("p_gamma", p_gamma)
    b, i1, pa, pg = np.broadcast_arrays(b, i1, pa, pg)
    one_minus, one_plus = 2.0 * np.sin(0.5 * b) ** 2, 2.0 * np.cos(0.5 * b) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        rate = 0.5 * (np.where(pa == pg, 0.0, (pa - pg) / one_minus)
                      + np.where(pa == -pg, 0.0, (pa + pg) / one_plus)) / i1
    return rate[()]


def spin_rate(
    beta: ArrayLike, I1: ArrayLike, I3: ArrayLike, p_alpha: ArrayLike, p_gamma: ArrayLike
) -> NDArray[np.float64]:
    """Spin rate ``γ̇ = p_γ/I3 − α̇ cos β`` (R18), rad/s, with ``α̇`` from :func:`precession_rate`."""
    i3 = positive("I3", I3)
    return (as_real("p_gamma", p_gamma) / i3
            - precession_rate(beta, I1, p_alpha, p_gamma) * np.cos(as_real("beta", beta)))[()]


def effective_potential(
    beta: ArrayLike, I1: ArrayLike, Mgl: ArrayLike, p_alpha: ArrayLike, p_gamma: ArrayLike
) -> NDArray[np.float64]:
    """``V_eff(β) = (p_α − p_γ cos β)²/(2 I1 sin²β) + Mgl cos β`` (R16), J.

    Evaluated as ``½ I1 (α̇ sin β)² + Mgl cos β`` with the pole-stable ``α̇`` of
    :func:`precession_rate`: finite (``Mgl cos β``) at a pole where ``p_α = ±p_γ``, ``inf``
    at a pole that the top cannot reach.
    """
    rate = precession_rate(beta, I1, p_alpha, p_gamma)
    b = as_real("beta", beta)
    i1, mgl = positive("I1", I1), positive("Mgl", Mgl)
    with np.errstate(invalid="ignore"):
        kinetic = np.where(np.sin(b) == 0, np.where(np.isfinite(rate), 0.0, np.inf),
                           0.5 * i1 * (rate * np.sin(b)) ** 2)
    return (kinetic + mgl * np.cos(b))[()]


def cubic_roots(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Roots ``u1 ≤ u2 ≤ u3`` of ``f(u) = (1 − u²)(A − Bu) − (b − au)²`` (R17).

    ``−1 ≤ u1 ≤ u2 ≤ 1 ≤ u3`` (``u3 = 1`` only for an unstable sleeping top at rest, where
    ``u2 = u3 = 1``). Computed about ``u0 = cos β0`` without cancellation; see
    ``solver.nutation``.
    """
    shape, cubic, _ = _cubic(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    u = cubic.u
    return _out(u[:, 0], shape), _out(u[:, 1], shape), _out(u[:, 2], shape)


def turning_points(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Nutation limits ``β1 = arccos u2 ≤ β2 = arccos u1`` (R17), rad.

    The roots of ``V_eff(β) = E'`` bracketing ``β0``. For ``β0 = 0``: ``β1 = 0`` and ``β2`` is
    the other root (``0`` for a stable sleeping top). Computed as
    ``2 atan2(√(1 − u), √(1 + u))`` from pole distances carried to full relative accuracy.
    """
    shape, cubic, _ = _cubic(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    beta = cubic.beta
    return _out(beta[:, 1], shape), _out(beta[:, 0], shape)


def _sleeping(flat) -> NDArray[np.bool_]:
    """Started exactly upright and at rest in β, with a stable spin (R19): a sleeping top."""
    i1, i3, mgl, b0, _, bd, _ = flat
    upright = (b0 == 0) & (bd == 0)
    if upright.any():  # rare: the stability test only where it can matter
        upright[upright] = sleeping_top_stable(i1[upright], i3[upright], mgl[upright],
                                               _omega3([x[upright] for x in flat]))
    return upright


def _revolves(cubic: NutationCubic) -> NDArray[np.bool_]:
    """Planar pendulum (``p_α = p_γ = 0``) going over the top: ``u`` runs over all of
    ``[−1, 1]`` (``u1 = −1``, ``u2 = 1`` exact roots, ``u3 = A/B > 1``) and the axis never stops."""
    planar = (cubic.b_minus_a == 0) & (cubic.b_plus_a == 0)
    return (planar & (cubic.one_minus_u[:, 1] == 0) & (cubic.one_plus_u[:, 0] == 0)
            & (cubic.u3_minus_one > 0))


def _motion(cubic: NutationCubic, flat) -> NDArray[np.str_]:
    sleeping = _sleeping(flat)
    rates = np.stack([precession_rate_at(cubic, 0), precession_rate_at(cubic, 1)])
    num = cubic.Q[None, :] - cubic.a[None, :] * cubic.w[:, :2].T  # b − a u_i, no cancellation
    scale = np.abs(cubic.Q)[None, :] + np.abs(cubic.a[None, :] * cubic.w[:, :2].T)
    off_pole = (cubic.one_minus_u[:, :2].T > 0) & (cubic.one_plus_u[:, :2].T > 0)
    cusp = (np.abs(num) <= 32.0 * _EPS * scale) & off_pole
    kind = np.where(rates[0] * rates[1] < 0, "loops", "waves")
    kind = np.where(cusp.any(axis=0), "cusps", kind)
    kind = np.where(cubic.steady, "steady", kind)
    kind = np.where(_revolves(cubic), "revolves", kind)
    return np.where(sleeping, "sleeping", kind).astype(str)


def motion_type(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> NDArray[np.str_]:
    """Figure traced by the axis (R18): ``"waves"``, ``"loops"``, ``"cusps"``, ``"steady"``,
    ``"sleeping"``, ``"revolves"`` — see the module docstring for the tolerance logic.
    """
    shape, cubic, flat = _cubic(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    return _out(_motion(cubic, flat), shape)


def _period(cubic: NutationCubic, flat) -> NDArray[np.float64]:
    return nutation_period_of(cubic)


def nutation_period(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> NDArray[np.float64]:
    """Nutation period ``T_nut = 4 K(k)/√(B (u3 − u1))`` (R20), s.

    Carlson form ``4 R_F(0, u3 − u2, u3 − u1)/√B``. For steady precession and a sleeping top
    (no nutation) it is the limit, the period of an infinitesimal nutation about that state
    (``2π/√(B (u3 − u1))``; for a sleeping top ``2π I1/√(p_γ² − 4 Mgl I1)``, R19); ``inf``
    for an unstable sleeping top at rest (``u2 = u3``: it leaves the vertical only
    asymptotically). Never NaN.
    """
    shape, cubic, flat = _cubic(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    return _out(_period(cubic, flat), shape)


def _mean_rate(cubic: NutationCubic, flat, period, angle=None) -> NDArray[np.float64]:
    sleeping = _sleeping(flat)
    if angle is None:
        angle = precession_angle_of(cubic)
    with np.errstate(invalid="ignore"):
        mean = angle / period
    mean = np.where(np.isfinite(period), mean, np.nan)
    steady = cubic.steady
    if steady.any():
        mean = np.where(steady, precession_rate_at(cubic, 1), mean)
    return np.where(sleeping, np.nan, mean)


def mean_precession_rate(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> NDArray[np.float64]:
    """Mean precession rate ``⟨α̇⟩ = Δα / T_nut`` over a nutation period (R20), rad/s.

    ``Δα = 2 ∫_{u1}^{u2} (b − a u)/((1 − u²) √f(u)) du`` exactly, with Carlson's ``R_F`` and
    ``R_J`` (see ``solver.nutation.precession_angle_of``, which keeps every term of one sign).
    Steady precession gives its own rate (the limit of the formula). NaN, with the reason in
    :func:`undefined_reasons`, for a sleeping top (``α`` is undefined on the vertical, and the
    limit depends on how the vertical is left) and for an unstable sleeping top at rest
    (infinite period). A top whose axis passes through a pole gets the mean of its finite
    ``α̇`` (``α`` jumps by π at the pole; see ``precession_angle_of``).
    """
    shape, cubic, flat = _cubic(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    return _out(_mean_rate(cubic, flat, _period(cubic, flat)), shape)


def nutation(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> dict[str, NDArray[np.float64]]:
    """Turning points, nutation period and mean precession rate in one vectorised pass (R17, R20).

    The same values as :func:`turning_points`, :func:`nutation_period` and
    :func:`mean_precession_rate`, from one solution of the cubic instead of three and one
    ``R_F`` for both integrals: the call to use for many tops at once. It solves them in blocks
    of ``_BLOCK``, whose temporaries stay in the processor's cache; ``benchmarks/
    bench_heavy_top.py`` times it on 10^6 tops against the special functions it calls.

    Returns
    -------
    dict
        ``beta1, beta2`` (rad), ``nutation_period`` (s), ``mean_precession_rate`` (rad/s), each
        of the broadcast shape of the inputs, NaN where the quantity does not exist (see the
        single-quantity functions).
    """
    shape, flat = _state(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    out = {key: np.empty(flat[0].size) for key in _NUTATION}
    for start in range(0, flat[0].size, _BLOCK):
        block = slice(start, start + _BLOCK)
        for key, column in zip(_NUTATION, _nutation_block([x[block] for x in flat]), strict=True):
            out[key][block] = column
    return {key: _out(column, shape) for key, column in out.items()}


_NUTATION = ("beta1", "beta2", "nutation_period", "mean_precession_rate")
_BLOCK = 16384  # tops solved together: a block's temporaries stay in the processor's cache


def _nutation_block(flat):
    """:func:`nutation`'s four columns for validated 1-D states."""
    cubic = nutation_cubic(*flat)
    period, angle = nutation_integrals(cubic)
    beta = cubic.beta
    return beta[:, 1], beta[:, 0], period, _mean_rate(cubic, flat, period, angle)


def cos_beta(
    t: ArrayLike, I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> NDArray[np.float64]:
    """``u(t) = cos β(t) = u1 + (u2 − u1) sn²(λ t + φ, k)`` (R20).

    ``λ = √(B (u3 − u1))/2``, ``k² = (u2 − u1)/(u3 − u1)``; the phase ``φ`` gives
    ``u(0) = cos β0`` and ``β̇`` the sign of ``β̇0`` at ``t = 0``. Constant for steady and
    sleeping tops. ``t`` (s) broadcasts with the state.
    """
    tt = as_real("t", t)
    shape, flat = _state(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    full = np.broadcast_arrays(tt, *(np.reshape(x, shape) for x in flat))
    flat = [np.ravel(x) for x in full[1:]]
    cubic = nutation_cubic(*flat)
    return _out(cos_beta_of(cubic, np.ravel(full[0]), flat[5]), full[0].shape)


def solve_heavy_top_many(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike,
    alpha_dot0: ArrayLike, beta_dot0: ArrayLike, gamma_dot0: ArrayLike,
) -> dict[str, NDArray]:
    """Every ``eulertop solve heavy-top`` field for many initial states at once (R14–R21).

    Vectorised: one solution of the cubic for all states. Returns 1-D arrays over the
    broadcast (flattened) states: floats with NaN where a quantity does not exist (see
    :func:`solve_heavy_top`), ``motion`` as str, ``sleeping_stable`` as bool,
    ``steady_precession_rates`` as an (n, 2) array ``[slow, fast]`` (NaN when not real), and
    ``undefined`` (object array of dicts ``{field: reason}``, :func:`undefined_reasons`): every
    NaN or infinity in the table has its reason there.
    """
    state = (I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    _, cubic, flat = _cubic(*state)
    i1, i3, mgl, b0 = flat[0], flat[1], flat[2], flat[3]
    with np.errstate(all="ignore"):  # a non-finite result is explained in "undefined"
        return _many(cubic, flat, i1, i3, mgl, b0)


def _many(cubic, flat, i1, i3, mgl, b0) -> dict[str, NDArray]:
    p_alpha, p_gamma, e_prime = (np.ravel(x) for x in constants_of_motion(*flat))
    motion = _motion(cubic, flat)
    period = _period(cubic, flat)
    sleeping = motion == "sleeping"
    slow, fast = steady_precession_rates(i1, i3, mgl, b0, p_gamma)
    table = {
        "p_alpha": p_alpha,
        "p_gamma": p_gamma,
        "E_prime": e_prime,
        "beta1": cubic.beta[:, 1],
        "beta2": cubic.beta[:, 0],
        "alpha_dot_beta1": np.where(sleeping, np.nan, precession_rate_at(cubic, 1)),
        "alpha_dot_beta2": np.where(sleeping, np.nan, precession_rate_at(cubic, 0)),
        "nutation_period": period,
        "mean_precession_rate": _mean_rate(cubic, flat, period),
        "motion": motion,
        "sleeping_stable": np.asarray(sleeping_top_stable(i1, i3, mgl, _omega3(flat))),
        "omega3_critical": np.ravel(critical_spin(i1, i3, mgl)),
        "steady_precession_rates": np.stack([np.ravel(slow), np.ravel(fast)], axis=-1),
    }
    table["undefined"] = undefined_reasons(table)
    return table


# Why a field of solve_heavy_top is None (the only cases in which it is): field → reason.
REASONS = {
    "sleeping": "sleeping top: the axis stays on the vertical, where α (so α̇) is undefined",
    "unstable_rest": ("unstable sleeping top at rest (u2 = u3 = 1): it leaves the vertical only "
                      "asymptotically, so the nutation period is infinite"),
    "no_steady": "no real steady precession at beta0 with this p_gamma (p_γ² < 4 I1 Mgl cos β0)",
    "horizontal": "the fast steady precession of a horizontal axis (cos β0 = 0) is infinite",
    "overflow": "not finite in double precision: the state's magnitudes are out of range",
}


def undefined_reasons(table: dict[str, NDArray]) -> NDArray[np.object_]:
    """For each row of :func:`solve_heavy_top_many`'s table, ``{field: reason}`` for every
    field that has no finite value (``{}`` if none): the documented reasons of ``REASONS``.

    A NaN or infinity in the table is never left unexplained: a non-finite value outside the
    documented cases is reported as ``REASONS["overflow"]``. Vectorised: the reasons are
    decided column by column, and a dict is written out only for the rows that have one.
    """
    columns = [(key, bad, _why(table, key)) for key in _EXPLAINED
               if (bad := ~np.isfinite(table[key])).any()]
    slow, fast = table["steady_precession_rates"].T
    steady = np.where(~np.isfinite(slow), "no_steady", np.where(~np.isfinite(fast),
                                                               "horizontal", ""))
    out = np.empty(len(table["motion"]), dtype=object)
    out[:] = [{} for _ in range(out.size)]
    rows = (steady != "") | np.logical_or.reduce([bad for _, bad, _ in columns] or [False])
    for i in np.flatnonzero(rows):
        out[i].update((key, REASONS[why[i]]) for key, bad, why in columns if bad[i])
        if steady[i]:
            out[i]["steady_precession_rates"] = REASONS[steady[i]]
    return out


# The fields whose NaN or infinity undefined_reasons explains, in the order it lists them.
_EXPLAINED = ("alpha_dot_beta1", "alpha_dot_beta2", "nutation_period", "mean_precession_rate",
              "p_alpha", "p_gamma", "E_prime", "beta1", "beta2")


def _why(table, key) -> NDArray[np.str_]:
    """The ``REASONS`` key of a non-finite ``table[key]``, row by row."""
    sleeping = (table["motion"] == "sleeping") & (key != "nutation_period")
    unstable = np.isinf(table["nutation_period"]) & (
        key in ("nutation_period", "mean_precession_rate"))
    return np.where(sleeping, "sleeping", np.where(unstable, "unstable_rest", "overflow"))


def solve_heavy_top(
    I1: float, I3: float, Mgl: float, beta0: float,
    alpha_dot0: float, beta_dot0: float, gamma_dot0: float,
) -> dict[str, Any]:
    """Everything ``eulertop solve heavy-top`` prints for one initial state (R14–R21).

    Returns
    -------
    dict
        ``p_alpha, p_gamma, E_prime`` (R15/R16), ``beta1, beta2`` (R17, rad),
        ``alpha_dot_beta1, alpha_dot_beta2`` (α̇ at the turning points, rad/s, R18),
        ``nutation_period`` (s), ``mean_precession_rate`` (rad/s) (R20), ``motion`` (str),
        ``sleeping_stable`` (bool, R19: would a vertical spin with this ``ω3`` be stable),
        ``omega3_critical`` (rad/s, R19), ``steady_precession_rates`` (``[slow, fast]`` at
        ``β0`` with this ``p_γ``, R21; ``None`` when not real, ``[slow, None]`` for a horizontal
        axis), and ``undefined``: ``{field: reason}`` for every field that is ``None`` (``{}``
        when all exist; reasons from ``REASONS``). Python floats, str, bool, ``None`` or that
        dict: ``None`` only where a quantity does not exist or is not finite — α̇ and ⟨α̇⟩ of a
        sleeping top, the infinite period (and so ⟨α̇⟩) of an unstable sleeping top at rest,
        steady rates that are not real. Steady and sleeping tops have the limit nutation
        period (infinitesimal nutation); ``motion`` says that they do not nutate.

    Raises
    ------
    ParameterError
        If the state is invalid, or not scalar.
    """
    state = (I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)
    for name, value in zip(_STATE, state, strict=True):
        if np.ndim(as_real(name, value)) != 0:
            raise ParameterError(name, "solve_heavy_top takes one state: a number, not an array")
    return heavy_top_record(solve_heavy_top_many(*state), 0)


def heavy_top_record(table: dict[str, NDArray], i: int) -> dict[str, Any]:
    """Row ``i`` of :func:`solve_heavy_top_many`'s table as plain Python (None for NaN/inf,
    explained in the row's ``undefined``)."""
    slow, fast = table["steady_precession_rates"][i]
    row: dict[str, Any] = {}
    for key, column in table.items():
        if key == "steady_precession_rates":
            row[key] = None if not math.isfinite(slow) else [float(slow), _finite(fast)]
        elif key == "motion":
            row[key] = str(column[i])
        elif key == "sleeping_stable":
            row[key] = bool(column[i])
        elif key == "undefined":
            row[key] = dict(column[i])
        else:
            row[key] = _finite(column[i])
    return row


def _omega3(flat):
    """``ω3 = α̇0 cos β0 + γ̇0`` (R12), straight from the state (exact at β0 = 0)."""
    return flat[4] * np.cos(flat[3]) + flat[6]


def _finite(x) -> float | None:
    value = float(np.ravel(x)[0])
    return value if math.isfinite(value) else None
