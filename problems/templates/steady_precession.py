"""Steady precession of a gyroscope: the slow and fast rates and the fast-top approximation (R21).

A real top (:func:`~problems.templates.sleeping_top.draw_top`) is described by its data sheet:
mass ``M``, distance ``l`` from the pivot to the centre of mass, transverse moment ``Icm`` about
the centre of mass, axial moment ``I3``, and ``g``; it spins at ``ω3`` with its axis at the tilt
``β0`` (above the horizontal). The student forms ``I1 = Icm + M l²`` (about the pivot, R2) and
``p_γ = I3 ω3`` (R15). Asked:

``slow``, ``fast``
    The two steady-precession rates ``[p_γ ∓ √(p_γ² − 4 I1 Mgl cos β0)]/(2 I1 cos β0)`` (R21).
``slow_approx``, ``fast_approx``
    Their fast-top approximations ``Mgl/p_γ`` and ``p_γ/(I1 cos β0)`` (R21).
``slow_error``
    The relative error of the slow approximation, ``(slow_approx − slow)/slow`` (negative).

The key comes from :func:`solver.heavy_top.steady_precession_rates` (cancellation-free) and
:func:`solver.heavy_top.fast_top_rates`.

Known mistakes (computed by those functions from the mistaken inputs): ``I1`` about the centre
of mass, ``I1`` and ``I3`` swapped, ``β0`` read as degrees, Hz for rad/s, slow and fast
exchanged, the fast-top approximation where the exact rate was asked (and the exact rate where
the approximation was asked), the 2 of the quadratic formula's denominator dropped; for the
relative error: the opposite sign, the error relative to the approximation, a percentage.

Sampling: ``s = p_γ²/(4 I1 Mgl cos β0)`` in ``STIFFNESS`` (1.25 to 30): both roots real with a
margin (``s ≥ 1.25``: the discriminant is at least a fifth of ``p_γ²``), and a top slow enough
that the fast-top approximation is off by ≳ 1/(4s) ≥ 0.8 % — distinguishable from the exact
rate at the tolerance. ``β0`` in (0.25, 1.35) rad keeps ``cos β0`` well away from 0.

Tolerances: the rates and approximations have ``rtol = 1e-3`` (closed forms of 3-figure
data; the textbook form of the slow root loses ``log10(4s)`` ≤ 2.1 digits to cancellation,
harmless in double precision). ``slow_error`` is a difference of nearly equal numbers; its
absolute error is the student's relative error in ``slow`` (≲ 1e-13 in floating point), so
``rtol = 1e-3`` of a value ≥ 8e-3 in magnitude is ample.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from problems.answers import Answer, Mistake
from problems.family import IllPosed, Parameter, distinguishable, reject_unless
from problems.genuine import SAME
from problems.rounding import latex_sig, round_sig
from problems.templates.sleeping_top import TOP_KINDS, TOP_PARAMETERS, draw_top
from solver.heavy_top import fast_top_rates, steady_precession_rates

NAME = "steady_precession"
TITLE = "Steady precession of a gyroscope: exact rates and the fast-top approximation"
SUMMARY = "steady precession: slow and fast rates, fast-top approximations and their error"
RESULTS = ("R2", "R15", "R21")
CONVENTIONS = ('euler_angles', 'heavy_top')
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

SIG = 3
"""Significant figures of every displayed parameter."""
RTOL = 1e-3
MARGIN = 5.0
"""Known mistakes must lie this many tolerances from the key and from each other."""
STIFFNESS = (1.25, 30.0)
"""``p_γ²/(4 I1 Mgl cos β0)``: above 1 both steady rates are real (R21)."""
TILT = (0.25, 1.35)
"""β0, rad."""
MAX_ATTEMPTS = 1000

_DEGREES = "β0 is in radians; this value comes from reading it as degrees."
_HZ = ("That is the rate in revolutions per second (divided by 2π); give the angular velocity "
       "in rad/s.")
_I1_CM = ("I1 must be the transverse moment about the pivot, not about the centre of mass: "
          "I1 = Icm + M l² (parallel-axis theorem, R2).")
_SWAPPED = ("I1 and I3 are swapped: p_γ = I3 ω3 uses the moment about the symmetry axis, the "
            "quadratic's leading coefficient I1 cos β0 the transverse moment about the pivot.")
_FACTOR_2 = ("The quadratic formula divides by 2a: α̇ = [p_γ ± √(p_γ² − 4 I1 Mgl cos β0)] / "
             "(2 I1 cos β0) (R21).")


class _Rates(NamedTuple):
    """Exact and fast-top rates ``(slow, fast)`` for a (possibly mistaken) set of inputs."""

    exact: tuple[float, float]
    approx: tuple[float, float]


def _rates_many(inputs: Sequence[tuple[float, ...]]) -> list[_Rates]:
    """:class:`_Rates` of each ``(I1, I3, Mgl, β0, ω3)`` (R21, ``p_γ = I3 ω3``), the solver
    called once for all of them (element by element what one set alone gives)."""
    I1, I3, Mgl, beta0, omega3 = np.array(inputs, dtype=float).T
    p_gamma = I3 * omega3
    exact = np.stack(steady_precession_rates(I1, I3, Mgl, beta0, p_gamma), axis=-1).tolist()
    approx = np.stack(fast_top_rates(I1, I3, Mgl, beta0, p_gamma), axis=-1).tolist()
    return [_Rates(tuple(e), tuple(a)) for e, a in zip(exact, approx, strict=True)]


_WRONG = {"I1_about_cm": _I1_CM, "I1_I3_swapped": _SWAPPED, "degrees": _DEGREES}
"""The mistaken inputs of :func:`_inputs` after the key's, in order, and their feedback."""


def _inputs(M, arm, Icm, I3, g, beta0, omega3) -> list[tuple[float, ...]]:
    """The key's ``(I1, I3, Mgl, β0, ω3)`` (``I1 = Icm + M l²``, R2), then those of
    :data:`_WRONG`: I1 about the centre of mass, I1 and I3 swapped, β0 read as degrees."""
    Mgl, I1 = M * g * arm, Icm + M * arm**2
    return [(I1, I3, Mgl, beta0, omega3), (Icm, I3, Mgl, beta0, omega3),
            (I3, I1, Mgl, beta0, omega3), (I1, I3, Mgl, math.radians(beta0), omega3)]


def _finite(mistakes: list[Mistake]) -> tuple[Mistake, ...]:
    return tuple(m for m in mistakes if math.isfinite(m.value))


def _answers(rates: Sequence[_Rates]) -> tuple[Answer, ...]:
    """The answers from :func:`_rates_many` of :func:`_inputs`."""
    key = rates[0]
    wrong = {name: (r, text) for (name, text), r in zip(_WRONG.items(), rates[1:], strict=True)}
    answers = []
    for i, which in enumerate(("slow", "fast")):
        exact, approx = key.exact[i], key.approx[i]
        mistakes = [
            Mistake("slow_fast_exchanged", key.exact[1 - i], "Slow and fast are exchanged: the "
                    "slow rate takes the minus sign, the fast one the plus sign (R21)."),
            Mistake("fast_top", approx, "That is the fast-top approximation; the exact root of "
                    "I1 cos β0 α̇² − p_γ α̇ + Mgl = 0 (R21) is asked."),
            Mistake("hz", exact / (2 * math.pi), _HZ),
            Mistake("missing_factor_2", 2 * exact, _FACTOR_2),
            # the slow rate is Mgl/p_γ·(1 + O(1/s)): I1 and β0 enter only at order 1/s, so
            # those mistakes are indistinguishable from the key or from `fast_top`
            *(Mistake(name, rates.exact[i], text) for name, (rates, text) in wrong.items()
              if i == 1 or name == "I1_I3_swapped"),
        ]
        answers.append(Answer(which, "scalar", exact, unit="rad/s", rtol=RTOL,
                              mistakes=_finite(mistakes),
                              description=f"{which} steady precession rate (exact)"))
    for i, which in enumerate(("slow", "fast")):
        mistakes = [
            Mistake("exact", key.exact[i], "That is the exact rate; the fast-top approximation "
                    f"({'Mgl/p_γ' if i == 0 else 'p_γ/(I1 cos β0)'}, R21) is asked."),
            Mistake("hz", key.approx[i] / (2 * math.pi), _HZ),
            *(Mistake(name, rates.approx[i], text) for name, (rates, text) in wrong.items()
              if i == 1 or name == "I1_I3_swapped"),  # Mgl/p_γ has neither I1 nor β0
        ]
        answers.append(Answer(f"{which}_approx", "scalar", key.approx[i], unit="rad/s",
                              rtol=RTOL, mistakes=_finite(mistakes), points=0.5,
                              description=f"fast-top approximation of the {which} rate"))
    error = (key.approx[0] - key.exact[0]) / key.exact[0]
    mistakes = (
        Mistake("sign", -error, "Relative error here means (approximation − exact)/exact: the "
                "approximation is below the exact slow rate, so the error is negative."),
        Mistake("relative_to_approx", (key.approx[0] - key.exact[0]) / key.approx[0],
                "Divide by the exact value, not by the approximation."),
        Mistake("percent", 100 * error, "Give the relative error as a plain fraction, not in "
                "percent."),
    )
    answers.append(Answer("slow_error", "scalar", error, rtol=RTOL, mistakes=mistakes,
                          description="(slow_approx − slow)/slow",
                          depends_on=("slow", "slow_approx")))
    return tuple(answers)


def _statement(noun: str, p: Mapping[str, Any]) -> str:
    def show(name: str, symbol: str, unit: str) -> str:
        return f"${symbol} = {latex_sig(p[name], SIG)}$ {unit} (`{name}`)"

    icm = show("Icm", r"I_\mathrm{cm}", "kg m²")
    omega3, beta0 = show("omega3", r"\omega_3", "rad/s"), show("beta0", r"\beta_0", "rad")
    return (
        f"A top, {noun}, spins on a fixed pivot: mass {show('M', 'M', 'kg')}, centre of mass "
        f"{show('l', 'l', 'm')} from the pivot, {icm} about a transverse axis through the "
        f"centre of mass, {show('I3', 'I_3', 'kg m²')} about the symmetry axis; "
        f"{show('g', 'g', 'm/s²')}. It spins at {omega3}, its axis tilted at {beta0}. For "
        "steady precession at that tilt, find:\n\n"
        "1. `slow`, `fast`: the exact slow and fast precession rates;\n"
        "2. `slow_approx`, `fast_approx`: their fast-top approximations;\n"
        "3. `slow_error`: (`slow_approx` − `slow`)/`slow`, with its sign."
    )


PARAMETERS: dict[str, Parameter] = {
    "top": TOP_PARAMETERS["top"],
    "M": Parameter(unit="kg", description="mass"),
    "l": Parameter(unit="m", description="pivot to centre of mass"),
    "Icm": Parameter(unit="kg m^2", description="transverse moment about the centre of mass"),
    "I3": Parameter(unit="kg m^2", description="moment about the symmetry axis"),
    "g": TOP_PARAMETERS["g"],
    "omega3": Parameter(unit="rad/s", description="spin"),
    "beta0": Parameter(unit="rad", low=TILT[0], high=TILT[1], description="tilt"),
}


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A real top's data sheet (rounded), the tilt, and a spin whose stiffness
    ``p_γ²/(4 I1 Mgl cos β0)`` is drawn in :data:`STIFFNESS`."""
    top = draw_top(rng)
    M, arm, Icm, I3 = (round_sig(x, SIG) for x in (top.M, top.arm, top.I_cm, top.I3))
    beta0 = round_sig(rng.uniform(*TILT), SIG)
    I1, Mgl = Icm + M * arm**2, M * top.g * arm
    spin = 2.0 * math.sqrt(rng.uniform(*STIFFNESS) * I1 * Mgl * math.cos(beta0)) / I3
    return {"top": top.kind.shape, "M": M, "l": arm, "Icm": Icm, "I3": I3, "g": top.g,
            "omega3": round_sig(spin, SIG), "beta0": beta0}


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``slow``, ``fast``, their fast-top approximations and ``slow_error`` (R21), from the
    shown parameters (``I1 = Icm + M l²``, R2).

    Raises :class:`~problems.family.IllPosed` when the rounding moved the stiffness out of
    :data:`STIFFNESS`, or a known mistake is close to the key.
    """
    inputs = _posed_inputs(params)
    return distinguishable(lambda: _answers(_rates_many(inputs)), MARGIN)


def _posed_inputs(params: Mapping[str, Any]) -> list[tuple[float, ...]]:
    """:func:`_inputs` of the shown parameters; IllPosed when the rounding moved the stiffness
    out of :data:`STIFFNESS`."""
    M, arm, Icm, I3, g, omega3, beta0 = (params[n] for n in ("M", "l", "Icm", "I3", "g",
                                                              "omega3", "beta0"))
    I1, Mgl = Icm + M * arm**2, M * g * arm
    stiffness = (I3 * omega3) ** 2 / (4 * I1 * Mgl * math.cos(beta0))
    reject_unless(STIFFNESS[0] <= stiffness <= STIFFNESS[1], "stiffness out of range")
    return _inputs(M, arm, Icm, I3, g, beta0, omega3)


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): the exact and fast-top rates of every
    student's key and mistaken inputs in one solver call each."""
    posed: list[list[tuple[float, ...]] | IllPosed] = []
    for params in many:
        try:
            posed.append(_posed_inputs(params))
        except IllPosed as e:
            posed.append(e)
    inputs = [row for p in posed if not isinstance(p, IllPosed) for row in p]
    rates = iter(_rates_many(inputs) if inputs else ())
    found: list[tuple[Answer, ...] | IllPosed] = []
    for p in posed:
        try:
            if isinstance(p, IllPosed):
                raise p
            mine = [next(rates) for _ in p]
            found.append(distinguishable(lambda mine=mine: _answers(mine), MARGIN))
        except IllPosed as e:
            found.append(e)
    return found


def statement(params: Mapping[str, Any]) -> str:
    noun = next(k.noun for k in TOP_KINDS if k.shape == params["top"])
    return _statement(noun, params)


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``slow_error`` from the student's own slow rate and its approximation, as the statement
    defines it: (``slow_approx`` − ``slow``)/``slow``."""
    if name != "slow_error":
        raise LookupError(name)
    slow, approx = float(earlier["slow"]), float(earlier["slow_approx"])
    return (approx - slow) / slow


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's rates leave nothing to work out for ``slow_error`` (R21: the fast-top
    approximation is off the exact slow rate by ≳ 1/(4s), never nothing): ``slow`` zero (no
    relative error of it), or ``slow`` and ``slow_approx`` the same number (the error is then
    zero, nothing compared). None otherwise."""
    if name != "slow_error":
        raise LookupError(name)
    slow, approx = float(earlier["slow"]), float(earlier["slow_approx"])
    if slow == 0:
        return "your {slow} is zero: there is no relative error {slow_error} of it (R21)"
    if abs(approx - slow) <= SAME * abs(slow):
        return ("your {slow} and {slow_approx} are the same number, which makes {slow_error} "
                "zero with nothing compared (R21)")
    return None
