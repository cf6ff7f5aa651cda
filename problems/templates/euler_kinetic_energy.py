"""Rotational kinetic energy in Euler angles: a number, and the symmetric top's expression (R13).

Two scenes, drawn at random:

``toy_top``
    A toy top (a disc of 2–5 cm radius and 30–100 g on a light axle, the disc 2–6 cm above the
    tip): principal moments ``I1`` (about the tip, R2's disc plus the parallel-axis term) and
    ``I3``, shown to 3 significant figures, with the Euler angles and rates of a top spinning at
    60–150 rad/s.
``tumbling_box``
    A smartphone or a book tossed in the air, a uniform box (R2) with ``I1 < I2 < I3``, tumbling
    at rates of up to 15 rad/s.

Answers: ``T``, the number from R13 (``½ Σ I_i ω_i²`` with R12's ω), and ``T_expr``, the
symmetric top's ``T`` as an expression in ``I1, I3, beta, alpha_dot, beta_dot, gamma_dot``,
derived by :func:`solver.symbolic.kinetic_energy_euler_expr` with ``I2 = I1``.

Known mistakes: the missing ½, a calculator in degree mode, the rates taken as the components of
ω, two moments swapped (for the expression: ``I1`` and ``I3``), the cross term of
``(α̇ cos β + γ̇)²`` dropped, and ``sin β``/``cos β`` exchanged (β taken from the horizontal).

Tolerance: ``T`` has ``rtol = 1e-3`` (the moments are exact 3-figure inputs; 4 figures kept in
the working suffice). The expression is compared at sample points with ``rtol = 1e-6``: a right
formula agrees to rounding error (≈1e-15), so the tolerance only has to absorb a decimal
coefficient such as ``0.5``; any wrong term changes the values by far more at generic points.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from functools import cache
from typing import Any

import numpy as np
import sympy as sp

from problems.answers import Answer, Mistake
from problems.derivation_cache import kept
from problems.family import IllPosed, Parameter, drawn_scene, reject_unless
from problems.rounding import latex_sig, round_sig
from solver.euler_angles import kinetic_energy_euler
from solver.inertia import parallel_axis, shape_tensor
from solver.parameters import principal_moments
from solver.symbolic import SYMBOLS, kinetic_energy_euler_expr

NAME = "euler_kinetic_energy"
TITLE = "Kinetic energy in Euler angles"
SUMMARY = "kinetic energy from Euler angles and rates: a number, and the symmetric top's formula"
RESULTS = ("R12", "R13")

RTOL = 1e-3
RTOL_EXPRESSION = 1e-6
SEPARATION = 5.0  # key and mistakes at least this many tolerances apart
MAX_TRIES = 200
EXPRESSION_SYMBOLS = ("I1", "I3", "beta", "alpha_dot", "beta_dot", "gamma_dot")

# Boxes tossed in the air: (a, b, c ranges in m, mass range in kg).
BOXES = {
    "smartphone": ((0.14, 0.17), (0.065, 0.08), (0.007, 0.01), (0.14, 0.22)),
    "book": ((0.20, 0.30), (0.13, 0.21), (0.015, 0.05), (0.4, 1.5)),
}

_HALF = "T = ½ Σ I_i ω_i² (R13): the factor ½ is missing."
_DEGREE_MODE = (
    "The angles are in radians, but this value comes from reading them as degrees (a calculator "
    "in degree mode, or numpy.deg2rad applied to radians)."
)
_RATES = (
    "The Euler-angle rates are not the components of ω: ω = α̇ ẑ + β̇ ê'₂ + γ̇ ê₃ along three "
    "non-orthogonal axes; take its body components from R12 before using T = ½ Σ I_i ω_i²."
)
CONVENTIONS = ("euler_angles",)
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""
_OMEGA3_IS_GAMMA_DOT = (
    "ω₃ = γ̇ + α̇ cos β (R12): this value takes ω₃ = γ̇, leaving out the precession's "
    "component α̇ cos β along ê₃."
)
_EXPRESSION_TASK = (
    "`T_expr`: for a **symmetric** body ($I_2 = I_1$), $T$ as an expression in "
    "`I1, I3, beta, alpha_dot, beta_dot, gamma_dot` (sympy, or a string such as "
    "`\"I1*beta_dot**2/2 + ...\"`)."
)


@cache
def _symmetric_top_energy() -> sp.Expr:
    """The symmetric top's ``T`` (R13 with ``I2 = I1``), derived by :mod:`solver.symbolic`.

    Simplified term by term in the moments, which gives the textbook form
    ``I1 (α̇² sin²β + β̇²)/2 + I3 (α̇ cos β + γ̇)²/2`` (γ drops out).
    """
    S = SYMBOLS
    T = kinetic_energy_euler_expr().subs(S["I2"], S["I1"])
    parts = sp.collect(sp.expand(T), [S["I1"], S["I3"]], evaluate=False)
    return sp.Add(*(k * sp.factor(sp.trigsimp(v)) for k, v in parts.items()))


@cache
def _expression_answer() -> Answer:
    texts = kept(f"{NAME}.T_expr", [sys.modules[__name__]], _derived_texts)
    return Answer(
        "T_expr", "expression", texts["key"], unit="J", rtol=RTOL_EXPRESSION, points=1.0,
        symbols=EXPRESSION_SYMBOLS, description="T of a symmetric top (I2 = I1) in Euler angles",
        mistakes=tuple(Mistake(n, e, f) for n, e, f in texts["mistakes"]),
    )


def _derived_texts() -> dict[str, Any]:
    """The symmetric top's ``T`` (:func:`_symmetric_top_energy`) and its mistakes, as the text
    of each expression: what :func:`_expression_answer` keeps between runs
    (:func:`problems.derivation_cache.kept`)."""
    S = SYMBOLS
    I1, I3, beta = S["I1"], S["I3"], S["beta"]
    T = _symmetric_top_energy()
    mistakes = (
        ("missing_half", 2 * T, _HALF),
        ("I1_I3_swapped", T.subs({I1: I3, I3: I1}, simultaneous=True),
         "I1 and I3 are swapped: I3 is the moment about the symmetry axis ê₃, so it multiplies "
         "ω₃² = (α̇ cos β + γ̇)²."),
        ("missing_cross_term", T - I3 * S["alpha_dot"] * S["gamma_dot"] * sp.cos(beta),
         "(α̇ cos β + γ̇)² has a cross term 2 α̇ γ̇ cos β: square the sum, not each term."),
        ("sin_cos_swapped", T.subs(beta, sp.pi / 2 - beta),
         "sin β and cos β are exchanged: β is measured from the upward vertical, so the "
         "component of α̇ ẑ along ê₃ is α̇ cos β (R12)."),
    )
    return {"key": str(T), "mistakes": [[n, str(e), f] for n, e, f in mistakes]}


def prepare() -> None:
    """Derive the expression answer (about a third of a second of sympy, kept between runs:
    :func:`problems.derivation_cache.kept`) before the first draw; the generator calls it once,
    before forking its worker processes."""
    _expression_answer()


def _energy_states(moments, angles, rates, swap: tuple[int, int]) -> list[tuple[float, ...]]:
    """The states ``(I1, I2, I3, β, γ, α̇, β̇, γ̇)`` whose ``T`` :func:`_energy_answer` takes:
    the key's, the angles read as degrees, the moments ``swap`` exchanged, and the state whose
    ω3 = γ̇' + α̇ cos β equals the given γ̇ (R12: ω3 taken to be γ̇)."""
    beta, gamma = angles
    swapped = list(moments)
    swapped[swap[0]], swapped[swap[1]] = swapped[swap[1]], swapped[swap[0]]
    alpha_dot, beta_dot, gamma_dot = rates
    return [(*moments, beta, gamma, *rates), (*moments, *np.radians(angles), *rates),
            (*swapped, beta, gamma, *rates),
            (*moments, beta, gamma, alpha_dot, beta_dot, gamma_dot - alpha_dot * np.cos(beta))]


def _energies(states: Sequence[tuple[float, ...]]) -> list[float]:
    """``T`` of each of ``states`` (R13), in one solver call."""
    return kinetic_energy_euler(*np.array(states, dtype=float).T).tolist()


def _energy_answer(moments, rates, swap: tuple[int, int], energies: Sequence[float]
                   ) -> Answer | None:
    """``T`` with its mistakes, from :func:`_energies` of :func:`_energy_states`, or None if
    two of them are within SEPARATION tolerances."""
    T, in_degrees, swapped, spin_only = energies
    names = ("I1", "I2", "I3")
    pair = f"{names[swap[0]]}_{names[swap[1]]}_swapped"
    mistakes = (
        ("missing_half", 2 * T, _HALF),
        ("degree_mode", in_degrees, _DEGREE_MODE),
        ("rates_as_components", 0.5 * float(np.dot(moments, np.square(rates))), _RATES),
        (pair, swapped,
         f"{names[swap[0]]} and {names[swap[1]]} are swapped: I_i multiplies ω_i², the square "
         "of the component along the same principal axis ê_i."),
    )
    values = np.array([T, *(v for _, v, _ in mistakes)])
    gaps = np.abs(values[:, None] - values[None, :])
    if np.min(gaps[~np.eye(len(values), dtype=bool)]) <= SEPARATION * RTOL * abs(T):
        return None
    # ω3 taken to be γ̇ (R12): kept where it is clear of the key and the other mistakes; the
    # draw is not rejected for it.
    if np.min(np.abs(values - spin_only)) > SEPARATION * RTOL * abs(T):
        mistakes += (("omega3_is_gamma_dot", spin_only, _OMEGA3_IS_GAMMA_DOT),)
    return Answer("T", "scalar", T, unit="J", rtol=RTOL, description="kinetic energy",
                  mistakes=tuple(Mistake(n, v, f) for n, v, f in mistakes))


_NAMES = ("beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot")


def _toy_top(rng: np.random.Generator) -> dict[str, Any]:
    """A toy top's moments about its tip (3 figures), Euler angles and rates."""
    M, R = rng.uniform(0.03, 0.1), rng.uniform(0.02, 0.05)
    h = rng.uniform(0.02, 0.06)
    about_tip = parallel_axis(shape_tensor("disc", M, radius=R), M, [0.0, 0.0, h])
    I1, I3 = round_sig(np.diag(about_tip)[[0, 2]], 3)
    angles = (round_sig(rng.uniform(0.1, 1.3), 3), round_sig(rng.uniform(0.1, 6.2), 3))
    rates = round_sig([rng.uniform(1.0, 6.0), rng.uniform(-2.0, 2.0), rng.uniform(60, 150)], 3)
    return {"scene": "toy_top", "I1": float(I1), "I3": float(I3),
            **dict(zip(_NAMES, map(float, (*angles, *rates)), strict=True))}


def _tumbling_box(rng: np.random.Generator) -> dict[str, Any]:
    """A smartphone's or book's principal moments (3 figures), Euler angles and rates."""
    kind = list(BOXES)[int(rng.integers(len(BOXES)))]
    *edges, mass_range = BOXES[kind]
    dims = dict(zip("abc", (rng.uniform(*r) for r in edges), strict=True))
    moments = round_sig(np.diag(shape_tensor("box", rng.uniform(*mass_range), **dims)), 3)
    principal_moments(*moments)  # a physical body (R4); guards the sampling ranges
    angles = tuple(round_sig([rng.uniform(0.2, 2.9), rng.uniform(0.1, 6.2)], 3))
    rates = round_sig(rng.uniform(-15.0, 15.0, size=3), 3)
    return {"scene": "tumbling_box", "box": kind,
            **dict(zip(("I1", "I2", "I3"), map(float, moments), strict=True)),
            **dict(zip(_NAMES, map(float, (*angles, *rates)), strict=True))}


def _moments(params: Mapping[str, Any]) -> tuple[tuple[float, float, float], tuple[int, int]]:
    """``(I1, I2, I3)`` and the pair a student may swap: ``I1, I3`` of the symmetric toy top
    (``I2 = I1``), ``I1, I2`` of a box."""
    if params["scene"] == "toy_top":
        return (params["I1"], params["I1"], params["I3"]), (0, 2)
    return (params["I1"], params["I2"], params["I3"]), (0, 1)


def _body_text(params: Mapping[str, Any]) -> str:
    I1, I3 = latex_sig(params["I1"], 3), latex_sig(params["I3"], 3)
    if params["scene"] == "toy_top":
        return (
            "A toy top spins on a fixed tip. Its principal moments about the tip are "
            f"$I_1 = I_2 = {I1}$ kg m² (`I1`) and $I_3 = {I3}$ kg m² (`I3`, about the symmetry "
            "axis)."
        )
    return (
        f"A {params['box']} tumbles in the air. Its principal moments about the centre of mass "
        f"are $I_1 = {I1}$ kg m² (`I1`), $I_2 = {latex_sig(params['I2'], 3)}$ kg m² (`I2`) and "
        f"$I_3 = {I3}$ kg m² (`I3`)."
    )


SCENES = {"toy_top": _toy_top, "tumbling_box": _tumbling_box}

PARAMETERS: dict[str, Parameter] = {
    "scene": Parameter(choices=tuple(SCENES), description="a toy top, or a tumbling box"),
    "box": Parameter(choices=tuple(BOXES), description="the box's object"),
    **{f"I{i}": Parameter(unit="kg m^2", description=f"principal moment I{i}") for i in (1, 2, 3)},
    "beta": Parameter(unit="rad", description="Euler angle β"),
    "gamma": Parameter(unit="rad", low=0.1, high=6.2, description="Euler angle γ"),
    **{n: Parameter(unit="rad/s", description=f"rate of {n[:-4]}") for n in _NAMES[2:]},
}


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A scene of :data:`SCENES`: its moments, Euler angles and rates."""
    return SCENES[drawn_scene(SCENES, rng)](rng)


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``T`` (R12, R13) from the shown values, and ``T_expr``, the symmetric top's ``T``
    derived by :mod:`solver.symbolic`.

    Raises :class:`~problems.family.IllPosed` when two of ``T``'s mistakes are close.
    """
    moments, angles, rates, swap = _question(params)
    return _answers(moments, rates, swap, _energies(_energy_states(moments, angles, rates, swap)))


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): the kinetic energies of every
    student's key and mistaken states in one solver call."""
    questions = [_question(p) for p in many]
    states = [s for moments, angles, rates, swap in questions
              for s in _energy_states(moments, angles, rates, swap)]
    energies = _energies(states) if states else []
    found: list[tuple[Answer, ...] | IllPosed] = []
    for i, (moments, _, rates, swap) in enumerate(questions):
        try:
            found.append(_answers(moments, rates, swap, energies[4 * i:4 * i + 4]))
        except IllPosed as e:
            found.append(e)
    return found


def _answers(moments: np.ndarray, rates: np.ndarray, swap: tuple[int, int],
             energies: Sequence[float]) -> tuple[Answer, ...]:
    energy = _energy_answer(moments, rates, swap, energies)
    reject_unless(energy is not None, "two known mistakes of T are close")
    return (energy, _expression_answer())


def _question(params: Mapping[str, Any]) -> tuple[np.ndarray, tuple, np.ndarray, tuple]:
    """The shown moments, angles and rates, and the pair of moments a student may swap."""
    moments, swap = _moments(params)
    angles = (params["beta"], params["gamma"])
    return np.array(moments, dtype=float), angles, np.array([params[n] for n in _NAMES[2:]]), swap


def heading(params: Mapping[str, Any]) -> str:
    if params["scene"] == "toy_top":
        return "A spinning toy top"
    return f"A tumbling {params['box']}"


def statement(params: Mapping[str, Any]) -> str:
    symbols = (r"\beta", r"\gamma", r"\dot\alpha", r"\dot\beta", r"\dot\gamma")
    shown = ", ".join(f"${s} = {latex_sig(params[n], 3)}$ {PARAMETERS[n].unit} (`{n}`)"
                      for s, n in zip(symbols, _NAMES, strict=True))
    return (
        f"{_body_text(params)} At one instant its Euler angles and rates are {shown}.\n\n"
        "1. `T`: its kinetic energy at that instant;\n"
        f"2. {_EXPRESSION_TASK}"
    )
