"""The sleeping top (R19): the least spin for which a vertical top is stable, and a given spin.

A real top is drawn (:func:`draw_top`): a brass or steel disc on a light axle, a thick steel
rotor (solid cylinder) on a light axle, or a wooden toy top (solid cone spinning on its apex),
with real sizes: radius 2–5 cm, mass 30–500 g, centre of mass 2–6 cm from the tip. The statement
gives the body (mass ``M``, radius ``R``, thickness or height ``h``, tip-to-centre distance ``l``
for the axle tops, ``g``); the student finds ``I1`` about the tip (R2 and the parallel-axis
theorem), ``I3`` and ``M g l``. Asked:

``omega3_c``
    The critical spin ``ω3_c = 2 √(M g l I1) / I3`` (R19), rad/s.
``stable``
    Whether a vertical spin at the given ``ω3`` sleeps (``ω3 ≥ ω3_c``), a boolean.

Known mistakes of ``omega3_c`` (each computed by :func:`solver.heavy_top.critical_spin` from the
mistaken inputs): ``I1`` about the centre of mass instead of about the tip, ``I1`` and ``I3``
swapped, the factor 2 missing, the answer in Hz (divided by 2π).

Rejected draws (resampled): a given spin within ``THRESHOLD_MARGIN`` (3 %) of the critical spin
(the boolean would hang on the rounding of the data), and known mistakes within ``MARGIN``
tolerances of the key or of each other.

Tolerance: ``omega3_c`` has ``rtol = 1e-3``: it is one square root of products of 3-figure
data, which any careful computation reproduces to ~1e-15; the known mistakes differ by factors
of order one.

:func:`draw_top` is shared with the other heavy-top templates
(:mod:`~problems.templates.nutation_precession`, :mod:`~problems.templates.steady_precession`,
:mod:`~problems.templates.symbolic_derivation`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np

from problems.answers import Answer, Mistake
from problems.family import IllPosed, Parameter, batch_of_one, distinguishable, reject_unless
from problems.genuine import statement_number
from problems.rounding import latex_sig, round_sig
from problems.written import Written
from solver.heavy_top import critical_spin, sleeping_top_stable
from solver.inertia import centre_of_mass_offset, parallel_axis, shape_tensor

NAME = "sleeping_top"
TITLE = "The sleeping top: how fast must it spin?"
SUMMARY = "sleeping top: least spin for a stable upright top; stable or not at a given spin"
RESULTS = ("R2", "R19")
CONVENTIONS = ('euler_angles', 'heavy_top')
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

SIG = 3
"""Significant figures of every displayed parameter."""
G = 9.81
"""Gravitational acceleration shown to students, m/s²."""
RTOL = 1e-3
MARGIN = 5.0
"""Known mistakes must lie this many tolerances from the key and from each other."""
SPIN_RATIO = (0.5, 2.0)
"""The given spin, as a multiple of the critical spin."""
THRESHOLD_MARGIN = 0.03
"""Least relative distance of the given spin from the critical one."""
MAX_ATTEMPTS = 1000


# --------------------------------------------------------------------------------------------
# A real top (shared with the other heavy-top templates)


@dataclass(frozen=True)
class TopKind:
    """A kind of real top: its solver shape, materials and size ranges (SI)."""

    noun: str
    shape: str  # a shape of solver.inertia.SHAPES
    mass: tuple[float, float]  # kg
    radius: tuple[float, float]  # m
    height: tuple[float, float] | None  # m; None for a thin disc
    arm_range: tuple[float, float] | None  # tip-to-centre distance l, m; None: the cone's own


TOP_KINDS: tuple[TopKind, ...] = (
    TopKind("a brass disc on a light axle", "disc", (0.05, 0.5), (0.02, 0.05), None,
            (0.02, 0.06)),
    TopKind("a steel rotor (a solid cylinder) on a light axle", "solid_cylinder", (0.1, 0.5),
            (0.02, 0.04), (0.008, 0.025), (0.03, 0.06)),
    TopKind("a wooden toy top (a solid cone spinning on its apex)", "solid_cone", (0.03, 0.12),
            (0.02, 0.04), (0.03, 0.06), None),
)


@dataclass(frozen=True)
class Top:
    """A symmetric top on a fixed tip, from displayed (rounded) dimensions (SI units).

    ``h`` is the thickness (solid cylinder) or height (cone), ``None`` for a thin disc; ``arm`` is
    ``l``, the distance from the tip to the centre of mass (``3h/4`` for a cone on its apex).
    """

    kind: TopKind
    M: float
    R: float
    h: float | None
    arm: float  # l
    g: float = G

    def _dims(self) -> dict[str, float]:
        return {"radius": self.R} | ({} if self.h is None else {"height": self.h})

    @cached_property  # computed once per top (several templates ask often)
    def tensor_cm(self) -> np.ndarray:
        """Inertia tensor about the centre of mass, kg m² (R2), symmetry axis along z
        (read-only: shared by the moments below)."""
        tensor = shape_tensor(self.kind.shape, self.M, **self._dims())
        tensor.flags.writeable = False
        return tensor

    @cached_property
    def I_cm(self) -> float:
        """Transverse moment about the centre of mass, kg m² (R2)."""
        return float(self.tensor_cm[0, 0])

    @cached_property
    def I1(self) -> float:
        """Transverse moment about the tip, kg m² (parallel-axis theorem, R2)."""
        return float(parallel_axis(self.tensor_cm, self.M, [0.0, 0.0, self.arm])[0, 0])

    @cached_property
    def I3(self) -> float:
        """Moment about the symmetry axis, kg m²."""
        return float(self.tensor_cm[2, 2])

    @property
    def Mgl(self) -> float:
        """Weight times tip-to-centre distance, J."""
        return self.M * self.g * self.arm


def top_moments(tops: Sequence[Top]) -> tuple[np.ndarray, np.ndarray]:
    """``I1`` (about the tip) and ``I3`` of each top, kg m² (R2): :func:`top_moments_cm`."""
    _, I1, I3 = top_moments_cm(tops)
    return I1, I3


def top_moments_cm(tops: Sequence[Top]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``I_cm`` (transverse, about the centre of mass), ``I1`` (about the tip) and ``I3`` of
    each top, kg m² (R2): bit for bit :attr:`Top.I_cm`, :attr:`Top.I1` and :attr:`Top.I3`,
    the tops of each kind stacked in one call of the solver."""
    I_cm, I1, I3 = np.empty(len(tops)), np.empty(len(tops)), np.empty(len(tops))
    for kind in TOP_KINDS:
        rows = [i for i, top in enumerate(tops) if top.kind.shape == kind.shape]
        if not rows:
            continue
        M, R, arm = (np.array([getattr(tops[i], n) for i in rows]) for n in ("M", "R", "arm"))
        height = {} if kind.height is None else {"height": np.array([tops[i].h for i in rows])}
        tensor_cm = shape_tensor(kind.shape, M, radius=R, **height)
        offset = np.zeros((len(rows), 3))
        offset[:, 2] = arm
        I1[rows] = parallel_axis(tensor_cm, M, offset)[:, 0, 0]
        I_cm[rows], I3[rows] = tensor_cm[:, 0, 0], tensor_cm[:, 2, 2]
    return I_cm, I1, I3


def top_weights(tops: Sequence[Top]) -> np.ndarray:
    """``M g l`` of each top, J: bit for bit :attr:`Top.Mgl`."""
    return np.array([top.Mgl for top in tops], dtype=float)


def draw_top(rng: np.random.Generator, sig: int = SIG) -> Top:
    """A real top with dimensions drawn from :data:`TOP_KINDS` and rounded to ``sig`` figures.

    For a cone the tip is the apex, ``l = 3h/4`` (:func:`solver.inertia.centre_of_mass_offset`);
    it is computed from the rounded ``h`` and not rounded itself.
    """
    kind = TOP_KINDS[int(rng.integers(len(TOP_KINDS)))]

    def u(bounds: tuple[float, float]) -> float:
        return round_sig(rng.uniform(*bounds), sig)

    M, R = u(kind.mass), u(kind.radius)
    h = None if kind.height is None else u(kind.height)
    if kind.arm_range is None:
        return top_of(kind, M, R, h)
    # the axle must leave the rotor clear of the tip: l ≥ h/2 + 1 cm
    low = max(kind.arm_range[0], (h or 0.0) / 2 + 0.01)
    return Top(kind, M, R, h, u((low, kind.arm_range[1])))


def top_of(kind: TopKind, M: float, R: float, h: float | None, arm: float | None = None) -> Top:
    """The top of these shown dimensions; ``arm`` (``l``) None for a cone on its apex, whose
    ``l = 3h/4`` follows from ``h``."""
    if arm is None:
        arm = float(centre_of_mass_offset(kind.shape, radius=R, height=h))
    return Top(kind, M, R, h, arm)


TOP_PARAMETERS: dict[str, Parameter] = {
    "top": Parameter(choices=tuple(k.shape for k in TOP_KINDS), description="the kind of top"),
    "M": Parameter(unit="kg", low=0.03, high=0.5, description="mass"),
    "R": Parameter(unit="m", low=0.02, high=0.05, description="radius"),
    "h": Parameter(unit="m", low=0.008, high=0.06,
                   description="thickness of the rotor, or height of the cone"),
    "l": Parameter(unit="m", low=0.02, high=0.06, description="tip to centre of mass"),
    "g": Parameter(unit="m/s^2", description="gravitational acceleration"),
}
"""The shown dimensions of a top (:func:`top_params`); shared with the other heavy-top
templates. A range is the union of the kinds' ranges."""


def top_params(top: Top) -> dict[str, float | str]:
    """The top's parameters: its kind, ``M``, ``R``, ``h`` (not for a disc), ``l`` (not for a
    cone), ``g``."""
    params: dict[str, float | str] = {"top": top.kind.shape, "M": top.M, "R": top.R}
    if top.h is not None:
        params["h"] = top.h
    if top.kind.arm_range is not None:
        params["l"] = top.arm
    return params | {"g": top.g}


def top_from_params(params: Mapping[str, Any]) -> Top:
    """The :class:`Top` of :func:`top_params`."""
    kind = next(k for k in TOP_KINDS if k.shape == params["top"])
    top = top_of(kind, params["M"], params["R"], params.get("h"), params.get("l"))
    return replace(top, g=params["g"])


# --------------------------------------------------------------------------------------------
# The question


_HZ = ("That is the critical spin in revolutions per second (divided by 2π); give the angular "
       "velocity in rad/s.")
_I1_CM = ("I1 must be the transverse moment about the fixed tip, not about the centre of mass: "
          "add M l² (parallel-axis theorem, R2).")
_SWAPPED = ("I1 and I3 are swapped: p_γ = I3 ω3 involves the moment about the symmetry axis, "
            "and the gravity term M g l I1 the transverse moment about the tip (R19).")
_FACTOR_2 = ("A factor 2 is missing: the condition is p_γ² ≥ 4 M g l I1, so "
             "ω3 ≥ 2 √(M g l I1)/I3 (R19).")


def _critical_spins(I_cm: np.ndarray, I1: np.ndarray, I3: np.ndarray,
                    Mgl: np.ndarray) -> list[list[float]]:
    """Each top's critical spin (R19, I1 about the tip), rad/s, then its mistakes': I1 about
    the centre of mass, I1 and I3 swapped — of all the tops in one solver call."""
    return critical_spin(np.stack([I1, I_cm, I3], axis=-1), np.stack([I3, I3, I1], axis=-1),
                         Mgl[:, None]).tolist()


def _spin_answer(critical: Sequence[float]) -> Answer:
    """``omega3_c`` from :func:`_critical_spins` of its top."""
    w, about_cm, swapped = critical
    mistakes = (
        Mistake("I1_about_cm", about_cm, _I1_CM),
        Mistake("I1_I3_swapped", swapped, _SWAPPED),
        Mistake("missing_factor_2", w / 2, _FACTOR_2),
        Mistake("hz", w / (2 * math.pi), _HZ),
    )
    return Answer("omega3_c", "scalar", w, unit="rad/s", rtol=RTOL, mistakes=mistakes,
                  description="least spin for which the vertical top is stable")


def _stable_answer(stable: bool) -> Answer:
    """``stable``: whether the top sleeps at the given spin (R19)."""
    why = ("The vertical spin is stable exactly when ω3 is at least the critical spin "
           "2 √(M g l I1)/I3 (R19, with I1 about the tip): compare the given spin with it.")
    return Answer("stable", "boolean", stable, points=0.5,
                  mistakes=(Mistake("wrong_side", not stable, why),),
                  description="does the top sleep (stay vertical) at the given spin?",
                  depends_on=("omega3_c",))


def _statement(top: Top, omega3: float) -> str:
    R, M, g = latex_sig(top.R, SIG), latex_sig(top.M, SIG), latex_sig(top.g, SIG)
    body = f"mass $M = {M}$ kg (`M`), {'base ' if top.h and top.kind.arm_range is None else ''}"
    body += f"radius $R = {R}$ m (`R`)"
    if top.kind.shape == "solid_cylinder":
        body += f", thickness $h = {latex_sig(top.h, SIG)}$ m (`h`)"
    if top.kind.arm_range is None:  # the cone: its apex is the tip
        body += f", height $h = {latex_sig(top.h, SIG)}$ m (`h`; the centre of mass is $3h/4$ "
        body += "from the apex)"
    else:
        body += f", centre $l = {latex_sig(top.arm, SIG)}$ m (`l`) from the tip"
    return (
        f"A top, {top.kind.noun}, spins upright (sleeping) on a fixed tip. It is uniform: "
        f"{body}; $g = {g}$ m/s² (`g`).\n\n"
        "1. `omega3_c`: the least spin $\\omega_3$ for which the upright top is stable against "
        "small tilts;\n"
        f"2. `stable`: spun upright at $\\omega_3 = {latex_sig(omega3, SIG)}$ rad/s (`omega3`), "
        "does it keep sleeping (`True`) or wobble away from the vertical (`False`)?"
    )


PARAMETERS: dict[str, Parameter] = {
    **TOP_PARAMETERS,
    "omega3": Parameter(unit="rad/s", description="the given spin (a multiple of the critical)"),
}


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A real top (:func:`draw_top`) and a spin between half and twice its critical spin."""
    return draw_many([rng])[0]


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any]]:
    """:func:`draw` of each generator — the batch form (:mod:`problems.family`): each
    student's top and spin ratio drawn in order, then the critical spins (R19) of all the
    tops (their moments stacked, :func:`top_moments`) in one solver call."""
    if not rngs:
        return []
    drawn = [(draw_top(rng), rng.uniform(*SPIN_RATIO)) for rng in rngs]
    tops = [top for top, _ in drawn]
    critical = critical_spin(*top_moments(tops), top_weights(tops))
    omega3 = round_sig(critical * np.array([ratio for _, ratio in drawn]), SIG).tolist()
    return [{**top_params(top), "omega3": w} for top, w in zip(tops, omega3, strict=True)]


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``omega3_c`` (R19, with ``I1`` about the tip, R2) and ``stable``, from the shown values.

    Raises :class:`~problems.family.IllPosed` when the given spin is within
    ``THRESHOLD_MARGIN`` of the critical one, or a known mistake is close to the key.
    """
    return batch_of_one(answers_many, params)


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): the moments (R2) of every student's
    top, their critical spins and those of the mistakes (R19), and whether each top sleeps at
    its spin, each in one solver call."""
    if not many:
        return []
    tops = [top_from_params(p) for p in many]
    I_cm, I1, I3 = top_moments_cm(tops)
    Mgl = top_weights(tops)
    critical = _critical_spins(I_cm, I1, I3, Mgl)
    omega3 = [p["omega3"] for p in many]
    stable = sleeping_top_stable(I1, I3, Mgl, np.array(omega3, dtype=float)).tolist()
    found: list[tuple[Answer, ...] | IllPosed] = []
    for w, spins, sleeps in zip(omega3, critical, stable, strict=True):
        try:
            found.append(_answers(w, spins, sleeps))
        except IllPosed as e:
            found.append(e)
    return found


def _answers(omega3: float, critical: Sequence[float], stable: bool) -> tuple[Answer, ...]:
    """The key of a given spin, its top's :func:`_critical_spins` and whether it sleeps."""
    reject_unless(abs(omega3 / critical[0] - 1.0) >= THRESHOLD_MARGIN,
                  "the given spin is too close to the critical one")
    return distinguishable(lambda: (_spin_answer(critical), _stable_answer(stable)), MARGIN)


def statement(params: Mapping[str, Any]) -> str:
    return _statement(top_from_params(params), params["omega3"])


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``stable`` from the student's own critical spin: the given spin at least it (R19)."""
    if name != "stable":
        raise LookupError(name)
    return bool(params["omega3"] >= float(earlier["omega3_c"]))


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's ``omega3_c`` leaves nothing to work out for ``stable`` (R19: the top
    sleeps when ω3 ≥ ω3_c): a critical spin that is not positive (every spin is above it), or a
    number of the statement copied (the given spin itself, say). None otherwise."""
    if name != "stable":
        raise LookupError(name)
    critical = float(earlier["omega3_c"])
    if critical <= 0:
        return ("your {omega3_c} is not a positive spin: every spin is above it, so {stable} "
                "follows with nothing of R19 worked out")
    top = top_from_params(params)
    copied = statement_number(critical, params, float(critical_spin(top.I1, top.I3, top.Mgl)))
    if copied is not None:
        return (f"your {{omega3_c}} is the statement's {{{copied}}}, copied: {{stable}} then "
                "follows with nothing of R19 worked out")
    return None


SLEEPING_CONDITION = Written(
    "sleeping_condition",
    "Show that a top spinning upright ($\\beta \\approx 0$) is stable exactly when "
    "$p_\\gamma^2 \\ge 4 M g l I_1$, by expanding the effective potential about "
    "$\\beta = 0$.",
    3,
    [("$p_\\alpha = p_\\gamma$ argued for a top through the vertical", 1),
     ("$V_\\text{eff}$ expanded to order $\\beta^2$: "
      "$\\left(\\frac{p_\\gamma^2}{8 I_1} - \\frac{Mgl}{2}\\right) \\beta^2 + Mgl$", 1),
     ("stability as a non-negative $\\beta^2$ coefficient, giving "
      "$p_\\gamma^2 \\ge 4 M g l I_1$", 1)],
    "why the upright spin is stable above ω3_c (R16, R19)",
)
"""R16 (the effective potential) near ``β = 0``, which gives R19: the derivation behind this
family's critical spin (``docs/physics/index.md``)."""


def written(params: Mapping[str, Any]) -> tuple[Written, ...]:
    """The written part an assignment may ask for: :data:`SLEEPING_CONDITION`."""
    return (SLEEPING_CONDITION,)
