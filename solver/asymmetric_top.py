"""Exact motion of the torque-free asymmetric top in Jacobi elliptic functions (R10).

Landau–Lifshitz §37 solve Euler's equations (R7) for ``I1 < I2 < I3`` and ``L² > 2T I2``:
``ω1 ∝ cn``, ``ω2 ∝ sn``, ``ω3 ∝ dn`` of ``τ = λ t`` with modulus ``k`` fixed by the
invariants ``T`` and ``L²``. This module extends that formula to every initial condition:

*Any moment order.* The moments are sorted and ω is relabelled to match. Euler's equations
keep their form under a cyclic relabelling; an odd one (a transposition) makes the frame
left-handed and flips the sign of their right-hand side, which is a time reversal. Relabelled
motion therefore runs at ``τ = π t`` with ``π = ±1`` the parity of the relabelling.

*Both sides of the separatrix.* ``ω ∝ (cn, sn, dn)`` holds with the "dn axis" (the one ω
circles) last: ascending order (``c = a, b, c`` = axes of the smallest, intermediate, largest
moment) when ``L² ≥ 2T I_mid``, descending order (roles of 1 and 3 exchanged) when
``L² < 2T I_mid``. Written with ``|I_i − I_j|`` the formulas are the same for both orders;
descending order reverses the sign of every coefficient of Euler's equations, i.e. time
once more, so that ascending or descending, ω moves at ``u = u0 + π_asc λ t`` with
``π_asc`` the parity of the *ascending* sort.

With (in the chosen order) ``d_ij = |I_i − I_j|``, ``P1 = |2T I3 − L²| = I1 d31 ω1² + I2 d32 ω2²``,
``P3 = |L² − 2T I1| = I2 d21 ω2² + I3 d31 ω3²`` and ``D = |L² − 2T I2| = I3 d32 ω3² − I1 d21 ω1²``
(each formed from ω directly, so the tiny ``D`` near the separatrix has no cancellation
beyond that of its own two terms, which are summed in extended precision)::

    ω1 = s1 A1 cn(u, m),  ω2 = s1 s3 A2 sn(u, m),  ω3 = s3 A3 dn(u, m),
    A1² = P1/(I1 d31),  A2² = P1/(I2 d32),  A3² = P3/(I3 d31),
    λ² = d32 P3/(I1 I2 I3),  m = k² = d21 P1/(d32 P3),  1 − m = d31 D/(d32 P3),

``s1, s3`` the signs of ``ω1(0), ω3(0)`` (dn > 0, so ω3 never changes sign; choosing the sign
of the cn term from ω1(0) keeps ``cn(u0) ≥ 0``, which also covers the separatrix, where the
two half-orbits ``ω1 ≷ 0`` are distinct). The phase is ``u0 = F(φ0 | m)`` with
``sn φ0 = s1 s3 ω2(0)/A2``, ``cn φ0 = |ω1(0)|/A1``, evaluated as
``sin φ R_F(cos²φ, cos²φ + (1 − m) sin²φ, 1)`` (Carlson, DLMF 19.25.5) so that only the
complementary parameter ``1 − m`` enters. The period of ω is ``4K(m)/λ``.

Special cases: on the separatrix (``D = 0``, ``m = 1``) ``sn = tanh``, ``cn = dn = sech`` and
the period is infinite; for a symmetric top (``m = 0``) the formula is R8 (sin, cos, 1);
steady rotations (ω along a principal axis, any ω of a spherical top, ω in the degenerate
plane of a symmetric top) are detected from Euler's right-hand side vanishing exactly and
returned as constant ω with an infinite period.

Near the separatrix scipy's ``ellipj(u, m)`` is unusable and passing ``m = 1 − (1 − m)`` would
in any case round away the digits of ``1 − m``: sn, cn, dn come from
:func:`solver.jacobi.jacobi_sncndn` (descending Landen transformation), in ``1 − m``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ellipkm1, elliprf

from solver.jacobi import jacobi_sncndn
from solver.parameters import as_real, positive, principal_moments
from solver.torque_free import _gyroscopic_torque, invariants, near_axis_stability

__all__ = [
    "asymmetric_top_omega",
    "asymmetric_top_period",
    "flip_time",
    "solve_free_top",
]

def _parity(order: NDArray[np.intp]) -> NDArray[np.float64]:
    """+1 for an even permutation of (0, 1, 2) along the last axis, −1 for an odd one."""
    p0, p1, p2 = order[..., 0], order[..., 1], order[..., 2]
    return np.sign((p1 - p0) * (p2 - p0) * (p2 - p1)).astype(float)


@dataclass(frozen=True)
class _EllipticMotion:
    """The R10 solution of one (broadcast) set of initial conditions, in the relabelled frame.

    ``order[..., i]`` is the original axis playing role ``i`` (cn, sn, dn axis); ω along
    role ``i`` is ``amplitude[..., i]`` times cn, sn, dn of ``u = u0 + direction λ t``.
    """

    order: NDArray[np.intp]
    amplitude: NDArray[np.float64]  # (..., 3), signed
    lam: NDArray[np.float64]
    m1: NDArray[np.float64]  # complementary parameter 1 − k²
    u0: NDArray[np.float64]
    direction: NDArray[np.float64]  # ±1
    steady: NDArray[np.bool_]  # Euler's right-hand side vanishes: ω is constant
    omega0: NDArray[np.float64]

    @property
    def period(self) -> NDArray[np.float64]:
        """``4K(m)/λ``; infinite on the separatrix and for steady rotation."""
        K = ellipkm1(self.m1)
        with np.errstate(divide="ignore"):
            return np.where(self.steady | (self.m1 == 0), np.inf, 4.0 * K / self.lam)

    def omega(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """ω(t), shape broadcast(t, initial conditions) + (3,)."""
        u = self.u0 + self.direction * self.lam * t
        sn, cn, dn = jacobi_sncndn(u, np.broadcast_to(self.m1, u.shape))
        relabelled = self.amplitude * np.stack([cn, sn, dn], axis=-1)
        order = np.broadcast_to(self.order, relabelled.shape)
        omega = np.empty_like(relabelled)
        np.put_along_axis(omega, order, relabelled, axis=-1)
        return np.where(self.steady[..., None], self.omega0, omega)


def _steady(moments: NDArray[np.float64], w: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Euler's right-hand side vanishes exactly: ω is a steady rotation."""
    return np.all(_gyroscopic_torque(moments, w) == 0, axis=-1)


def _elliptic_motion(moments: NDArray[np.float64], w0: NDArray[np.float64]) -> _EllipticMotion:
    """Amplitudes, λ, parameter and phase of R10 for moments (..., 3) and ω(0) (..., 3)."""
    steady = _steady(moments, w0)
    # Steady rotations get a harmless stand-in so that no division below meets a zero.
    stand_in = np.array([1.0, 2.0, 3.0]), np.array([1.0, 0.5, 1.0])
    moments = np.where(steady[..., None], stand_in[0], moments)
    w = np.where(steady[..., None], stand_in[1], w0)

    ascending = np.argsort(moments, axis=-1, kind="stable")
    J = np.take_along_axis(moments, ascending, axis=-1)
    v = np.take_along_axis(w, ascending, axis=-1)
    # L² − 2T I_mid; its two terms nearly cancel near the separatrix: sum in extended precision
    Jx, vx = J.astype(np.longdouble), v.astype(np.longdouble)
    D_signed = Jx[..., 0] * (Jx[..., 0] - Jx[..., 1]) * vx[..., 0] ** 2 + Jx[..., 2] * (
        Jx[..., 2] - Jx[..., 1]
    ) * vx[..., 2] ** 2
    order = np.where((D_signed >= 0)[..., None], ascending, ascending[..., ::-1])
    D = np.abs(D_signed).astype(float)

    J = np.take_along_axis(moments, order, axis=-1)
    v = np.take_along_axis(w, order, axis=-1)
    J1, J2, J3 = J[..., 0], J[..., 1], J[..., 2]
    v1, v2, v3 = v[..., 0], v[..., 1], v[..., 2]
    d21, d32, d31 = np.abs(J2 - J1), np.abs(J3 - J2), np.abs(J3 - J1)
    P1 = J1 * d31 * v1**2 + J2 * d32 * v2**2
    P3 = J2 * d21 * v2**2 + J3 * d31 * v3**2
    m1 = np.clip(d31 * D / (d32 * P3), 0.0, 1.0)
    A1, A2, A3 = np.sqrt(P1 / (J1 * d31)), np.sqrt(P1 / (J2 * d32)), np.sqrt(P3 / (J3 * d31))
    s1, s3 = np.where(v1 >= 0, 1.0, -1.0), np.where(v3 >= 0, 1.0, -1.0)

    # Phase: cn(u0) = |ω1|/A1 ≥ 0, sn(u0) = s1 s3 ω2/A2; u0 = F(φ0 | m) through R_F.
    cn0, sn0 = np.abs(v1) / A1, s1 * s3 * v2 / A2
    radius = np.hypot(cn0, sn0)
    cn0, sn0 = cn0 / radius, sn0 / radius
    u0 = sn0 * elliprf(cn0**2, cn0**2 + m1 * sn0**2, 1.0)

    return _EllipticMotion(
        order=order,
        amplitude=np.stack([s1 * A1, s1 * s3 * A2, s3 * A3], axis=-1),
        lam=np.sqrt(d32 * P3 / (J1 * J2 * J3)),
        m1=m1,
        u0=u0,
        direction=_parity(ascending),
        steady=steady,
        omega0=w0,
    )


def _motion_from_inputs(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, omega0: ArrayLike, extra_shape: tuple = (),
    rigid_body: bool = True,
) -> _EllipticMotion:
    """Validate, broadcast (with ``extra_shape``, e.g. the time grid's) and solve R10."""
    if rigid_body:
        moments = np.stack(principal_moments(I1, I2, I3), axis=-1)
    else:  # Euler's equations as an ODE: any positive coefficients (see asymmetric_top_omega)
        moments = np.stack(
            np.broadcast_arrays(positive("I1", I1), positive("I2", I2), positive("I3", I3)),
            axis=-1,
        )
    w0 = as_real("omega0", omega0, shape_tail=(3,))
    shape = np.broadcast_shapes(moments.shape[:-1], w0.shape[:-1], extra_shape)
    return _elliptic_motion(
        np.broadcast_to(moments, (*shape, 3)), np.broadcast_to(w0, (*shape, 3))
    )


def asymmetric_top_omega(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, omega0: ArrayLike, t: ArrayLike,
    *, rigid_body: bool = True,
) -> NDArray[np.float64]:
    """Exact ω(t) of the torque-free rigid body, in Jacobi elliptic functions (R10).

    Works for any order of the moments, on either side of the separatrix ``L² = 2T I_mid``
    and on it, for symmetric tops (where it is R8) and spherical ones (constant ω).
    See the module docstring for the formulas, signs and phase.

    Parameters
    ----------
    I1, I2, I3 : array_like
        Principal moments (kg m²), any order, obeying the triangle inequality.
    omega0 : array_like, shape (..., 3)
        Body components of ω at ``t = 0`` (rad/s).
    t : array_like
        Times (s).
    rigid_body : bool, keyword-only
        ``True`` (default): the moments must be those of a rigid body (triangle inequality).
        ``False``: any positive moments — Euler's equations taken as an ODE, as in numerical
        analysts' test problems (Hairer, Lubich & Wanner's free rigid body has
        ``I = (2, 1, 2/3)``, which no body has); the solution is the same formula.

    Returns
    -------
    ndarray, shape broadcast(moments, omega0[..., 0], t) + (3,)
        Body components of ω(t) (rad/s).

    Examples
    --------
    >>> w = asymmetric_top_omega(1.0, 2.0, 3.0, [0.0, 1.0, 0.0], [0.0, 5.0])
    >>> w.tolist()  # spin exactly about the intermediate axis is steady
    [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    """
    time = as_real("t", t)
    motion = _motion_from_inputs(I1, I2, I3, omega0, time.shape, rigid_body)
    return motion.omega(time)


def asymmetric_top_period(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, omega0: ArrayLike, *, rigid_body: bool = True
) -> NDArray[np.float64]:
    """Period of ω(t), ``4K(k)/λ`` (R10), in s.

    ``inf`` on the separatrix ``L² = 2T I_mid`` (k = 1) and for steady rotation (ω along a
    principal axis, spherical top, ω in a symmetric top's degenerate plane), where ω(t) is
    constant or never returns. For a symmetric top it equals ``2π/|Ω|`` of R8.
    Shape: broadcast of the moments and ``omega0[..., 0]``. ``rigid_body`` as in
    :func:`asymmetric_top_omega`.
    """
    return _motion_from_inputs(I1, I2, I3, omega0, rigid_body=rigid_body).period


def flip_time(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, omega0: ArrayLike
) -> NDArray[np.float64]:
    """Intermediate-axis (Dzhanibekov) flip time: half the period of ω(t) (R10), in s.

    Defined as the time for the intermediate-axis component ω2 (``∝ sn``) to go from its
    maximum to its minimum — from one orientation of the flip to the reversed one — which is
    ``2K(k)/λ`` on either side of the separatrix; ``inf`` where the period is.
    """
    return 0.5 * asymmetric_top_period(I1, I2, I3, omega0)


def solve_free_top(
    I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, omega0: ArrayLike, t: ArrayLike = 0.0
) -> dict[str, NDArray]:
    """Everything about a torque-free rigid body from its moments and ω(0) (R7–R10).

    Returns
    -------
    dict
        ``omega``: ω(t), shape broadcast(...) + (3,), e.g. (3,) or (n, 3) (rad/s);
        ``T``: kinetic energy (J); ``L``: ``|L|`` (kg m²/s);
        ``period``: period of ω(t) (s): ``4K/λ``, ``2π/|Ω|`` for a symmetric top, ``inf`` on
        the separatrix and for steady rotation (spherical top, spin about a principal axis);
        ``stability``: bool array (..., 3), spin about principal axis 1, 2, 3 stable (R9).
    """
    T, L2 = invariants(I1, I2, I3, omega0)
    stability = np.stack(
        [near_axis_stability(I1, I2, I3, 1.0, axis=a)["stable"] for a in (1, 2, 3)], axis=-1
    )
    return {
        "omega": asymmetric_top_omega(I1, I2, I3, omega0, t),
        "T": T,
        "L": np.sqrt(L2),
        "period": asymmetric_top_period(I1, I2, I3, omega0),
        "stability": stability,
    }
