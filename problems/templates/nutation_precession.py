"""Nutation period and mean precession rate of a heavy symmetric top (R15–R17, R20).

A real top (:func:`~problems.templates.sleeping_top.draw_top`: a disc or rotor on a light axle,
or a wooden cone) stands on a fixed tip with its moments ``I1`` (about the tip) and ``I3`` and
its ``M g l`` given to 3 figures. It is let go at the tilt ``β0`` with ``β̇ = 0``, spinning at
``ω3`` (1.2 to 5 times the sleeping top's critical spin), either with no precession
(``α̇0 = 0``: the axis traces cusps) or with a push ``α̇0`` (waves or loops). Asked:

``T_nut``
    The nutation period ``T = 4 K(k)/√(B (u3 − u1))`` (R20), s.
``mean_rate``
    The mean precession rate over one nutation period, ``⟨α̇⟩ = Δα / T`` (R20), rad/s.

The key comes from :func:`solver.heavy_top.nutation` (Carlson ``R_F``/``R_J``, exact); a student
uses ``numpy.roots`` for the cubic of R17, ``scipy.special.ellipk`` for ``K`` and
``scipy.integrate.quad`` for ``Δα`` — the statement says so.

Known mistakes (each computed by the solver from the mistaken physics): for ``T_nut`` the
small-oscillation period ``2π I1/p_γ`` of a fast top (R21), half the period (one sweep
``β1 → β2``), ``ellipk`` called with ``k`` instead of its parameter ``m = k²``, ``β0`` read as
degrees, ``I1`` and ``I3`` swapped; for ``mean_rate`` the fast top's slow precession
``Mgl/p_γ`` (R21), the rate in Hz (÷ 2π), ``Δα`` over one sweep only (the factor 2 of R20
missing), ``β0`` read as degrees, ``I1`` and ``I3`` swapped (when that swap is still a body,
``I1 ≤ 2 I3``).

Rejected draws (resampled): turning points closer than ``MIN_AMPLITUDE`` (nearly steady: the
fast-top values are then within tolerance), ``k² > MAX_K2`` (near the separatrix of an unstable
upright top, where the period diverges logarithmically and 3-figure data decide too much), an
axis swinging below ``MAX_BETA2`` from the vertical, and known mistakes within ``MARGIN``
tolerances of the key or of each other.

Tolerance ``rtol = 1e-3``: the data are exact 3-figure numbers; ``numpy.roots`` gives the roots
of this well-separated cubic to ~1e-13, ``ellipk`` is accurate to ~1e-15, and ``quad`` of the
``Δα`` integrand (inverse-square-root end singularities, which QUADPACK's extrapolation handles)
to ~1e-8 — or better after the substitution ``u = u1 + (u2 − u1) sin²θ``. So a correct method
lands far inside 1e-3, and every known mistake is at least 5e-3 away.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import ellipk

from problems.answers import Answer, Mistake
from problems.family import IllPosed, Parameter, distinguishable, reject_unless
from problems.rounding import latex_sig, round_sig
from problems.templates.sleeping_top import (
    TOP_KINDS,
    TOP_PARAMETERS,
    Top,
    draw_top,
    top_moments,
    top_weights,
)
from solver.heavy_top import constants_of_motion, critical_spin, cubic_roots, nutation

NAME = "nutation_precession"
TITLE = "Nutation period and mean precession rate of a heavy top"
SUMMARY = "heavy top let go at a tilt: exact nutation period and mean precession rate (elliptic)"
RESULTS = ("R15", "R17", "R20")
CONVENTIONS = ('euler_angles', 'heavy_top')
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

SIG = 3
"""Significant figures of every displayed parameter."""
RTOL = 1e-3
MARGIN = 5.0
"""Known mistakes must lie this many tolerances from the key and from each other."""
SPIN_RATIO = (1.2, 5.0)
"""ω3 as a multiple of the sleeping top's critical spin 2√(Mgl I1)/I3 (R19)."""
TILT = (0.2, 1.2)
"""β0, rad."""
PUSH = (-1.5, 3.0)
"""α̇0 of a pushed top, as a multiple of the fast top's slow precession Mgl/p_γ."""
MIN_AMPLITUDE = 0.02
"""Least β2 − β1, rad."""
MAX_K2 = 0.9
"""Largest k² = (u2 − u1)/(u3 − u1)."""
MAX_BETA2 = 2.5
"""Largest β2, rad."""
MAX_ATTEMPTS = 1000

_TOOLS = (
    "Tools: `numpy.roots` (the cubic in $u = \\cos\\beta$), `scipy.special.ellipk(m)` "
    "($m = k^2$), `scipy.integrate.quad` (substitute $u = u_1 + (u_2 - u_1)\\sin^2\\theta$)."
)


def _state(I1, I3, Mgl, beta0, omega3, alpha_dot0):
    """The solver's initial state; ``γ̇0 = ω3 − α̇0 cos β0`` (R12) from the displayed values."""
    return (I1, I3, Mgl, beta0, alpha_dot0, 0.0, omega3 - alpha_dot0 * math.cos(beta0))


def _well_posed(state) -> bool:
    return _well_posed_motion(cubic_roots(*state), nutation(*state))


def _well_posed_motion(roots, n) -> bool:
    """Whether the motion of ``roots`` (u1, u2, u3) and ``n`` (its ``nutation``) is asked."""
    u1, u2, u3 = (float(x) for x in roots)
    amplitude = float(n["beta2"]) - float(n["beta1"])
    return (amplitude >= MIN_AMPLITUDE and (u2 - u1) / (u3 - u1) <= MAX_K2
            and float(n["beta2"]) <= MAX_BETA2 and math.isfinite(n["nutation_period"]))


def _values(states: dict[str, tuple]) -> dict[str, tuple[float, float]]:
    """``{label: (T_nut, mean_rate)}`` for each state, in one vectorised solver call."""
    return _values_many([states])[0]


def _values_many(many: list[dict[str, tuple]]) -> list[dict[str, tuple[float, float]]]:
    """:func:`_values` of each student's states, in one solver call for all of them."""
    if not many:
        return []
    columns = np.array([state for states in many for state in states.values()], dtype=float).T
    n = nutation(*columns)
    period, mean = n["nutation_period"], n["mean_precession_rate"]
    found, first = [], 0
    for states in many:
        found.append({k: (float(period[first + j]), float(mean[first + j]))
                      for j, k in enumerate(states)})
        first += len(states)
    return found


def _solved(states: dict[str, tuple]) -> tuple:
    """What :func:`_answers` takes from the solver for ``states``: their ``(T_nut, mean_rate)``,
    the key's ``p_γ`` and its roots ``u1, u2, u3``."""
    _, p_gamma, _ = constants_of_motion(*states["key"])
    return _values(states), p_gamma, tuple(float(x) for x in cubic_roots(*states["key"]))


def _states(I1, I3, Mgl, beta0, omega3, alpha_dot0) -> dict[str, tuple]:
    """The key's state and each mistaken one the solver computes, by label (key first)."""
    states = {"key": _state(I1, I3, Mgl, beta0, omega3, alpha_dot0),
              "degrees": _state(I1, I3, Mgl, math.radians(beta0), omega3, alpha_dot0)}
    if I1 <= 2 * I3:  # the swapped moments still describe a body (R4)
        states["swapped"] = _state(I3, I1, Mgl, beta0, omega3, alpha_dot0)
    if alpha_dot0 != 0.0:  # the given ω3 taken for γ̇0 (R12): γ̇0 = ω3, so ω3 would be larger
        states["spin"] = (I1, I3, Mgl, beta0, alpha_dot0, 0.0, omega3)
    return states


_GAMMA_DOT_IS_OMEGA3 = (
    "ω3 is the given spin about the symmetry axis; the spin-angle rate is γ̇ = ω3 − α̇ cos β "
    "(R12), not ω3: with the precession pushed in, the two differ."
)


def _apart(value: float, others: list[float]) -> bool:
    """``value`` lies ``MARGIN`` tolerances from each of ``others`` (the key and mistakes)."""
    return math.isfinite(value) and all(
        abs(value - o) > MARGIN * RTOL * max(abs(value), abs(o)) for o in others)


def _answers(I1, I3, Mgl, beta0, omega3, alpha_dot0, solved=None) -> tuple[Answer, Answer]:
    """The two answers; ``solved``: :func:`_solved` of :func:`_states`, if already computed."""
    if solved is None:
        solved = _solved(_states(I1, I3, Mgl, beta0, omega3, alpha_dot0))
    values, p_gamma, (u1, u2, u3) = solved
    T, mean = values["key"]
    scale = 4.0 / math.sqrt(2.0 * Mgl / I1 * (u3 - u1))
    k = math.sqrt((u2 - u1) / (u3 - u1))

    degrees = "β0 is in radians; this value comes from reading it as degrees."
    swapped = ("I1 and I3 are swapped: p_γ = I3 ω3 uses the moment about the symmetry axis, "
               "I1 the transverse moment about the tip.")
    t_mistakes = [
        Mistake("small_oscillation", 2 * math.pi * I1 / float(p_gamma),
                "That is the fast top's small-nutation period 2π I1/p_γ (R21); the exact period "
                "4K(k)/√(B(u3 − u1)) of R20 is asked."),
        Mistake("half_period", T / 2, "That is one sweep from β1 to β2; a full nutation period "
                "goes there and back: T = 2K(k)/λ (R20)."),
        Mistake("ellipk_of_k", scale * float(ellipk(k)), "scipy.special.ellipk takes the "
                "parameter m = k², not the modulus k: use ellipk(k**2)."),
        Mistake("degrees", values["degrees"][0], degrees),
    ]
    r_mistakes = [
        Mistake("fast_top", Mgl / float(p_gamma), "That is the fast-top slow precession "
                "Mgl/p_γ (R21), an approximation; the exact mean Δα/T_nut of R20 is asked."),
        Mistake("hz", mean / (2 * math.pi), "That is the rate in revolutions per second "
                "(divided by 2π); give it in rad/s."),
        Mistake("missing_factor_2", mean / 2, "Δα over a full nutation period is twice the "
                "integral from u1 to u2 (there and back): Δα = 2∫(b − au)/((1 − u²)√f) du (R20)."),
        Mistake("degrees", values["degrees"][1], degrees),
    ]
    if "swapped" in values:
        t_mistakes.append(Mistake("I1_I3_swapped", values["swapped"][0], swapped))
        r_mistakes.append(Mistake("I1_I3_swapped", values["swapped"][1], swapped))
    t_mistakes = [m for m in t_mistakes if math.isfinite(m.value)]
    r_mistakes = [m for m in r_mistakes if math.isfinite(m.value)]
    if "spin" in values:  # kept only where it moves the answer clear of the others
        for mistakes, value in zip((t_mistakes, r_mistakes), values["spin"], strict=True):
            if _apart(value, [T if mistakes is t_mistakes else mean,
                              *(m.value for m in mistakes)]):
                mistakes.append(Mistake("gamma_dot_is_omega3", value, _GAMMA_DOT_IS_OMEGA3))
    return (
        Answer("T_nut", "scalar", T, unit="s", rtol=RTOL, mistakes=tuple(t_mistakes),
               description="nutation period (exact)"),
        Answer("mean_rate", "scalar", mean, unit="rad/s", rtol=RTOL,
               mistakes=tuple(r_mistakes), description="mean precession rate over one period"),
    )


def _statement(noun: str, p: Mapping[str, Any]) -> str:
    def show(name: str, symbol: str, unit: str) -> str:
        return f"${symbol} = {latex_sig(p[name], SIG)}$ {unit} (`{name}`)"

    beta0 = show("beta0", r"\beta_0", "rad")
    omega3 = show("omega3", r"\omega_3", "rad/s")
    alpha_dot0 = show("alpha_dot0", r"\dot\alpha_0", "rad/s")
    how = "without precessing" if p["alpha_dot0"] == 0.0 else "pushed sideways"
    return (
        f"A top, {noun}, spins on a fixed tip: {show('I1', 'I_1', 'kg m²')} about the tip, "
        f"{show('I3', 'I_3', 'kg m²')} about its symmetry axis, {show('Mgl', 'Mgl', 'J')}. It "
        f"is let go at the tilt {beta0} with $\\dot\\beta = 0$, spinning at {omega3}, {how}: "
        f"{alpha_dot0}. Exactly (not in the fast-top approximation), find:\n\n"
        "1. `T_nut`: the nutation period ($\\beta$ from $\\beta_1$ to $\\beta_2$ and back);\n"
        "2. `mean_rate`: the mean precession rate $\\langle\\dot\\alpha\\rangle$ over one "
        f"nutation period.\n\n{_TOOLS}"
    )


PARAMETERS: dict[str, Parameter] = {
    "top": TOP_PARAMETERS["top"],
    "I1": Parameter(unit="kg m^2", description="transverse moment about the tip"),
    "I3": Parameter(unit="kg m^2", description="moment about the symmetry axis"),
    "Mgl": Parameter(unit="J", description="weight times tip-to-centre distance"),
    "beta0": Parameter(unit="rad", low=TILT[0], high=TILT[1], description="tilt when let go"),
    "omega3": Parameter(unit="rad/s", description="spin (a multiple of the critical spin)"),
    "alpha_dot0": Parameter(unit="rad/s", description="precession rate when let go"),
}


_NUMBERS = ("I1", "I3", "Mgl", "beta0", "omega3", "alpha_dot0")
"""The numbers of a parameter set, in the order drawn."""


@dataclass(frozen=True)
class _Draws:
    """What one student's generator gives :func:`draw_many`, in the order it is drawn: a real
    top, then the state's random numbers (unrounded)."""

    top: Top
    spin: float  # ω3 in critical spins
    tilt: float  # β0, rad
    push: float | None  # α̇0 in Mgl/p_γ; None: let go without precessing

    @classmethod
    def of(cls, rng: np.random.Generator) -> _Draws:
        top = draw_top(rng)
        spin, tilt = rng.uniform(*SPIN_RATIO), rng.uniform(*TILT)
        return cls(top, spin, tilt, rng.uniform(*PUSH) if rng.random() < 0.5 else None)


def draw(rng: np.random.Generator) -> dict[str, Any] | None:
    """A real top's moments and ``Mgl`` (rounded), its spin (a multiple of the critical spin),
    the tilt, and one time in two a push ``α̇0`` (a multiple of ``Mgl/p_γ``)."""
    return draw_many([rng])[0]


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any] | None]:
    """:func:`draw` of each generator — the batch form (:mod:`problems.family`): each
    student's random numbers drawn in order, then the tops' moments (R2, stacked by
    :func:`~problems.templates.sleeping_top.top_moments`) and critical spins (R19) of all at
    once."""
    if not rngs:
        return []
    draws = [_Draws.of(rng) for rng in rngs]
    tops = [d.top for d in draws]
    I1, I3 = (round_sig(x, SIG) for x in top_moments(tops))
    Mgl = round_sig(top_weights(tops), SIG)
    omega3 = round_sig(critical_spin(I1, I3, Mgl) * np.array([d.spin for d in draws]), SIG)
    beta0 = round_sig(np.array([d.tilt for d in draws]), SIG)
    pushed = np.array([d.push is not None for d in draws])
    push = np.array([0.0 if d.push is None else d.push for d in draws])
    alpha_dot0 = np.where(pushed, round_sig(push * Mgl / (I3 * omega3), SIG), 0.0)
    # a body's I3 ≤ 2 I1 (R4): a real top's rounded moments never cross it (its l² term keeps
    # 2 I1 at least 1.6 I3), so testing it after the whole draw rejects nothing
    body = (I3 <= 2 * I1).tolist()
    rows = zip(*(c.tolist() for c in (I1, I3, Mgl, beta0, omega3, alpha_dot0)), strict=True)
    return [{"top": d.top.kind.shape, **dict(zip(_NUMBERS, numbers, strict=True))} if ok
            else None for d, ok, numbers in zip(draws, body, rows, strict=True)]


def _numbers(params: Mapping[str, Any]) -> tuple[float, ...]:
    return tuple(params[n] for n in _NUMBERS)


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``T_nut`` and ``mean_rate`` (R20), from :func:`solver.heavy_top.nutation` on the shown
    (3-figure) parameters.

    Raises :class:`~problems.family.IllPosed` for a nearly steady motion, one near the
    separatrix or swinging too low, or a known mistake close to the key.
    """
    numbers = _numbers(params)
    reject_unless(_well_posed(_state(*numbers)), "nearly steady, near the separatrix, or low")
    return distinguishable(lambda: _answers(*numbers), MARGIN)


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set, an :class:`~problems.family.IllPosed` for each
    rejected one — the family's batch form (:mod:`problems.family`): the solver is called for
    all of them at once (the roots and motions of the keys, then every state's period and
    mean rate, then the keys' ``p_γ``), the rest as for one."""
    numbers = [_numbers(params) for params in many]
    keys = np.array([_state(*n) for n in numbers], dtype=float).T
    roots, motions = np.array(cubic_roots(*keys)).T, nutation(*keys)
    posed = [i for i in range(len(many))
             if _well_posed_motion(roots[i], {k: v[i] for k, v in motions.items()})]
    states = [_states(*numbers[i]) for i in posed]
    values = _values_many(states)
    _, p_gamma, _ = constants_of_motion(*keys[:, posed])
    found: list[tuple[Answer, ...] | IllPosed] = [
        IllPosed("nearly steady, near the separatrix, or low")] * len(many)
    for j, i in enumerate(posed):
        solved = (values[j], p_gamma[j], tuple(float(x) for x in roots[i]))
        try:
            found[i] = distinguishable(lambda i=i, s=solved: _answers(*numbers[i], solved=s),
                                       MARGIN)
        except IllPosed as e:
            found[i] = e
    return found


def statement(params: Mapping[str, Any]) -> str:
    noun = next(k.noun for k in TOP_KINDS if k.shape == params["top"])
    return _statement(noun, params)
