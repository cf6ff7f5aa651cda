"""Torque-free symmetric top (R8): a coin, a plate, a puck, a can or a rolling pin in free flight.

The body (``I1 = I2`` transverse, ``I3`` about the symmetry axis ``ê3``) is tossed with ω
mostly along ``ê3`` and a wobble. Asked: the body-frame precession rate
``Ω = ω3 (I3 − I1)/I1`` (signed) and its period ``2π/|Ω|``, ω(t) in the body frame at a
given time, the space-frame precession rate of the symmetry axis about L, ``L/I1``, and the
half-angle θ of the cone ``ê3`` sweeps around L (``tan θ = I1 |ω⊥| / (I3 ω3)``).

Oblate bodies (coin, plate, puck: ``I3 > I1``, Ω > 0) and prolate ones (can, rolling pin:
``I3 < I1``, Ω < 0) are both drawn. Moments come from :func:`solver.inertia.shape_tensor` of a
uniform solid cylinder with real objects' sizes; ω3 from real tossing spin rates.

Rejected draws (resampled): a known mistake within five tolerances of the key or of another
mistake (e.g. ``sin Ωt ≈ 0``, where turning ω the wrong way round gives the same vector).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from problems.answers import Answer, Mistake
from problems.family import IllPosed, Parameter, distinguishable, reject_unless
from problems.genuine import statement_number
from problems.rounding import latex_sig, round_sig
from problems.written import Written
from solver.inertia import shape_tensor
from solver.parameters import ParameterError
from solver.torque_free import (
    body_precession_rate,
    invariants,
    space_precession_rate,
    symmetric_top_omega,
)

NAME = "symmetric_free_top"
TITLE = "A tossed symmetric body: precession in the body frame and in space"
SUMMARY = "torque-free symmetric top: body rate Ω and its period, ω(t), space rate L/I1, cone angle"
RESULTS = ("R7", "R8")
CONVENTIONS = ('free_body',)
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

SIG = 3
"""Significant figures of ω(0), t and the body's dimensions."""
SIG_MOMENTS = 4
"""Moments get one more: a thin coin has I3 within 1 % of 2 I1 (the triangle inequality's edge),
which 3-figure rounding could cross."""
RTOL = 1e-3
"""Hand or numpy computation from 3–4 figure data reproduces the key to ~1e-12; 1e-3 leaves
room for a student who carries 4 figures through, and is far from every known mistake."""
MARGIN = 5.0
"""Known mistakes must lie this many tolerances from the key and from each other."""
MAX_ATTEMPTS = 1000


@dataclass(frozen=True)
class Body:
    """A uniform solid cylinder from everyday life, and how it is thrown (SI ranges)."""

    label: str  # its parameter value
    noun: str
    story: str
    mass: tuple[float, float]  # kg
    radius: tuple[float, float]  # m
    height: tuple[float, float]  # m (thickness of a coin, length of a rolling pin)
    spin: tuple[float, float]  # ω3, rad/s


BODIES: tuple[Body, ...] = (
    Body("coin", "a coin", "is flipped into the air", (3e-3, 10e-3), (9.5e-3, 15e-3),
         (1.5e-3, 2.5e-3), (100.0, 250.0)),
    Body("plate", "a dinner plate", "is tossed up spinning", (0.4, 0.7), (0.11, 0.14),
         (0.015, 0.025), (5.0, 15.0)),
    Body("puck", "an ice-hockey puck", "slides off the ice and tumbles through the air",
         (0.156, 0.170), (0.037, 0.039), (0.024, 0.026), (20.0, 60.0)),
    Body("can", "a can of soup", "is thrown like a spiral pass", (0.30, 0.45), (0.033, 0.042),
         (0.10, 0.12), (10.0, 30.0)),
    Body("rolling_pin", "a rolling pin", "is thrown spinning about its long axis", (0.6, 1.0),
         (0.025, 0.03), (0.38, 0.45), (5.0, 15.0)),
)

TILT = (math.radians(5.0), math.radians(30.0))
"""Angle between ω(0) and ê3: a visible wobble, not a tumble."""
PHASE_TIME = (0.15, 1.6)
"""t in units of the body-frame period 2π/|Ω|."""


@dataclass(frozen=True)
class Draw:
    """Displayed (rounded) values of one variant, SI."""

    body: Body
    I1: float
    I3: float
    omega0: tuple[float, float, float]
    t: float


def draw(rng: np.random.Generator) -> dict[str, Any] | None:
    """A body of :data:`BODIES`, its moments (4 figures), ω(0) and ``t`` (None: the rounding
    pushed ``I3`` past ``2 I1``, no rigid body)."""
    body = BODIES[rng.integers(len(BODIES))]
    mass, radius, height = (round_sig(rng.uniform(*r), SIG)
                            for r in (body.mass, body.radius, body.height))
    moments = np.diag(shape_tensor("solid_cylinder", mass, radius=radius, height=height))
    I1, I3 = (round_sig(moments[i], SIG_MOMENTS) for i in (0, 2))
    if I3 > 2 * I1:
        return None
    omega3 = rng.uniform(*body.spin)
    wobble = omega3 * math.tan(rng.uniform(*TILT))
    phi = rng.uniform(0.0, 2.0 * math.pi)
    omega0 = round_sig([wobble * math.cos(phi), wobble * math.sin(phi), omega3], SIG).tolist()
    period = 2.0 * math.pi / abs(float(body_precession_rate(I1, I3, omega0[2])))
    t = round_sig(rng.uniform(*PHASE_TIME) * period, SIG)
    return {"body": body.label, "I1": I1, "I3": I3, "omega0": omega0, "t": t}


def _draw_of(params: Mapping[str, Any]) -> Draw:
    body = next(b for b in BODIES if b.label == params["body"])
    return Draw(body, params["I1"], params["I3"], tuple(params["omega0"]), params["t"])


PARAMETERS: dict[str, Parameter] = {
    "body": Parameter(choices=tuple(b.label for b in BODIES), description="the body thrown"),
    "I1": Parameter(unit="kg m^2", figures=SIG_MOMENTS, description="transverse moment"),
    "I3": Parameter(unit="kg m^2", figures=SIG_MOMENTS, description="axial moment"),
    "omega0": Parameter(unit="rad/s", shape=(3,), description="ω(0), body frame"),
    "t": Parameter(unit="s", description="the time ω(t) is asked at"),
}


def _turned(omega0: tuple[float, ...], rate: float, t: float) -> list[float]:
    """ω(0) turned about ê3 by ``rate·t``: ω(t) of a student who uses a wrong rate."""
    return Rotation.from_rotvec([0.0, 0.0, rate * t]).apply(omega0).tolist()


def _swapped_rate(d: Draw) -> float | None:
    """Ω with I1 and I3 exchanged, ``ω3 (I1 − I3)/I3``; None where the exchanged moments are no
    rigid body's (a slender rolling pin: I1 > 2 I3), so the solver refuses them."""
    try:
        return float(body_precession_rate(d.I3, d.I1, d.omega0[2]))
    except ParameterError:
        return None


class _Solved(NamedTuple):
    """What the solver gives one throw (R8): Ω, α̇ = L/I1, L² (R7) and ω(t)."""

    Omega: float
    alpha_dot: float
    L2: float
    omega_t: list[float]


def _solve_many(draws: Sequence[Draw]) -> list[_Solved]:
    """:class:`_Solved` of each draw (rigid bodies: ``I3 ≤ 2 I1``), every solver function
    called once for all of them (element by element what one draw alone gives)."""
    I1, I3, t = (np.array([getattr(d, n) for d in draws], dtype=float) for n in ("I1", "I3", "t"))
    omega0 = np.array([d.omega0 for d in draws], dtype=float)
    columns = (body_precession_rate(I1, I3, omega0[:, 2]), space_precession_rate(I1, I3, omega0),
               invariants(I1, I1, I3, omega0)[1], symmetric_top_omega(I1, I3, omega0, t))
    return [_Solved(*row) for row in zip(*(c.tolist() for c in columns), strict=True)]


def _answers(d: Draw, solved: _Solved) -> tuple[Answer, ...]:
    Omega, alpha_dot, L2 = solved.Omega, solved.alpha_dot, solved.L2
    L_perp = d.I1 * math.hypot(d.omega0[0], d.omega0[1])
    theta = math.atan2(L_perp, d.I3 * d.omega0[2])  # cos θ = I3 ω3 / L
    omega_tilt = math.atan2(math.hypot(d.omega0[0], d.omega0[1]), d.omega0[2])
    swapped = _swapped_rate(d)
    period = 2.0 * math.pi / abs(Omega)
    two_pi = 2.0 * math.pi

    omega_m = [
        Mistake("hz", Omega / two_pi, "That is in revolutions per second (Hz); Ω is asked in "
                "rad/s — multiply by 2π."),
        Mistake("sign", -Omega, "Check the sign: Ω = ω3 (I3 − I1)/I1 is positive for an oblate "
                "body (I3 > I1) and negative for a prolate one (I3 < I1)."),
        Mistake("space_rate", alpha_dot, "That is L/I1, the precession rate of the symmetry axis "
                "about L seen from the inertial frame; Ω is the rate at which ω circles ê3 in "
                "the body frame (R8)."),
    ]
    period_m = [
        Mistake("angular_frequency", abs(Omega), "That is the angular frequency |Ω| (rad/s); "
                "the period is 2π/|Ω|."),
        Mistake("missing_2pi", 1.0 / abs(Omega), "A factor 2π is missing: the period is 2π/|Ω|."),
        Mistake("space_period", two_pi / alpha_dot, "That is the period of the precession of the "
                "symmetry axis about L in space (2π I1/L); the body-frame period is 2π/|Ω|."),
    ]
    if swapped is not None:
        omega_m.append(Mistake("I1_I3_swapped", swapped, "I1 and I3 are exchanged: "
                               "Ω = ω3 (I3 − I1)/I1, with I3 the moment about the symmetry axis."))
        period_m.append(Mistake("I1_I3_swapped", two_pi / abs(swapped), "I1 and I3 are "
                                "exchanged: Ω = ω3 (I3 − I1)/I1, I3 about the symmetry axis."))
    vector_m = [
        Mistake("wrong_sense", _turned(d.omega0, -Omega, d.t), "(ω1, ω2) turns the wrong way "
                "round: ω1 + iω2 = (ω1(0) + iω2(0)) e^{iΩt} with Ω = ω3 (I3 − I1)/I1."),
        Mistake("hz", _turned(d.omega0, Omega / two_pi, d.t), "The phase is Ωt in radians with "
                "Ω in rad/s; it looks as if Ω was taken in Hz."),
        Mistake("space_rate", _turned(d.omega0, alpha_dot, d.t), "In the body frame ω turns at "
                "Ω = ω3 (I3 − I1)/I1, not at the space-frame rate L/I1."),
    ]
    alpha_m = [
        Mistake("body_rate", Omega, "That is Ω, the body-frame rate; seen from the inertial "
                "frame the symmetry axis precesses about L at L/I1."),
        Mistake("hz", alpha_dot / two_pi, "That is in Hz; the rate is asked in rad/s."),
        Mistake("I3", float(np.sqrt(L2)) / d.I3, "Divide L by the transverse moment I1, not I3."),
    ]
    theta_m = [
        Mistake("degrees", math.degrees(theta), "That looks like degrees; give θ in radians."),
        Mistake("complement", math.pi / 2 - theta, "That is the angle between L and the plane "
                "of ê1, ê2; θ is measured from ê3 (cos θ = I3 ω3 / L)."),
        Mistake("omega_angle", omega_tilt, "That is the angle between ω and ê3; the cone of "
                "the symmetry axis is around L, at cos θ = I3 ω3 / L."),
    ]
    return (
        Answer("Omega", "scalar", Omega, unit="rad/s", rtol=RTOL, mistakes=tuple(omega_m),
               description="Ω, body-frame precession rate of ω about ê3 (signed)"),
        Answer("T_body", "scalar", period, unit="s", rtol=RTOL, mistakes=tuple(period_m),
               description="period of the body-frame precession", depends_on=("Omega",)),
        Answer("omega_t", "vector", solved.omega_t, unit="rad/s", rtol=RTOL,
               mistakes=tuple(vector_m),
               description="[ω1, ω2, ω3] at time t, body frame"),
        Answer("alpha_dot", "scalar", alpha_dot, unit="rad/s", rtol=RTOL,
               mistakes=tuple(alpha_m), description="precession rate of ê3 about L, space frame"),
        Answer("theta", "angle", theta, unit="rad", rtol=RTOL, mistakes=tuple(theta_m),
               description="half-angle of the cone ê3 sweeps around L"),
    )




def _statement(d: Draw) -> str:
    b = d.body
    w1, w2, w3 = (latex_sig(w, SIG) for w in d.omega0)
    return (
        f"{b.noun[0].upper()}{b.noun[1:]} (a uniform cylinder) {b.story}. Its principal "
        f"moments about the centre of mass are $I_1 = I_2 = {latex_sig(d.I1, SIG_MOMENTS)}$ kg "
        "m² (`I1`) and "
        f"$I_3 = {latex_sig(d.I3, SIG_MOMENTS)}$ kg m² (`I3`, about the symmetry axis "
        "$\\hat e_3$). At $t = 0$ its angular velocity is "
        f"$\\boldsymbol\\omega = ({w1},\\ {w2},\\ {w3})$ rad/s in body components "
        "(`omega0`).\n\n"
        "1. `Omega`: the rate $\\Omega$ at which $\\boldsymbol\\omega$ precesses about "
        "$\\hat e_3$ in the body frame, positive when $(\\omega_1, \\omega_2)$ turns from "
        "$\\hat e_1$ towards $\\hat e_2$;\n"
        "2. `T_body`: the period of that precession;\n"
        f"3. `omega_t`: $\\boldsymbol\\omega$ in body components at $t = {latex_sig(d.t, SIG)}$ s "
        "(`t`);\n"
        "4. `alpha_dot`: the rate at which $\\hat e_3$ precesses about $\\mathbf L$, seen from "
        "the inertial frame;\n"
        "5. `theta`: the angle between $\\hat e_3$ and $\\mathbf L$."
    )


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``Omega``, ``T_body``, ``omega_t``, ``alpha_dot`` and ``theta`` (R8), computed by
    :mod:`solver.torque_free` from the shown (rounded) values.

    Raises :class:`~problems.family.IllPosed` for no rigid body (``I3 > 2 I1``) or a known
    mistake close to the key (e.g. ``sin Ωt ≈ 0``).
    """
    d = _draw_of(params)
    reject_unless(d.I3 <= 2 * d.I1, _NO_RIGID_BODY)
    solved = _solve_many([d])[0]
    return distinguishable(lambda: _answers(d, solved), MARGIN)


_NO_RIGID_BODY = "no rigid body: I3 > 2 I1"


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): Ω, α̇, L² and ω(t) of every rigid
    body's throw in one solver call each."""
    draws = [_draw_of(p) for p in many]
    rigid = [d for d in draws if d.I3 <= 2 * d.I1]
    solved = iter(_solve_many(rigid) if rigid else ())
    found: list[tuple[Answer, ...] | IllPosed] = []
    for d in draws:
        try:
            reject_unless(d.I3 <= 2 * d.I1, _NO_RIGID_BODY)
            mine = next(solved)
            found.append(distinguishable(lambda d=d, mine=mine: _answers(d, mine), MARGIN))
        except IllPosed as e:
            found.append(e)
    return found


def statement(params: Mapping[str, Any]) -> str:
    return _statement(_draw_of(params))


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``T_body`` from the student's own precession rate: the period 2π/|Ω| (R8)."""
    if name != "T_body":
        raise LookupError(name)
    return 2 * math.pi / abs(float(earlier["Omega"]))


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's ``Omega`` is no ground for ``T_body = 2π/|Ω|`` (R8): zero (a body that
    does not precess has no period), or a number of the statement copied (ω3 itself, say) —
    not the rate ``Ω = ω3 (I3 − I1)/I1`` worked out. None otherwise."""
    if name != "T_body":
        raise LookupError(name)
    rate = float(earlier["Omega"])
    if rate == 0:
        return "your {Omega} is zero: a body that does not precess has no period {T_body} (R8)"
    d = _draw_of(params)
    copied = statement_number(rate, params, float(body_precession_rate(d.I1, d.I3, d.omega0[2])))
    if copied is not None:
        return (f"your {{Omega}} is a number of the statement's {{{copied}}}, copied, not R8's "
                "rate worked out: {T_body} from it shows nothing")
    return None


BODY_PRECESSION = Written(
    "body_precession",
    "Show, from Euler's equations without torque, that $\\omega_3$ is constant for a "
    "symmetric top ($I_1 = I_2$) and that $(\\omega_1, \\omega_2)$ turns about $\\hat e_3$ "
    "in the body frame at the rate $\\Omega = \\omega_3 (I_3 - I_1)/I_1$.",
    3,
    [("the third equation with $I_1 = I_2$ gives $\\dot\\omega_3 = 0$", 1),
     ("$\\dot\\omega_1 = -\\Omega\\,\\omega_2$ and $\\dot\\omega_2 = \\Omega\\,\\omega_1$ "
      "derived, with $\\Omega$ as stated", 1),
     ("solved: $\\omega_1 = A\\cos(\\Omega t + \\varphi)$, "
      "$\\omega_2 = A\\sin(\\Omega t + \\varphi)$, a turn at rate $\\Omega$", 1)],
    "why ω precesses about the symmetry axis (R7, R8)",
)
"""R7 (Euler's equations) for ``I1 = I2``, which give R8: the derivation behind this family's
precession rate (``docs/physics/index.md``)."""


def written(params: Mapping[str, Any]) -> tuple[Written, ...]:
    """The written part an assignment may ask for: :data:`BODY_PRECESSION`."""
    return (BODY_PRECESSION,)
