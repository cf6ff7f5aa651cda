"""Euler angles: body/inertial rotation, angular velocity and kinetic energy (R11–R13).

Convention of R11 (``docs/physics/index.md``; Fetter & Walecka, Goldstein's z-y'-z'' variant):
rotate by ``α`` about the inertial ``z``, then ``β`` about the new ``y'``, then ``γ`` about the
body ``ê3``. ``R = R_γ R_β R_α`` maps inertial components ``V`` to body components ``V' = R V``.

In terms of ``scipy.spatial.transform.Rotation`` (active rotations), ``R`` is the *transpose* of
``Rotation.from_euler("ZYZ", [α, β, γ]).as_matrix()`` (intrinsic z-y'-z''): the columns of that
active matrix are the body axes in inertial components, the rows of ``R``.

All functions are vectorised: angle and rate arguments broadcast; vectors carry a trailing axis
of 3 and matrices two trailing axes of 3. Angles in rad, rates in rad/s, moments in kg m².
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.parameters import ParameterError, as_real, principal_moments

__all__ = [
    "GIMBAL_LOCK_SIN_BETA",
    "euler_rates",
    "kinetic_energy_euler",
    "omega_body",
    "rotation_matrix",
    "solve_euler_angles",
    "to_body",
    "to_inertial",
]

#: ``euler_rates`` refuses ``|sin β|`` below this: the inverse of R12 has condition number
#: ``cot(β/2) ≈ 2/|sin β|``, so past √ε it amplifies rounding beyond half the digits of a double
#: (and near β = π, sin β itself is only known to ``ε/|sin β|`` relative).
GIMBAL_LOCK_SIN_BETA = float(np.sqrt(np.finfo(float).eps))

# A user-supplied rotation matrix is orthogonal only up to the rounding of its entries.
_ORTHOGONALITY_ATOL = 1e-6


def rotation_matrix(alpha: ArrayLike, beta: ArrayLike, gamma: ArrayLike) -> NDArray[np.float64]:
    """Rotation from inertial to body components, ``R = R_γ R_β R_α`` (R11).

    ``V' = R V`` gives the body components ``V'`` of a vector with inertial components ``V``;
    ``R`` is orthogonal with determinant 1, so ``V = Rᵀ V'``.

    Parameters
    ----------
    alpha, beta, gamma : array_like
        Euler angles in rad (precession, nutation from the upward vertical, spin); broadcast.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> R = rotation_matrix(0.0, np.pi / 2, 0.0)
    >>> np.round(to_body(R, [0.0, 0.0, 1.0]), 12) + 0.0  # ẑ in body components: −ê1
    array([-1.,  0.,  0.])
    """
    a, b, g = np.broadcast_arrays(
        as_real("alpha", alpha), as_real("beta", beta), as_real("gamma", gamma)
    )
    return _about_z(g) @ _about_y(b) @ _about_z(a)


def to_body(R: ArrayLike, V: ArrayLike) -> NDArray[np.float64]:
    """Body components ``V' = R V`` of a vector with inertial components ``V`` (R11).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrix from :func:`rotation_matrix` (orthogonal, det +1).
    V : array_like, shape (..., 3)
        Inertial components; broadcasts with ``R``.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    r = _rotation("R", R)
    v = as_real("V", V, shape_tail=(3,))
    return np.einsum("...ij,...j->...i", r, v)


def to_inertial(R: ArrayLike, V_body: ArrayLike) -> NDArray[np.float64]:
    """Inertial components ``V = Rᵀ V'`` of a vector with body components ``V'`` (R11).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrix from :func:`rotation_matrix` (orthogonal, det +1).
    V_body : array_like, shape (..., 3)
        Body components; broadcasts with ``R``.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    r = _rotation("R", R)
    v = as_real("V_body", V_body, shape_tail=(3,))
    return np.einsum("...ji,...j->...i", r, v)


def omega_body(
    beta: ArrayLike,
    gamma: ArrayLike,
    alpha_dot: ArrayLike,
    beta_dot: ArrayLike,
    gamma_dot: ArrayLike,
) -> NDArray[np.float64]:
    """Body components of the angular velocity from Euler-angle rates (R12).

    ``ω = α̇ ẑ + β̇ ê'2 + γ̇ ê3``:
    ``ω1 = −α̇ sin β cos γ + β̇ sin γ``, ``ω2 = α̇ sin β sin γ + β̇ cos γ``,
    ``ω3 = α̇ cos β + γ̇``.

    Parameters
    ----------
    beta, gamma : array_like
        Euler angles in rad (α does not enter).
    alpha_dot, beta_dot, gamma_dot : array_like
        Euler-angle rates in rad/s. All five broadcast.

    Returns
    -------
    ndarray, shape (..., 3)
        ``(ω1, ω2, ω3)`` in rad/s, principal body frame.
    """
    b, g, ad, bd, gd = _broadcast_reals(
        beta=beta, gamma=gamma, alpha_dot=alpha_dot, beta_dot=beta_dot, gamma_dot=gamma_dot
    )
    sb, cb, sg, cg = np.sin(b), np.cos(b), np.sin(g), np.cos(g)
    return np.stack(
        (-ad * sb * cg + bd * sg, ad * sb * sg + bd * cg, ad * cb + gd), axis=-1
    )


def euler_rates(
    beta: ArrayLike, gamma: ArrayLike, omega_body: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Euler-angle rates from the body components of ω: the inverse of R12.

    ``β̇ = ω1 sin γ + ω2 cos γ``, ``α̇ = (−ω1 cos γ + ω2 sin γ)/sin β``,
    ``γ̇ = ω3 − α̇ cos β``.

    The map is singular at ``sin β = 0`` (gimbal lock: ``ẑ`` and ``ê3`` coincide, so only
    ``α̇ + γ̇`` or ``α̇ − γ̇`` is defined); its condition number is ``cot(β/2)`` for
    ``0 < β ≤ π/2`` (``≈ 2/β``).

    Parameters
    ----------
    beta, gamma : array_like
        Euler angles in rad.
    omega_body : array_like, shape (..., 3)
        ``(ω1, ω2, ω3)`` in rad/s; leading dimensions broadcast with ``beta`` and ``gamma``.

    Returns
    -------
    alpha_dot, beta_dot, gamma_dot : ndarray
        Rates in rad/s, of the broadcast shape.

    Raises
    ------
    ParameterError
        Naming ``beta`` where ``|sin β| <`` :data:`GIMBAL_LOCK_SIN_BETA` (gimbal lock).
    """
    w = as_real("omega_body", omega_body, shape_tail=(3,))
    b, g, w1, w2, w3 = _broadcast_reals(
        beta=beta, gamma=gamma, w1=w[..., 0], w2=w[..., 1], w3=w[..., 2]
    )
    sb = np.sin(b)
    locked = np.abs(sb) < GIMBAL_LOCK_SIN_BETA
    if np.any(locked):
        raise ParameterError(
            "beta",
            f"gimbal lock at beta = {b[locked].ravel()[0]:.6g}: sin(beta) ≈ 0, so the Euler-angle "
            "rates are not determined by omega (R12 is singular there)",
        )
    sg, cg = np.sin(g), np.cos(g)
    alpha_dot = (-w1 * cg + w2 * sg) / sb
    beta_dot = w1 * sg + w2 * cg
    gamma_dot = w3 - alpha_dot * np.cos(b)
    return alpha_dot, beta_dot, gamma_dot


def kinetic_energy_euler(
    I1: ArrayLike,
    I2: ArrayLike,
    I3: ArrayLike,
    beta: ArrayLike,
    gamma: ArrayLike,
    alpha_dot: ArrayLike,
    beta_dot: ArrayLike,
    gamma_dot: ArrayLike,
) -> NDArray[np.float64]:
    """Rotational kinetic energy in Euler angles, in J (R13).

    ``T = ½ (I1 ω1² + I2 ω2² + I3 ω3²)`` with ``ω`` from R12 (:func:`omega_body`); for
    ``I1 = I2`` this is ``½ I1 (α̇² sin²β + β̇²) + ½ I3 (α̇ cos β + γ̇)²``.

    Parameters
    ----------
    I1, I2, I3 : array_like
        Principal moments in kg m² (positive, obeying the triangle inequality).
    beta, gamma : array_like
        Euler angles in rad.
    alpha_dot, beta_dot, gamma_dot : array_like
        Euler-angle rates in rad/s. All eight broadcast.

    Returns
    -------
    ndarray
        ``T``, of the broadcast shape.
    """
    moments = np.stack(np.broadcast_arrays(*principal_moments(I1, I2, I3)), axis=-1)
    w = omega_body(beta, gamma, alpha_dot, beta_dot, gamma_dot)
    return 0.5 * np.sum(moments * w**2, axis=-1)


def solve_euler_angles(
    alpha: ArrayLike,
    beta: ArrayLike,
    gamma: ArrayLike,
    alpha_dot: ArrayLike,
    beta_dot: ArrayLike,
    gamma_dot: ArrayLike,
    I1: ArrayLike | None = None,
    I2: ArrayLike | None = None,
    I3: ArrayLike | None = None,
) -> dict[str, NDArray[np.float64]]:
    """Rotation matrix, body angular velocity and (given the moments) kinetic energy (R11–R13).

    Returns
    -------
    dict
        ``"R"`` (..., 3, 3) from :func:`rotation_matrix`; ``"omega_body"`` (..., 3) rad/s from
        :func:`omega_body`; ``"T"`` in J from :func:`kinetic_energy_euler`, present only when
        ``I1``, ``I2`` and ``I3`` are all given.

    Raises
    ------
    ParameterError
        If some but not all of ``I1, I2, I3`` are given (naming a missing one), or for invalid
        angles, rates or moments.
    """
    result = {
        "R": rotation_matrix(alpha, beta, gamma),
        "omega_body": omega_body(beta, gamma, alpha_dot, beta_dot, gamma_dot),
    }
    moments = {"I1": I1, "I2": I2, "I3": I3}
    missing = [name for name, value in moments.items() if value is None]
    if len(missing) == 3:
        return result
    if missing:
        raise ParameterError(
            missing[0], "the kinetic energy needs all three principal moments I1, I2, I3"
        )
    result["T"] = kinetic_energy_euler(
        I1, I2, I3, beta, gamma, alpha_dot, beta_dot, gamma_dot
    )
    return result


def _about_z(angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """R_α (and R_γ) of R11: components in a frame turned by ``angle`` about z."""
    c, s, one, zero = np.cos(angle), np.sin(angle), np.ones_like(angle), np.zeros_like(angle)
    return _matrix(((c, s, zero), (-s, c, zero), (zero, zero, one)))


def _about_y(angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """R_β of R11: components in a frame turned by ``angle`` about y."""
    c, s, one, zero = np.cos(angle), np.sin(angle), np.ones_like(angle), np.zeros_like(angle)
    return _matrix(((c, zero, -s), (zero, one, zero), (s, zero, c)))


def _matrix(rows) -> NDArray[np.float64]:
    """Stack nested rows of equally shaped arrays into (..., 3, 3)."""
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def _broadcast_reals(**values: ArrayLike) -> list[NDArray[np.float64]]:
    """Validate named parameters as finite reals and broadcast them together."""
    arrays = [as_real(name, value) for name, value in values.items()]
    try:
        return np.broadcast_arrays(*arrays)
    except ValueError:
        shapes = ", ".join(f"{n} {a.shape}" for n, a in zip(values, arrays, strict=True))
        raise ParameterError(
            next(iter(values)), f"shapes do not broadcast together: {shapes}"
        ) from None


def _rotation(name: str, R: ArrayLike) -> NDArray[np.float64]:
    """Validate a (..., 3, 3) rotation matrix: orthogonal (up to rounding) with det +1."""
    r = as_real(name, R, shape_tail=(3, 3))
    gram = np.swapaxes(r, -1, -2) @ r
    if np.any(np.abs(gram - np.eye(3)) > _ORTHOGONALITY_ATOL) or np.any(np.linalg.det(r) < 0):
        raise ParameterError(name, "must be a rotation matrix (orthogonal, determinant +1)")
    return r
