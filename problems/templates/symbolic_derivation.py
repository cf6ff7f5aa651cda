"""A symbolic derivation for the heavy symmetric top (R14–R16, R18, R19), then a number.

Each variant asks for one of :data:`QUANTITIES`, drawn at random, as a sympy expression in named
symbols (graded by evaluation at random points), and then for its value for a real top
(:func:`~problems.templates.sleeping_top.draw_top`) at a given state (graded as a scalar):

``p_alpha``
    ``∂L/∂α̇ = I1 α̇ sin²β + I3 cos β (α̇ cos β + γ̇)`` from R14's Lagrangian (R15).
``p_gamma``
    ``∂L/∂γ̇ = I3 (α̇ cos β + γ̇)`` (R15).
``E_prime``
    ``E' = E − p_γ²/(2 I3) = ½ I1 (α̇² sin²β + β̇²) + Mgl cos β`` in the velocities (R16).
``V_eff``
    ``(p_α − p_γ cos β)²/(2 I1 sin²β) + Mgl cos β`` (R16).
``alpha_dot``
    The precession rate from the momenta, ``(p_α − p_γ cos β)/(I1 sin²β)`` (R18).
``c2``
    The coefficient of ``β²`` in ``V_eff`` of a top at ``p_α = p_γ`` near ``β = 0``,
    ``p_γ²/(8 I1) − Mgl/2`` (R19).

Every key is *derived* by :mod:`solver.symbolic` (about a second of sympy, kept between runs as
text by :func:`problems.derivation_cache.kept`). Each known mistake is the derivation redone
with the mistaken physics — a term dropped by the chain rule, ``β`` taken from the horizontal
(``sin``/``cos`` exchanged) or from the downward vertical (the sign of gravity), ``I1`` and
``I3`` swapped, the momenta exchanged, the factor ½ of ``1 − cos β ≈ β²/2`` lost — and the
numerical answer has the same mistakes evaluated at the state, plus ``β`` read as degrees. The
expressions and their ``lambdify``'d functions are cached per quantity, so drawing does no sympy
work beyond that.

Tolerances: the expression has ``rtol = 1e-6`` (a right formula agrees to rounding, ~1e-15; the
margin absorbs decimal coefficients such as ``0.5``; every mistake changes the value by far more
at generic points). The number has ``rtol = 1e-3``: one evaluation of a closed form with exact
3-figure data. Draws whose numerical mistakes come within ``MARGIN`` tolerances of the key or of
each other are resampled.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
import sympy as sp

from problems.answers import Answer, Mistake
from problems.derivation_cache import kept
from problems.family import Parameter, distinguishable
from problems.rounding import latex_sig, round_sig
from problems.templates.sleeping_top import Top, draw_top, top_moments
from solver.heavy_top import constants_of_motion, critical_spin
from solver.symbolic import (
    SYMBOLS,
    conjugate_momenta,
    effective_potential_expr,
    energy_expr,
    sleeping_top_expansion,
)

NAME = "symbolic_derivation"
TITLE = "A heavy-top derivation in symbols"
SUMMARY = "heavy top in symbols: p_α, p_γ, E', V_eff, α̇(β) or the sleeping-top β² coefficient"
RESULTS = ("R14", "R15", "R16", "R18", "R19")
CONVENTIONS = ('euler_angles', 'heavy_top')
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

SIG = 3
"""Significant figures of every displayed parameter."""
RTOL = 1e-3
RTOL_EXPRESSION = 1e-6
MARGIN = 5.0
"""Numerical mistakes must lie this many tolerances from the key and from each other."""
TILT = (0.2, 1.4)
"""β, rad."""
PRECESSION = (0.05, 0.4)
"""|α̇| as a fraction of γ̇."""
MAX_ATTEMPTS = 1000

S = SYMBOLS
_PARAM = {  # parameter name → (LaTeX symbol, unit shown, unit recorded)
    "I1": ("I_1", "kg m²", "kg m^2"),
    "I3": ("I_3", "kg m²", "kg m^2"),
    "Mgl": ("Mgl", "J", "J"),
    "beta": (r"\beta", "rad", "rad"),
    "alpha_dot": (r"\dot\alpha", "rad/s", "rad/s"),
    "beta_dot": (r"\dot\beta", "rad/s", "rad/s"),
    "gamma_dot": (r"\dot\gamma", "rad/s", "rad/s"),
    "p_alpha": (r"p_\alpha", "kg m²/s", "kg m^2/s"),
    "p_gamma": (r"p_\gamma", "kg m²/s", "kg m^2/s"),
}

# Mistakes shared by several quantities
_FROM_HORIZONTAL = ("sin β and cos β are exchanged: β is measured from the upward vertical "
                    "(the component of α̇ ẑ along ê₃ is α̇ cos β, R12).")
_GRAVITY_SIGN = ("The sign of the gravity term is wrong: with β from the upward vertical the "
                 "centre of mass is at height l cos β, so V = +Mgl cos β (R14).")
_SWAPPED = ("I1 and I3 are swapped: I3 is the moment about the symmetry axis ê₃ and goes with "
            "ω₃ = α̇ cos β + γ̇; I1 is the transverse moment about the tip.")
_MOMENTA_SWAPPED = ("p_α and p_γ are exchanged: it is p_α − p_γ cos β, from "
                    "p_α = I1 α̇ sin²β + p_γ cos β (R15).")


def _from_horizontal(expr: sp.Expr) -> sp.Expr:
    return expr.subs(S["beta"], sp.pi / 2 - S["beta"])


def _swap(expr: sp.Expr, a: str, b: str) -> sp.Expr:
    return expr.subs({S[a]: S[b], S[b]: S[a]}, simultaneous=True)


@cache
def _precession_rate() -> sp.Expr:
    """α̇ in terms of ``p_α, p_γ, β`` (R18), by inverting R15's momenta."""
    p = conjugate_momenta()
    eqs = [sp.Eq(S["p_alpha"], p["p_alpha"]), sp.Eq(S["p_gamma"], p["p_gamma"])]
    (solution,) = sp.solve(eqs, [S["alpha_dot"], S["gamma_dot"]], dict=True)
    numerator, denominator = sp.fraction(sp.factor(solution[S["alpha_dot"]]))
    if numerator.could_extract_minus_sign():  # print p_alpha - p_gamma*cos(beta) first
        numerator, denominator = -numerator, -denominator
    return sp.expand(numerator) / denominator


@cache
def _reduced_energy() -> sp.Expr:
    """``E' = E − p_γ²/(2 I3)`` in the velocities (R16)."""
    E_prime = energy_expr() - conjugate_momenta()["p_gamma"] ** 2 / (2 * S["I3"])
    kinetic, potential = sp.expand(E_prime).as_independent(S["I1"], as_Add=True)[::-1]
    return sp.factor(kinetic) + potential


def _p_alpha_mistakes(key: sp.Expr):
    I1, I3, beta = S["I1"], S["I3"], S["beta"]
    alpha_dot, gamma_dot = S["alpha_dot"], S["gamma_dot"]
    return (
        ("missing_spin_term", I1 * alpha_dot * sp.sin(beta) ** 2,
         "The spin term ½ I3 (α̇ cos β + γ̇)² of L also depends on α̇: it adds "
         "I3 cos β (α̇ cos β + γ̇) to p_α (R15)."),
        ("missing_chain_factor", I1 * alpha_dot * sp.sin(beta) ** 2
         + I3 * (alpha_dot * sp.cos(beta) + gamma_dot),
         "Chain rule: ∂/∂α̇ of ½ I3 (α̇ cos β + γ̇)² is I3 (α̇ cos β + γ̇) cos β — the factor "
         "cos β is missing."),
        ("sin_cos_swapped", _from_horizontal(key), _FROM_HORIZONTAL),
        ("I1_I3_swapped", _swap(key, "I1", "I3"), _SWAPPED),
    )


def _p_gamma_mistakes(key: sp.Expr):
    return (
        ("spin_only", S["I3"] * S["gamma_dot"],
         "ω₃ = α̇ cos β + γ̇ (R12): the precession also contributes to the spin about ê₃, so "
         "p_γ = I3 (α̇ cos β + γ̇)."),
        ("sin_cos_swapped", _from_horizontal(key), _FROM_HORIZONTAL),
        ("I1_I3_swapped", _swap(key, "I1", "I3"), _SWAPPED),
    )


def _energy_mistakes(key: sp.Expr):
    return (
        ("full_energy", energy_expr(),
         "That is the whole energy E; E' = E − p_γ²/(2 I3) leaves out the constant spin part "
         "(R16)."),
        ("gravity_sign", key - 2 * S["Mgl"] * sp.cos(S["beta"]), _GRAVITY_SIGN),
        ("sin_cos_swapped", _from_horizontal(key), _FROM_HORIZONTAL),
    )


def _potential_mistakes(key: sp.Expr):
    return (
        ("momenta_swapped", _swap(key, "p_alpha", "p_gamma"), _MOMENTA_SWAPPED),
        ("gravity_sign", key - 2 * S["Mgl"] * sp.cos(S["beta"]), _GRAVITY_SIGN),
        ("missing_half", key + (key - S["Mgl"] * sp.cos(S["beta"])),
         "The kinetic part is ½ I1 α̇² sin²β = (p_α − p_γ cos β)²/(2 I1 sin²β): the 2 in the "
         "denominator is missing."),
    )


def _rate_mistakes(key: sp.Expr):
    return (
        ("momenta_swapped", _swap(key, "p_alpha", "p_gamma"), _MOMENTA_SWAPPED),
        ("sin_not_squared", key * sp.sin(S["beta"]),
         "p_α − p_γ cos β = I1 α̇ sin²β: divide by I1 sin²β, not by I1 sin β."),
        ("sin_cos_swapped", _from_horizontal(key), _FROM_HORIZONTAL),
    )


def _c2_mistakes(key: sp.Expr):
    I1, Mgl, p_gamma = S["I1"], S["Mgl"], S["p_gamma"]
    return (
        ("gravity_sign", key + Mgl, "Mgl cos β ≈ Mgl (1 − β²/2): the gravity term lowers the β² "
                                    "coefficient by Mgl/2."),
        ("cos_expansion", p_gamma**2 / (2 * I1) - Mgl / 2,
         "1 − cos β ≈ β²/2, so (1 − cos β)²/sin²β ≈ β²/4: the spin term is p_γ² β²/(8 I1)."),
        ("missing_gravity", p_gamma**2 / (8 * I1),
         "Mgl cos β also contributes to β²: −Mgl β²/2."),
    )


@dataclass(frozen=True)
class Quantity:
    """One quantity to derive: its key, mistakes, symbols and what is shown."""

    name: str
    title: str
    task: str  # Markdown: what to derive
    unit: str
    symbols: tuple[str, ...]  # allowed in the expression, and the numeric parameters
    derive: Callable[[], sp.Expr]
    mistakes: Callable[[sp.Expr], tuple[tuple[str, sp.Expr, str], ...]]


QUANTITIES: tuple[Quantity, ...] = (
    Quantity("p_alpha", "The momentum conjugate to α",
             "$p_\\alpha = \\partial L/\\partial\\dot\\alpha$ in the Euler angles and rates",
             "kg m^2/s",
             ("I1", "I3", "beta", "alpha_dot", "gamma_dot"),
             lambda: conjugate_momenta()["p_alpha"], _p_alpha_mistakes),
    Quantity("p_gamma", "The momentum conjugate to γ",
             "$p_\\gamma = \\partial L/\\partial\\dot\\gamma$ in the Euler angles and rates",
             "kg m^2/s",
             ("I1", "I3", "beta", "alpha_dot", "gamma_dot"),
             lambda: conjugate_momenta()["p_gamma"], _p_gamma_mistakes),
    Quantity("E_prime", "The reduced energy E'",
             "$E' = E - p_\\gamma^2/(2 I_3)$ in the Euler angles and rates (not the momenta)",
             "J",
             ("I1", "I3", "Mgl", "beta", "alpha_dot", "beta_dot", "gamma_dot"),
             _reduced_energy, _energy_mistakes),
    Quantity("V_eff", "The effective potential",
             "$V_\\mathrm{eff}(\\beta)$, defined by "
             "$E' = \\tfrac12 I_1 \\dot\\beta^2 + V_\\mathrm{eff}(\\beta)$, in the momenta "
             "$p_\\alpha$, $p_\\gamma$", "J",
             ("I1", "Mgl", "beta", "p_alpha", "p_gamma"),
             effective_potential_expr, _potential_mistakes),
    Quantity("alpha_dot", "The precession rate from the momenta",
             "the precession rate $\\dot\\alpha(\\beta)$ in the momenta $p_\\alpha$, "
             "$p_\\gamma$", "rad/s",
             ("I1", "beta", "p_alpha", "p_gamma"), _precession_rate, _rate_mistakes),
    Quantity("c2", "The sleeping top's β² coefficient",
             "for $p_\\alpha = p_\\gamma$ (an axis through the vertical), $c_2$ in "
             "$V_\\mathrm{eff}(\\beta) = c_0 + c_2 \\beta^2 + O(\\beta^4)$", "J",
             ("I1", "Mgl", "p_gamma"), lambda: sleeping_top_expansion()[1], _c2_mistakes),
)


@dataclass(frozen=True)
class _Compiled:
    """A quantity's expression answer and numeric functions (built once per process)."""

    expression: Answer
    key: Callable[..., float]
    mistakes: tuple[tuple[str, Callable[..., float], str], ...]


@cache
def _compiled(index: int) -> _Compiled:
    q = QUANTITIES[index]
    texts = kept(f"{NAME}.{q.name}", [sys.modules[__name__]], lambda: _derived_texts(q))
    args = [S[name] for name in q.symbols]
    answer = Answer(
        f"{q.name}_expr", "expression", texts["key"], unit=q.unit, rtol=RTOL_EXPRESSION,
        symbols=q.symbols, description=f"{q.name} as an expression",
        mistakes=tuple(Mistake(n, e, f) for n, e, f in texts["mistakes"]),
    )
    numeric = tuple((n, sp.lambdify(args, _parsed(e), "math"), f)
                    for n, e, f in texts["mistakes"])
    return _Compiled(answer, sp.lambdify(args, _parsed(texts["key"]), "math"), numeric)


def _derived_texts(q: Quantity) -> dict[str, Any]:
    """``q``'s key and mistakes derived (:mod:`solver.symbolic`), as the text of each
    expression: what :func:`_compiled` keeps between runs
    (:func:`problems.derivation_cache.kept`)."""
    key = q.derive()
    return {"key": str(key), "mistakes": [[n, str(e), f] for n, e, f in q.mistakes(key)]}


def _parsed(text: str) -> sp.Expr:
    """A derived expression from its text (the same expression: ``str`` of one of
    :mod:`solver.symbolic`'s prints it so that it reads back unchanged)."""
    return sp.parse_expr(text, local_dict=dict(S))


def prepare() -> None:
    """Derive and compile every quantity (:func:`_compiled`) before the first draw;
    the generator calls it once, before forking its worker processes."""
    for index in range(len(QUANTITIES)):
        _compiled(index)


@dataclass(frozen=True)
class _Draws:
    """What one student's generator gives :func:`_states`, in the order it is drawn: a
    quantity, a real top, then the state's random numbers (unrounded)."""

    quantity: Quantity
    top: Top
    tilt: float  # β, rad
    spin: float  # γ̇ in critical spins
    precession: float  # |α̇| / γ̇
    sense: float  # of α̇, ±1
    nod: float  # |β̇|, rad/s
    nod_sense: float  # of β̇, ±1

    @classmethod
    def of(cls, rng: np.random.Generator) -> _Draws:
        q = QUANTITIES[int(rng.integers(len(QUANTITIES)))]
        top = draw_top(rng)
        tilt, spin = rng.uniform(*TILT), rng.uniform(1.5, 5.0)
        precession, sense = rng.uniform(*PRECESSION), rng.choice([-1.0, 1.0])
        return cls(q, top, tilt, spin, precession, sense, rng.uniform(0.3, 3.0),
                   rng.choice([-1.0, 1.0]))


def _states(draws: Sequence[_Draws]) -> list[dict[str, float]]:
    """Every parameter a quantity may need, for each student: a real top in a plausible state
    (rounded); the tops' moments (R2), critical spins (R19) and momenta (R15) of all at once."""
    I1, I3 = (round_sig(x, SIG) for x in top_moments([d.top for d in draws]))
    Mgl = round_sig(np.array([d.top.Mgl for d in draws]), SIG)
    beta = round_sig(np.array([d.tilt for d in draws]), SIG)
    critical = critical_spin(I1, I3, Mgl)
    gamma_dot = round_sig(np.array([float(w) * d.spin for w, d in zip(critical, draws,
                                                                     strict=True)]), SIG)
    # a knocked top: precessing at a good fraction of its spin (else α̇ cos β is lost beside γ̇
    # and p_γ ≈ I3 γ̇ hides the mistakes), either sense, and nodding
    alpha_dot = round_sig(np.array([d.precession * float(w) * d.sense
                                    for d, w in zip(draws, gamma_dot, strict=True)]), SIG)
    beta_dot = round_sig(np.array([d.nod * d.nod_sense for d in draws]), SIG)
    state = (I1, I3, Mgl, beta, alpha_dot, beta_dot, gamma_dot)
    p_alpha, p_gamma, _ = constants_of_motion(*state)
    names = ("I1", "I3", "Mgl", "beta", "alpha_dot", "beta_dot", "gamma_dot", "p_alpha",
             "p_gamma")
    columns = (*state, round_sig(p_alpha, SIG), round_sig(p_gamma, SIG))
    return [dict(zip(names, values, strict=True))
            for values in zip(*(c.tolist() for c in columns), strict=True)]


def _number_answer(q: Quantity, c: _Compiled, values: list[float]) -> Answer:
    mistakes = [Mistake(n, float(f(*values)), text) for n, f, text in c.mistakes]
    if "beta" in q.symbols:
        i = q.symbols.index("beta")
        in_degrees = [*values[:i], math.radians(values[i]), *values[i + 1:]]
        mistakes.append(Mistake("degrees", float(c.key(*in_degrees)),
                                "β is in radians; this value comes from reading it as degrees."))
    return Answer(q.name, "scalar", float(c.key(*values)), unit=q.unit, rtol=RTOL,
                  mistakes=tuple(m for m in mistakes if math.isfinite(m.value)),
                  description=f"{q.name} for the given top and state",
                  depends_on=(f"{q.name}_expr",))


def _statement(q: Quantity, params: dict[str, float]) -> str:
    names = ", ".join(f"`{n}`" for n in q.symbols)
    mgl = "; `Mgl` is one symbol" if "Mgl" in q.symbols else ""
    shown = ", ".join(f"${_PARAM[n][0]} = {latex_sig(v, SIG)}$ {_PARAM[n][1]} (`{n}`)"
                      for n, v in params.items())
    return (
        "A heavy symmetric top spins on a fixed tip; its Lagrangian (R14) is\n\n"
        "$$L = \\tfrac12 I_1 (\\dot\\alpha^2 \\sin^2\\beta + \\dot\\beta^2) + \\tfrac12 I_3 "
        "(\\dot\\alpha\\cos\\beta + \\dot\\gamma)^2 - Mgl\\cos\\beta .$$\n\n"
        f"1. `{q.name}_expr`: derive {q.task}, as a sympy expression or a string in {names} "
        f"(and `sin`, `cos`, `sqrt`, `pi`{mgl});\n"
        f"2. `{q.name}`: its value for {shown}."
    )


PARAMETERS: dict[str, Parameter] = {
    "quantity": Parameter(choices=tuple(q.name for q in QUANTITIES),
                          description="the quantity to derive"),
    **{name: Parameter(unit=unit, description=f"${symbol}$")
       for name, (symbol, _, unit) in _PARAM.items()},
}
"""The quantity, and the numbers it needs: those of its symbols (:attr:`Quantity.symbols`)."""


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A quantity of :data:`QUANTITIES`, and the values of its symbols for a real top in a
    plausible state (:func:`_states`)."""
    return draw_many([rng])[0]


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any]]:
    """:func:`draw` of each generator, the states of all worked out together (the batch
    form, :mod:`problems.family`)."""
    draws = [_Draws.of(rng) for rng in rngs]
    return [{"quantity": d.quantity.name, **{n: state[n] for n in d.quantity.symbols}}
            for d, state in zip(draws, _states(draws), strict=True)]


def _quantity(params: Mapping[str, Any]) -> tuple[Quantity, _Compiled]:
    index = next(i for i, q in enumerate(QUANTITIES) if q.name == params["quantity"])
    return QUANTITIES[index], _compiled(index)


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``<quantity>_expr`` (derived by :mod:`solver.symbolic`) and ``<quantity>``, its value
    at the shown parameters.

    Raises :class:`~problems.family.IllPosed` when a numerical mistake is close to the key.
    """
    q, c = _quantity(params)
    values = [params[n] for n in q.symbols]
    (number,) = distinguishable(lambda: (_number_answer(q, c, values),), MARGIN)
    return (c.expression, number)


def heading(params: Mapping[str, Any]) -> str:
    return _quantity(params)[0].title


def statement(params: Mapping[str, Any]) -> str:
    q, _ = _quantity(params)
    return _statement(q, {n: params[n] for n in q.symbols})


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """The value from the student's own expression, evaluated at the given parameters
    (:func:`problems.expressions.evaluate_expression`: parsed within its limits, never run)."""
    from problems.expressions import evaluate_expression

    q, _ = _quantity(params)
    if name != q.name:
        raise LookupError(name)
    points = {n: np.array([float(params[n])]) for n in q.symbols}
    return float(evaluate_expression(str(earlier[f"{q.name}_expr"]), q.symbols, points)[0])


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's expression leaves nothing to work out for its value: it has none of the
    symbols (a number, not a derivation from R14's Lagrangian), or it is one symbol alone (its
    value a number of the statement copied). None otherwise."""
    from problems.expressions import parse_expression

    q, _ = _quantity(params)
    if name != q.name:
        raise LookupError(name)
    expression = f"{q.name}_expr"
    expr = parse_expression(str(earlier[expression]), q.symbols)
    if not expr.free_symbols:
        return (f"your {{{expression}}} has none of the symbols: a number, not a derivation "
                f"from R14's Lagrangian, so {{{name}}} from it shows nothing")
    if expr.is_Symbol:
        return (f"your {{{expression}}} is one given symbol alone, which makes {{{name}}} a "
                "number of the statement copied, nothing derived from R14's Lagrangian")
    return None
