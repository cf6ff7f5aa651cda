"""Spin of an asymmetric body near a principal axis (R9): the tennis-racket theorem.

A phone, a book, a brick, a tennis racket or a T-handle is tossed spinning about one of its
principal axes with a small wobble. Asked: for each principal axis, whether steady spin about
it is stable (booleans), and for the axis actually spun about the linear (R9) rate: the angular
frequency ``√(Ω1Ω2)`` of the small oscillation if stable, the growth rate ``√(−Ω1Ω2)`` if not.

The moments are labelled by named body axes, *not* necessarily in increasing order, so a student
must find the intermediate one. They come from :mod:`solver.inertia`: uniform boxes, and for
the racket (a solid-cylinder handle and a disc head) and the T-handle (two solid cylinders)
composite bodies combined with the parallel-axis theorem. :func:`draw_body` is shared with
:mod:`problems.templates.asymmetric_free_top`.

Rejected draws (resampled): nearly degenerate moments (two within ``MIN_GAP`` of each other,
where stability hangs on the rounding and rates are tiny); for a stable spin, a wobble large
enough that the exact (R10) period differs from the linear one by more than ``LINEAR_RTOL``;
known mistakes within five tolerances of the key or of one another.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from problems.answers import Answer, Mistake
from problems.family import (
    IllPosed,
    Parameter,
    distinguishable,
    stacked_distinguishable,
    unless_ill_posed,
)
from problems.rounding import latex_sig, round_sig
from problems.written import Written
from solver.asymmetric_top import asymmetric_top_period
from solver.inertia import parallel_axis, shape_tensor
from solver.torque_free import near_axis_stability

NAME = "near_axis_stability"
TITLE = "Spin about a principal axis: which axes are stable?"
SUMMARY = "asymmetric top near a principal axis: stability of each axis, wobble frequency or growth"
RESULTS = ("R7", "R9")
CONVENTIONS = ('free_body',)
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

SIG = 3
"""Significant figures of ω(0) and of the body's dimensions."""
SIG_MOMENTS = 4
"""Moments get one more: a phone is nearly a flat plate, whose largest moment is within 0.5 % of
the sum of the other two (the triangle inequality's edge), which 3-figure rounding can cross."""
RTOL = 1e-3
"""The rate is one square root of 3-figure data: any careful computation agrees to ~1e-12."""
MARGIN = 5.0
"""Known mistakes must lie this many tolerances from the key and from each other."""
MIN_GAP = 0.08
"""Least relative difference |Ii − Ij|/max(I) between any two moments."""
WOBBLE = (0.005, 0.03)
"""Transverse components of ω(0), as fractions of the spin."""
LINEAR_RTOL = 0.01
"""A stable wobble must be small enough that R9's frequency is within 1 % of the exact one."""
MAX_ATTEMPTS = 1000


@dataclass(frozen=True)
class Body:
    """A body and its three principal axes, ``axes[i]`` naming the axis whose moment is
    ``moments[i]`` (kg m², about the centre of mass; None when rebuilt from recorded
    parameters, which hold the rounded moments instead)."""

    label: str  # its parameter value: a key of KINDS
    moments: tuple[float, float, float] | None = None

    @property
    def noun(self) -> str:
        return KINDS[self.label].noun

    @property
    def axes(self) -> tuple[str, str, str]:
        return KINDS[self.label].axes

    @property
    def spin(self) -> tuple[float, float]:
        """Range of the spin, rad/s."""
        return KINDS[self.label].spin

    @property
    def description(self) -> str:
        """The body in words."""
        return KINDS[self.label].description


_RANGES: dict[str, tuple[tuple[float, float], ...]] = {
    "smartphone": ((0.14, 0.22), (0.14, 0.165), (0.065, 0.078), (0.007, 0.009)),
    "book": ((0.3, 1.2), (0.20, 0.28), (0.13, 0.20), (0.015, 0.05)),
    "brick": ((2.0, 3.0), (0.20, 0.23), (0.09, 0.11), (0.05, 0.075)),
    "racket": ((0.09, 0.12), (0.013, 0.016), (0.30, 0.36), (0.16, 0.20), (0.12, 0.14)),
    "t_handle": ((0.03, 0.06), (0.006, 0.01), (0.08, 0.12), (0.015, 0.035), (0.005, 0.008),
                 (0.04, 0.07)),
}
"""Kind of body → the ranges (kg, m) its masses and dimensions are drawn from, in the order
drawn: a box's mass, length, width and thickness; the racket's handle mass, radius and length,
then its head's mass and radius; the T-handle's crossbar mass, radius and length, then its
stem's. The kinds in the order of the draw's ``rng.integers(5)``."""

_LABELS = tuple(_RANGES)
_Z_TO_X = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
_Z_TO_Y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])


def _diagonal(tensors: np.ndarray) -> np.ndarray:
    """The diagonals (n, 3) of tensors (n, 3, 3): the principal moments of these bodies, whose
    tensors are diagonal."""
    return np.diagonal(tensors, axis1=-2, axis2=-1)


def _along(*components: np.ndarray) -> np.ndarray:
    """Displacements (n, 3), m, of which each component is an array (n,) or 0."""
    return np.stack(np.broadcast_arrays(*components), axis=-1).astype(float)


def _box_moments(m: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Principal moments (n, 3), kg m², of uniform boxes (R2) of mass ``m`` (kg) and edges
    ``a``, ``b``, ``c`` (m) along x, y, z."""
    return _diagonal(shape_tensor("box", m, a=a, b=b, c=c))


def _racket_moments(m_h: np.ndarray, r_h: np.ndarray, l_h: np.ndarray, m_d: np.ndarray,
                    r_d: np.ndarray) -> np.ndarray:
    """Principal moments (n, 3), kg m², of rackets: handle and shaft (a solid cylinder along x)
    and head (a disc in the xy plane, the plane of the strings), joined end to rim; about the
    common centre of mass (R2)."""
    handle = _Z_TO_X @ shape_tensor("solid_cylinder", m_h, radius=r_h, height=l_h) @ _Z_TO_X
    head = shape_tensor("disc", m_d, radius=r_d)
    x_h, x_d = l_h / 2, l_h + r_d
    x_cm = (m_h * x_h + m_d * x_d) / (m_h + m_d)
    return _diagonal(parallel_axis(handle, m_h, _along(x_h - x_cm, 0.0, 0.0))
                     + parallel_axis(head, m_d, _along(x_d - x_cm, 0.0, 0.0)))


def _t_handle_moments(m_c: np.ndarray, r_c: np.ndarray, l_c: np.ndarray, m_s: np.ndarray,
                      r_s: np.ndarray, l_s: np.ndarray) -> np.ndarray:
    """Principal moments (n, 3), kg m², of T-handles like Dzhanibekov's wing nut: a crossbar
    (solid cylinder along x) with a stem (solid cylinder along y) fixed to its middle; about
    the common centre of mass (R2)."""
    bar = _Z_TO_X @ shape_tensor("solid_cylinder", m_c, radius=r_c, height=l_c) @ _Z_TO_X
    stem = _Z_TO_Y @ shape_tensor("solid_cylinder", m_s, radius=r_s, height=l_s) @ _Z_TO_Y
    y_s = r_c + l_s / 2  # the stem starts at the crossbar's surface
    y_cm = m_s * y_s / (m_c + m_s)
    return _diagonal(parallel_axis(bar, m_c, _along(0.0, -y_cm, 0.0))
                     + parallel_axis(stem, m_s, _along(0.0, y_s - y_cm, 0.0)))


_MOMENTS: dict[str, Callable[..., np.ndarray]] = {
    "smartphone": _box_moments, "book": _box_moments, "brick": _box_moments,
    "racket": _racket_moments, "t_handle": _t_handle_moments,
}
"""Kind of body → its principal moments from its masses and dimensions (:data:`_RANGES`)."""


@dataclass(frozen=True)
class Kind:
    """What the statement says about a kind of body, and its range of spins (rad/s)."""

    noun: str
    description: str
    axes: tuple[str, str, str]
    spin: tuple[float, float]


_BOX_AXES = ("along its length", "along its width", "perpendicular to its largest face")
KINDS: dict[str, Kind] = {
    "smartphone": Kind("a smartphone", "a uniform box", _BOX_AXES, (5.0, 20.0)),
    "book": Kind("a book", "a uniform box", _BOX_AXES, (3.0, 12.0)),
    "brick": Kind("a brick", "a uniform box", _BOX_AXES, (3.0, 10.0)),
    "racket": Kind("a tennis racket", "a handle ending in a round head",
                   ("along the handle", "in the plane of the strings, across the handle",
                    "perpendicular to the strings"), (4.0, 12.0)),
    "t_handle": Kind("a T-handle", "a crossbar with a stem fixed to its middle",
                     ("along the crossbar", "along the stem",
                      "perpendicular to crossbar and stem"), (5.0, 20.0)),
}
"""Label → kind of body (the bodies of :func:`draw_body`)."""

ORDERS = tuple("".join(map(str, p)) for p in itertools.permutations(range(3)))
"""Which body axis is ê1, ê2, ê3, as a label: ``"201"`` makes ê1 the body's third axis."""


def body_parameters() -> dict[str, Parameter]:
    """The parameters of a body and its spin (shared with asymmetric_free_top): its kind,
    which body axis is each ê_i, the rounded moments (computed from dimensions the student is
    not shown), the axis spun about and ω(0)."""
    return {
        "body": Parameter(choices=tuple(KINDS), description="the body tossed"),
        "order": Parameter(choices=ORDERS, description="body axis of ê1, ê2, ê3"),
        **{f"I{i}": Parameter(unit="kg m^2", figures=SIG_MOMENTS, description=f"moment I{i}")
           for i in (1, 2, 3)},
        "spin_axis": Parameter(choices=("1", "2", "3"), description="the axis spun about"),
        "omega0": Parameter(unit="rad/s", shape=(3,), description="ω(0), body frame"),
    }


def draw_body(rng: np.random.Generator) -> Body:
    """A random everyday asymmetric body: smartphone, book, brick, tennis racket or T-handle.

    Dimensions and masses are drawn from real objects' ranges and rounded to ``SIG`` figures;
    the moments (unrounded) are computed from the rounded dimensions by :mod:`solver.inertia`.
    """
    return draw_bodies([rng])[0]


def draw_bodies(rngs: Sequence[np.random.Generator]) -> list[Body]:
    """:func:`draw_body` of each generator: each body's numbers drawn from its own generator
    as alone, then the moments of the bodies of a kind worked out together."""
    drawn = [_drawn(rng) for rng in rngs]
    moments = np.empty((len(drawn), 3))
    for label in dict.fromkeys(label for label, _ in drawn):
        rows = [i for i, (kind, _) in enumerate(drawn) if kind == label]
        sizes = round_sig(np.array([drawn[i][1] for i in rows]), SIG)
        moments[rows] = _MOMENTS[label](*sizes.T)
    return [Body(label, tuple(m)) for (label, _), m in zip(drawn, moments.tolist(), strict=True)]


def _drawn(rng: np.random.Generator) -> tuple[str, list[float]]:
    """A kind of body and its masses and dimensions (kg, m; not yet rounded), drawn from
    ``rng`` in the order of :data:`_RANGES`."""
    label = _LABELS[rng.integers(5)]
    return label, [rng.uniform(low, high) for low, high in _RANGES[label]]


@dataclass(frozen=True)
class Draw:
    """Displayed (rounded) values: axis ``i + 1`` is ``body.axes[order[i]]``."""

    body: Body
    order: tuple[int, int, int]
    moments: tuple[float, float, float]  # I1, I2, I3
    spin_axis: int  # 1, 2 or 3
    omega0: tuple[float, float, float]

    @property
    def axes(self) -> tuple[str, str, str]:
        """The names of the principal axes ê1, ê2, ê3."""
        return tuple(self.body.axes[i] for i in self.order)

    def params(self) -> dict[str, Any]:
        """The recorded parameters."""
        I1, I2, I3 = self.moments
        return {"body": self.body.label,
                "order": "".join(map(str, self.order)), "I1": I1, "I2": I2, "I3": I3,
                "spin_axis": str(self.spin_axis), "omega0": list(self.omega0)}

    @classmethod
    def of(cls, params: Mapping[str, Any]) -> Draw:
        """The draw of recorded parameters."""
        return cls(Body(params["body"]), tuple(int(i) for i in params["order"]),
                   (params["I1"], params["I2"], params["I3"]), int(params["spin_axis"]),
                   tuple(params["omega0"]))


def _draws(rngs: Sequence[np.random.Generator]) -> list[Draw]:
    """A draw from each generator (:func:`draw`): each student's numbers drawn from their own
    generator as alone, then rounded together."""
    bodies = draw_bodies(rngs)
    orders, spin_axes, wobbles, spins = [], [], [], []
    for rng, body in zip(rngs, bodies, strict=True):
        orders.append(rng.permutation(3))
        spin_axes.append(int(rng.integers(1, 4)))
        wobbles.append(rng.uniform(*WOBBLE, size=3) * rng.choice([-1.0, 1.0], size=3))
        spins.append(rng.uniform(*body.spin))
    order = np.array(orders)
    moments = round_sig(np.take_along_axis(np.array([b.moments for b in bodies]), order, axis=1),
                        SIG_MOMENTS)
    spin = np.array(spins)
    omega = spin[:, None] * np.array(wobbles)
    omega[np.arange(len(spins)), np.array(spin_axes) - 1] = spin
    return [Draw(body, tuple(o), tuple(m), s, tuple(w)) for body, o, m, s, w in zip(
        bodies, order.tolist(), moments.tolist(), spin_axes, round_sig(omega, SIG).tolist(),
        strict=True)]


def _rigid_apart(moments: np.ndarray) -> np.ndarray:
    """Whether the moments (n, 3), kg m², are a rigid body's, no two within ``MIN_GAP`` of the
    largest (the rounding may have crossed the triangle inequality, or left them nearly
    degenerate)."""
    I1, I2, I3 = moments.T
    largest = moments.max(axis=1)
    gaps = np.minimum(np.minimum(np.abs(I1 - I2), np.abs(I1 - I3)), np.abs(I2 - I3))
    return ~((2 * largest > I1 + I2 + I3) | (gaps < MIN_GAP * largest))


def _r9(moments: np.ndarray, spin: np.ndarray, axes: np.ndarray) -> dict[str, np.ndarray]:
    """R9 for the spins ``spin`` (n,), rad/s, about the axes ``axes`` (n,) (1, 2 or 3) of
    bodies of moments (n, 3): :func:`solver.torque_free.near_axis_stability`'s values, one
    solver call per axis."""
    found = {"Omega1": np.empty(len(spin)), "Omega2": np.empty(len(spin)),
             "rate": np.empty(len(spin)), "stable": np.empty(len(spin), dtype=bool)}
    for axis in (1, 2, 3):
        rows = np.flatnonzero(axes == axis)
        if rows.size:
            r9 = near_axis_stability(*moments[rows].T, spin[rows], axis=axis)
            for name, values in found.items():
                values[rows] = r9[name]
    return found


def _posed_many(draws: Sequence[Draw]) -> list[tuple[Answer, ...] | IllPosed]:
    """The answers of each draw, or the :class:`IllPosed` that rejects it: moments not a
    rigid body's or nearly degenerate, a stable wobble beyond R9's linear regime (checked
    against R10's exact period), or a known mistake within ``MARGIN`` tolerances of the key or
    of another. The solver called once per axis for all draws, their mistakes tested apart
    together (:func:`problems.family.stacked_distinguishable`); answers built for the accepted
    draws alone."""
    moments = np.array([d.moments for d in draws], dtype=float)
    omega0 = np.array([d.omega0 for d in draws], dtype=float)
    axes = np.array([d.spin_axis for d in draws])
    spin = omega0[np.arange(len(draws)), axes - 1]
    found: list[tuple[Answer, ...] | IllPosed] = [IllPosed(_ILL_POSED)] * len(draws)
    rows = np.flatnonzero(_rigid_apart(moments))  # the solver refuses no rigid body
    r9 = _r9(moments[rows], spin[rows], axes[rows])
    # an unstable spin's growth rate describes the flip's start, however it ends
    stable = np.flatnonzero(r9["stable"])
    linear = np.ones(len(rows), dtype=bool)
    if stable.size:
        period = asymmetric_top_period(*moments[rows[stable]].T, omega0[rows[stable]])
        linear[stable] = np.abs(period * r9["rate"][stable] / (2 * math.pi) - 1) < LINEAR_RTOL
    rows, r9 = rows[linear], {name: values[linear] for name, values in r9.items()}
    stable_axes = [near_axis_stability(*moments[rows].T, 1.0, axis=a)["stable"]
                   for a in (1, 2, 3)] if rows.size else []
    rate3 = near_axis_stability(*moments[rows].T, spin[rows], axis=3)["rate"] \
        if rows.size else np.empty(0)
    rate, O1, O2 = r9["rate"], np.abs(r9["Omega1"]), np.abs(r9["Omega2"])
    wrong = np.stack([rate, rate / (2 * math.pi),
                      np.where(r9["stable"], 2 * math.pi / rate, 1 / rate), O1, O2, rate3],
                     axis=-1)
    # the ê3 formula is a mistake only for a spin about another axis
    about3 = axes[rows] == 3
    apart = np.where(about3, stacked_distinguishable(wrong[:, :5], MARGIN * RTOL),
                     stacked_distinguishable(wrong, MARGIN * RTOL))
    finite = np.all(np.isfinite(wrong), axis=1)
    for k, i in enumerate(rows.tolist()):
        build = partial(_built, tuple(bool(x[k]) for x in stable_axes), int(axes[i]),
                        wrong[k].tolist(), bool(r9["stable"][k]))
        if not finite[k]:  # Answer reads (and refuses) such values itself: as one alone
            found[i] = unless_ill_posed(distinguishable, build, MARGIN)
        else:
            found[i] = build() if apart[k] else IllPosed(_CLOSE)
    return found


def _built(stable_axes: tuple[bool, bool, bool], s: int, wrong: list[float],
           stable: bool) -> tuple[Answer, ...]:
    """The answers of a draw spun about ê``s``: :func:`_stability_answers` and
    :func:`_rate_answer` of the values :func:`_posed_many` stacked (``wrong``: the rate, then
    its mistakes' values, the ê3 formula's last)."""
    return (*_stability_answers(stable_axes),
            _rate_answer(s, *wrong[:5], stable, None if s == 3 else wrong[5]))


def _stability_answers(stable_axes: tuple[bool, bool, bool]) -> list[Answer]:
    """``stable1``–``stable3``: whether steady spin about each principal axis is stable (R9)."""
    answers = []
    for axis, stable in zip((1, 2, 3), stable_axes, strict=True):
        if stable:
            why = (f"Spin about ê{axis} is stable: its moment is the largest or the smallest, so "
                   "Ω1Ω2 > 0 in R9 (small deviations oscillate).")
        else:
            why = (f"Spin about ê{axis} is unstable: its moment is the intermediate one, so "
                   "Ω1Ω2 < 0 in R9 (small deviations grow exponentially).")
        answers.append(Answer(
            f"stable{axis}", "boolean", stable, points=0.5,
            mistakes=(Mistake("wrong_stability", not stable, why),),
            description=f"is steady spin about ê{axis} stable?",
        ))
    return answers


def _rate_answer(s: int, rate: float, hz: float, period: float, O1: float, O2: float,
                 stable: bool, rate3: float | None) -> Answer:
    """``rate`` for the spin about ê``s``: R9's rate (1/s), its mistakes' values (the rate in
    Hz, the period 2π/rate or the e-folding time 1/rate, |Ω1|, |Ω2|, and R9's formula for ê3
    applied to the spin about another axis, ``rate3``)."""
    mistakes = [
        Mistake("hz", hz, "That is the rate divided by 2π; give it in rad/s "
                "(an angular frequency)." if stable else "A growth rate has no factor 2π: "
                "perturbations grow as exp(√(−Ω1Ω2) t)."),
        Mistake("period", period, "That is the period 2π/√(Ω1Ω2); the angular "
                "frequency is asked.") if stable else
        Mistake("e_folding_time", period, "That is the e-folding time 1/√(−Ω1Ω2); the "
                "growth rate (1/s) is asked."),
        Mistake("Omega1_only", O1, "R9's rate is the geometric mean √|Ω1Ω2| of both "
                "coefficients, not one of them."),
        Mistake("Omega2_only", O2, "R9's rate is the geometric mean √|Ω1Ω2| of both "
                "coefficients, not one of them."),
    ]
    if rate3 is not None:
        mistakes.append(Mistake("axis3_formula", rate3, f"The spin is about ê{s}, not ê3: "
                                "relabel R9's axes cyclically so that the spin axis plays "
                                "the role of ê3."))
    # Unit and description are the same whether the spin is stable or not: the text of the
    # question must not tell which (rad/s and 1/s are one unit; the wobble's angular frequency
    # and the growth rate are both √|Ω1Ω2|).
    return Answer("rate", "scalar", rate, unit="1/s", rtol=RTOL, mistakes=tuple(mistakes),
                  description=RATE_DESCRIPTION.format(axis=s))


RATE_DESCRIPTION = ("R9 rate for the spin about ê{axis}: wobble angular frequency if stable, "
                    "growth rate if not")
"""The ``rate`` answer's description: identical for a stable and an unstable spin."""


def axes_text(d: Draw) -> str:
    """``$\\hat e_1$ along its length, $I_1 = …$ kg m²; …`` for the shown moments."""
    return "; ".join(f"$\\hat e_{i}$ {d.axes[i - 1]}, "
                     f"$I_{i} = {latex_sig(d.moments[i - 1], SIG_MOMENTS)}$ kg m²"
                     for i in (1, 2, 3))


def _statement(d: Draw) -> str:
    b, s = d.body, d.spin_axis
    w = ",\\ ".join(latex_sig(x, SIG) for x in d.omega0)
    return (
        f"{b.noun[0].upper()}{b.noun[1:]} ({b.description}) is tossed into the air, spun mainly "
        f"about $\\hat e_{s}$: $\\boldsymbol\\omega(0) = ({w})$ rad/s in body components "
        "(`omega0`). Its principal axes and moments about the centre of mass, **not** "
        f"necessarily in increasing order: {axes_text(d)} (`I1`, `I2`, `I3`).\n\n"
        "1. `stable1`, `stable2`, `stable3`: is steady spin about $\\hat e_k$ stable against "
        "small perturbations?\n"
        f"2. `rate`: for the spin about $\\hat e_{s}$, in the linear approximation (R9): the "
        "angular frequency of the wobble if it is stable, else its growth rate $\\gamma$ "
        "($\\propto e^{\\gamma t}$)."
    )


PARAMETERS: dict[str, Parameter] = body_parameters()


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A body (:func:`draw_body`), its axes in random order, and a spin about one of them with
    a small wobble."""
    return draw_many([rng])[0]


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any]]:
    """:func:`draw` of each generator — the batch form (:mod:`problems.family`): the bodies'
    moments, and the rounding, of all at once."""
    return [d.params() for d in _draws(rngs)]


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``stable1``–``stable3`` and ``rate`` (R9), from :mod:`solver.torque_free` on the shown
    moments and ω(0).

    Raises :class:`~problems.family.IllPosed` for no rigid body, nearly degenerate moments, a
    stable wobble beyond R9's linear regime, or a known mistake close to the key.
    """
    found = _posed_many([Draw.of(params)])[0]
    if isinstance(found, IllPosed):
        raise found
    return found


_ILL_POSED = "degenerate moments, or a wobble beyond the linear regime"
_CLOSE = f"a known mistake within {MARGIN:g} tolerances of the key or another"


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): the solver called for all at once,
    their mistakes tested apart together."""
    return _posed_many([Draw.of(p) for p in many])


def statement(params: Mapping[str, Any]) -> str:
    return _statement(Draw.of(params))


INTERMEDIATE_AXIS = Written(
    "intermediate_axis",
    "Explain, from Euler's equations without torque, why spin about the axis of the "
    "intermediate moment is unstable while spin about the largest or the smallest is stable.",
    3,
    [("Euler's equations linearised for $\\omega_1, \\omega_2$ small ($\\omega_3$ "
      "constant to first order)", 1),
     ("$\\ddot\\omega_1 = -\\Omega_1 \\Omega_2\\, \\omega_1$ derived, with "
      "$\\Omega_1 = \\omega_3 (I_3 - I_2)/I_1$ and $\\Omega_2 = \\omega_3 (I_3 - I_1)/I_2$", 1),
     ("the sign of $\\Omega_1 \\Omega_2$ argued: positive for the largest or smallest "
      "moment (oscillation), negative for the intermediate one (exponential growth)", 1)],
    "why the intermediate axis is unstable (R7, R9)",
)
"""R7 (Euler's equations) linearised into R9 (rotation near a principal axis): the derivation
behind this family's stability answers (``docs/physics/index.md``)."""


def written(params: Mapping[str, Any]) -> tuple[Written, ...]:
    """The written part an assignment may ask for: :data:`INTERMEDIATE_AXIS`."""
    return (INTERMEDIATE_AXIS,)
