"""Exact torque-free asymmetric top (R10): the period of ω(t) and the Dzhanibekov flip time.

A phone, a book, a brick, a tennis racket or a T-handle (bodies of
:func:`problems.templates.near_axis_stability.draw_body`) is tossed either mainly about its
intermediate axis with a small perturbation (it flips over and back: Dzhanibekov's wing nut) or
mainly about its smallest or largest axis with a large wobble. Moments are ordered
``I1 < I2 < I3``. Asked:

``period``
    the period of ω(t) in the body frame, ``4K(k)/λ`` (R10): the least ``P > 0`` with
    ``ω(t + P) = ω(t)`` for all three components (``ω`` of the dn axis alone repeats after
    ``P/2``);
``t_flip``
    the flip time as :func:`solver.asymmetric_top.flip_time` defines it: the time for ``ω2``
    (the intermediate-axis component, ``∝ sn``) to go from a maximum to the next minimum,
    ``2K(k)/λ = P/2``;
``circled_axis``
    the principal axis ω circles in the body frame (the "dn axis", whose component never
    changes sign): ê3 when ``L² > 2T I2``, ê1 when ``L² < 2T I2``.

Rejected draws (resampled): moments within ``MIN_GAP`` of each other; motion within
``SEPARATRIX_GAP`` of the separatrix ``L² = 2T I2`` (where the period diverges and the
circled axis hangs on the last digit); known mistakes within five tolerances of the key or of
one another (e.g. a small-amplitude R9 period indistinguishable from the exact one).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import partial
from typing import Any, NamedTuple

import numpy as np
from scipy.special import ellipk

from problems.answers import Answer, Mistake
from problems.family import (
    IllPosed,
    distinguishable,
    stacked_distinguishable,
    unless_ill_posed,
)
from problems.rounding import latex_sig, round_sig
from problems.templates import near_axis_stability as near_axis
from problems.templates.near_axis_stability import Draw, draw_bodies
from solver.asymmetric_top import asymmetric_top_period, flip_time
from solver.torque_free import invariants, near_axis_stability

NAME = "asymmetric_free_top"
TITLE = "The tumbling asymmetric body: exact period and intermediate-axis flip"
SUMMARY = "exact asymmetric top (elliptic functions): period of ω(t), Dzhanibekov flip time"
RESULTS = ("R7", "R10")
CONVENTIONS = ('free_body',)
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

SIG = 3
"""Significant figures of ω(0)."""
SIG_MOMENTS = 4
"""Moments get one more: a phone is nearly a flat plate, whose largest moment is within 0.5 % of
the sum of the other two (the triangle inequality's edge), which 3-figure rounding can cross."""
RTOL = 1e-3
"""K(k) from scipy or a table and 3-figure data reproduce the key to ~1e-10; 1e-3 leaves room
for a student who carries 4 figures, and is far from every known mistake."""
MARGIN = 5.0
"""Known mistakes must lie this many tolerances from the key and from each other."""
MIN_GAP = 0.05
"""Least relative difference between two moments (the order I1 < I2 < I3 must be clear)."""
SEPARATRIX_GAP = 1e-5
"""Least ``|L² − 2T I2| / L²``. Closer, the period grows like ``ln(1/gap)`` and which axis ω
circles is decided by digits beyond those shown."""
FLIP_PERTURBATION = (0.02, 0.1)
"""Flip scenario: ω1, ω3 as fractions of ω2."""
WOBBLE = (0.15, 0.7)
"""Wobble scenario: the two smaller components as fractions of the spin about ê1 or ê3."""
MAX_ATTEMPTS = 1000


def _draws(rngs: Sequence[np.random.Generator]) -> list[Draw]:
    """A draw from each generator (:func:`draw`): each student's numbers drawn from their own
    generator as alone, then ordered and rounded together."""
    bodies = draw_bodies(rngs)
    spin_axes, omegas, spins = [], [], []
    for rng, body in zip(rngs, bodies, strict=True):
        axis = 2 if rng.random() < 0.5 else int(rng.choice([1, 3]))
        fractions = FLIP_PERTURBATION if axis == 2 else WOBBLE
        spin_axes.append(axis)
        omegas.append(rng.uniform(*fractions, size=3) * rng.choice([-1.0, 1.0], size=3))
        spins.append(rng.uniform(*body.spin))
    unordered = np.array([b.moments for b in bodies])
    order = np.argsort(unordered, axis=1)
    moments = round_sig(np.take_along_axis(unordered, order, axis=1), SIG_MOMENTS)
    omega = np.array(omegas)
    omega[np.arange(len(spins)), np.array(spin_axes) - 1] = 1.0
    omega *= np.array(spins)[:, None]
    return [Draw(body, tuple(o), tuple(m), s, tuple(w)) for body, o, m, s, w in zip(
        bodies, order.tolist(), moments.tolist(), spin_axes, round_sig(omega, SIG).tolist(),
        strict=True)]


def _rigid(d: Draw) -> bool:
    """Moments of a rigid body, clearly apart (the rounding may have made them neither)."""
    I1, I2, I3 = d.moments
    return not (I3 > I1 + I2 or min(I2 - I1, I3 - I2) < MIN_GAP * I3)


def _off_separatrix(d: Draw, T: float, L2: float) -> bool:
    return abs(float(L2 - 2 * T * d.moments[1])) >= SEPARATRIX_GAP * float(L2)


class _Solved(NamedTuple):
    """What the solver gives one motion: its invariants (R7), its period and flip time (R10),
    and R9's rate about ê1 and about ê3 with that axis's component of ω(0)."""

    T: float
    L2: float
    period: float
    t_flip: float
    rate1: float
    rate3: float


def _moments_and_omega(draws: list[Draw]) -> tuple[np.ndarray, ...]:
    I1, I2, I3 = np.array([d.moments for d in draws], dtype=float).T
    return I1, I2, I3, np.array([d.omega0 for d in draws], dtype=float)


def _solve_many(draws: list[Draw]) -> list[_Solved | IllPosed]:
    """:class:`_Solved` of each draw, or the :class:`IllPosed` of one not well posed; every
    solver function called once for all of them (element by element what one draw alone
    gives)."""
    found: list[_Solved | IllPosed | None] = [
        None if _rigid(d) else IllPosed("moments too close, or no rigid body") for d in draws]
    rigid = [i for i, f in enumerate(found) if f is None]
    kept = {}
    if rigid:
        for i, t, l2 in zip(rigid, *invariants(*_moments_and_omega([draws[i] for i in rigid])),
                            strict=True):
            if _off_separatrix(draws[i], t, l2):
                kept[i] = (t, l2)
            else:
                found[i] = IllPosed("a motion near the separatrix")
    if kept:
        I1, I2, I3, omega = _moments_and_omega([draws[i] for i in kept])
        columns = zip(asymmetric_top_period(I1, I2, I3, omega), flip_time(I1, I2, I3, omega),
                      near_axis_stability(I1, I2, I3, omega[:, 0], axis=1)["rate"],
                      near_axis_stability(I1, I2, I3, omega[:, 2], axis=3)["rate"], strict=True)
        for (i, invariant), solved in zip(kept.items(), columns, strict=True):
            found[i] = _Solved(*invariant, *solved)
    return found


def _parameter_m(moments: np.ndarray, T: np.ndarray, L2: np.ndarray) -> np.ndarray:
    """R10's ``m = k²`` of motions of bodies of moments (n, 3), energies ``T`` and squared
    momenta ``L2`` (n,): ``x = (I2 − I1)(2T I3 − L²)/((I3 − I2)(L² − 2T I1))`` for
    ``L² > 2T I2``, and ``1/x`` (indices 1 and 3 exchanged) otherwise; so ``m = min(x, 1/x)``."""
    I1, I2, I3 = moments.T
    x = (I2 - I1) * (2 * T * I3 - L2) / ((I3 - I2) * (L2 - 2 * T * I1))
    return np.where(1 / x < x, 1 / x, x)  # as Python's min(x, 1/x)


def _values(draws: list[Draw], solved: list[_Solved]) -> tuple[np.ndarray, np.ndarray,
                                                                np.ndarray]:
    """Of motions solved: the values (n, 5), s, of ``period`` and its mistakes (in their
    order), those (n, 4) of ``t_flip`` and its mistakes, and the circled axes (n,) (R10)."""
    moments = np.array([d.moments for d in draws], dtype=float)
    T, L2, period, t_flip, rate1, rate3 = np.array(solved, dtype=float).reshape(-1, 6).T
    circled = np.where(L2 > 2 * T * moments[:, 1], 3, 1)  # ê3 if L² > 2T I2, else ê1 (R10)
    r9 = np.where(circled == 3, rate3, rate1)
    m = _parameter_m(moments, T, L2)
    # scipy's ellipk takes the parameter m = k²; passing the modulus k is the classic slip
    modulus_slip = ellipk(np.sqrt(m)) / ellipk(m)
    return (np.stack([period, period / 2, 2 * math.pi / r9, 2 * math.pi / period,
                      period * modulus_slip], axis=-1),
            np.stack([t_flip, period, period / 4, t_flip * modulus_slip], axis=-1), circled)


def _answers(period: list[float], flip: list[float], c: int) -> tuple[Answer, ...]:
    """``period``, ``t_flip`` and ``circled_axis`` from the values of :func:`_values`."""
    period_m = (
        Mistake("flip_time", period[1], "That is half the period (the flip time): ω2 goes "
                "from its maximum to its minimum in P/2, and ω is back where it started after P "
                "= 4K(k)/λ."),
        Mistake("small_amplitude", period[2], "That is 2π/√(Ω1Ω2), the small-amplitude "
                "period of R9; the exact period is 4K(k)/λ (R10)."),
        Mistake("angular_frequency", period[3], "That is an angular frequency "
                "(rad/s); the period (s) is asked."),
        Mistake("ellipk_modulus", period[4], "scipy.special.ellipk(m) takes the "
                "parameter m = k², not the modulus k."),
    )
    flip_m = (
        Mistake("full_period", flip[1], "That is the full period of ω(t); the flip (ω2 from "
                "maximum to minimum) takes half of it, 2K(k)/λ."),
        Mistake("quarter_period", flip[2], "That is a quarter period (ω2 from zero to its "
                "maximum); from maximum to minimum takes 2K(k)/λ."),
        Mistake("ellipk_modulus", flip[3], "scipy.special.ellipk(m) takes the "
                "parameter m = k², not the modulus k."),
    )
    rule = "ω circles ê3 when L² > 2T I2 and ê1 when L² < 2T I2 (R10)."
    axis_m = (
        Mistake("intermediate", "2", "ω never circles the intermediate axis ê2 (R9: spin about "
                "it is unstable); " + rule),
        Mistake("other_side", str(4 - c), "Compare L² with 2T I2: " + rule),
    )
    return (
        Answer("period", "scalar", period[0], unit="s", rtol=RTOL, mistakes=period_m,
               description="period of ω(t) in the body frame (exact)"),
        Answer("t_flip", "scalar", flip[0], unit="s", rtol=RTOL, mistakes=flip_m,
               description="time for ω2 to go from a maximum to the next minimum"),
        Answer("circled_axis", "choice", str(c), options=("1", "2", "3"), mistakes=axis_m,
               description="the principal axis ω circles in the body frame"),
    )


def _posed_many(draws: list[Draw]) -> list[tuple[Answer, ...] | IllPosed]:
    """The answers of each draw, or the :class:`IllPosed` that rejects it (:func:`answers`):
    the solver called once for all (:func:`_solve_many`), the known mistakes tested apart
    together (:func:`problems.family.stacked_distinguishable`; ``circled_axis``'s are always
    apart), answers built for the accepted draws alone."""
    found = _solve_many(draws)
    rows = [i for i, f in enumerate(found) if not isinstance(f, IllPosed)]
    if not rows:
        return found
    period, flip, circled = _values([draws[i] for i in rows], [found[i] for i in rows])
    apart = (stacked_distinguishable(period, MARGIN * RTOL)
             & stacked_distinguishable(flip, MARGIN * RTOL))
    finite = np.all(np.isfinite(period), axis=1) & np.all(np.isfinite(flip), axis=1)
    for k, (i, p, f, c) in enumerate(zip(rows, period.tolist(), flip.tolist(),
                                         circled.tolist(), strict=True)):
        if not finite[k]:  # Answer reads (and refuses) such values itself: as one alone
            found[i] = unless_ill_posed(distinguishable, partial(_answers, p, f, c), MARGIN)
        else:
            found[i] = _answers(p, f, c) if apart[k] else IllPosed(_CLOSE)
    return found


_CLOSE = f"a known mistake within {MARGIN:g} tolerances of the key or another"


def _statement(d: Draw) -> str:
    b, s = d.body, d.spin_axis
    w = ",\\ ".join(latex_sig(x, SIG) for x in d.omega0)
    how = ("mainly about its intermediate axis $\\hat e_2$, with a small perturbation"
           if s == 2 else f"mainly about $\\hat e_{s}$, with a large wobble")
    return (
        f"{b.noun[0].upper()}{b.noun[1:]} ({b.description}) is tossed spinning {how}. Its "
        "principal axes and moments about the centre of mass, **ordered** $I_1 < I_2 < I_3$, "
        f"are: {near_axis.axes_text(d)} (`I1`, `I2`, `I3`). At $t = 0$, "
        f"$\\boldsymbol\\omega = ({w})$ rad/s in body components (`omega0`). Solve Euler's "
        "equations exactly (Jacobi elliptic functions).\n\n"
        "1. `period`: the least $P > 0$ with $\\boldsymbol\\omega(t + P) = "
        "\\boldsymbol\\omega(t)$, all three components;\n"
        "2. `t_flip`: the time $\\omega_2$ takes from a maximum to the next minimum;\n"
        "3. `circled_axis`: the principal axis that $\\boldsymbol\\omega$ circles in the body "
        'frame (its component never changes sign): `"1"`, `"2"` or `"3"`.'
    )


PARAMETERS = near_axis.body_parameters()


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A body (:func:`~problems.templates.near_axis_stability.draw_body`), its axes ordered
    ``I1 < I2 < I3``, spun about ê2 with a small perturbation or about ê1 or ê3 with a large
    wobble."""
    return draw_many([rng])[0]


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any]]:
    """:func:`draw` of each generator — the batch form (:mod:`problems.family`): the bodies'
    moments, their order and the rounding of all at once."""
    return [d.params() for d in _draws(rngs)]


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``period``, ``t_flip`` and ``circled_axis`` (R10), from :mod:`solver.asymmetric_top` on
    the shown moments and ω(0).

    Raises :class:`~problems.family.IllPosed` for moments out of order or too close, a motion
    near the separatrix, or a known mistake close to the key.
    """
    found = _posed_many([Draw.of(params)])[0]
    if isinstance(found, IllPosed):
        raise found
    return found


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): every motion's invariants, period,
    flip time and R9 rates in one solver call each, the known mistakes tested apart
    together."""
    return _posed_many([Draw.of(p) for p in many])


def statement(params: Mapping[str, Any]) -> str:
    return _statement(Draw.of(params))
