"""An independent high-precision reference for the heavy symmetric top (R15–R20), in mpmath.

Written from the formulas of ``docs/physics/index.md`` alone: it imports nothing from ``solver``
and shares none of its numerics (no offset cubic, no pole frames, no Carlson forms). It is what
the fuzz suite (:mod:`solver.bench.fuzz`) and the accuracy tests measure the solver against.

For a state given as binary floats (exact inputs), at ``dps`` decimal digits:

* R15/R16: ``p_γ = I3 (α̇ cos β + γ̇)``, ``p_α = I1 α̇ sin²β + p_γ cos β``,
  ``E' = ½ I1 (β̇² + α̇² sin²β) + Mgl cos β``;
* R17: the roots of the *expanded* cubic ``B u³ − (A + a²) u² + (2ab − B) u + (A − b²)`` by
  ``mpmath.polyroots``, sorted; ``β1 = arccos u2``, ``β2 = arccos u1``;
* R20: ``T = 4 K(m)/√(B (u3 − u1))``, ``m = (u2 − u1)/(u3 − u1)`` (Legendre ``K``), and
  ``Δα = [(b − a) J₊ + (b + a) J₋]/√B`` with the Legendre third-kind integrals
  ``J₊ = 2 Π(n₊ | m)/((1 − u1) √(u3 − u1))``, ``n₊ = (u2 − u1)/(1 − u1)`` and
  ``J₋ = 2 Π(n₋ | m)/((1 + u1) √(u3 − u1))``, ``n₋ = −(u2 − u1)/(1 + u1)`` (the substitution
  ``u = u1 + (u2 − u1) sin²φ``), ``⟨α̇⟩ = Δα/T``. These two terms can cancel (up to ~10¹⁶ for a
  fast top looping near a pole): the default 50 digits leave ≥ 30 after the worst cancellation
  the fuzz regions produce. A pole the top reaches (``b = ±a`` exactly) contributes 0;
* R18: ``α̇ = (b − a u)/(1 − u²)`` at the turning points (its finite limit at a reached pole)
  decides the figure: cusps (``α̇ = 0`` at a turning point off the poles), loops (opposite
  signs), waves; plus sleeping (R19), steady (``u1 = u2``) and revolves (planar pendulum over
  the top: ``p_α = p_γ = 0``, ``A > B``).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath as mp

__all__ = ["Reference", "reference"]

DPS = 50


@dataclass(frozen=True)
class Reference:
    """Reference values of one state (mpmath numbers, or ``None`` where undefined).

    Attributes
    ----------
    beta1, beta2 : mpf
        Turning points, rad.
    period : mpf or None
        Nutation period, s (``+inf`` when ``u2 = u3``).
    mean_rate : mpf or None
        ⟨α̇⟩, rad/s (None for a sleeping top or an infinite period).
    gap : mpf
        ``u2 − u1``.
    rates : tuple of mpf
        ``α̇`` at ``u2`` (β1) and ``u1`` (β2), rad/s.
    label : str
        R18's figure (see the module docstring).
    """

    beta1: mp.mpf
    beta2: mp.mpf
    period: mp.mpf | None
    mean_rate: mp.mpf | None
    gap: mp.mpf
    rates: tuple
    label: str


def reference(state: tuple[float, ...], dps: int = DPS) -> Reference:
    """The reference values of ``state = (I1, I3, Mgl, beta0, alpha_dot0, beta_dot0,
    gamma_dot0)`` (binary floats, taken as exact, or mpmath numbers) with at least ``dps − 25``
    correct digits.

    Precision is raised where ``dps`` digits would not do: a turning point at ``1 − u`` from a
    pole, or a ``Δα`` whose two terms cancel ``C``-fold, need ``log10(1/(1 − u))``, ``log10 C``
    more digits (the case is recomputed with them).
    """
    with mp.workdps(30):
        tilt = mp.mpf(state[3])
        near = min(abs(tilt), abs(mp.pi - tilt))
    if 0 < near < 1e-6:  # cos β0 itself must resolve 1 − cos β0 ≈ β0²/2
        dps = max(dps, int(-2 * mp.log10(near)) + 30)
    for _ in range(6):
        ref, lost = _reference(state, dps)
        if lost <= dps - 30:
            break
        dps = max(int(lost) + 40, 2 * dps)
    if ref is None:
        raise ArithmeticError(f"no reference for {state}: a turning point unresolved from a "
                              f"pole at {dps} digits")
    return ref


def _reference(state, dps: int) -> tuple[Reference | None, float]:
    """(the reference at ``dps`` digits, the digits that pole distances and cancellation cost);
    (None, ...) where a turning point is not told apart from a pole at these digits."""
    with mp.workdps(dps):
        I1, I3, Mgl, b0, ad, bd, gd = (x if isinstance(x, mp.mpf) else mp.mpf(float(x))
                                       for x in state)
        c, s = mp.cos(b0), mp.sin(b0)
        if b0 == 0:
            c, s = mp.mpf(1), mp.mpf(0)
        pg = I3 * (ad * c + gd)  # R15
        pa = I1 * ad * s**2 + pg * c
        e_prime = I1 * (bd**2 + ad**2 * s**2) / 2 + Mgl * c  # R16
        a, b, A, B = pg / I1, pa / I1, 2 * e_prime / I1, 2 * Mgl / I1  # R17
        u1, u2, u3 = _roots(a, b, A, B, c if bd == 0 else None)
        # a turning point exactly on a pole needs b = ±a exactly; anything else at or beyond a
        # pole is the working precision failing to resolve 1 ∓ u: ask for more digits
        distances = [d for d, reached in ((1 - u2, b == a), (1 + u1, b == -a)) if not reached]
        pole = min(distances, default=mp.mpf(1))
        if pole <= 0:  # nothing at these digits means anything (α̇ there would be a/0)
            return None, float(2 * dps)
        lost = float(-mp.log10(pole))
        beta1, beta2 = mp.acos(min(u2, 1)), mp.acos(max(u1, -1))
        rates = (_rate(a, b, u2), _rate(a, b, u1))
        if bd == 0 and s != 0:  # u0 = cos β0 is a turning point off the poles: α̇ = α̇0 there
            rates = (ad, rates[1]) if u2 == c else (rates[0], ad) if u1 == c else rates
        sleeping = b0 == 0 and bd == 0 and pg**2 >= 4 * Mgl * I1
        period = _period(u1, u2, u3, B)
        mean = None
        if not sleeping and mp.isfinite(period):
            angle, size = _precession_angle(a, b, B, u1, u2, u3)
            mean = angle / period
            if angle != 0:
                lost = max(lost, float(mp.log10(size / abs(angle))))
        label = _label(a, b, A, B, u1, u2, rates, sleeping)
        return Reference(beta1, beta2, period, mean, u2 - u1, rates, label), lost


def _roots(a, b, A, B, u0=None):
    """Sorted roots of R17's cubic. Exact roots are deflated exactly, not found numerically: a
    double root at a pole (a top at rest on the vertical: ``f(±1) = f'(±1) = 0``), and
    ``u0 = cos β0`` when ``β̇0 = 0`` (``f(u0) = sin²β0 β̇0² = 0``), so that a steady or nearly
    steady top's two close roots are not split at the square root of the working precision."""
    if a == 0 and b == 0:  # the planar pendulum: f(u) = (1 − u²)(A − B u)
        return sorted([mp.mpf(-1), mp.mpf(1), A / B])
    for pole in (1, -1):
        if b == pole * a and A == pole * B:  # f(u) = (1 − u²)(A − Bu) − a²(1 − pole·u)²
            other = a * a / B - 1 if pole == 1 else 1 - a * a / B
            return sorted([mp.mpf(pole), mp.mpf(pole), other])
    coeffs = [B, -(A + a * a), 2 * a * b - B, A - b * b]
    if u0 is not None:  # synthetic division by (u − u0), then the quadratic without cancellation
        q1 = coeffs[1] + B * u0
        q0 = coeffs[2] + q1 * u0
        disc = max(q1 * q1 - 4 * B * q0, 0)
        big = -(q1 + mp.sign(q1) * mp.sqrt(disc)) / 2 if q1 != 0 else mp.sqrt(-B * q0)
        return sorted([u0, big / B, q0 / big])
    polished = _newton_roots(coeffs)
    if polished is not None:
        return polished
    roots = mp.polyroots(coeffs, maxsteps=200, extraprec=mp.mp.prec)
    return sorted(mp.re(r) for r in roots)


def _newton_roots(coeffs):
    """The three real roots by Newton's method from double-precision starts (numpy's companion
    matrix), accepted only if they are distinct and satisfy Vieta's sum and product to the
    working precision; None otherwise (then ``polyroots`` decides)."""
    import numpy as np

    with mp.workdps(20):
        scaled = [float(c / coeffs[0]) for c in coeffs]
    starts = np.roots(scaled)
    if np.any(np.abs(starts.imag) > 0) or not np.all(np.isfinite(starts)):
        return None
    roots = []
    tol = mp.mpf(10) ** (-mp.mp.dps + 5)
    for x0 in sorted(starts.real):
        x = mp.mpf(float(x0))
        for _ in range(60):
            f = mp.polyval(coeffs, x)
            df = mp.polyval([3 * coeffs[0], 2 * coeffs[1], coeffs[2]], x)
            if df == 0:
                return None
            step = f / df
            x -= step
            if abs(step) <= tol * max(1, abs(x)):
                break
        else:
            return None
        roots.append(x)
    roots.sort()
    scale = max(1, *(abs(r) for r in roots))
    if min(roots[1] - roots[0], roots[2] - roots[1]) <= mp.mpf(10) ** (-mp.mp.dps / 2) * scale:
        return None
    vieta_sum = -coeffs[1] / coeffs[0]
    vieta_product = -coeffs[3] / coeffs[0]
    if abs(sum(roots) - vieta_sum) > tol * scale * 10 or abs(
            roots[0] * roots[1] * roots[2] - vieta_product) > tol * scale**3 * 10:
        return None
    return roots


def _rate(a, b, u):
    """α̇ = (b − a u)/(1 − u²) (R18), with its finite limit at a pole the top reaches."""
    if b == a and b == -a:
        return mp.mpf(0)
    if b == a:
        return a / (1 + u)
    if b == -a:
        return -a / (1 - u)
    # ½[(b − a)/(1 − u) + (b + a)/(1 + u)]; a root found exactly at a pole (b ∓ a = 0 up to the
    # working precision) contributes its finite part only
    plus = (b - a) / (1 - u) if u != 1 else 0
    minus = (b + a) / (1 + u) if u != -1 else 0
    return (plus + minus) / 2


def _period(u1, u2, u3, B):
    if u3 - u2 <= 0:
        return mp.inf
    m = (u2 - u1) / (u3 - u1)
    return 4 * _ellipk(m) / mp.sqrt(B * (u3 - u1))


def _arb_backend() -> bool:
    try:
        import flint  # noqa: F401
    except ImportError:
        return False
    return True


USE_ARB = _arb_backend()


def _ellipk(m):
    """Legendre ``K(m)``: Arb (python-flint, rigorous error balls; ~30× faster) if installed,
    else mpmath — the two agree (``tests/solver/test_fuzz.py``)."""
    if not USE_ARB:
        return mp.ellipk(m)
    from flint import acb, ctx

    ctx.dps = mp.mp.dps + 5
    return _to_mp(acb.elliptic_k(acb(_to_arb(m))))


def _ellippi(n, m):
    """Legendre complete ``Π(n | m)`` (same backends as :func:`_ellipk`)."""
    if not USE_ARB:
        return mp.ellippi(n, m)
    from flint import acb, ctx

    ctx.dps = mp.mp.dps + 5
    return _to_mp(acb.elliptic_pi(acb(_to_arb(n)), acb(_to_arb(m))))


def _to_arb(x):
    from flint import arb

    return arb(mp.nstr(x, mp.mp.dps + 5, strip_zeros=False, min_fixed=1, max_fixed=0))


def _to_mp(z):
    value = z.real.mid().str(mp.mp.dps + 5, radius=False)
    return mp.mpf(value)


def _precession_angle(a, b, B, u1, u2, u3):
    """(Δα, the sum of the magnitudes of its two terms)."""
    g, z = u2 - u1, u3 - u1
    m = g / z
    terms = [mp.mpf(0), mp.mpf(0)]
    if b != a and u2 != 1:  # a pole on the path (u2 = 1 exactly) means b = a: no term
        n = g / (1 - u1)
        terms[0] = (b - a) * 2 * _ellippi(n, m) / ((1 - u1) * mp.sqrt(z))
    if b != -a and u1 != -1:
        n = -g / (1 + u1)
        terms[1] = (b + a) * 2 * _ellippi(n, m) / ((1 + u1) * mp.sqrt(z))
    return (terms[0] + terms[1]) / mp.sqrt(B), (abs(terms[0]) + abs(terms[1])) / mp.sqrt(B)


def _label(a, b, A, B, u1, u2, rates, sleeping) -> str:
    if sleeping:
        return "sleeping"
    if a == 0 and b == 0 and A > B:
        return "revolves"
    if u2 - u1 == 0:
        return "steady"
    off_pole = (1 - u2 > 0, 1 + u1 > 0)
    if any(r == 0 and ok for r, ok in zip(rates, off_pole, strict=True)):
        return "cusps"
    return "loops" if rates[0] * rates[1] < 0 else "waves"
