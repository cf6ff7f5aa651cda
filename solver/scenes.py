"""Scenes, and the one dispatcher that answers each with the cheapest model exact for it.

"Model no more than a scene needs": a scene is a rigid body and its initial state; its *kind*
decides the model, here and nowhere else (:func:`choose_model`):

====================  ============================================  ===========================
scene kind            when                                          model (``METHODS`` key)
====================  ============================================  ===========================
free_symmetric        ``FreeBody`` with ``I1 = I2``                 ``R8``  closed form
free_asymmetric       ``FreeBody`` otherwise                        ``R10`` Jacobi elliptic
sleeping              ``HeavyBody``, ``I1 = I2``, ``β0 = β̇0 = 0``   ``sleeping`` (``u ≡ 1``)
heavy_symmetric       ``HeavyBody``, ``I1 = I2``, otherwise         ``R20`` sn² + Carlson roots
torqued_asymmetric    ``HeavyBody`` with ``I1 ≠ I2``                ``DOP853`` at rtol 1e-12,
                                                                    quaternions: the one scene
                                                                    that must integrate
====================  ============================================  ===========================

A free body with another pair of equal moments (``I2 = I3``, ``I1 = I3``) is symmetric about a
different axis; R10 covers it exactly (it reduces to R8 relabelled), so it is ``free_asymmetric``
by the rule above, not a special case. Equalities are exact comparisons of the given moments:
the caller decides whether ``I1 = 1.0000001 I2`` is symmetric. Measured costs and accuracies of
each model are on the documentation site's page ``docs/speed.md`` (written by ``eulertop bench``).

The fast-top approximation of R21 is a model choice too: :func:`fast_top_error` gives its
relative error against the exact steady rates, a function of ``ε = 2 I1 Mgl/(I3 ω3)²``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.methods import METHODS, Trajectory, solve
from solver.parameters import ParameterError, as_real, positive, principal_moments
from solver.steady_precession import _tilt, fast_top_rates, steady_precession_rates

__all__ = [
    "MODEL_FOR_KIND",
    "ODE_RTOL",
    "FreeBody",
    "HeavyBody",
    "SceneSolution",
    "choose_model",
    "fast_top_error",
    "fast_top_parameter",
    "solve_scene",
]

ODE_RTOL = 1e-12  # torqued asymmetric body (bench, heavy top: 3e-9 in cos β after 50 T_nut)

MODEL_FOR_KIND: dict[str, str] = {
    "free_symmetric": "R8",
    "free_asymmetric": "R10",
    "sleeping": "sleeping",
    "heavy_symmetric": "R20",
    "torqued_asymmetric": "DOP853",
}


@dataclass(frozen=True)
class FreeBody:
    """A torque-free rigid body (R7–R10).

    Attributes
    ----------
    I1, I2, I3 : float
        Principal moments (kg m²), a rigid body's (triangle inequality).
    omega0 : tuple of 3 floats
        Body components of ω at ``t = 0`` (rad/s).
    """

    I1: float
    I2: float
    I3: float
    omega0: tuple[float, float, float]

    def __post_init__(self) -> None:
        principal_moments(self.I1, self.I2, self.I3)
        w = as_real("omega0", self.omega0, shape_tail=(3,))
        if w.shape != (3,):
            raise ParameterError("omega0", f"one body at a time: shape (3,), got {w.shape}")
        object.__setattr__(self, "omega0", tuple(float(x) for x in w))

    @property
    def kind(self) -> str:
        """``"free_symmetric"`` (``I1 = I2``) or ``"free_asymmetric"``."""
        return "free_symmetric" if self.I1 == self.I2 else "free_asymmetric"


@dataclass(frozen=True)
class HeavyBody:
    """A rigid body on a fixed tip under gravity, centre of mass on its axis ``ê3`` (R14–R21).

    Attributes
    ----------
    I1, I2, I3 : float
        Principal moments about the tip (kg m²); ``I1 = I2`` is the heavy symmetric top.
    Mgl : float
        Weight times tip-to-centre-of-mass distance (J), > 0.
    beta0 : float
        Initial tilt of ``ê3`` from the upward vertical (rad, in [0, π]).
    alpha_dot0, beta_dot0, gamma_dot0 : float
        Initial Euler-angle rates (rad/s), R11/R12 conventions (``α0 = γ0 = 0``).
    """

    I1: float
    I2: float
    I3: float
    Mgl: float
    beta0: float
    alpha_dot0: float
    beta_dot0: float
    gamma_dot0: float

    def __post_init__(self) -> None:
        principal_moments(self.I1, self.I2, self.I3)
        positive("Mgl", self.Mgl)
        _tilt("beta0", self.beta0)
        for name in ("alpha_dot0", "beta_dot0", "gamma_dot0"):
            as_real(name, getattr(self, name))

    @property
    def kind(self) -> str:
        """``"torqued_asymmetric"``, ``"sleeping"`` or ``"heavy_symmetric"``."""
        if self.I1 != self.I2:
            return "torqued_asymmetric"
        if self.beta0 == 0 and self.beta_dot0 == 0:
            return "sleeping"
        return "heavy_symmetric"

    def heavy_top_state(self) -> tuple[float, ...]:
        """``(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)`` of solver.heavy_top."""
        return (self.I1, self.I3, self.Mgl, self.beta0, self.alpha_dot0, self.beta_dot0,
                self.gamma_dot0)


@dataclass(frozen=True)
class SceneSolution:
    """What :func:`solve_scene` answers: the model it chose and the trajectory.

    Attributes
    ----------
    model : str
        The ``METHODS`` key used.
    trajectory : Trajectory
    """

    model: str
    trajectory: Trajectory


def choose_model(scene: FreeBody | HeavyBody) -> str:
    """The cheapest model exact for ``scene`` (a ``METHODS`` key); see the module table."""
    return MODEL_FOR_KIND[scene.kind]


def solve_scene(scene: FreeBody | HeavyBody, times: ArrayLike) -> SceneSolution:
    """Answer ``scene`` at ``times`` (s) with :func:`choose_model`'s model.

    Examples
    --------
    >>> sol = solve_scene(FreeBody(1.0, 1.0, 1.5, (0.1, 0.0, 2.0)), [0.0, 1.0])
    >>> sol.model, sol.trajectory.nfev
    ('R8', 0)
    """
    model = choose_model(scene)
    control = ODE_RTOL if METHODS[model].control == "rtol" else None
    return SceneSolution(model, solve(scene, times, model, control))


def fast_top_parameter(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, omega3: ArrayLike
) -> NDArray[np.float64]:
    """``ε = 2 I1 Mgl / (I3 ω3)²``: small for a fast top (R19, R21), dimensionless.

    ``ε ≤ ½`` is the sleeping-top stability condition of R19.
    """
    i1, i3, mgl = positive("I1", I1), positive("I3", I3), positive("Mgl", Mgl)
    return (2.0 * i1 * mgl / (i3 * as_real("omega3", omega3)) ** 2)[()]


def fast_top_error(
    I1: ArrayLike, I3: ArrayLike, Mgl: ArrayLike, beta0: ArrayLike, p_gamma: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Relative errors of :func:`~solver.steady_precession.fast_top_rates` (R21).

    ``approx/exact − 1`` for the slow and the fast steady-precession rate, against
    :func:`~solver.steady_precession.steady_precession_rates`. With
    ``ε = 2 I1 Mgl/p_γ²`` (:func:`fast_top_parameter`) and ``x = 2 ε cos β0``:
    slow ``(√(1 − x) − 1)/2 ≈ −ε cos β0 / 2``, fast ``2/(1 + √(1 − x)) − 1 ≈ +ε cos β0 / 2``;
    so the approximation is good to ``rtol`` while ``ε |cos β0| ≲ 2 rtol``. NaN where the
    exact rates are not real (``x > 1``) or do not exist. Arguments as in
    :func:`~solver.steady_precession.steady_precession_rates`.
    """
    slow, fast = steady_precession_rates(I1, I3, Mgl, beta0, p_gamma)
    slow_approx, fast_approx = fast_top_rates(I1, I3, Mgl, beta0, p_gamma)
    with np.errstate(invalid="ignore", divide="ignore"):
        return (slow_approx / slow - 1.0)[()], (fast_approx / fast - 1.0)[()]
