"""Nutation of the heavy symmetric top: the cubic ``f(u)``, its roots, and its elliptic integrals.

R17 and R20 of the physics page (``docs/physics/``). With ``u = cos β`` the motion obeys ``u̇² =
f(u)``, ``f(u) = (1 − u²)(A − B u) − (b − a u)² = B (u − u1)(u − u2)(u − u3)``.

Numerical design (why it is not ``np.roots``)
---------------------------------------------
The expanded coefficients of ``f`` cancel catastrophically for a fast top (``a²``, ``2ab``,
``b²`` are huge, the roots ``u1, u2`` are not), and ``u1 ≈ u2`` (steady precession) is a double
root whose position ``np.roots`` gets to only ``√ε``. Everything here is therefore written in
the offset ``w = u − u0`` from ``u0 = cos β0``, with the coefficients taken straight from the
initial rates, where nothing cancels::

    f = B w³ + c2 w² + c1 w + c0,
    c0 = sin²β0 β̇0²                         (= f(u0) ≥ 0)
    c1 = −B sin²β0 − 2 u0 P + 2 a Q
    c2 = 2 u0 B − P − a²
    P  = A − B u0 = β̇0² + α̇0² sin²β0,   Q = b − a u0 = α̇0 sin²β0.

* ``β̇0 = 0``: ``w = 0`` is an exact root; it is deflated analytically, and the remaining
  quadratic ``B w² + c2 w + c1`` is solved in the cancellation-free ("citardauq") form.
* ``β̇0 ≠ 0``: the largest root ``w3`` is found by Newton's method started above it — at the
  trigonometric (Viète) root raised a little, where that is provably above it, else at
  Fujiwara's bound (a cubic with three real roots is increasing and convex there, so the
  iterates decrease monotonically; they stop when they stop decreasing), then Vieta gives
  ``w1 + w2 = (c1 + c0/w3)/(B w3)`` and ``w1 w2 = −c0/(B w3)``; the discriminant of that
  quadratic is a sum of two non-negative terms, so the two nutation limits — however close —
  come out to full relative accuracy.

Distances to the poles ``1 ∓ u`` are carried separately (``1 − u0 = 2 sin²(β0/2)``). Where
``1 + u1`` would be a cancelling difference it is taken from the exact identity
``(b + a)² = B (1 + u1)(1 + u2)(1 + u3)`` (``f(−1) = −(b + a)²``); ``1 − u2`` and ``u3 − 1`` come
from the cubic re-solved in ``v = 1 − u`` (:func:`_upper_pole_distances`), whose two small roots
solve a quadratic with a non-negative discriminant — no signed difference, so no NaN; also where
``u2 ≈ u3`` (a swing from near the upright pole) makes the offsets ``w2, w3`` themselves
inaccurate (:func:`_root_errors`). Angles are
``β = 2 atan2(√(1 − u), √(1 + u))``: full accuracy at both poles. ``b = ±a`` exactly (a top that
reaches a pole, the planar pendulum) makes the pole an exact root.

The nutation period and the precession angle per period are complete elliptic integrals,
evaluated with Carlson's symmetric forms (``scipy.special.elliprf``, ``elliprj``); see
:func:`nutation_period_of` and :func:`precession_angle_of`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.special import elliprf, elliprj

from solver.jacobi import incomplete_f, jacobi_sncndn

__all__ = [
    "NutationCubic",
    "cos_beta_of",
    "nutation_cubic",
    "nutation_integrals",
    "nutation_period_of",
    "precession_angle_of",
    "precession_rate_at",
]

_EPS = np.finfo(float).eps
_TINY = np.finfo(float).tiny
_NEWTON_MAX_ITER = 200  # monotone Newton: ~10 linear steps from Fujiwara's bound, then quadratic


@dataclass(frozen=True)
class NutationCubic:
    """The cubic ``f(u)`` of R17 about ``u0 = cos β0``, with its roots, for a batch of tops.

    All fields are 1-D float arrays of one length (one entry per top), dimensionless except
    ``B`` (s⁻²), ``a``, ``Q``, ``b_minus_a``, ``b_plus_a`` (s⁻¹) and ``c0..c2`` (s⁻²).

    Attributes
    ----------
    u0, one_minus_u0, one_plus_u0 : ndarray
        ``cos β0``, ``2 sin²(β0/2)``, ``2 cos²(β0/2)``.
    B, a, Q : ndarray
        ``2 Mgl / I1``, ``p_γ / I1``, ``b − a u0 = α̇0 sin²β0``.
    b_minus_a, b_plus_a : ndarray
        ``(p_α ∓ p_γ) / I1``, computed without cancellation from the initial state.
    c0, c1, c2 : ndarray
        Coefficients of ``f = B w³ + c2 w² + c1 w + c0`` in ``w = u − u0``.
    w : ndarray, shape (n, 3)
        Roots ``u_i − u0``, ascending (``w1 ≤ 0 ≤ w2``, ``w3 ≥ 1 − u0``).
    one_minus_u, one_plus_u : ndarray, shape (n, 3)
        ``1 − u_i`` and ``1 + u_i`` to full relative accuracy near the poles (``1 − u3 ≤ 0``
        is stored as 0: use ``u3_minus_one``).
    u3_minus_one : ndarray
        ``u3 − 1 ≥ 0`` to full relative accuracy (0 for the swinging planar pendulum).
    exact_root : ndarray of bool
        ``β̇0 = 0``: ``u0`` itself is a turning point, deflated exactly.
    steady_tolerance : ndarray
        Width below which ``u2 − u1`` is rounding of ``c1`` (see :func:`nutation_cubic`).
    """

    u0: NDArray[np.float64]
    one_minus_u0: NDArray[np.float64]
    one_plus_u0: NDArray[np.float64]
    B: NDArray[np.float64]
    a: NDArray[np.float64]
    Q: NDArray[np.float64]
    b_minus_a: NDArray[np.float64]
    b_plus_a: NDArray[np.float64]
    c0: NDArray[np.float64]
    c1: NDArray[np.float64]
    c2: NDArray[np.float64]
    w: NDArray[np.float64]
    one_minus_u: NDArray[np.float64]
    one_plus_u: NDArray[np.float64]
    u3_minus_one: NDArray[np.float64]
    exact_root: NDArray[np.bool_]
    steady_tolerance: NDArray[np.float64]

    @property
    def u(self) -> NDArray[np.float64]:
        """Roots ``(u1, u2, u3)`` of R17, shape (n, 3)."""
        return self.u0[:, None] + self.w

    @property
    def beta(self) -> NDArray[np.float64]:
        """``arccos u_i`` of the two turning points ``(u1, u2)``: shape (n, 2), rad.

        ``2 atan2(√(1 − u), √(1 + u))``: full accuracy at both poles.
        """
        return 2.0 * np.arctan2(np.sqrt(self.one_minus_u[:, :2]), np.sqrt(self.one_plus_u[:, :2]))

    @property
    def steady(self) -> NDArray[np.bool_]:
        """``β1 = β2`` up to the rounding of the initial rates (and ``β̇0 = 0``)."""
        return self.exact_root & (self.w[:, 1] - self.w[:, 0] <= self.steady_tolerance)


def nutation_cubic(
    I1: NDArray[np.float64],
    I3: NDArray[np.float64],
    Mgl: NDArray[np.float64],
    beta0: NDArray[np.float64],
    alpha_dot0: NDArray[np.float64],
    beta_dot0: NDArray[np.float64],
    gamma_dot0: NDArray[np.float64],
) -> NutationCubic:
    """Build the cubic of R17 in ``w = u − cos β0`` and find its roots (vectorised).

    Parameters
    ----------
    I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0 : ndarray
        Validated, broadcast 1-D arrays of one length: the heavy top's initial state (SI, rad).

    Returns
    -------
    NutationCubic

    Notes
    -----
    ``steady_tolerance`` is ``32 ε`` times the largest term of ``c1`` over the size of the
    other root of the deflated quadratic: a separation ``u2 − u1`` below it is the rounding of
    ``c1`` (e.g. a steady-precession rate typed with 16 digits), not nutation.
    """
    u0, s2, hm, hp = _tilt_terms(beta0)
    B = 2.0 * Mgl / I1
    a = I3 * (alpha_dot0 * u0 + gamma_dot0) / I1
    Q = alpha_dot0 * s2
    P = beta_dot0**2 + alpha_dot0**2 * s2
    c0 = s2 * beta_dot0**2
    c1_terms = (-B * s2, -2.0 * u0 * P, 2.0 * a * Q)
    c1 = c1_terms[0] + c1_terms[1] + c1_terms[2]
    c2 = 2.0 * u0 * B - P - a * a

    exact = c0 == 0
    w, big = _roots(exact, B, c0, c1, c2, hm)
    c1_scale = np.maximum(np.maximum(np.abs(c1_terms[0]), np.abs(c1_terms[1])),
                          np.abs(c1_terms[2]))
    steady_tol = 32.0 * _EPS * c1_scale / np.maximum(np.abs(big), 1e-300)

    b_minus_a = Q - a * hm
    b_plus_a = Q + a * hp
    c2_scale = 2.0 * np.abs(u0) * B + P + a * a
    root_err = _root_errors(w, B, c0, c1_scale, c2_scale)
    s1, s2, d = _upper_pole_distances(hm, w, *root_err, B, a, Q, P, b_minus_a)
    t1, t2, t3 = _lower_pole_distances(hp, w, B, a, Q, b_plus_a)
    one_minus_u = _columns(s1, s2, np.zeros_like(s1))
    one_plus_u = _columns(t1, t2, t3)
    return NutationCubic(u0, hm, hp, B, a, Q, b_minus_a, b_plus_a, c0, c1, c2, w,
                         one_minus_u, one_plus_u, d, exact, steady_tol)


def _tilt_terms(beta0):
    """``cos β0``, ``sin²β0``, ``1 − cos β0 = 2 sin²(β0/2)`` and ``1 + cos β0 = 2 cos²(β0/2)``,
    each to full relative accuracy."""
    half_sin, half_cos = np.sin(0.5 * beta0), np.cos(0.5 * beta0)
    s0 = np.sin(beta0)
    return np.cos(beta0), s0 * s0, 2.0 * half_sin * half_sin, 2.0 * half_cos * half_cos


def _columns(*columns):
    """An (n, k) array whose columns are contiguous in memory (each is read as a whole)."""
    return np.stack(columns).T


def _roots(exact, B, c0, c1, c2, hm):
    """The cubic's roots ``w``, (n, 3) ascending, and ``big`` (see :func:`_roots_with_zero`).

    Where ``β̇0 = 0`` (``exact``) the root ``w = 0`` is deflated exactly; the other tops go
    through Newton. A batch mixing both computes both for every top and picks, which costs
    less than gathering each kind's rows apart.
    """
    if exact.all():
        w, big = _roots_with_zero(B, c1, c2)
        return _ascending(*w), big
    with np.errstate(divide="ignore", invalid="ignore"):
        w, big = _roots_general(B, c0, c1, c2, hm), np.ones_like(B)
        if exact.any():
            zero, q = _roots_with_zero(B, c1, c2)
            w, big = np.where(exact, zero, w), np.where(exact, q, big)
    return _ascending(*w), big


def _ascending(x, y, z):
    """The three roots of each top in ascending order, (n, 3): a sorting network of elementwise
    minima and maxima (a NaN root, from a state out of double range, makes all three NaN)."""
    low, high = np.minimum(x, y), np.maximum(x, y)
    middle, top = np.minimum(high, z), np.maximum(high, z)
    return _columns(np.minimum(low, middle), np.maximum(low, middle), top)


def _roots_with_zero(B, c1, c2):
    """Roots of ``w (B w² + c2 w + c1)``: 0 and the quadratic's, cancellation-free."""
    disc = np.maximum(c2 * c2 - 4.0 * B * c1, 0.0)  # ≥ 0 for a physical state; clip rounding
    q = -0.5 * (c2 + np.where(c2 < 0, -1.0, 1.0) * np.sqrt(disc))
    with np.errstate(divide="ignore", invalid="ignore"):
        small = np.where(q != 0, c1 / q, 0.0)
    return np.stack([np.zeros_like(B), q / B, small]), q


def _roots_general(B, c0, c1, c2, hm):
    """Roots of ``B w³ + c2 w² + c1 w + c0`` with ``c0 > 0``: Newton for w3, then Vieta."""
    w3 = _newton_from_above(B, c0, c1, c2, _start_above_w3(B, c0, c1, c2, hm))
    s = (c1 + c0 / w3) / (B * w3)  # w1 + w2
    p = -c0 / (B * w3)  # w1 w2 < 0
    q = 0.5 * (s + np.where(s < 0, -1.0, 1.0) * np.sqrt(s * s - 4.0 * p))
    return np.stack([q, p / q, w3])


def _start_above_w3(B, c0, c1, c2, hm):
    """A start for Newton above the largest root ``w3``, close to it where that can be proved.

    The trigonometric (Viète) formula for the largest root, raised by 10⁻⁹ of its scale, is
    kept where ``f > 0`` and ``f' > 0`` right of the inflection point — which puts it above
    ``w3`` — so Newton needs two or three steps; elsewhere Fujiwara's bound, which exceeds
    every root's magnitude (``w3 ≥ 1 − u0`` anyway).
    """
    shift = c2 / (3.0 * B)
    a1 = c1 / B
    p = a1 - 3.0 * shift * shift  # t³ + p t + q = 0 in t = w + shift
    q = shift * (2.0 * shift * shift - a1) + c0 / B
    with np.errstate(invalid="ignore", divide="ignore"):
        m = 2.0 * np.sqrt(-p / 3.0)
        t = m * np.cos(np.arccos(np.clip(3.0 * q / (p * m), -1.0, 1.0)) / 3.0)
    x = t - shift
    x += 1e-9 * (np.abs(x) + np.abs(shift) + m)
    fx = ((B * x + c2) * x + c1) * x + c0
    slope = (3.0 * B * x + 2.0 * c2) * x + c1
    above = (fx > 0) & (slope > 0) & (x > -shift)  # False where NaN
    if above.all():
        return x
    bound = 2.0 * np.maximum.reduce(
        [np.abs(3.0 * shift), np.sqrt(np.abs(a1)), np.cbrt(np.abs(c0 / (2.0 * B)))]
    )
    fujiwara = np.maximum(bound, hm) * (1.0 + 4.0 * _EPS) + _TINY
    return np.where(above, x, fujiwara)


def _newton_from_above(B, c0, c1, c2, w3):
    """Newton's method on the cubic from ``w3`` above its largest root.

    Above that root the cubic is increasing and convex, so the iterates decrease monotonically;
    each stops when it stops decreasing. All tops step together while many still move (no
    indexing), the stragglers (a near-double ``w2 ≈ w3`` converges linearly) on their own.
    """
    for _ in range(_NEWTON_MAX_ITER):
        fx = ((B * w3 + c2) * w3 + c1) * w3 + c0
        with np.errstate(divide="ignore", invalid="ignore"):
            nxt = w3 - fx / ((3.0 * B * w3 + 2.0 * c2) * w3 + c1)
        moving = (fx > 0) & (nxt < w3)
        count = np.count_nonzero(moving)
        if count == 0:
            return w3
        w3 = np.where(moving, nxt, w3)
        if 16 * count < w3.size:
            break
    else:
        return w3
    rows = np.flatnonzero(moving)
    w3[rows] = _newton_from_above(B[rows], c0[rows], c1[rows], c2[rows], w3[rows])
    return w3


def _root_errors(
    w: NDArray[np.float64], B: NDArray[np.float64], c0: NDArray[np.float64],
    c1_scale: NDArray[np.float64], c2_scale: NDArray[np.float64],
) -> list[NDArray[np.float64]]:
    """Rounding errors of the roots ``w2``, ``w3``: ``4 ε Σ|terms of f(w)| / |f'(w)|`` (R17).

    ``f'(w_i) = B ∏_{j≠i} (w_i − w_j)`` from the roots, so a near-double ``u2 ≈ u3`` (a top
    swinging from near the upright pole) gets the large error its offsets have, not
    ``ε |w_i|``: then ``1 − u2`` and ``u3 − 1`` must come from the re-solved cubic. The exact
    root ``w = 0`` (``c0 = 0``) gets 0, or NaN if it is double (``0/0``: no comparison with a
    NaN prefers the re-solved form, and the exact difference is kept).
    """
    w1, w2, w3 = w[:, 0], w[:, 1], w[:, 2]
    gap = w3 - w2
    errors = []
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for x, other in ((w2, w2 - w1), (w3, w3 - w1)):
            ax = np.abs(x)
            t = B * ax
            t += c2_scale
            t *= ax
            t += c1_scale
            t *= ax
            t += c0
            other *= gap  # f'(x)/B
            other *= B
            t /= np.abs(other, out=other)
            t *= 4.0 * _EPS
            errors.append(t)
    return errors


def _upper_pole_distances(hm, w, err2, err3, B, a, Q, P, b_minus_a):
    """``1 − u1``, ``1 − u2`` and ``u3 − 1``, each to full relative accuracy (R17).

    ``1 − u1 = (1 − u0) − w1`` adds two non-negative numbers. ``1 − u2 = (1 − u0) − w2`` and
    ``u3 − 1 = w3 − (1 − u0)`` cancel when ``u2`` or ``u3`` lies near the upper pole; there the
    cubic is solved again in ``v = 1 − u``, whose coefficients come straight from the state::

        f(1 − v) = −B v³ + (2B − C − a²) v² + 2 K v − (b − a)²,
        C = A − B = P − B (1 − u0),   K = C − a (b − a) = P − a Q + (1 − u0)(a² − B).

    Its roots are ``1 − u1`` (known), ``1 − u2 ≥ 0`` and ``1 − u3 ≤ 0``; by Vieta the last two
    solve ``v² − S v − p = 0`` with ``p = (b − a)²/(B (1 − u1)) ≥ 0`` and
    ``S = (p − 2K/B)/(1 − u1)``, whose discriminant ``S² + 4p`` is a sum of non-negative terms:
    the two pole distances come out with no signed difference at all. Each element keeps the
    form with the smaller rounding estimate (the direct difference's is the larger of the
    subtraction's and its root's own error ``err2``, ``err3``: large for a near-double
    ``u2 ≈ u3``, see :func:`_root_errors`);
    ``b = a`` exactly (a top that reaches the pole, or the planar pendulum) makes ``p = 0`` and
    the pole an exact root.
    """
    s1 = hm - w[:, 0]
    aq, aa = a * Q, a * a
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        p = b_minus_a * b_minus_a / (B * s1)
        S = (p - 2.0 * (P - aq + hm * (aa - B)) / B) / s1  # K = P − a Q + (1 − u0)(a² − B)
        root = np.sqrt(S * S + 4.0 * p)
        q = 0.5 * (S + np.copysign(root, S))  # the larger-magnitude root (S is never −0)
        small = np.where(q != 0, -p / q, 0.0)  # the other root, a quotient: relative accuracy
        k_terms = np.abs(P) + np.abs(aq) + hm * (aa + B)
        err_big = 8.0 * _EPS * ((p + 2.0 * k_terms / B) / s1 + root + np.abs(S))
        rel_p = 4.0 * _EPS * (np.abs(Q) + np.abs(a) * hm) / np.abs(b_minus_a) + 4.0 * _EPS
        err_small = np.abs(small) * (rel_p + err_big / np.abs(q))
    up = S >= 0  # q = 1 − u2 (u2 far from the pole) or q = 1 − u3 (u3 far from it)
    forced = np.isfinite(q) & np.isfinite(small)
    usable = forced & (b_minus_a != 0)
    forced &= b_minus_a == 0
    s2 = _better(np.where(up, q, small), np.where(up, err_big, err_small), hm - w[:, 1],
                 np.maximum(8.0 * _EPS * (hm + np.abs(w[:, 1])), err2), usable, forced)
    d = _better(-np.where(up, small, q), np.where(up, err_small, err_big), w[:, 2] - hm,
                np.maximum(8.0 * _EPS * (hm + np.abs(w[:, 2])), err3), usable, forced)
    return s1, s2, d


def _better(pole, err_pole, direct, err_direct, usable, forced):
    """A pole distance (clipped at 0): the re-solved ``pole`` form where ``forced``, or where
    ``usable`` and its rounding estimate ``err_pole`` is below the direct difference's
    ``err_direct`` (the larger of the subtraction's and the root's); the ``direct`` difference
    elsewhere."""
    use = forced | (usable & (err_pole < err_direct))
    return np.maximum(np.where(use, pole, direct), 0.0)


def _lower_pole_distances(hp, w, B, a, Q, b_plus_a):
    """``1 + u1``, ``1 + u2`` and ``1 + u3`` to full relative accuracy (R17).

    ``1 + u2 = (1 + u0) + w2`` and ``1 + u3 = (1 + u0) + w3`` add non-negative numbers;
    ``1 + u1 = (1 + u0) + w1`` cancels near the lower pole, where the exact identity
    ``(b + a)² = B (1 + u1)(1 + u2)(1 + u3)`` (from ``f(−1) = −(b + a)²``) gives it as a
    quotient of accurate numbers — exactly 0 when ``b = −a`` (a top that reaches the lower
    pole, the planar pendulum). Each element keeps the form with the smaller rounding estimate.
    """
    t2 = hp + w[:, 1]
    t3 = hp + w[:, 2]
    direct = np.maximum(hp + w[:, 0], 0.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ident = b_plus_a * b_plus_a / (B * t2 * t3)
        rel = 4.0 * _EPS * (np.abs(Q) + np.abs(a) * hp) / np.abs(b_plus_a) + 8.0 * _EPS
    err_direct = 8.0 * _EPS * (hp + np.abs(w[:, 0]))
    use = (b_plus_a == 0) | (np.isfinite(ident) & (rel * ident < err_direct))
    return np.where(use, np.where(b_plus_a == 0, 0.0, ident), direct), t2, t3


def precession_rate_at(cubic: NutationCubic, i: int) -> NDArray[np.float64]:
    """``α̇ = (b − a u)/(1 − u²)`` at root ``u_i`` (R18), from the better-conditioned form.

    Away from the poles ``(Q − a w_i) / ((1 − u_i)(1 + u_i))``: its numerator has no
    cancellation (for a fast top ``b`` and ``a u`` are huge, their difference is not). Near a
    pole ``½[(b − a)/(1 − u) + (b + a)/(1 + u)]``, whose terms are finite there (a pole that
    the top reaches has ``b ∓ a = 0`` exactly: the limit ``(b ± a)/4``). Each element takes the
    form with the smaller rounding estimate.
    """
    om, op = cubic.one_minus_u[:, i], cubic.one_plus_u[:, i]
    q, aw = cubic.Q, cubic.a * cubic.w[:, i]
    pole_form = 0.5 * (_ratio(cubic.b_minus_a, om) + _ratio(cubic.b_plus_a, op))
    with np.errstate(divide="ignore", invalid="ignore"):
        direct = (q - aw) / (om * op)
        err_direct = (np.abs(q) + np.abs(aw)) * (1.0 / om + 1.0 / op) / (om * op)
        err_pole = ((np.abs(q) + np.abs(cubic.a) * cubic.one_minus_u0 + np.abs(cubic.b_minus_a))
                    / om**2 + (np.abs(q) + np.abs(cubic.a) * cubic.one_plus_u0
                               + np.abs(cubic.b_plus_a)) / op**2)
    use_direct = (om > 0) & (op > 0) & ~(err_pole < err_direct)
    return np.where(use_direct, direct, pole_form)


def _ratio(num, den):
    """``num / den`` with ``0 / 0 = 0``: a pole the top reaches has ``b ∓ a = 0`` exactly."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(num == 0, 0.0, num / den)


def nutation_period_of(cubic: NutationCubic) -> NDArray[np.float64]:
    """``T_nut = 2 ∫ du/√f = 4 R_F(0, u3 − u2, u3 − u1) / √B`` (R20), s.

    Equal to ``4 K(k) / √(B (u3 − u1))``; the homogeneous Carlson form needs no ``k``, so
    ``k → 1`` (``u3 − u2 → 0``) loses nothing; it is ``inf`` at ``u2 = u3`` (the asymptotic
    fall of an unstable sleeping top).
    """
    return _period_from(elliprf(0.0, *_gaps(cubic)), cubic)


def _period_from(rf, cubic):
    with np.errstate(divide="ignore"):
        return 4.0 * rf / np.sqrt(cubic.B)


def nutation_integrals(cubic: NutationCubic) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`nutation_period_of` and :func:`precession_angle_of` from one evaluation of
    ``R_F(0, u3 − u2, u3 − u1)``, which both need."""
    rf = elliprf(0.0, *_gaps(cubic))
    return _period_from(rf, cubic), precession_angle_of(cubic, rf)


def _gaps(cubic):
    """``u3 − u2 = (u3 − 1) + (1 − u2)`` and ``u3 − u1 = (u3 − 1) + (1 − u1)``: sums of
    non-negative, fully accurate distances, so neither cancels (not even as ``u2 → u3``)."""
    d = cubic.u3_minus_one
    return d + cubic.one_minus_u[:, 1], d + cubic.one_minus_u[:, 0]


def precession_angle_of(
    cubic: NutationCubic, rf: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """Precession ``Δα`` over one nutation period (R20), rad, without cancellation.

    ``Δα = 2 ∫_{u1}^{u2} (b − a u) / ((1 − u²) √f) du = [(b − a) J₊ + (b + a) J₋] / √B`` with
    ``J± = ∫ du / ((1 ∓ u) √((u − u1)(u2 − u)(u3 − u)))`` (partial fractions
    ``(b − au)/(1 − u²) = ½[(b − a)/(1 − u) + (b + a)/(1 + u)]``). With ``y = u3 − u2``,
    ``z = u3 − u1``, ``g = u2 − u1`` there are two exact Carlson forms of the same ``Δα``:

    1. (``b − a`` and ``b + a`` of one sign, ``|p_α| ≥ |p_γ|``; the substitution
       ``u = u1 + g z/(t + z)`` for J₊, ``u = u1 + g t/(t + y)`` for J₋)::

           √B Δα = 2 R_F(0,y,z) [(b − a)/(1 − u1) + (b + a)/(1 + u2)]
                   + (2/3) g [(b − a) z/(1 − u1)² R_J(0,y,z, z(1 − u2)/(1 − u1))
                              + (b + a) y/(1 + u2)² R_J(0,y,z, y(1 + u1)/(1 + u2))]

       — every term has the sign of ``b ± a``: nothing cancels.
    2. (``b − a`` and ``b + a`` of opposite signs, ``|p_γ| > |p_α|``: the axis loops, and for a
       fast top whose loop passes near a pole the terms of form 1 are ±π each and cancel to
       the tiny drift)::

           Δα = π [sgn(b − a) + sgn(b + a)]
                + (2/(3√B)) [(b + a) R_J(0,y,z, u3 + 1) − (b − a) R_J(0,y,z, u3 − 1)]

       — the π of each ``J`` is split off exactly (``(b ∓ a)² = B (1 ∓ u1)(1 ∓ u2)|u3 ∓ 1|``
       makes ``|b ∓ a| J±/√B = π − (remainder)``), the π's cancel symbolically, and the two
       remaining terms have one sign. The remainder identity is
       ``∫₀^π dθ / (√d √(d + s)(√d + √(d + s))) = (2/3) R_J(0, y, z, d)`` for ``u = u1 + g
       (1 − cos θ)/2``, ``s = 1 − u``, ``d = u3 − 1`` (and likewise with ``1 + u``, ``u3 + 1``).

    Each top uses the form in which its terms share one sign. A top whose axis passes through a
    pole (``b = ±a``, ``sgn 0 = 0``) has the mean of the finite ``α̇`` between the jumps of π
    that ``α`` makes there (the average of the two one-sided limits); the planar pendulum
    (``a = b = 0``) has ``Δα = 0``. ``rf``, if given, is ``R_F(0, y, z)`` already evaluated.
    """
    y, z = _gaps(cubic)
    if rf is None:
        rf = elliprf(0.0, y, z)
    opposite = cubic.b_minus_a * cubic.b_plus_a < 0
    om, op = cubic.one_minus_u, cubic.one_plus_u
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # each top's two third-kind integrals, those of its form: two R_J calls for all tops
        rj_plus = elliprj(0.0, y, z, np.where(opposite, cubic.u3_minus_one,
                                                z * om[:, 1] / om[:, 0]))
        rj_minus = elliprj(0.0, y, z, np.where(opposite, op[:, 2], y * op[:, 0] / op[:, 1]))
        angle = np.where(opposite, _split_form(cubic, rj_plus, rj_minus),
                         _same_sign_form(cubic, rj_plus, rj_minus, rf, y, z))
    return angle


def _same_sign_form(cubic: NutationCubic, rj_plus, rj_minus, rf, y, z) -> NDArray[np.float64]:
    """Form 1 of :func:`precession_angle_of`, given its ``R_J`` and ``R_F``."""
    om1, op2 = cubic.one_minus_u[:, 0], cubic.one_plus_u[:, 1]
    bma, bpa = cubic.b_minus_a, cubic.b_plus_a
    value_terms = _ratio(bma, om1) + _ratio(bpa, op2)
    third_kind = _product(bma, z / om1**2 * rj_plus) + _product(bpa, y / op2**2 * rj_minus)
    gap = cubic.w[:, 1] - cubic.w[:, 0]
    return (2.0 * rf * value_terms + (2.0 / 3.0) * gap * third_kind) / np.sqrt(cubic.B)


def _split_form(cubic: NutationCubic, rj_plus, rj_minus) -> NDArray[np.float64]:
    """Form 2 of :func:`precession_angle_of` (π split off), given its two ``R_J``."""
    bma, bpa = cubic.b_minus_a, cubic.b_plus_a
    split = (2.0 / 3.0) * (_product(bpa, rj_minus) - _product(bma, rj_plus))
    return np.pi * (np.sign(bma) + np.sign(bpa)) + split / np.sqrt(cubic.B)


def _product(coef, integral):
    """``coef · integral`` with ``0 · ∞ = 0`` (a pole on the path of the top: ``b ∓ a = 0``)."""
    with np.errstate(invalid="ignore"):
        return np.where(coef == 0, 0.0, coef * integral)


def cos_beta_of(
    cubic: NutationCubic, t: NDArray[np.float64], beta_dot0: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``u(t) = u1 + (u2 − u1) sn²(λ t + φ, k)`` (R20), ``λ = √(B (u3 − u1))/2``.

    The phase ``φ = ∓F(ψ0, k)`` with ``sin²ψ0 = (u0 − u1)/(u2 − u1)`` puts ``u(0) = u0``; its
    sign is opposite to ``β̇0`` (``sn²`` increases on ``(0, K)``, and ``u̇ = −sin β β̇``).
    ``t`` and the cubic's arrays are 1-D of one length.
    """
    w1, w2 = cubic.w[:, 0], cubic.w[:, 1]
    y, z = _gaps(cubic)
    gap = w2 - w1
    with np.errstate(divide="ignore", invalid="ignore"):
        # k'² = 1 − k² = (u3 − u2)/(u3 − u1) from the root gaps, so nothing cancels as k → 1
        # (u2 near the vertical); sn and F in the complementary parameter (solver.jacobi).
        m1 = np.where(gap > 0, y / z, 1.0)
        sin_psi0 = np.where(gap > 0, np.sqrt(np.clip(-w1 / gap, 0.0, 1.0)), 0.0)
        cos_psi0 = np.where(gap > 0, np.sqrt(np.clip(w2 / gap, 0.0, 1.0)), 1.0)
        phase = np.where(beta_dot0 > 0, -1.0, 1.0) * incomplete_f(sin_psi0, cos_psi0, m1)
        sn = jacobi_sncndn(0.5 * np.sqrt(cubic.B * z) * t + phase, m1)[0]
    u = cubic.u0 + w1 + gap * sn * sn
    # No motion in β: steady or sleeping, or resting on the unstable vertical (u2 = u3 = u0).
    still = (gap == 0) | ((y == 0) & (w2 == 0))
    return np.where(still, cubic.u0, u)
