"""Sleeping and steadily precessing heavy symmetric tops (R19, R21 of ``docs/physics/``).

Both results are closed forms; the only care needed is rounding: the slow precession root
``[p_γ − √(p_γ² − 4 I1 Mgl cos β0)] / (2 I1 cos β0)`` cancels catastrophically for a fast top,
so it is evaluated as ``2 Mgl / (p_γ + √…)`` (the product of the two roots is
``Mgl / (I1 cos β0)``), which also survives ``cos β0 = 0``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.parameters import ParameterError, any_true, as_real, positive

__all__ = ["critical_spin", "fast_top_rates", "sleeping_top_stable", "steady_precession_rates"]


def critical_spin(I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike) -> NDArray[np.float64]:
    """Smallest spin ``ω3`` for which a sleeping (vertical) top is stable (R19).

    ``ω3_c = 2 √(Mgl I1) / I3``, from ``p_γ² ≥ 4 Mgl I1`` with ``p_γ = I3 ω3``.

    Parameters
    ----------
    I1 : array_like
        Transverse moment of inertia about the fixed tip, kg m².
    I3 : array_like
        Moment of inertia about the symmetry axis, kg m².
    Mgl : array_like
        Weight times tip-to-centre-of-mass distance, J (N m).

    Returns
    -------
    ndarray
        ``ω3_c`` in rad/s, broadcast shape of the inputs.

    Examples
    --------
    >>> float(critical_spin(2.0e-4, 1.0e-4, 0.02))
    40.0
    """
    i1, i3, mgl = np.broadcast_arrays(positive("I1", I1), positive("I3", I3), positive("Mgl", Mgl))
    return (2.0 * np.sqrt(mgl * i1) / i3)[()]


def sleeping_top_stable(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, omega3: ArrayLike
) -> NDArray[np.bool_]:
    """Whether a top spinning vertically (β = 0) at ``omega3`` is stable (R19).

    Stable iff ``|ω3| ≥ 2 √(Mgl I1) / I3``, tested as ``(I3 ω3)² ≥ 4 Mgl I1`` (no square root, so
    the boundary case given exactly is classified exactly; the sense of spin does not matter).

    Parameters
    ----------
    I1, I3, Mgl : array_like
        As in :func:`critical_spin`.
    omega3 : array_like
        Spin about the symmetry axis, rad/s (any sign).

    Returns
    -------
    ndarray of bool
        Broadcast shape of the inputs.
    """
    i1, i3, mgl = positive("I1", I1), positive("I3", I3), positive("Mgl", Mgl)
    w3 = as_real("omega3", omega3)
    i1, i3, mgl, w3 = np.broadcast_arrays(i1, i3, mgl, w3)
    return ((i3 * w3) ** 2 >= 4.0 * mgl * i1)[()]


def steady_precession_rates(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike, p_gamma: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Slow and fast steady-precession rates at tilt ``beta0`` (R21).

    Roots of ``I1 cos β0 α̇² − p_γ α̇ + Mgl = 0``:
    ``α̇ = [p_γ ± √(p_γ² − 4 I1 Mgl cos β0)] / (2 I1 cos β0)``. With ``q = p_γ + sgn(p_γ) √D``
    the roots are ``q / (2 I1 cos β0)`` (fast) and ``2 Mgl / q`` (slow: the smaller magnitude),
    free of cancellation.

    Parameters
    ----------
    I1, I3, Mgl : array_like
        As in :func:`critical_spin` (``I3`` is only validated: ``p_γ`` already contains it).
    beta0 : array_like
        Tilt of the axis from the upward vertical, rad, in [0, π].
    p_gamma : array_like
        ``p_γ = I3 ω3``, kg m²/s.

    Returns
    -------
    slow, fast : ndarray
        rad/s, broadcast shape. Both NaN where ``p_γ² < 4 I1 Mgl cos β0`` (no real steady
        precession). For ``cos β0 = 0`` exactly (horizontal axis) the fast root does not exist
        (it has gone to infinity) and is NaN, the slow one is ``Mgl / p_γ``; both are NaN when
        also ``p_γ = 0``. Below the horizontal the roots have opposite signs.

    Examples
    --------
    >>> slow, fast = steady_precession_rates(2.0e-4, 1.0e-4, 0.02, 0.5, 1.0e-4 * 150.0)
    >>> round(float(slow), 6), round(float(fast), 3)
    (1.354811, 84.107)
    """
    i1, _, mgl = np.broadcast_arrays(positive("I1", I1), positive("I3", I3), positive("Mgl", Mgl))
    b0 = _tilt("beta0", beta0)
    pg = as_real("p_gamma", p_gamma)
    i1, mgl, b0, pg = np.broadcast_arrays(i1, mgl, b0, pg)
    u0 = np.cos(b0)
    disc = pg * pg - 4.0 * i1 * mgl * u0
    real = disc >= 0
    q = pg + np.where(pg < 0, -1.0, 1.0) * np.sqrt(np.where(real, disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        slow = np.where(real & (q != 0), 2.0 * mgl / q, np.nan)
        fast = np.where(real & (u0 != 0), q / (2.0 * i1 * u0), np.nan)
    return slow[()], fast[()]


def fast_top_rates(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike, p_gamma: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Fast-top limits of the steady-precession rates (R21).

    ``slow ≈ Mgl / p_γ`` and ``fast ≈ p_γ / (I1 cos β0)``: the leading terms of
    :func:`steady_precession_rates` when ``p_γ² ≫ 4 I1 Mgl |cos β0|`` (relative error of order
    ``I1 Mgl cos β0 / p_γ²``).

    Parameters
    ----------
    I1, I3, Mgl, beta0 : array_like
        As in :func:`steady_precession_rates`.
    p_gamma : array_like
        ``p_γ = I3 ω3``, kg m²/s; must be nonzero (a top that does not spin is not fast).

    Returns
    -------
    slow, fast : ndarray
        rad/s, broadcast shape; ``fast`` is NaN where ``cos β0 = 0`` exactly (it is infinite).

    Raises
    ------
    ParameterError
        Naming ``p_gamma`` if any ``p_γ = 0``.
    """
    i1, _, mgl = np.broadcast_arrays(positive("I1", I1), positive("I3", I3), positive("Mgl", Mgl))
    b0 = _tilt("beta0", beta0)
    pg = as_real("p_gamma", p_gamma)
    if np.any(pg == 0):
        raise ParameterError("p_gamma", "must be nonzero: the fast-top limit needs a spinning top")
    i1, mgl, b0, pg = np.broadcast_arrays(i1, mgl, b0, pg)
    u0 = np.cos(b0)
    with np.errstate(divide="ignore"):
        fast = np.where(u0 != 0, pg / (i1 * u0), np.nan)
    return (mgl / pg)[()], fast[()]


def _tilt(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """An angle from the upward vertical: finite and within [0, π]."""
    arr = as_real(name, value)
    if any_true((arr < 0) | (arr > np.pi)):
        bad = arr[(arr < 0) | (arr > np.pi)].ravel()[0]
        raise ParameterError(name, f"must lie in [0, π] (from the upward vertical), got {bad:.6g}")
    return arr
