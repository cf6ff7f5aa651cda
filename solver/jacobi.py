"""Jacobi elliptic functions accurate up to the separatrix, in the complementary parameter.

Both exact solutions in Jacobi functions — the free asymmetric top (R10) and the heavy top's
nutation ``u(t) = u1 + (u2 − u1) sn²`` (R20) — approach ``m = k² → 1`` (a separatrix, or the
upper turning point near the vertical), where ``1 − m`` carries all the information. Both
functions here therefore take the *complementary* parameter ``m1 = 1 − m``, formed by the caller
from differences that do not cancel, never ``m`` itself.

Near ``m = 1`` scipy's ``ellipj(u, m)`` is unusable (measured: for ``1 − m = 2⁻⁴⁰`` it returns
values of order 1e13 at ``u ≈ 2K``; at ``2⁻³⁰`` errors reach 1e-12), so :func:`jacobi_sncndn`
applies the descending Landen transformation (DLMF 22.7.1–22.7.3), which takes ``m1`` to
``4√m1/(1 + √m1)²`` without cancellation, until ``m1 ≥ 1/16``, and only then calls ``ellipj``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ellipj, ellipkm1, elliprf

__all__ = ["incomplete_f", "jacobi_sncndn"]

# From this complementary parameter on, scipy's ellipj is accurate to ~1e-15 over a period
# (measured against mpmath); below it the Landen transformation is applied first.
_DIRECT_M1 = 1.0 / 16.0


def jacobi_sncndn(
    u: ArrayLike, m1: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """sn, cn, dn of ``u`` for parameter ``m = 1 − m1``, accurate as ``m1 → 0`` (R10, R20).

    ``u`` is first reduced modulo the period ``4K``; ``m1 = 0`` gives tanh, sech, sech.
    Arrays broadcast. Matches mpmath's ``ellipfun`` to ~2e-14 for ``m1`` from 1 down to 1e-200.
    """
    u, m1 = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(m1, dtype=float))
    K = ellipkm1(m1)
    finite = m1 > 0
    turns = np.where(finite, np.round(u / np.where(finite, 4 * K, 1.0)), 0.0)
    u = u - 4 * np.where(finite, K, 0.0) * turns
    sn, cn, dn = _landen_sncndn(u, np.where(finite, m1, 1.0))
    with np.errstate(over="ignore"):  # cosh overflows to inf far out: sech is then 0
        sech = 1.0 / np.cosh(u)
    return np.where(finite, sn, np.tanh(u)), np.where(finite, cn, sech), np.where(finite, dn, sech)


def _landen_sncndn(
    u: NDArray[np.float64], m1: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Descending Landen transformation (DLMF 22.7.1–22.7.3) down to ``m1 ≥ _DIRECT_M1``."""
    near = m1 < _DIRECT_M1
    if not np.any(near):
        sn, cn, dn, _ = ellipj(u, 1.0 - m1)
        return sn, cn, dn
    kc = np.sqrt(m1)  # complementary modulus k'
    k1 = (1.0 - kc) / (1.0 + kc)  # the transformed modulus
    m1_next = 4.0 * kc / (1.0 + kc) ** 2  # 1 − k1², free of cancellation
    s, c, d = _landen_sncndn(np.where(near, u / (1.0 + k1), u), np.where(near, m1_next, m1))
    denom = 1.0 + k1 * s**2
    sn = (1.0 + k1) * s / denom
    cn = c * d / denom
    # dn = (1 − k1 s²)/(1 + k1 s²), with 1 − k1 s² = c² + (1 − k1) s² summed without cancellation
    dn = (c**2 + 2.0 * kc / (1.0 + kc) * s**2) / denom
    return np.where(near, sn, s), np.where(near, cn, c), np.where(near, dn, d)


def incomplete_f(sin_phi: ArrayLike, cos_phi: ArrayLike, m1: ArrayLike) -> NDArray[np.float64]:
    """Incomplete elliptic integral of the first kind ``F(φ | m)``, ``m = 1 − m1``, ``|φ| ≤ π/2``.

    Carlson's form (DLMF 19.25.5) ``sin φ · R_F(cos²φ, cos²φ + m1 sin²φ, 1)``, in which only the
    complementary parameter enters, so ``F`` stays accurate as ``m → 1``. ``sin_phi`` and
    ``cos_phi ≥ 0`` are passed separately so the caller's quadrant information is not lost.
    """
    s, c, m1 = (np.asarray(x, dtype=float) for x in (sin_phi, cos_phi, m1))
    c2 = c * c
    return s * elliprf(c2, c2 + m1 * s * s, 1.0)
