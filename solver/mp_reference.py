"""An independent high-precision reference for the heavy symmetric top (R15–R20), in mpmath.

Written from ``physics.md`` alone: it imports nothing from ``solver`` and shares none of its
numerics (no offset cubic, no pole frames, no Carlson forms). It is what the fuzz suite
(:mod:`solver.fuzz`) and the accuracy tests measure the solver against.

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
    gamma_dot0)`` (binary floats, taken as exact) at ``dps`` digits."""
    with mp.workdps(dps):
        I1, I3, Mgl, b0, ad, bd, gd = (mp.mpf(float(x)) for x in state)
        c, s = mp.cos(b0), mp.sin(b0)
        if b0 == 0:
            c, s = mp.mpf(1), mp.mpf(0)
        pg = I3 * (ad * c + gd)  # R15
        pa = I1 * ad * s**2 + pg * c
        e_prime = I1 * (bd**2 + ad**2 * s**2) / 2 + Mgl * c  # R16
        a, b, A, B = pg / I1, pa / I1, 2 * e_prime / I1, 2 * Mgl / I1  # R17
        u1, u2, u3 = _roots(a, b, A, B)
        beta1, beta2 = mp.acos(min(u2, 1)), mp.acos(max(u1, -1))
        rates = (_rate(a, b, u2), _rate(a, b, u1))
        sleeping = b0 == 0 and bd == 0 and pg**2 >= 4 * Mgl * I1
        period = _period(u1, u2, u3, B)
        mean = None
        if not sleeping and mp.isfinite(period):
            mean = _precession_angle(a, b, B, u1, u2, u3) / period
        label = _label(a, b, A, B, u1, u2, rates, sleeping)
        return Reference(beta1, beta2, period, mean, u2 - u1, rates, label)


def _roots(a, b, A, B):
    coeffs = [B, -(A + a * a), 2 * a * b - B, A - b * b]
    roots = mp.polyroots(coeffs, maxsteps=200, extraprec=2 * mp.mp.prec)
    return sorted(mp.re(r) for r in roots)


def _rate(a, b, u):
    """α̇ = (b − a u)/(1 − u²) (R18), with its finite limit at a pole the top reaches."""
    if b == a and b == -a:
        return mp.mpf(0)
    if b == a:
        return a / (1 + u)
    if b == -a:
        return -a / (1 - u)
    return (b - a * u) / ((1 - u) * (1 + u))


def _period(u1, u2, u3, B):
    if u3 - u2 <= 0:
        return mp.inf
    m = (u2 - u1) / (u3 - u1)
    return 4 * mp.ellipk(m) / mp.sqrt(B * (u3 - u1))


def _precession_angle(a, b, B, u1, u2, u3):
    g, z = u2 - u1, u3 - u1
    m = g / z
    total = mp.mpf(0)
    if b != a:
        n = g / (1 - u1)
        total += (b - a) * 2 * mp.ellippi(n, m) / ((1 - u1) * mp.sqrt(z))
    if b != -a:
        n = -g / (1 + u1)
        total += (b + a) * 2 * mp.ellippi(n, m) / ((1 + u1) * mp.sqrt(z))
    return total / mp.sqrt(B)


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
