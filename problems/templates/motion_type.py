"""Heavy symmetric top: the precession rate at the turning points, and the figure the axis traces
(R18).

The tops are those of :mod:`problems.templates.heavy_top_constants` (a toy top on a table, a
gyroscope on a post, a disc hanging from a ball joint). The figure is chosen first, each of the
three equally often, and the initial state drawn to produce it (``Ω = Mgl/(I3 γ̇0)``, the
fast-top precession rate of R21):

``cusps``
    released with ``α̇0 = β̇0 = 0`` (the classroom case): then ``p_α = p_γ cos β0`` and
    ``α̇ = 0`` *exactly* at ``β1 = β0``;
``waves``
    ``α̇0`` in the sense of ``Ω``, 0.3–0.8 or 1.2–1.7 times it, ``β̇0 = 0``;
``loops``
    ``α̇0`` against ``Ω`` (0.3–1.5 times it), or beyond twice ``Ω``, or ``α̇0 = 0`` with a nod
    ``β̇0 ≠ 0``.

Asked: ``alpha_dot1``, ``alpha_dot2``, the precession rate ``α̇ = (p_α − p_γ cos β)/(I1 sin²β)``
at the turning points ``β1 ≤ β2`` (R17, R18), and ``motion``, one of ``"waves"``, ``"loops"``,
``"cusps"``. Answers from :func:`solver.heavy_top.solve_heavy_top` on the shown values.

Robustness: the solver's classification is kept only if it is unambiguous. A cusp must be the
exact released case; otherwise both rates must be at least ``MIN_RATE_RATIO`` of the larger in
size, so that no student's rounding of a turning point can turn waves or loops into cusps.
Also rejected: steady and sleeping tops, turning points closer than ``MIN_NUTATION`` and motions
outside the scene's limits (as in :mod:`~problems.templates.turning_points`).

Known mistakes for the rates: ``α̇(β1)`` and ``α̇(β2)`` exchanged and the sign flipped (not for
the cusp's exact zero), always listed (a draw where they are confusable is rejected); ``I1``
about the centre of mass and ``I1``, ``I3`` swapped (when the solver accepts the swapped moments,
``I1 ≤ 2 I3``), listed where they move the rate by more than five tolerances. For the figure,
each wrong option, with the reason it is wrong.

Tolerance: ``rtol = 1e-3`` and ``atol = 1e-3`` of the larger ``|α̇|`` (a cusp's rate is exactly
zero, and a student's turning point carried to 1e-8 leaves a residue there far below that).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from typing import Any

import numpy as np

from problems.answers import Answer, Mistake
from problems.family import IllPosed
from problems.templates.heavy_top_constants import (
    CONVENTIONS as CONVENTIONS,  # the same convention topics (problems.conventions)
)
from problems.templates.heavy_top_constants import (
    FEEDBACK,
    RTOL,
    State,
    Top,
    draw_state,
    draw_tops,
    mistaken_states,
    motion_within_limits,
    pick,
    select_mistakes,
    state_args,
    state_from_params,
    state_text,
    top_from_params,
    variant_params,
)
from problems.templates.heavy_top_constants import (
    PARAMETERS as PARAMETERS,  # the same tops and states
)
from solver.heavy_top import (
    constants_of_motion,
    heavy_top_record,
    precession_rate,
    solve_heavy_top,
    solve_heavy_top_many,
    turning_points,
)

NAME = "motion_type"
TITLE = "Heavy symmetric top: waves, loops or cusps?"
SUMMARY = "heavy symmetric top: α̇ at the turning points and the figure (waves, loops, cusps)"
RESULTS = ("R17", "R18")

OPTIONS = ("waves", "loops", "cusps")
MIN_RATE_RATIO = 0.05
"""Outside the exact cusp, ``min |α̇(βi)| ≥ MIN_RATE_RATIO · max |α̇(βi)|``."""
MAX_ATTEMPTS = 500

_FEEDBACK = {
    **FEEDBACK,
    "turning_points_exchanged": (
        "The rates at β1 and β2 are exchanged: β1 ≤ β2 is the smaller tilt (the axis at its "
        "highest)."
    ),
    "sign_flipped": (
        "The sign is flipped: α̇ = (p_α − p_γ cos β)/(I1 sin²β) (R18), positive when the axis "
        "precesses counter-clockwise seen from above."
    ),
}

_FIGURE_FEEDBACK = {
    ("waves", "loops"): "α̇ has the same sign at both turning points (R18), so the axis never "
                        "moves backwards: waves, not loops.",
    ("waves", "cusps"): "α̇ vanishes at neither turning point (R18): the axis never stops, so "
                        "the figure is waves, not cusps.",
    ("loops", "waves"): "α̇ has opposite signs at the two turning points (R18): the axis moves "
                        "backwards near one of them and traces loops.",
    ("loops", "cusps"): "α̇ is not zero at a turning point; it changes sign between them (R18): "
                        "loops, not cusps.",
    ("cusps", "waves"): "α̇ = 0 at the upper turning point (R18: released with α̇0 = β̇0 = 0, "
                        "p_α = p_γ cos β0): the axis stops there and traces cusps.",
    ("cusps", "loops"): "α̇ vanishes at the upper turning point but never changes sign (R18): "
                        "the axis stops there without moving backwards — cusps, not loops.",
}


def _draw_state(rng: np.random.Generator, top: Top, figure: str) -> State:
    """An initial state meant to give ``figure`` (the solver has the last word)."""
    if figure == "cusps":
        return draw_state(rng, top, 0.0, 0.0)
    if figure == "waves":
        return draw_state(rng, top, pick(rng, (0.3, 1.2)) + rng.uniform(0.0, 0.5), 0.0)
    kind = int(rng.integers(3))
    if kind == 0:
        return draw_state(rng, top, -rng.uniform(0.3, 1.5), 0.0)
    if kind == 1:
        return draw_state(rng, top, rng.uniform(2.3, 3.0), 0.0)
    return draw_state(rng, top, 0.0, pick(rng, (1.0, -1.0)) * rng.uniform(0.03, 0.15))


def _robust(state: State, figure: str, rates: tuple[float, float]) -> bool:
    if figure == "cusps":  # only the exact case: released from rest in α and β
        return state.alpha_dot0 == 0 and state.beta_dot0 == 0
    sizes = sorted(abs(r) for r in rates)
    return figure in OPTIONS and sizes[0] >= MIN_RATE_RATIO * sizes[1]


def _moment_mistakes_many(motions: list[tuple[Top, State]]) -> list[tuple]:
    """Each ``(top, state)``'s moment mistakes (their names), their solver arguments (columns,
    the key's first) and the turning points ``(β1, β2)`` of each: one solver call for all,
    done first since it is the cheap rejection test."""
    mistaken = [{k: v for k, v in mistaken_states(top, state).items() if k != "degree_mode"}
                for top, state in motions]
    rows = [np.array([state_args(top, state), *m.values()]).T
            for (top, state), m in zip(motions, mistaken, strict=True)]
    ends = np.cumsum([r.shape[1] for r in rows])[:-1]
    beta1, beta2 = (np.split(np.atleast_1d(b), ends)
                    for b in turning_points(*np.concatenate(rows, axis=1)))
    return list(zip(mistaken, rows, beta1, beta2, strict=True))


def _wrong_rates_many(moments: list[tuple]) -> list[tuple[list[float], list[float]]]:
    """The precession rates (R18) at ``β1`` and at ``β2`` of each motion's moment mistakes,
    from its :func:`_moment_mistakes_many` (the solver on the mistaken moments): the
    constants of all and their rates in one call each."""
    _, rows, beta1, beta2 = (list(part) for part in zip(*moments, strict=True))
    ends = np.cumsum([r.shape[1] for r in rows])[:-1]
    rows = np.concatenate(rows, axis=1)
    p_alpha, p_gamma, _ = constants_of_motion(*rows)
    at1, at2 = (np.split(np.atleast_1d(precession_rate(np.concatenate(b), rows[0], p_alpha,
                                                       p_gamma)), ends)
                for b in (beta1, beta2))
    return [(r1[1:].tolist(), r2[1:].tolist()) for r1, r2 in zip(at1, at2, strict=True)]


def _rate_answers(rates: tuple[float, float], names: tuple[str, ...],
                  wrong: tuple[list[float], list[float]]) -> list[Answer] | None:
    """``alpha_dot1``, ``alpha_dot2`` with their mistakes (None if confusable). ``wrong``:
    the rates at ``β1`` and at ``β2`` of the moment mistakes ``names``
    (:func:`_wrong_rates_many`)."""
    scale = max(abs(r) for r in rates)
    answers = []
    for i, name in enumerate(("alpha_dot1", "alpha_dot2")):
        key = rates[i]
        primary = {"turning_points_exchanged": rates[1 - i]}
        if key != 0:  # the cusp's exact zero has no sign to flip
            primary["sign_flipped"] = -key
        mistakes = select_mistakes(key, primary, dict(zip(names, wrong[i], strict=True)),
                                   atol=RTOL * scale, feedback=_FEEDBACK)
        if mistakes is None:
            return None
        answers.append(Answer(name, "scalar", key, unit="rad/s", rtol=RTOL, atol=RTOL * scale,
                              mistakes=mistakes,
                              description=f"precession rate α̇ at the turning point β{i + 1}"))
    return answers


@cache  # one of three, the same for every student (answers are immutable)
def _figure_answer(figure: str) -> Answer:
    mistakes = tuple(Mistake(f"said_{other}", other, _FIGURE_FEEDBACK[figure, other])
                     for other in OPTIONS if other != figure)
    return Answer("motion", "choice", figure, options=OPTIONS, mistakes=mistakes,
                  description='the figure the axis traces: "waves", "loops" or "cusps"',
                  depends_on=("alpha_dot1", "alpha_dot2"))


def _statement(top: Top, state: State) -> str:
    return (
        f"{top.text} {state_text(state)}\n\n"
        "1. `alpha_dot1`, `alpha_dot2`: the precession rate $\\dot\\alpha$ when the tilt is at "
        "the turning points $\\beta_1 \\le \\beta_2$ of the nutation;\n"
        "2. `motion`: the figure the symmetry axis traces on a sphere about the fixed point: "
        '`"waves"`, `"loops"` or `"cusps"`.'
    )


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A real top, a figure drawn (each equally often) and a state meant to trace it."""
    return draw_many([rng])[0]


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any]]:
    """:func:`draw` of each generator, the tops drawn together (:func:`draw_tops`; the batch
    form, :mod:`problems.family`)."""
    return [variant_params(top, _draw_state(rng, top, OPTIONS[int(rng.integers(len(OPTIONS)))]))
            for rng, top in zip(rngs, draw_tops(rngs), strict=True)]


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``alpha_dot1``, ``alpha_dot2`` and ``motion`` (R18), from
    :func:`solver.heavy_top.solve_heavy_top` on the shown (rounded) parameters.

    Raises :class:`~problems.family.IllPosed` for a motion outside the scene's limits, a figure
    the rounding of a turning point could change, or a primary mistake close to the key.
    """
    (found,) = answers_many([params])
    if isinstance(found, IllPosed):
        raise found
    return found


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): the turning points of every state,
    the solver's summary of every key inside the scene's limits (its exact α̇ = 0 at a cusp,
    and the figure), then the moment mistakes' rates of every unambiguous figure, each in one
    call."""
    motions = [(top_from_params(p), state_from_params(p)) for p in many]
    moments = _moment_mistakes_many(motions)
    inside = [i for i, ((top, _), (*_, beta1, beta2)) in enumerate(zip(motions, moments,
                                                                         strict=True))
              if motion_within_limits(top, float(beta1[0]), float(beta2[0]))]
    keys = {}
    if inside:
        table = solve_heavy_top_many(*np.array([state_args(*motions[i]) for i in inside]).T)
        keys = {i: _key(heavy_top_record(table, j)) for j, i in enumerate(inside)}
    posed = [i for i in inside
             if None not in keys[i][0] and _robust(motions[i][1], keys[i][1], keys[i][0])]
    wrong = dict(zip(posed, _wrong_rates_many([moments[i] for i in posed]) if posed else (),
                     strict=True))
    return [_answers(keys.get(i), moments[i][0], wrong.get(i)) for i in range(len(many))]


def _key(solution: dict) -> tuple[tuple[float | None, float | None], str]:
    """The rates at the turning points and the figure of the solver's summary of a motion."""
    return (solution["alpha_dot_beta1"], solution["alpha_dot_beta2"]), solution["motion"]


def _answers(key: tuple | None, mistaken: Mapping[str, Any],
             wrong: tuple[list[float], list[float]] | None) -> tuple[Answer, ...] | IllPosed:
    """One motion's answers from its :func:`_key` (None: outside the scene's limits) and its
    moment mistakes' rates (:func:`_wrong_rates_many`; None: an ambiguous figure), or why it
    is rejected."""
    if key is None:
        return IllPosed("the motion leaves the scene's limits")
    if wrong is None:
        return IllPosed("an ambiguous figure")
    rates, figure = key
    found = _rate_answers(rates, tuple(mistaken), wrong)
    if found is None:
        return IllPosed("a mistake close to the key")
    return (*found, _figure_answer(figure))


def heading(params: Mapping[str, Any]) -> str:
    return f"{top_from_params(params).title}: waves, loops or cusps?"


def statement(params: Mapping[str, Any]) -> str:
    return _statement(top_from_params(params), state_from_params(params))


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``motion`` from the student's own precession rates at the turning points (R18): a rate
    zero (within the answers' own tolerance, ``RTOL`` of the larger) makes cusps; rates of
    opposite signs, loops; else waves."""
    if name != "motion":
        raise LookupError(name)
    rates = (float(earlier["alpha_dot1"]), float(earlier["alpha_dot2"]))
    scale = max(abs(r) for r in rates)
    if scale == 0 or min(abs(r) for r in rates) <= RTOL * scale:
        return "cusps"
    return "loops" if rates[0] * rates[1] < 0 else "waves"


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's precession rates leave nothing to work out for ``motion`` (R18: the
    figure is read off the rates at the turning points): both zero (a top that never
    precesses traces no figure, and "cusps" follows), or one zero where the top's rate there
    is not (a cusp by fiat). None otherwise."""
    if name != "motion":
        raise LookupError(name)
    rates = [float(earlier[n]) for n in ("alpha_dot1", "alpha_dot2")]
    if not any(rates):
        return ("your {alpha_dot1} and {alpha_dot2} are both zero: a top that never precesses "
                "traces no figure, and {motion} follows with nothing of R18 worked out")
    solution = solve_heavy_top(*state_args(top_from_params(params), state_from_params(params)))
    key = (solution["alpha_dot_beta1"], solution["alpha_dot_beta2"])
    for n, rate, right in zip(("alpha_dot1", "alpha_dot2"), rates, key, strict=True):
        if rate == 0 and right:
            return (f"your {{{n}}} is zero where the top precesses, which makes {{motion}} "
                    "cusps with nothing of R18 worked out")
    return None
