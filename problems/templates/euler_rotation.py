"""Euler angles: the rotation matrix, a vector transformed body ↔ inertial, ω from the rates.

The convention is R11's (``docs/physics/index.md``): ``R = R_γ R_β R_α`` (α about the inertial
z, β about the new y', γ about the body ê3; β from the upward vertical), and ``V' = R V`` maps
inertial components to body components. The statement spells it out, with the three elementary
matrices.

A spinning top in the lab or a quadcopter drone, at one instant: Euler angles (rad) and their
rates (rad/s). Answers:

- ``R``: the whole matrix, as a flat list of its 9 entries row by row (R11);
- either the lab components of a marker on the body, from its body coordinates (``Rᵀ r'``), or
  the body components of a force given in lab components (``R F``) (R11);
- ``omega_body``: the body components of ω from the Euler-angle rates (R12).

Known mistakes: Rᵀ for R (inertial ↔ body confused), the product in the wrong order
(``R_α R_β R_γ``), a calculator in degree mode (the radian values read as degrees), the rates
taken as the components of ω, and ω given in lab components.

Tolerance: ``rtol = 1e-3`` on the norm of each vector. Angles have 3 significant figures but
are exact inputs; entries of R are O(1) and a student computing with numpy is exact to 1e-15.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from problems.answers import Answer, Mistake
from problems.family import IllPosed, Parameter, follows_from, reject_unless
from problems.rounding import format_sig, latex_sig, round_sig
from solver.euler_angles import omega_body, rotation_matrix, to_body, to_inertial

NAME = "euler_rotation"
TITLE = "Euler angles: rotation matrix and angular velocity"
SUMMARY = "rotation matrix from Euler angles, a vector body ↔ lab, ω (body) from Euler-angle rates"
RESULTS = ("R11", "R12")

RTOL = 1e-3
SEPARATION = 5.0  # key and mistakes at least this many tolerances apart
MAX_TRIES = 200

# Bodies: label -> (words, β range rad, α̇ range, β̇ range, γ̇ range in rad/s).
BODIES = {
    "toy_top": ("a toy top spinning on a table", (0.1, 1.4), (1.0, 6.0), (-1.5, 1.5),
                (60.0, 150.0)),
    "drone": ("a quadcopter drone in a turn", (0.05, 0.6), (-1.5, 1.5), (-1.0, 1.0),
              (-2.0, 2.0)),
}

CONVENTIONS = ("euler_angles",)
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

_DEGREE_MODE = (
    "The angles are in radians, but this value comes from reading them as degrees (a calculator "
    "in degree mode, or numpy.deg2rad applied to radians)."
)
_TRANSPOSE = (
    "R maps lab components to body components, V' = R V; the inverse is the transpose, "
    "V = Rᵀ V' (R11). This answer uses the wrong one of the two."
)


def _answer(name, key, mistakes, unit, description) -> Answer | None:
    """A vector answer, or None if a mistake is within SEPARATION tolerances of the key or of
    another mistake (the draw is then rejected)."""
    values = [np.ravel(np.asarray(v, float)) for v in (key, *(m[1] for m in mistakes))]
    tol = SEPARATION * RTOL * np.linalg.norm(values[0])
    if any(np.linalg.norm(a - b) <= tol for i, a in enumerate(values) for b in values[i + 1:]):
        return None
    return Answer(
        name, "vector", values[0].tolist(), unit=unit, rtol=RTOL, description=description,
        mistakes=tuple(Mistake(n, v.tolist(), f) for (n, _, f), v in zip(mistakes, values[1:],
                                                                          strict=True)),
    )


class _Solved(NamedTuple):
    """What the solver gives one instant: R, the mistaken matrices (the product reversed,
    the angles read as degrees), ω in body components and ω with the angles read as degrees;
    the asked vector (``r_lab`` or ``F_body``) and its mistakes (the other of ``R``, ``Rᵀ``;
    ``R`` of the angles read as degrees); and ω in lab components."""

    R: np.ndarray
    reversed_order: np.ndarray
    R_deg: np.ndarray
    omega: np.ndarray
    omega_deg: np.ndarray
    vector: np.ndarray
    vector_transposed: np.ndarray
    vector_deg: np.ndarray
    omega_lab: np.ndarray


def _solve_many(many: list[Mapping[str, Any]]) -> list[_Solved]:
    """:class:`_Solved` of each instant, every matrix and ω of all of them in one solver call
    each (element by element what one instant alone gives)."""
    alpha, beta, gamma = np.array([[p[n] for n in _ANGLES] for p in many], dtype=float).T
    rates = np.array([[p[n] for n in _RATES] for p in many], dtype=float).T
    in_degrees = np.radians([alpha, beta, gamma])  # radian values read as degrees
    R, R_deg = rotation_matrix(alpha, beta, gamma), rotation_matrix(*in_degrees)
    omega = omega_body(beta, gamma, *rates)
    # a marker goes body → lab (Rᵀ r'), a force lab → body (R F): each the other's transpose
    marker = np.array(["r_body" in p for p in many])[:, None]
    given = np.array([p["r_body"] if "r_body" in p else p["F_lab"] for p in many], dtype=float)
    to_lab, to_own = to_inertial(R, given), to_body(R, given)
    to_lab_deg, to_own_deg = to_inertial(R_deg, given), to_body(R_deg, given)
    return [_Solved(*found) for found in zip(
        R, rotation_matrix(gamma, beta, alpha),  # R_α R_β R_γ: α and γ trade places
        R_deg, omega, omega_body(*in_degrees[1:], *rates),
        np.where(marker, to_lab, to_own), np.where(marker, to_own, to_lab),
        np.where(marker, to_lab_deg, to_own_deg), to_inertial(R, omega), strict=True)]


def _matrix_answer(solved: _Solved) -> Answer | None:
    R = solved.R
    return _answer("R", R, [
        ("transpose", R.T, "This is Rᵀ, which maps body components to lab components. "
         "R = R_γ R_β R_α maps lab components V to body components V' = R V (R11)."),
        ("reversed_order", solved.reversed_order, "The product is in the wrong order: the first "
         "rotation (α) acts first on V, so it stands rightmost, R = R_γ R_β R_α."),
        ("degree_mode", solved.R_deg, _DEGREE_MODE),
    ], "", "R, its 9 entries row by row: [R11, R12, R13, R21, …, R33]")


def _vector_answer(params: Mapping[str, Any], solved: _Solved) -> Answer | None:
    """Either a marker body → lab (``r_body`` given), or a force lab → body (``F_lab``)."""
    mistakes = [("transpose", solved.vector_transposed, _TRANSPOSE),
                ("degree_mode", solved.vector_deg, _DEGREE_MODE)]
    if "r_body" in params:
        return _answer("r_lab", solved.vector, mistakes, "m",
                       "lab components of the marker's position")
    return _answer("F_body", solved.vector, mistakes, "N", "body components of the force")


def _vector_text(params: Mapping[str, Any]) -> str:
    """The sentence asking for :func:`_vector_answer`'s vector."""
    if "r_body" in params:
        shown = ", ".join(format_sig(x, 2) for x in np.array(params["r_body"]))
        return ("`r_lab`: the lab coordinates of a marker at the body coordinates "
                f"$\\mathbf r' = ({shown})$ m (`r_body`) from the fixed point;")
    shown = ", ".join(format_sig(x, 3) for x in np.array(params["F_lab"]))
    return ("`F_body`: the body components of a force with the lab components "
            f"$\\mathbf F = ({shown})$ N (`F_lab`);")


def _omega_answer(beta, rates, solved: _Solved) -> Answer | None:
    w = solved.omega
    return _answer("omega_body", w, [
        ("rates_as_components", rates, "The Euler-angle rates are not the components of ω: "
         "ω = α̇ ẑ + β̇ ê'₂ + γ̇ ê₃ is a sum along three axes that are not orthogonal (R12)."),
        ("lab_components", solved.omega_lab,
         "These are the lab components of ω; the question asks for its body components "
         "(ω₁, ω₂, ω₃) along ê₁, ê₂, ê₃ (R12)."),
        ("degree_mode", solved.omega_deg, _DEGREE_MODE),
        *_spin_mistake(w, beta, rates),
    ], "rad/s", "body components (ω1, ω2, ω3) of the angular velocity")


_OMEGA3_IS_GAMMA_DOT = (
    "ω₃ = γ̇ + α̇ cos β (R12): the spin-angle rate γ̇ alone is not the component along ê₃; the "
    "precession α̇ ẑ contributes α̇ cos β to it."
)


def _spin_mistake(w: np.ndarray, beta: float, rates: np.ndarray) -> list[tuple]:
    """``omega3_is_gamma_dot`` (ω₃ taken to be γ̇), where it is clear of the key by more than
    ``SEPARATION`` tolerances; otherwise none (the draw is not rejected for it)."""
    wrong = np.array([w[0], w[1], rates[2]])
    if np.linalg.norm(wrong - w) <= 2 * SEPARATION * RTOL * np.linalg.norm(w):
        return []
    return [("omega3_is_gamma_dot", wrong, _OMEGA3_IS_GAMMA_DOT)]


_ANGLES = ("alpha", "beta", "gamma")
_RATES = ("alpha_dot", "beta_dot", "gamma_dot")

PARAMETERS: dict[str, Parameter] = {
    "body": Parameter(choices=tuple(BODIES), description="the body"),
    "alpha": Parameter(unit="rad", low=0.1, high=6.18, description="Euler angle α"),
    "beta": Parameter(unit="rad", description="Euler angle β"),
    "gamma": Parameter(unit="rad", low=0.1, high=6.18, description="Euler angle γ"),
    **{n: Parameter(unit="rad/s", description=f"rate of {n[:-4]}") for n in _RATES},
    "r_body": Parameter(unit="m", shape=(3,), figures=2, description="a marker, body frame"),
    "F_lab": Parameter(unit="N", shape=(3,), description="a force, lab frame"),
}


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A body of :data:`BODIES` at one instant: Euler angles and rates in its ranges, then a
    marker's body coordinates or a force's lab components (each one time in two)."""
    label = list(BODIES)[int(rng.integers(len(BODIES)))]
    beta_range, *rate_ranges = BODIES[label][1:]
    alpha, gamma = round_sig(rng.uniform(0.1, 2 * np.pi - 0.1, size=2), 3)
    beta = round_sig(rng.uniform(*beta_range), 3)
    rates = [round_sig(rng.uniform(*r), 3) for r in rate_ranges]
    params = {"body": label, **dict(zip(_ANGLES, map(float, (alpha, beta, gamma)), strict=True)),
              **dict(zip(_RATES, map(float, rates), strict=True))}
    if rng.integers(2):
        return params | {"r_body": round_sig(rng.uniform(-0.08, 0.08, size=3), 2).tolist()}
    return params | {"F_lab": round_sig(rng.uniform(-5.0, 5.0, size=3), 3).tolist()}


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``R`` (its 9 entries), ``r_lab`` (m) or ``F_body`` (N), and ``omega_body`` (rad/s),
    R11, R12.

    Raises :class:`~problems.family.IllPosed` when a known mistake is close to the key.
    """
    return _answers(params, _solve_many([params])[0])


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): every instant's matrices and ω in
    one solver call each."""
    found: list[tuple[Answer, ...] | IllPosed] = []
    for params, solved in zip(many, _solve_many(many), strict=True):
        try:
            found.append(_answers(params, solved))
        except IllPosed as e:
            found.append(e)
    return found


def _answers(params: Mapping[str, Any], solved: _Solved) -> tuple[Answer, ...]:
    """:func:`answers` from the instant's :func:`_solve_many`."""
    rates = np.array([params[n] for n in _RATES])
    found = (_matrix_answer(solved), follows_from(_vector_answer(params, solved), "R"),
             _omega_answer(params["beta"], rates, solved))
    reject_unless(None not in found, "a known mistake close to the key")
    return found


def heading(params: Mapping[str, Any]) -> str:
    return f"Euler angles of {BODIES[params['body']][0]}"


def statement(params: Mapping[str, Any]) -> str:
    symbols = (r"\alpha", r"\beta", r"\gamma", r"\dot\alpha", r"\dot\beta", r"\dot\gamma")
    shown = ", ".join(
        f"${s} = {latex_sig(params[n], 3)}$ {PARAMETERS[n].unit} (`{n}`)"
        for s, n in zip(symbols, (*_ANGLES, *_RATES), strict=True)
    )
    return (
        f"At one instant, the Euler angles of {BODIES[params['body']][0]} and their rates are "
        f"{shown}.\n\n"
        "1. `R`: the rotation matrix, its nine entries row by row (e.g. `R.ravel()`);\n"
        f"2. {_vector_text(params)}\n"
        "3. `omega_body`: the body components of the angular velocity."
    )


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``r_lab`` or ``F_body`` with the student's own rotation matrix ``R`` (its 9 entries row
    by row): ``Rᵀ r'`` or ``R F`` (R11, :func:`solver.euler_angles.to_inertial`,
    :func:`~solver.euler_angles.to_body`)."""
    R = np.array(earlier["R"], dtype=float).reshape(3, 3)
    if name == "r_lab" and "r_body" in params:
        return to_inertial(R, np.array(params["r_body"])).tolist()
    if name == "F_body" and "F_lab" in params:
        return to_body(R, np.array(params["F_lab"])).tolist()
    raise LookupError(name)


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's ``R`` leaves nothing to work out for ``r_lab`` or ``F_body`` (R11):
    the identity (the given vector copied), or any matrix of only 0 and ±1 entries (its
    components reordered or their signs flipped) — which no draw's angles give. None
    otherwise."""
    if name not in ("r_lab", "F_body"):
        raise LookupError(name)
    given = "{r_body}" if name == "r_lab" else "{F_lab}"
    R = np.array(earlier["R"], dtype=float).reshape(3, 3)
    if np.array_equal(R, np.eye(3)):
        return (f"your {{R}} is the identity matrix, which makes {{{name}}} a copy of the "
                f"given {given} (R11)")
    if np.all(np.isin(R, (-1.0, 0.0, 1.0))):
        return (f"your {{R}} has only 0 and ±1 entries, which makes {{{name}}} the given "
                f"{given} reordered or with signs flipped: nothing of R11 worked out")
    return None
