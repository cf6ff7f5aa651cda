"""The torque-free rigid body: Euler's equations, their invariants, the symmetric top and
the stability of spin about a principal axis (R7–R9 of the physics page, ``docs/physics/``).

Conventions: principal body frame, right-handed; ``omega`` holds the body components
``(ω1, ω2, ω3)`` in its last axis (rad/s); moments of inertia in kg m²; times in s.
The exact asymmetric solution (R10) lives in :mod:`solver.asymmetric_top`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.parameters import ParameterError, as_real, principal_moments

__all__ = [
    "body_precession_rate",
    "euler_rhs",
    "invariants",
    "near_axis_stability",
    "space_precession_rate",
    "symmetric_top_omega",
]


def _moments_vector(I1: ArrayLike, I2: ArrayLike, I3: ArrayLike) -> NDArray[np.float64]:
    """Validated principal moments stacked on a trailing axis of 3."""
    return np.stack(principal_moments(I1, I2, I3), axis=-1)


def euler_rhs(
    t: float,
    omega: ArrayLike,
    I1: ArrayLike,
    I2: ArrayLike,
    I3: ArrayLike,
    torque: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Right-hand side of Euler's equations, dω/dt in the principal body frame (R7).

    ``I1 ω̇1 = (I2 − I3) ω2 ω3 + τ1`` and cyclically, i.e. ``I ω̇ = (Iω) × ω + τ``.

    Parameters
    ----------
    t : float
        Time (s); unused (autonomous system), present for ``scipy.integrate.solve_ivp``.
    omega : array_like, shape (..., 3)
        Body components of the angular velocity (rad/s).
    I1, I2, I3 : array_like
        Principal moments (kg m²), broadcast against ``omega[..., 0]``.
    torque : array_like, shape (..., 3), optional
        Body components of the applied torque (N m); zero if omitted.

    Returns
    -------
    ndarray, shape (..., 3)
        dω/dt (rad/s²).

    Examples
    --------
    >>> from functools import partial
    >>> rhs = partial(euler_rhs, I1=1.0, I2=2.0, I3=3.0)
    >>> rhs(0.0, [1.0, 1.0, 1.0]).tolist()
    [-1.0, 1.0, -0.3333333333333333]
    """
    w = as_real("omega", omega, shape_tail=(3,))
    moments = _moments_vector(I1, I2, I3)
    dL = _gyroscopic_torque(moments, w)
    if torque is not None:
        dL = dL + as_real("torque", torque, shape_tail=(3,))
    return dL / moments


def _gyroscopic_torque(moments: NDArray[np.float64], w: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(I_j − I_k) ω_j ω_k`` for ``(i, j, k)`` cyclic: ``(Iω) × ω`` in R7's own form.

    Forming the moment difference first makes it exactly zero whenever two moments are equal
    or the rotation is about a principal axis (a cross product would leave rounding residue).
    """
    return (np.roll(moments, -1, -1) - np.roll(moments, -2, -1)) * (
        np.roll(w, -1, -1) * np.roll(w, -2, -1)
    )


def invariants(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, omega: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Kinetic energy ``T = ½ Σ I_i ω_i²`` (J) and ``L² = Σ I_i² ω_i²`` (kg² m⁴ s⁻²) (R7).

    Both are conserved by the torque-free motion. ``omega`` has shape (..., 3); the results
    have the broadcast shape of the moments and ``omega[..., 0]``.
    """
    w = as_real("omega", omega, shape_tail=(3,))
    moments = _moments_vector(I1, I2, I3)
    T = 0.5 * np.sum(moments * w**2, axis=-1)
    L2 = np.sum((moments * w) ** 2, axis=-1)
    return T, L2


def body_precession_rate(I1: ArrayLike, I3: ArrayLike, omega3: ArrayLike) -> NDArray[np.float64]:
    """Body-frame precession rate ``Ω = ω3 (I3 − I1)/I1`` of a symmetric top (R8), rad/s.

    ``I1 = I2`` is the transverse moment, ``I3`` the moment about the symmetry axis. ``ω``
    turns about ``ê3`` counter-clockwise for ``Ω > 0`` (oblate body spun positively).
    """
    a, _, c = principal_moments(I1, I1, I3)
    return as_real("omega3", omega3) * (c - a) / a


def space_precession_rate(I1: ArrayLike, I3: ArrayLike, omega0: ArrayLike) -> NDArray[np.float64]:
    """Inertial precession rate ``α̇ = L/I1`` of a free symmetric top's axis about L (R8), rad/s.

    ``omega0`` (..., 3) is any body angular velocity of the motion (``L`` is conserved).
    """
    w = as_real("omega0", omega0, shape_tail=(3,))
    a, _, c = principal_moments(I1, I1, I3)
    L = np.sqrt(a**2 * (w[..., 0] ** 2 + w[..., 1] ** 2) + c**2 * w[..., 2] ** 2)
    return L / a


def symmetric_top_omega(
    I1: ArrayLike, I3: ArrayLike, omega0: ArrayLike, t: ArrayLike
) -> NDArray[np.float64]:
    """Exact ω(t) of the torque-free symmetric top ``I1 = I2`` (R8).

    ``ω3`` is constant and ``ω1 + i ω2`` turns at ``Ω = ω3 (I3 − I1)/I1``:
    ``ω1 + i ω2 = (ω1(0) + i ω2(0)) e^{iΩt}``.

    Parameters
    ----------
    I1, I3 : array_like
        Transverse and axial principal moments (kg m²); ``I3 ≤ 2 I1``.
    omega0 : array_like, shape (..., 3)
        ω at ``t = 0`` (rad/s), body frame.
    t : array_like
        Times (s), broadcast with the leading shape of the other parameters.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    w0 = as_real("omega0", omega0, shape_tail=(3,))
    time = as_real("t", t)
    rate = body_precession_rate(I1, I3, w0[..., 2])
    phase = rate * time
    c, s = np.cos(phase), np.sin(phase)
    w1 = w0[..., 0] * c - w0[..., 1] * s
    w2 = w0[..., 0] * s + w0[..., 1] * c
    w1, w2, w3 = np.broadcast_arrays(w1, w2, w0[..., 2])
    return np.stack([w1, w2, w3], axis=-1)


def near_axis_stability(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, omega_spin: ArrayLike, axis: int = 3
) -> dict[str, NDArray]:
    """Linear stability of spin about one principal axis (R9, any axis by cyclic relabelling).

    For spin ``ω_a = omega_spin`` about axis ``a`` and the other two axes ``b, c`` taken in
    cyclic order (``a, b, c`` = 3,1,2 / 1,2,3 / 2,3,1 for ``axis`` = 3 / 1 / 2), the small
    components obey ``ω̇_b = −Ω1 ω_c``, ``ω̇_c = Ω2 ω_b`` with
    ``Ω1 = ω_a (I_a − I_c)/I_b`` and ``Ω2 = ω_a (I_a − I_b)/I_c``
    (for ``axis=3`` exactly R9: ``Ω1 = ω3 (I3 − I2)/I1``, ``Ω2 = ω3 (I3 − I1)/I2``).

    ``Ω1 Ω2 > 0`` (largest or smallest moment): stable, oscillation at ``rate = √(Ω1Ω2)``;
    ``Ω1 Ω2 < 0`` (intermediate moment): unstable, growth ``e^{rate t}``,
    ``rate = √(−Ω1Ω2)``.

    Equal moments: if exactly one of ``Ω1, Ω2`` vanishes (spin about an axis lying in a
    degenerate plane, e.g. a transverse axis of a symmetric top), the linearised motion grows
    linearly in time (ω wanders round the symmetry axis): reported ``stable=False``,
    ``rate=0``. If both vanish (spherical top, or ``omega_spin = 0``) perturbations stay
    constant: ``stable=True``, ``rate=0``.

    Parameters
    ----------
    I1, I2, I3 : array_like
        Principal moments (kg m²).
    omega_spin : array_like
        Spin rate about ``axis`` (rad/s).
    axis : {1, 2, 3}
        The principal axis spun about.

    Returns
    -------
    dict
        ``Omega1``, ``Omega2`` (rad/s), ``stable`` (bool), ``rate`` (rad/s or 1/s).
    """
    if axis not in (1, 2, 3):
        raise ParameterError("axis", f"must be 1, 2 or 3, got {axis!r}")
    moments = principal_moments(I1, I2, I3)
    spin = as_real("omega_spin", omega_spin)
    a = axis - 1
    Ia, Ib, Ic = moments[a], moments[(a + 1) % 3], moments[(a + 2) % 3]
    Omega1 = spin * (Ia - Ic) / Ib
    Omega2 = spin * (Ia - Ib) / Ic
    product = Omega1 * Omega2
    both_zero = (Omega1 == 0) & (Omega2 == 0)
    return {
        "Omega1": Omega1,
        "Omega2": Omega2,
        "stable": (product > 0) | both_zero,
        "rate": np.sqrt(np.abs(product)),
    }

