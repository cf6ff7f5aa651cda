"""Every way to answer a scene, behind one call signature, listed in one table (``METHODS``).

``solve(scene, times, method, control) -> Trajectory``: a scene (:mod:`solver.scenes`), the
output times (s, from ``t = 0``), the method's name and its control — the relative tolerance of
an adaptive method, the step (s) of a fixed-step one, nothing for an exact solution — give the
trajectory of the scene's observable and what it cost (right-hand-side evaluations, steps).

Observables: ``"omega"`` (body ω, shape (n, 3), rad/s) for a free body — what R8 and R10 give
exactly; ``"cos_beta"`` (``u = cos β``, shape (n,)) for a heavy body — what R20 gives exactly.

==============  =========  ========================================================  ==============
method          control    what                                                      scenes
==============  =========  ========================================================  ==============
RK45, DOP853,   rtol       scipy's adaptive solvers (``solve_ivp``'s classes);       all
Radau, LSODA               free body: Euler's equations (R7) in ω; heavy body:
                           quaternion + ω
                           (:func:`~solver.integrators.heavy_body_rhs`)
RK4             step       classical Runge–Kutta, fixed step, same equations         all
LiePoisson2     step       McLachlan's explicit Lie–Poisson splitting (2nd order)    free bodies
LiePoisson4     step       its Yoshida triple jump (4th order)                       free bodies
EulerAngles     rtol       DOP853 on R14 in Euler angles (naive: ÷ sin β)            heavy symmetric
R8              —          closed form of the free symmetric top                     I1 = I2 free
R10             —          Jacobi elliptic functions (exact, any moments)            free bodies
R20             —          ``u = u1 + (u2 − u1) sn²`` with Carlson's roots           heavy symmetric
sleeping        —          ``u ≡ 1`` (the vertical is an equilibrium)                sleeping top
==============  =========  ========================================================  ==============

Absolute tolerances of the adaptive methods are ``rtol`` times each component's natural scale
(``|ω0|`` for angular velocities, 1 for quaternion components and angles). A numerical failure is
a ``Trajectory`` with ``success=False`` and a message, as in ``solve_ivp``; bad arguments raise
:class:`~solver.parameters.ParameterError`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.asymmetric_top import asymmetric_top_omega
from solver.heavy_top import cos_beta
from solver.integrators import (
    Integration,
    fixed_step,
    free_body_rhs,
    heavy_body_rhs,
    heavy_body_state,
    heavy_top_euler_rhs,
    integrate_adaptive,
    lie_poisson4_step,
    lie_poisson_step,
    quaternion_cos_beta,
    rk4_step,
)
from solver.parameters import ParameterError, as_real, positive
from solver.torque_free import symmetric_top_omega

if TYPE_CHECKING:
    from solver.scenes import FreeBody, HeavyBody

    Scene = FreeBody | HeavyBody

__all__ = ["FREE_KINDS", "HEAVY_KINDS", "METHODS", "Method", "Trajectory", "solve"]

FREE_KINDS = frozenset({"free_symmetric", "free_asymmetric"})
HEAVY_KINDS = frozenset({"heavy_symmetric", "sleeping", "torqued_asymmetric"})


@dataclass(frozen=True)
class Trajectory:
    """A scene's observable at the requested times, and the cost of computing it.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times (s); on failure, only those reached.
    y : ndarray
        ``"omega"``: (n, 3) body angular velocity (rad/s); ``"cos_beta"``: (n,) ``cos β``.
    observable : str
        ``"omega"`` or ``"cos_beta"``.
    method : str
        The ``METHODS`` key that produced it.
    nfev : int
        Right-hand-side evaluations (0 for an exact solution; exact sub-flows for a splitting).
    nsteps : int
        Steps taken (0 for an exact solution).
    success : bool
        ``False`` if the integrator failed (then ``message`` says why).
    message : str
    """

    t: NDArray[np.float64]
    y: NDArray[np.float64]
    observable: str
    method: str
    nfev: int = 0
    nsteps: int = 0
    success: bool = True
    message: str = ""


@dataclass(frozen=True)
class Method:
    """One row of ``METHODS``.

    Attributes
    ----------
    name : str
    control : str or None
        ``"rtol"`` (adaptive), ``"step"`` (fixed step, s) or ``None`` (exact).
    kinds : frozenset of str
        The scene kinds (:attr:`solver.scenes.FreeBody.kind`, …) it can answer.
    run : callable
        ``run(scene, times, control) -> Trajectory``.
    description : str
    """

    name: str
    control: str | None
    kinds: frozenset[str]
    run: Callable[..., Trajectory]
    description: str


def solve(scene: Scene, times: ArrayLike, method: str, control: float | None = None) -> Trajectory:
    """Answer ``scene`` at ``times`` with ``METHODS[method]`` (see the module table).

    Parameters
    ----------
    scene : FreeBody or HeavyBody
        From :mod:`solver.scenes`.
    times : array_like, shape (n,)
        Non-decreasing output times (s), ≥ 0; the motion starts at ``t = 0``.
    method : str
        A key of ``METHODS``.
    control : float, optional
        ``rtol`` for adaptive methods, the step (s) for fixed-step ones; ignored by exact ones.

    Raises
    ------
    ParameterError
        Naming ``method`` (unknown, or not for this scene kind), ``control`` or ``times``.
    """
    if method not in METHODS:
        raise ParameterError("method", f"must be one of {sorted(METHODS)}, got {method!r}")
    entry = METHODS[method]
    if scene.kind not in entry.kinds:
        raise ParameterError("method", f"{method} cannot answer a {scene.kind} scene "
                             f"(it answers {sorted(entry.kinds)})")
    if entry.control is not None:
        if control is None:
            raise ParameterError("control", f"{method} needs its {entry.control}")
        control = float(positive("control", control))
    t = as_real("times", times)
    if t.ndim != 1 or t.size == 0 or np.any(t < 0) or np.any(np.diff(t) < 0):
        raise ParameterError("times", "must be a non-empty 1-D array of non-decreasing times ≥ 0")
    return entry.run(scene, t, control)


# --- integrations ----------------------------------------------------------------------------


def _system(scene: Scene):
    """(rhs, y0, absolute scale per component, observable of the state) for the ODE methods."""
    if scene.kind in FREE_KINDS:
        w0 = np.array(scene.omega0, dtype=float)
        scale = np.full(3, max(np.linalg.norm(w0), np.finfo(float).tiny))
        return free_body_rhs(scene.I1, scene.I2, scene.I3), w0, scale, lambda y: y
    y0 = heavy_body_state(scene.beta0, scene.alpha_dot0, scene.beta_dot0, scene.gamma_dot0)
    scale = np.r_[np.ones(4), np.full(3, max(np.linalg.norm(y0[4:]), np.finfo(float).tiny))]
    rhs = heavy_body_rhs(scene.I1, scene.I2, scene.I3, scene.Mgl)
    return rhs, y0, scale, quaternion_cos_beta


def _trajectory(result: Integration, observe, scene: Scene, name: str) -> Trajectory:
    y = observe(result.y) if len(result.y) else result.y
    return Trajectory(result.t, y, _observable(scene), name, result.nfev, result.nsteps,
                      result.success, result.message)


def _observable(scene: Scene) -> str:
    return "omega" if scene.kind in FREE_KINDS else "cos_beta"


def _adaptive(name: str) -> Callable[..., Trajectory]:
    def run(scene: Scene, times: NDArray[np.float64], rtol: float) -> Trajectory:
        rhs, y0, scale, observe = _system(scene)
        result = integrate_adaptive(rhs, y0, times, name, rtol, rtol * scale)
        return _trajectory(result, observe, scene, name)

    return run


def _rk4(scene: Scene, times: NDArray[np.float64], step: float) -> Trajectory:
    rhs, y0, _, observe = _system(scene)
    result = fixed_step(lambda t, y, h: rk4_step(rhs, t, y, h), y0, times, step, 4)
    return _trajectory(result, observe, scene, "RK4")


def _lie_poisson(order: int) -> Callable[..., Trajectory]:
    one_step, flows = {2: (lie_poisson_step, 5), 4: (lie_poisson4_step, 15)}[order]

    def run(scene: Scene, times: NDArray[np.float64], step: float) -> Trajectory:
        moments = np.array([scene.I1, scene.I2, scene.I3], dtype=float)
        L0 = moments * np.array(scene.omega0, dtype=float)  # the splitting acts on L = Iω
        result = fixed_step(lambda t, L, h: one_step(L, h, moments), L0, times, step, flows)
        return _trajectory(result, lambda L: L / moments, scene, f"LiePoisson{order}")

    return run


def _euler_angles(scene: Scene, times: NDArray[np.float64], rtol: float) -> Trajectory:
    rhs = heavy_top_euler_rhs(scene.I1, scene.I3, scene.Mgl)
    y0 = np.array([0.0, scene.beta0, 0.0, scene.alpha_dot0, scene.beta_dot0, scene.gamma_dot0])
    rate_scale = max(np.abs(y0[3:]).max(), np.finfo(float).tiny)
    atol = rtol * np.r_[np.ones(3), np.full(3, rate_scale)]
    result = integrate_adaptive(rhs, y0, times, "DOP853", rtol, atol)
    return _trajectory(result, lambda y: np.cos(y[:, 1]), scene, "EulerAngles")


# --- exact solutions -------------------------------------------------------------------------


def _r8(scene: Scene, times: NDArray[np.float64], _=None) -> Trajectory:
    omega = symmetric_top_omega(scene.I1, scene.I3, scene.omega0, times)
    return Trajectory(times, omega, "omega", "R8")


def _r10(scene: Scene, times: NDArray[np.float64], _=None) -> Trajectory:
    omega = asymmetric_top_omega(scene.I1, scene.I2, scene.I3, scene.omega0, times)
    return Trajectory(times, omega, "omega", "R10")


def _r20(scene: Scene, times: NDArray[np.float64], _=None) -> Trajectory:
    return Trajectory(times, cos_beta(times, *scene.heavy_top_state()), "cos_beta", "R20")


def _sleeping(scene: Scene, times: NDArray[np.float64], _=None) -> Trajectory:
    # β0 = β̇0 = 0: the vertical is an equilibrium for any spin (R19 decides only its stability)
    return Trajectory(times, np.ones_like(times), "cos_beta", "sleeping")


_ALL = FREE_KINDS | HEAVY_KINDS
_SYMMETRIC_HEAVY = frozenset({"heavy_symmetric", "sleeping"})

METHODS: dict[str, Method] = {
    m.name: m
    for m in [
        *(Method(name, "rtol", _ALL, _adaptive(name), f"scipy {name}, adaptive")
          for name in ("RK45", "DOP853", "Radau", "LSODA")),
        Method("RK4", "step", _ALL, _rk4, "classical Runge–Kutta, fixed step"),
        Method("LiePoisson2", "step", FREE_KINDS, _lie_poisson(2),
               "McLachlan's explicit Lie–Poisson splitting, 2nd order"),
        Method("LiePoisson4", "step", FREE_KINDS, _lie_poisson(4),
               "Lie–Poisson splitting, Yoshida triple jump, 4th order"),
        Method("EulerAngles", "rtol", _SYMMETRIC_HEAVY, _euler_angles,
               "DOP853 on the heavy top's equations in Euler angles (R14)"),
        Method("R8", None, frozenset({"free_symmetric"}), _r8, "closed form (R8)"),
        Method("R10", None, FREE_KINDS, _r10, "Jacobi elliptic functions (R10)"),
        Method("R20", None, _SYMMETRIC_HEAVY, _r20, "sn² with Carlson-stable roots (R20)"),
        Method("sleeping", None, frozenset({"sleeping"}), _sleeping, "u ≡ 1 (closed form)"),
    ]
}
