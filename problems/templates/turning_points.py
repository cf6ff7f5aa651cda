"""Heavy symmetric top: the effective potential and the turning points of the nutation (R16, R17).

The tops and initial states are those of :mod:`problems.templates.heavy_top_constants` (a toy
top on a table, a gyroscope on a post, a disc hanging from a ball joint); one time in three the
top is released with ``α̇0 = β̇0 = 0`` (the classroom demonstration), otherwise it is launched
with a precession rate of either sense and a nod. Asked, as parts of one question on one top:

1. ``V_eff``: ``V_eff(β) = (p_α − p_γ cos β)²/(2 I1 sin²β) + Mgl cos β`` (R16) at a given tilt
   ``beta`` (drawn around the motion's range);
2. ``beta1 ≤ beta2``: the roots of ``V_eff(β) = E'`` bracketing ``β0`` (R17), in radians.

Answers come from :func:`solver.heavy_top.effective_potential` (with
:func:`~solver.heavy_top.constants_of_motion`) and :func:`solver.heavy_top.turning_points`, all
from the shown (rounded) values.

Known mistakes. ``V_eff``: the spin energy ``p_γ²/(2 I3)`` included; ``p_α`` without
``p_γ cos β``; degree mode; ``I1`` about the centre of mass; ``I1``, ``I3`` swapped. Turning
points: ``β1`` and ``β2`` exchanged; the angle given in degrees; the total energy ``E`` used for
``E'``; ``I1`` about the centre of mass; ``I1``, ``I3`` swapped (only when the swapped moments
are a rigid body's, ``I1 ≤ 2 I3``, where the solver accepts them). Moment and angle mistakes
that barely move a given answer are not listed for it (see
:func:`~problems.templates.heavy_top_constants.select_mistakes`).

Tolerance: ``rtol = 1e-3`` for all three. ``V_eff`` is a few products of exact 3-figure data.
The turning points are the roots of a cubic (R17): ``numpy.roots`` or ``brentq`` give them to
~1e-10, and a tilt off by 1e-3 relative is a visibly different nutation. Rejected draws: turning
points closer than ``MIN_NUTATION`` (nearly steady precession, where the roots are
ill-conditioned), a motion outside the scene's limits (the disc touching the table, a turning
point within ``POLE_MARGIN`` of a pole, the hanging disc rising above its joint), a ``V_eff``
that is a small difference of large terms, and a primary mistake (the spin energy in ``V_eff``;
exchanged turning points, degrees) within five tolerances of the key or of another mistake.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from problems.answers import Answer
from problems.family import IllPosed, Parameter, reject_unless
from problems.rounding import latex_sig, round_sig
from problems.templates import heavy_top_constants
from problems.templates.heavy_top_constants import (
    CONVENTIONS as CONVENTIONS,  # the same convention topics (problems.conventions)
)
from problems.templates.heavy_top_constants import (
    FEEDBACK,
    RTOL,
    SIG,
    State,
    Top,
    draw_state,
    draw_tops,
    mistaken_states,
    motion_within_limits,
    select_mistakes,
    state_args,
    state_from_params,
    state_text,
    top_from_params,
    variant_params,
    well_conditioned,
)
from problems.written import Written
from solver.heavy_top import constants_of_motion, effective_potential, turning_points

NAME = "turning_points"
TITLE = "Heavy symmetric top: effective potential and turning points"
SUMMARY = "heavy symmetric top: V_eff at a given tilt and the nutation's turning points β1, β2"
RESULTS = ("R15", "R16", "R17")

RELEASED = 1 / 3
"""Share of draws released from rest in α and β (``α̇0 = β̇0 = 0``)."""
QUERY_MARGIN = 0.3
"""``beta`` (rad) is drawn up to this far outside ``[β1, β2]``, ..."""
QUERY_MIN = 0.1
"""... and at least this far from a pole (rad)."""
MAX_ATTEMPTS = 500

_FEEDBACK = {
    **FEEDBACK,
    "spin_energy_included": (
        "V_eff (R16) does not contain the constant spin energy p_γ²/(2 I3): it belongs to E, "
        "and V_eff is compared with E' = E − p_γ²/(2 I3)."
    ),
    "turning_points_exchanged": (
        "β1 and β2 are exchanged: β1 ≤ β2, so β1 is the smaller tilt (the axis at its "
        "highest) and β2 the larger."
    ),
    "degrees": "That is the angle in degrees; give it in radians.",
    "E_not_E_prime": (
        "The turning points solve V_eff(β) = E' with E' = E − p_γ²/(2 I3) (R16): with the "
        "total energy E the axis would seem to swing nearly to the vertical and back."
    ),
}


def _energy_state(top: Top, state: State, p_gamma: float) -> tuple[float, ...]:
    """A state with the same ``p_α, p_γ`` whose ``E'`` is the true ``E``: the extra
    ``p_γ²/(2 I3)`` carried by ``½ I1 β̇²`` (turning points do not depend on the sign of β̇)."""
    beta_dot = math.sqrt(state.beta_dot0**2 + p_gamma**2 / (top.I1 * top.I3))
    return (top.I1, top.I3, top.Mgl, state.beta0, state.alpha_dot0, beta_dot, state.gamma_dot0)


def _potential_rows(top: Top, state: State, beta: float, mistaken: dict, p_alpha: np.ndarray,
                    p_gamma: np.ndarray) -> list[list[float]]:
    """The arguments of :func:`effective_potential` (``β``, ``I1``, ``Mgl``, ``p_α``, ``p_γ``)
    for ``V_eff(beta)`` of the key, of each ``mistaken`` state, and without ``p_γ cos β``;
    ``p_alpha``, ``p_gamma``: the key's constants, then those of each mistaken state."""
    pg = float(p_gamma[0])
    transverse = top.I1 * state.alpha_dot0 * math.sin(state.beta0) ** 2  # p_α without p_γ cos β
    rows = ("key", *mistaken, "missing_p_gamma_term")
    where = [math.radians(beta) if k == "degree_mode" else beta for k in rows]
    moment = [top.I1, *(args[0] for args in mistaken.values()), top.I1]
    return [where, moment, [top.Mgl] * len(rows), [*p_alpha, transverse], [*p_gamma, pg]]


def _potentials_many(rows: list[list[list[float]]]) -> list[np.ndarray]:
    """:func:`effective_potential` of each student's :func:`_potential_rows`, in one call."""
    values = effective_potential(*(np.concatenate(column) for column in zip(*rows, strict=True)))
    return _split(values, [r[0] for r in rows])  # each student's rows: one per value of β


def _potential_answer(top: Top, beta: float, mistaken: dict, p_gamma: np.ndarray,
                      values: np.ndarray) -> Answer | None:
    """``V_eff(beta)`` and its mistakes (None: ill-conditioned or confusable), from the
    :func:`_potentials_many` of its :func:`_potential_rows` (``values``)."""
    pg = float(p_gamma[0])
    key = float(values[0])
    potential = top.Mgl * math.cos(beta)
    if not well_conditioned(key, key - potential, potential):
        return None
    secondary = {"missing_p_gamma_term": values[-1],
                 **{k: values[i] for i, k in enumerate(mistaken, 1)}}
    mistakes = select_mistakes(key, {"spin_energy_included": key + pg**2 / (2 * top.I3)},
                               secondary, feedback=_FEEDBACK)
    if mistakes is None:
        return None
    return Answer("V_eff", "scalar", key, unit="J", rtol=RTOL, mistakes=mistakes,
                  description="effective potential V_eff at the given tilt beta")


def _turning_point_answers(names: tuple[str, ...], low: np.ndarray, high: np.ndarray):
    """``beta1``, ``beta2`` with their mistakes (None if confusable); ``low``, ``high``: the
    turning points of the key, then of each mistake in ``names``."""
    beta1, beta2 = float(low[0]), float(high[0])
    answers = []
    for name, key, other, wrong in (("beta1", beta1, beta2, low), ("beta2", beta2, beta1, high)):
        primary = {"turning_points_exchanged": other, "degrees": math.degrees(key)}
        mistakes = select_mistakes(key, primary, dict(zip(names, wrong[1:], strict=True)),
                                   feedback=_FEEDBACK)
        if mistakes is None:
            return None
        which = "smaller" if name == "beta1" else "larger"
        answers.append(Answer(name, "angle", key, unit="rad", rtol=RTOL, mistakes=mistakes,
                              description=f"the {which} turning point of β"))
    return tuple(answers)


def _statement(top: Top, state: State, beta: float) -> str:
    return (
        f"{top.text} {state_text(state)}\n\n"
        "1. `V_eff`: the effective potential $V_{\\mathrm{eff}}(\\beta)$ (which equals "
        "$E' = E - p_\\gamma^2/(2 I_3)$ at the turning points) at "
        f"$\\beta = {latex_sig(beta, SIG)}$ rad (`beta`);\n"
        "2. `beta1`, `beta2`: the turning points $\\beta_1 \\le \\beta_2$ of the nutation."
    )


PARAMETERS: dict[str, Parameter] = {
    **heavy_top_constants.PARAMETERS,
    "beta": Parameter(unit="rad", description="the tilt at which V_eff is asked"),
}


def _solve(top: Top, state: State) -> tuple[dict, np.ndarray, np.ndarray, dict, np.ndarray,
                                             np.ndarray]:
    """One solver pass for the key and every mistaken state (rows: key first): the mistaken
    states, ``p_α``, ``p_γ``, the states whose turning points move, and those turning points."""
    return _solve_many([(top, state)])[0]


def _solve_many(motions: list[tuple[Top, State]]) -> list[tuple]:
    """:func:`_solve` of each ``(top, state)``, each solver function called once for all."""
    mistaken = [mistaken_states(top, state) for top, state in motions]
    rows = [[state_args(top, state), *m.values()] for (top, state), m in
            zip(motions, mistaken, strict=True)]
    p_alpha, p_gamma, _ = (_split(x, rows) for x in constants_of_motion(*_columns(rows)))
    moved = []
    for (top, state), m, gamma in zip(motions, mistaken, p_gamma, strict=True):
        moved.append({k: v for k, v in m.items() if k != "degree_mode"})  # the answer is in rad
        moved[-1]["E_not_E_prime"] = _energy_state(top, state, float(gamma[0]))
    rows = [[state_args(top, state), *m.values()] for (top, state), m in
            zip(motions, moved, strict=True)]
    low, high = (_split(x, rows) for x in turning_points(*_columns(rows)))
    return list(zip(mistaken, p_alpha, p_gamma, moved, low, high, strict=True))


def _columns(rows: list[list[tuple]]) -> np.ndarray:
    """Every student's solver arguments (rows of rows), as the solver's columns."""
    return np.array([row for student in rows for row in student], dtype=float).T


def _split(column: np.ndarray, rows: list[list[tuple]]) -> list[np.ndarray]:
    """A solver result for all students back into each student's rows."""
    return np.split(np.atleast_1d(column), np.cumsum([len(r) for r in rows])[:-1])


def _draw_motions(rngs: Sequence[np.random.Generator]) -> list[tuple[Top, State]]:
    """:func:`_draw_motion` of each generator: each student's numbers drawn in order, the
    tops' shown numbers worked out together (:func:`draw_tops`)."""
    return [_launched(rng, top) for rng, top in zip(rngs, draw_tops(rngs), strict=True)]


def _draw_motion(rng: np.random.Generator) -> tuple[Top, State]:
    """A real top, released from rest in α and β one time in three, else launched."""
    return _draw_motions([rng])[0]


def _launched(rng: np.random.Generator, top: Top) -> tuple[Top, State]:
    """``top`` released from rest in α and β one time in three, else launched."""
    if rng.uniform() < RELEASED:
        return top, draw_state(rng, top, 0.0, 0.0)
    sense = rng.choice([1.0, 1.0, -1.0])
    nod = rng.choice([0.0, 1.0, -1.0]) * rng.uniform(0.02, 0.15)
    return top, draw_state(rng, top, sense * rng.uniform(0.3, 2.5), nod)


def _draw_query(rng: np.random.Generator, top: Top, state: State, low: np.ndarray,
                high: np.ndarray) -> dict[str, Any] | None:
    """The parameters of a drawn motion, with the tilt ``beta`` drawn around its range (None:
    the motion leaves the scene's limits)."""
    beta1, beta2 = float(low[0]), float(high[0])
    if not motion_within_limits(top, beta1, beta2):
        return None
    low_q = max(QUERY_MIN, beta1 - QUERY_MARGIN)
    beta = round_sig(rng.uniform(low_q, min(math.pi - QUERY_MIN, beta2 + QUERY_MARGIN)), SIG)
    return variant_params(top, state, beta=beta)


def draw(rng: np.random.Generator) -> dict[str, Any] | None:
    """A real top, released from rest in α and β one time in three, else launched; the tilt
    ``beta`` for ``V_eff`` drawn around the motion's range (None: the motion leaves the
    scene's limits)."""
    top, state = _draw_motion(rng)
    *_, low, high = _solve(top, state)
    return _draw_query(rng, top, state, low, high)


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any] | None]:
    """:func:`draw` of each generator, the motions solved together (the batch form,
    :mod:`problems.family`)."""
    motions = _draw_motions(rngs)
    return [_draw_query(rng, top, state, *solved[4:]) for rng, (top, state), solved
            in zip(rngs, motions, _solve_many(motions), strict=True)]


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected), the motions solved together (the batch form)."""
    motions = [(top_from_params(p), state_from_params(p)) for p in many]
    solved = _solve_many(motions)
    potentials = _potentials_many([_potential_rows(top, state, p["beta"], *s[:3]) for p,
                                   (top, state), s in zip(many, motions, solved, strict=True)])
    found: list[tuple[Answer, ...] | IllPosed] = []
    for p, (top, _), s, values in zip(many, motions, solved, potentials, strict=True):
        try:
            found.append(_answers(top, p["beta"], s, values))
        except IllPosed as e:
            found.append(e)
    return found


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``V_eff`` at ``beta`` (R16) and the turning points ``beta1 ≤ beta2`` (R17), computed by
    :mod:`solver.heavy_top` from the shown (rounded) parameters.

    Raises :class:`~problems.family.IllPosed` for a motion outside the scene's limits, an
    ill-conditioned ``V_eff``, or a primary mistake close to the key.
    """
    top, state = top_from_params(params), state_from_params(params)
    solved = _solve(top, state)
    (values,) = _potentials_many([_potential_rows(top, state, params["beta"], *solved[:3])])
    return _answers(top, params["beta"], solved, values)


def _answers(top: Top, beta: float, solved: tuple, values: np.ndarray) -> tuple[Answer, ...]:
    """:func:`answers` from the motion's :func:`_solve` and its ``V_eff`` values
    (:func:`_potentials_many`)."""
    mistaken, _, p_gamma, moved, low, high = solved
    reject_unless(motion_within_limits(top, float(low[0]), float(high[0])),
                  "the motion leaves the scene's limits")
    potential = _potential_answer(top, beta, mistaken, p_gamma, values)
    points = _turning_point_answers(tuple(moved), low, high)
    reject_unless(potential is not None and points is not None,
                  "ill-conditioned, or a mistake close to the key")
    return (potential, *points)


def heading(params: Mapping[str, Any]) -> str:
    return f"{top_from_params(params).title}: turning points"


def statement(params: Mapping[str, Any]) -> str:
    return _statement(top_from_params(params), state_from_params(params), params["beta"])


VEFF_MINIMUM = Written(
    "veff_minimum",
    "Show that $V_\\text{eff}(\\beta)$ has exactly one minimum between $\\beta = 0$ and "
    "$\\beta = \\pi$ when $|p_\\alpha| \\ne |p_\\gamma|$, so that the axis nods between "
    "two turning points.",
    3,
    [("$V_\\text{eff}$ written in terms of $p_\\alpha$, $p_\\gamma$, $I_1$ and $Mgl$", 1),
     ("$V_\\text{eff} \\to +\\infty$ at both ends argued (the numerator does not vanish "
      "there when $|p_\\alpha| \\ne |p_\\gamma|$)", 1),
     ("only one stationary point shown (with $u = \\cos\\beta$: $V_\\text{eff}'$ has one "
      "zero in $(-1, 1)$)", 1)],
    "why V_eff(β) has one minimum (R16, R17)",
)
"""R16 (the effective potential) and R17 (its two turning points): the derivation behind the
numbers this family asks for (``docs/physics/index.md``)."""


def written(params: Mapping[str, Any]) -> tuple[Written, ...]:
    """The written part an assignment may ask for: :data:`VEFF_MINIMUM`."""
    return (VEFF_MINIMUM,)
