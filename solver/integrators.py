"""Numerical integrators for the rigid body, each counting its own cost (R7, R14, R12).

The exact solutions (R8, R10, R20) need no integration; this module is what the bench measures
them against, and what a scene with no closed form (a torqued asymmetric body) falls back on.

Right-hand sides (built once from validated parameters, then called without re-validation)
------------------------------------------------------------------------------------------
=========================  =================================================================
``free_body_rhs``          Euler's equations ``I ω̇ = (Iω) × ω`` (R7), state ω (3,)
``heavy_body_rhs``         heavy rigid body on a fixed tip, centre of mass on ``ê3``: Euler's
                           equations with the gravity torque, orientation as a unit quaternion
                           (body → inertial); state ``(q, ω)`` (7,); any ``I1, I2, I3``
``heavy_top_euler_rhs``    the symmetric heavy top's Lagrange equations (R14) in Euler angles,
                           state ``(α, β, γ, α̇, β̇, γ̇)``; divides by ``sin β`` (gimbal lock)
=========================  =================================================================

Steppers
--------
``integrate_adaptive``: scipy's own ``OdeSolver`` classes (those of ``solve_ivp``: RK45, DOP853,
Radau, LSODA, …) stepped one by one, so that steps are counted exactly (``solve_ivp`` reports
``nfev`` but not the number of steps when ``t_eval`` is given); output times come from each
step's dense output, the final time from the step itself. ``fixed_step``: any one-step map with
a fixed step (``rk4_step``: classical Runge–Kutta; ``lie_poisson_step``: McLachlan's explicit
Lie–Poisson splitting of the free rigid body). Failures are returned (``success=False`` and a
message), never raised, as in ``solve_ivp``.

McLachlan's splitting (R. I. McLachlan, "Explicit Lie–Poisson integration and the Euler
equations", Phys. Rev. Lett. 71, 3043 (1993)) writes ``H = Σ L_i²/(2 I_i)`` and flows each
term exactly: under ``L_i²/(2 I_i)`` alone ``L̇ = L × (L_i/I_i) ê_i``, a rotation of ``L`` about
``ê_i`` by the angle ``−L_i h / I_i``. The symmetric composition
``R1(h/2) R2(h/2) R3(h) R2(h/2) R1(h/2)`` is second order and, being a product of rotations,
keeps ``|L|²`` to rounding; as a Poisson integrator its energy error stays bounded (no drift).
``lie_poisson4_step`` is Yoshida's triple-jump composition of it (fourth order).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import DOP853, LSODA, RK23, RK45, Radau

from solver.euler_angles import omega_body
from solver.parameters import ParameterError, as_real, positive, principal_moments

__all__ = [
    "ADAPTIVE",
    "Integration",
    "fixed_step",
    "free_body_rhs",
    "heavy_body_rhs",
    "heavy_body_state",
    "heavy_top_euler_rhs",
    "integrate_adaptive",
    "lie_poisson4_step",
    "lie_poisson_step",
    "quaternion_cos_beta",
    "rk4_step",
]

Rhs = Callable[[float, NDArray[np.float64]], NDArray[np.float64]]

# scipy's solver classes behind ``solve_ivp(method=...)``
ADAPTIVE: dict[str, type] = {
    "RK23": RK23, "RK45": RK45, "DOP853": DOP853, "Radau": Radau, "LSODA": LSODA,
}


@dataclass(frozen=True)
class Integration:
    """A numerical solution sampled at requested times, with its cost.

    Attributes
    ----------
    t : ndarray, shape (n,)
        The requested output times (s); on failure only those reached.
    y : ndarray, shape (n, d)
        The state at ``t``.
    nfev : int
        Right-hand-side evaluations (for a splitting method: exact sub-flows; see
        :func:`fixed_step`).
    nsteps : int
        Accepted steps.
    success : bool
        ``False`` if the integrator failed (non-finite state, step size underflow).
    message : str
        Why it failed, or ``""``.
    """

    t: NDArray[np.float64]
    y: NDArray[np.float64]
    nfev: int
    nsteps: int
    success: bool = True
    message: str = ""


# --- right-hand sides ------------------------------------------------------------------------


def free_body_rhs(I1: ArrayLike, I2: ArrayLike, I3: ArrayLike) -> Rhs:
    """Euler's equations of the torque-free body, ``dω/dt`` (R7), as ``fun(t, ω)``.

    The moments (kg m², a rigid body's) are validated here, once; the returned function does no
    validation (it is called ~10⁶ times by the bench). It is :func:`solver.torque_free.euler_rhs`
    with the moments bound, its coefficients ``(I_j − I_k)/I_i`` formed once (exactly zero for
    equal moments, as there) — five times faster than re-validating on every call.
    """
    coef = _euler_coefficients(principal_moments(I1, I2, I3))

    def rhs(t: float, omega: NDArray[np.float64]) -> NDArray[np.float64]:
        return coef * omega[_NEXT] * omega[_AFTER]

    return rhs


_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])


def _euler_coefficients(moments) -> NDArray[np.float64]:
    """``((I2 − I3)/I1, (I3 − I1)/I2, (I1 − I2)/I3)``: ``ω̇_i = coef_i ω_j ω_k`` (R7)."""
    m = np.array([float(x) for x in moments])
    return (m[_NEXT] - m[_AFTER]) / m


def _moments_about_tip(I1, I2, I3, Mgl) -> tuple[NDArray[np.float64], float]:
    moments = np.array([float(m) for m in principal_moments(I1, I2, I3)])
    return moments, float(positive("Mgl", Mgl))


def heavy_body_rhs(I1: ArrayLike, I2: ArrayLike, I3: ArrayLike, Mgl: ArrayLike) -> Rhs:
    """Heavy rigid body on a fixed tip in quaternions: ``d(q, ω)/dt`` (R6, R7 with torque).

    ``q = (w, x, y, z)`` rotates body components into inertial ones (``V = q V' q*``);
    ``q̇ = ½ q ⊗ (0, ω)``. The centre of mass is at ``l ê3``; the gravity torque in the body
    frame is ``τ = l ê3 × (−M g ẑ') = Mgl (ẑ'_2, −ẑ'_1, 0)`` with ``ẑ' = q* ẑ q`` the upward
    vertical in body components, so the energy ``½ ω·Iω + Mgl ẑ'_3`` is conserved. With
    ``I1 = I2`` this is the heavy symmetric top of R14 (``ẑ'_3 = cos β``); ``I1 ≠ I2`` is the
    torqued asymmetric body, which has no closed form. Nothing divides by ``sin β``.

    Parameters
    ----------
    I1, I2, I3 : float
        Principal moments about the tip (kg m²).
    Mgl : float
        Weight times the tip-to-centre-of-mass distance (J), > 0.
    """
    moments, mgl = _moments_about_tip(I1, I2, I3, Mgl)
    c1, c2, c3 = _euler_coefficients(moments)
    g1, g2 = mgl / moments[0], mgl / moments[1]

    def rhs(t: float, y: NDArray[np.float64]) -> NDArray[np.float64]:
        w, x, yq, z, p, q, r = y
        norm2 = w * w + x * x + yq * yq + z * z  # |q| drifts under integration: divide it out
        up1, up2 = 2.0 * (x * z - w * yq) / norm2, 2.0 * (yq * z + w * x) / norm2
        return np.array([
            0.5 * (-x * p - yq * q - z * r),
            0.5 * (w * p + yq * r - z * q),
            0.5 * (w * q + z * p - x * r),
            0.5 * (w * r + x * q - yq * p),
            c1 * q * r + g1 * up2,
            c2 * r * p - g2 * up1,
            c3 * p * q,
        ])

    return rhs


def heavy_body_state(
    beta0: float, alpha_dot0: float, beta_dot0: float, gamma_dot0: float
) -> NDArray[np.float64]:
    """Initial ``(q, ω)`` for :func:`heavy_body_rhs` from Euler angles (R11, R12), ``α = γ = 0``.

    ``R = R_γ R_β R_α`` maps inertial to body components, so body → inertial is
    ``Rz(α) Ry(β) Rz(γ)`` (active rotations), i.e. ``q = q_z(α) ⊗ q_y(β) ⊗ q_z(γ)``; with
    ``α = γ = 0``, ``q = (cos β/2, 0, sin β/2, 0)``. ω from R12.
    """
    b = float(as_real("beta0", beta0))
    w = omega_body(b, 0.0, alpha_dot0, beta_dot0, gamma_dot0)
    return np.array([np.cos(0.5 * b), 0.0, np.sin(0.5 * b), 0.0, *w])


def quaternion_cos_beta(y: ArrayLike) -> NDArray[np.float64]:
    """``cos β = ẑ'_3 = (w² + z² − x² − y²)/|q|²`` from states ``(..., ≥4)`` (R11)."""
    q = np.asarray(y, dtype=float)[..., :4]
    return (q[..., 0] ** 2 + q[..., 3] ** 2 - q[..., 1] ** 2 - q[..., 2] ** 2) / np.sum(
        q * q, axis=-1
    )


def heavy_top_euler_rhs(I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike) -> Rhs:
    """The heavy symmetric top's Lagrange equations (R14) in Euler angles.

    State ``(α, β, γ, α̇, β̇, γ̇)``; with ``p_γ = I3 (α̇ cos β + γ̇)`` (R15):
    ``α̈ = β̇ (p_γ − 2 I1 α̇ cos β)/(I1 sin β)`` (from ``ṗ_α = 0``),
    ``I1 β̈ = I1 α̇² sin β cos β − p_γ α̇ sin β + Mgl sin β``,
    ``γ̈ = −α̈ cos β + α̇ β̇ sin β`` (from ``ṗ_γ = 0``).
    The textbook formulation, and the naive one: it divides by ``sin β`` and returns NaN or
    infinity at ``β = 0`` (a sleeping top), and becomes stiff as the axis passes near the
    vertical. ``I1`` about the tip, ``I3`` axial (kg m²), ``Mgl`` (J).
    """
    moments, mgl = _moments_about_tip(I1, I1, I3, Mgl)
    i1, i3 = moments[0], moments[2]

    def rhs(t: float, y: NDArray[np.float64]) -> NDArray[np.float64]:
        _, b, _, ad, bd, gd = y
        sb, cb = np.sin(b), np.cos(b)
        pg = i3 * (ad * cb + gd)
        with np.errstate(divide="ignore", invalid="ignore"):
            add = bd * (pg - 2.0 * i1 * ad * cb) / (i1 * sb)
        bdd = (i1 * ad * ad * cb - pg * ad + mgl) * sb / i1
        return np.array([ad, bd, gd, add, bdd, -add * cb + ad * bd * sb])

    return rhs


# --- one-step maps ---------------------------------------------------------------------------


def rk4_step(fun: Rhs, t: float, y: NDArray[np.float64], h: float) -> NDArray[np.float64]:
    """One classical fourth-order Runge–Kutta step (4 evaluations of ``fun``)."""
    k1 = fun(t, y)
    k2 = fun(t + 0.5 * h, y + 0.5 * h * k1)
    k3 = fun(t + 0.5 * h, y + 0.5 * h * k2)
    k4 = fun(t + h, y + h * k3)
    return y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def _rotate_about(L: NDArray[np.float64], axis: int, angle: NDArray[np.float64]):
    """Rotate the vectors ``L`` (..., 3) about body axis ``axis`` by ``angle`` (rad)."""
    j, k = (axis + 1) % 3, (axis + 2) % 3
    c, s = np.cos(angle), np.sin(angle)
    out = L.copy()
    out[..., j] = c * L[..., j] - s * L[..., k]
    out[..., k] = s * L[..., j] + c * L[..., k]
    return out


def lie_poisson_step(
    L: NDArray[np.float64], h: float, moments: NDArray[np.float64]
) -> NDArray[np.float64]:
    """McLachlan's second-order Lie–Poisson splitting step for ``L = Iω`` (R7), 5 exact flows.

    ``R1(h/2) R2(h/2) R3(h) R2(h/2) R1(h/2)``, ``R_i(τ)``: rotation about ``ê_i`` by
    ``−L_i τ / I_i`` (the exact flow of ``L_i²/(2 I_i)``; ``L_i`` is constant along it).
    ``L`` has shape (..., 3): many bodies step at once.
    """
    for axis, frac in ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5)):
        L = _rotate_about(L, axis, -frac * h * L[..., axis] / moments[axis])
    return L


_YOSHIDA_W1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_YOSHIDA_W0 = 1.0 - 2.0 * _YOSHIDA_W1


def lie_poisson4_step(
    L: NDArray[np.float64], h: float, moments: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Fourth-order Lie–Poisson step: Yoshida's triple jump of :func:`lie_poisson_step`.

    Substeps ``w1 h, w0 h, w1 h`` with ``w1 = 1/(2 − 2^{1/3})``, ``w0 = 1 − 2 w1`` (H. Yoshida,
    Phys. Lett. A 150, 262 (1990)); 15 exact flows per step.
    """
    for w in (_YOSHIDA_W1, _YOSHIDA_W0, _YOSHIDA_W1):
        L = lie_poisson_step(L, w * h, moments)
    return L


# --- drivers ---------------------------------------------------------------------------------


def _output_times(times: ArrayLike) -> NDArray[np.float64]:
    t = as_real("times", times)
    if t.ndim != 1 or t.size == 0 or np.any(t < 0) or np.any(np.diff(t) < 0):
        raise ParameterError("times", "must be a non-empty 1-D array of non-negative, "
                             "non-decreasing times (the motion starts at t = 0)")
    return t


def fixed_step(
    step: Callable[[float, NDArray[np.float64], float], NDArray[np.float64]],
    y0: ArrayLike,
    times: ArrayLike,
    h: float,
    evals_per_step: int,
) -> Integration:
    """Advance ``y0`` from ``t = 0`` through ``times`` with a one-step map of step ≤ ``h``.

    Each interval between output times is cut into ``ceil(Δt/h)`` equal steps, so output
    times are hit exactly. ``step(t, y, h) -> y_next``; ``evals_per_step`` is its cost
    (4 for RK4; 5 sub-flows for the Lie–Poisson splitting, 15 for its fourth-order version).
    Stops with ``success=False`` at the first non-finite state.
    """
    t_out = _output_times(times)
    h = float(positive("step", h))
    y = np.array(y0, dtype=float)
    out, t, nsteps = [], 0.0, 0
    for t_next in t_out:
        n = int(np.ceil((t_next - t) / h - 1e-12)) if t_next > t else 0
        dt = (t_next - t) / n if n else 0.0
        for i in range(n):
            y = step(t + i * dt, y, dt)
        nsteps += n
        t = t_next
        if not np.all(np.isfinite(y)):
            return Integration(t_out[: len(out)], np.array(out), evals_per_step * nsteps, nsteps,
                               False, f"non-finite state before t = {t_next:g}")
        out.append(y)
    return Integration(t_out, np.array(out), evals_per_step * nsteps, nsteps)


def integrate_adaptive(
    fun: Rhs,
    y0: ArrayLike,
    times: ArrayLike,
    method: str,
    rtol: float,
    atol: float | ArrayLike,
) -> Integration:
    """Integrate with one of scipy's adaptive solvers (``ADAPTIVE``), counting steps exactly.

    The solver class is stepped as ``solve_ivp`` steps it; output times strictly inside a step
    use that step's dense output, the final time is a step end. ``nfev`` is scipy's count
    (finite-difference Jacobians of Radau included).
    """
    if method not in ADAPTIVE:
        raise ParameterError("method", f"must be one of {sorted(ADAPTIVE)}, got {method!r}")
    t_out = _output_times(times)
    y0 = np.array(y0, dtype=float)
    if not np.all(np.isfinite(fun(0.0, y0))):
        # scipy would shrink the step forever at t = 0 (its minimum step is 10 ε |t| = 0)
        return Integration(t_out[:0], np.empty((0, y0.size)), 1, 0, False,
                           "non-finite right-hand side at t = 0")
    solver = ADAPTIVE[method](fun, 0.0, y0, t_out[-1], rtol=rtol, atol=atol)
    out = [y0] * int(np.sum(t_out == 0.0))
    nsteps = 0
    while len(out) < t_out.size:
        message = solver.step()
        if solver.status == "failed" or not np.all(np.isfinite(solver.y)):
            return Integration(t_out[: len(out)], np.array(out).reshape(len(out), y0.size),
                               solver.nfev, nsteps, False, str(message or "non-finite state"))
        nsteps += 1
        inside = t_out[len(out):]
        inside = inside[inside <= solver.t]
        if inside.size:
            exact_end = inside == solver.t
            values = solver.dense_output()(inside).T if not exact_end.all() else None
            for i, ti in enumerate(inside):
                out.append(solver.y.copy() if ti == solver.t else values[i])
    return Integration(t_out, np.array(out), solver.nfev, nsteps)
