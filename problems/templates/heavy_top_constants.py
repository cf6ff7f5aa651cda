"""Heavy symmetric top: the constants of motion p_γ, p_α and E' from the initial state (R14–R16).

Three real tops, drawn at random (shared with :mod:`problems.templates.turning_points` and
:mod:`problems.templates.motion_type`, which import :func:`draw_top` or, for a class at
once, :func:`draw_tops`, and :func:`draw_state`):

``toy_top``
    A thin brass disc (radius 2–4 cm, 3–6 mm thick) on a light axle, its centre 2.5–6 cm from
    the axle's tip, which spins in a dimple of a table. The statement gives ``M, R, l``: the
    student finds ``I1 = M R²/4 + M l²`` (about the tip, R2's parallel-axis theorem) and
    ``I3 = M R²/2``. The disc's rim would touch the table at ``tan β = l/R``; draws whose axis
    nods down that far are rejected.
``gyroscope``
    A brass rotor on a steel axle (a thin rod, R2) resting in a cup on a post. Its moments
    about the pivot (computed with :mod:`solver.inertia`, shown to 3 figures) are given, with
    ``M`` and the pivot-to-centre-of-mass distance ``l``.
``hanging``
    A brass disc on a light rod hanging from a ball joint, below it (``β > π/2``): the same
    body as the toy top, but the fixed point is above the centre of mass.

Spins are tens to a few hundred rad/s; the precession rate is drawn as a multiple of the
fast-top rate ``Mgl/(I3 γ̇0)`` (R21), either sense, and the nodding rate ``β̇0`` as a fraction
of the nutation frequency ``p_γ/I1``. Every shown number is rounded to 3 figures (``g = 9.81``
m/s²) and the answers are computed from the shown values.

Asked (R15, R16): ``p_gamma = I3 (α̇ cos β + γ̇)``, ``p_alpha = I1 α̇ sin²β + p_γ cos β`` and
``E_prime = E − p_γ²/(2 I3)``, with the potential energy ``Mgl cos β`` (zero at the tip).

Known mistakes. The one each answer is about, always listed: ``ω3 = γ̇`` for ``p_γ`` (the
precession's share of the spin forgotten), ``p_α`` without ``p_γ cos β``, ``E`` for ``E'``.
Propagated ones, listed where they move the answer by more than five tolerances (see
:func:`select_mistakes`): a calculator in degree mode and ``I1`` about the centre of mass
(parallel-axis term forgotten; scenes where the student computes ``I1``), both from
:func:`solver.heavy_top.constants_of_motion` with the mistaken input, and ``I1``, ``I3``
swapped (R15 written out, :func:`_swapped_constants`: the solver refuses the swapped moments of
most tops as no rigid body's).

Tolerance: ``rtol = 1e-3``. The inputs are exact 3-figure numbers and each answer is a few
products of them, so any careful computation agrees to ~1e-15; a student carrying 4 figures
(e.g. ``I1`` rounded) stays within 1e-3. Rejected draws (resampled): answers that are a small
difference of large terms (``|p_α|`` or ``|E'|`` below a fifth of the sum of its terms' sizes,
where 1e-3 relative would demand more digits than the data carry), motions outside the scene's
limits (see :func:`motion_within_limits`), and a primary mistake within five tolerances of the
key or of another mistake.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from problems.answers import Answer, Mistake
from problems.family import IllPosed, Parameter, drawn_scene
from problems.genuine import statement_number
from problems.rounding import latex_sig, round_sig
from solver.heavy_top import constants_of_motion, turning_points
from solver.inertia import centre_of_mass_offset, parallel_axis, shape_tensor

NAME = "heavy_top_constants"
TITLE = "Heavy symmetric top: constants of motion"
SUMMARY = "heavy symmetric top: p_γ, p_α and E' from the initial conditions"
RESULTS = ("R14", "R15", "R16")

SIG = 3
"""Significant figures of every shown number."""
RTOL = 1e-3
"""Relative tolerance of every answer (see the module docstring)."""
MARGIN = 5.0
"""Known mistakes must lie this many tolerances from the key and from each other."""
G = 9.81
"""Gravitational acceleration shown in the statements, m/s²."""
BRASS, STEEL = 8500.0, 7850.0
"""Densities, kg/m³."""
POLE_MARGIN = 0.05
"""Least distance (rad) of a turning point from a pole: near ``β = 0`` the top nearly sleeps
and ``α̇`` at the turning point is ill-conditioned."""
TABLE_MARGIN = 0.05
"""Least clearance (rad) between the largest tilt and the tilt at which the rim touches."""
MIN_NUTATION = 0.02
"""Least ``β2 − β1`` (rad): nearly coinciding turning points are steady precession."""
MIN_CONDITION = 0.2
"""An answer must be at least this fraction of the sum of its terms' magnitudes."""
MAX_ATTEMPTS = 500

STATE_NAMES = ("beta0", "alpha_dot0", "beta_dot0", "gamma_dot0")
STATE_UNITS = {"beta0": "rad", "alpha_dot0": "rad/s", "beta_dot0": "rad/s", "gamma_dot0": "rad/s"}
_STATE_SYMBOLS = (r"\beta_0", r"\dot\alpha_0", r"\dot\beta_0", r"\dot\gamma_0")

CONVENTIONS = ("euler_angles", "heavy_top")
"""Topics of :mod:`problems.conventions` stated at the top of the notebook (shared with
turning_points and motion_type)."""

FEEDBACK = {
    "I1_about_cm": (
        "I1 must be the moment about the fixed point, not about the centre of mass: add M l² "
        "(parallel-axis theorem, R2), so I1 = M R²/4 + M l² for the disc."
    ),
    "I1_I3_swapped": (
        "I1 and I3 are swapped: I3 is the moment about the symmetry axis (it multiplies the "
        "spin ω3), I1 the transverse moment about the fixed point."
    ),
    "degree_mode": (
        "The angles are in radians, but this value comes from reading them as degrees (a "
        "calculator in degree mode, or numpy.deg2rad applied to radians)."
    ),
    "omega3_is_gamma_dot": (
        "ω3 = α̇ cos β + γ̇ (R12): the spin rate γ̇ alone is not the angular velocity about the "
        "symmetry axis; the precession adds α̇ cos β."
    ),
    "missing_p_gamma_term": (
        "p_α = ∂L/∂α̇ = I1 α̇ sin²β + I3 (α̇ cos β + γ̇) cos β (R15): the second term, "
        "p_γ cos β, is missing."
    ),
    "E_not_E_prime": (
        "That is the total energy E; E' = E − p_γ²/(2 I3) (R16) leaves out the constant spin "
        "energy."
    ),
}


# --------------------------------------------------------------------------------------------
# A real top and its initial state (shared with turning_points and motion_type)


@dataclass(frozen=True)
class Top:
    """A heavy symmetric top: what the statement shows, and its moments from the shown values.

    Attributes
    ----------
    scene : str
        ``"toy_top"``, ``"gyroscope"`` or ``"hanging"``.
    title : str
        Question title.
    describe : callable
        The Markdown describing the body, from ``params`` (:attr:`text`).
    params : dict
        The scene and its shown (rounded) numbers, SI.
    I1, I3, Mgl : float
        Moments about the fixed point (kg m²) and weight × lever arm (J), from ``params``.
    I1_cm : float or None
        Transverse moment about the centre of mass, when the student must shift it to the tip.
    tilt : tuple of float
        Range of the initial tilt ``β0`` (rad).
    limits : tuple of float
        Allowed ``[β1, β2]`` range of the motion (rad).
    spin : tuple of float
        Range of ``|γ̇0|`` (rad/s).
    """

    scene: str
    title: str
    describe: Callable[[Mapping[str, Any]], str]
    params: dict[str, Any]
    I1: float
    I3: float
    Mgl: float
    I1_cm: float | None
    tilt: tuple[float, float]
    limits: tuple[float, float]
    spin: tuple[float, float]

    @property
    def text(self) -> str:
        """Markdown describing the body; names every number of ``params`` in backticks
        (written when asked for: a statement's, not a draw's)."""
        return self.describe(self.params)


@dataclass(frozen=True)
class State:
    """Shown initial state: ``β0`` (rad) and the Euler-angle rates (rad/s, R11/R12)."""

    beta0: float
    alpha_dot0: float
    beta_dot0: float
    gamma_dot0: float

    def values(self) -> tuple[float, float, float, float]:
        """``(β0, α̇0, β̇0, γ̇0)``: ``astuple`` without its deep copy (they are floats)."""
        return (self.beta0, self.alpha_dot0, self.beta_dot0, self.gamma_dot0)


PARAMETERS: dict[str, Parameter] = {
    "scene": Parameter(choices=("toy_top", "gyroscope", "hanging"), description="the top"),
    "M": Parameter(unit="kg", description="mass"),
    "R": Parameter(unit="m", description="radius of the disc"),
    "l": Parameter(unit="m", description="fixed point to centre of mass"),
    "I1": Parameter(unit="kg m^2", description="transverse moment about the pivot"),
    "I3": Parameter(unit="kg m^2", description="moment about the symmetry axis"),
    "g": Parameter(unit="m/s^2", description="gravitational acceleration"),
    "beta0": Parameter(unit="rad", low=0.15, high=2.85, description="initial tilt"),
    "alpha_dot0": Parameter(unit="rad/s", description="initial precession rate"),
    "beta_dot0": Parameter(unit="rad/s", description="initial nodding rate"),
    "gamma_dot0": Parameter(unit="rad/s", description="initial spin rate"),
}
"""The parameters of a top and its initial state (shared with turning_points and
motion_type). ``beta0`` may be set (each scene accepts part of its range: a draw outside the
scene's limits is rejected)."""


def _r(x: float) -> float:
    return round_sig(x, SIG)


def pick(rng: np.random.Generator, options: Sequence[float]) -> float:
    """One of ``options``, uniformly: the very draw ``rng.choice(options)`` makes (one
    ``integers`` below ``len(options)``), without its array work."""
    return options[int(rng.integers(len(options)))]


def _disc_body(rng: np.random.Generator, lever: tuple[float, float]) -> dict[str, float]:
    """Shown ``M, R, l, g`` of a thin brass disc on a light axle."""
    R, thickness = _r(rng.uniform(0.02, 0.04)), rng.uniform(0.003, 0.006)
    M, arm = _r(BRASS * math.pi * R**2 * thickness), _r(rng.uniform(*lever))
    return {"M": M, "R": R, "l": arm, "g": G}


def _disc_moments(p: Mapping[str, Any]) -> tuple[float, float, float, float]:
    """``I1`` about the tip, ``I3``, ``Mgl`` and ``I1`` about the centre of mass of the disc
    scenes (R2: thin disc about a diameter, parallel-axis theorem)."""
    M, R, arm = p["M"], p["R"], p["l"]
    I1_cm = M * R**2 / 4
    return I1_cm + M * arm**2, M * R**2 / 2, M * p["g"] * arm, I1_cm


def _shown(p: Mapping[str, Any], name: str, symbol: str, unit: str) -> str:
    return f"${symbol} = {latex_sig(p[name], SIG)}$ {unit} (`{name}`)"


def _toy_top_text(p: Mapping[str, Any]) -> str:
    return (
        f"A toy top: a thin brass disc of mass {_shown(p, 'M', 'M', 'kg')} and radius "
        f"{_shown(p, 'R', 'R', 'm')} on a massless axle whose tip, {_shown(p, 'l', 'l', 'm')} "
        f"from the disc's centre, rests in a dimple of the table; {_shown(p, 'g', 'g', 'm/s²')}."
    )


def _toy_top(p: Mapping[str, Any]) -> Top:
    I1, I3, Mgl, I1_cm = _disc_moments(p)
    touch = math.atan2(p["l"], p["R"])  # the rim reaches the table
    return Top("toy_top", "A toy top on a table", _toy_top_text, dict(p), I1, I3, Mgl, I1_cm,
               (0.15, touch - 0.1), (POLE_MARGIN, touch - TABLE_MARGIN), (100.0, 300.0))


def _hanging_text(p: Mapping[str, Any]) -> str:
    return (
        f"A thin brass disc of mass {_shown(p, 'M', 'M', 'kg')} and radius "
        f"{_shown(p, 'R', 'R', 'm')} hangs on a massless rod from a ball joint, its centre "
        f"{_shown(p, 'l', 'l', 'm')} from the joint: the symmetry axis points below the "
        f"horizontal ($\\beta > \\pi/2$); {_shown(p, 'g', 'g', 'm/s²')}."
    )


def _hanging(p: Mapping[str, Any]) -> Top:
    I1, I3, Mgl, I1_cm = _disc_moments(p)
    return Top("hanging", "A spinning disc hanging from a ball joint", _hanging_text, dict(p),
               I1, I3, Mgl, I1_cm, (1.9, 2.85), (math.pi / 2, math.pi - POLE_MARGIN),
               (60.0, 250.0))


def _gyroscope_dimensions(rng: np.random.Generator) -> tuple[float, float, float, float]:
    """A gyroscope's drawn dimensions, m: the rotor's radius ``R``, its distance ``d`` from
    the pivot and its thickness, and the axle's length beyond the rotor."""
    R, d = rng.uniform(0.025, 0.04), rng.uniform(0.04, 0.07)
    return R, d, rng.uniform(0.004, 0.008), rng.uniform(0.01, 0.02)


def _gyroscope_bodies(dimensions: Sequence[tuple[float, ...]]) -> list[dict[str, float]]:
    """Brass rotor (thin disc) at ``d`` on a steel axle (thin rod from the pivot), R2: the
    shown ``M, l, I1, I3, g`` of each gyroscope of :func:`_gyroscope_dimensions`, the
    tensors of all in one call each (elementwise: each as alone, bit for bit)."""
    R, d, thickness, beyond = np.array(dimensions, dtype=float).reshape(-1, 4).T
    m_rotor = BRASS * math.pi * R**2 * thickness
    length, radius = d + beyond, 0.002
    m_axle = STEEL * math.pi * radius**2 * length
    rod_cm = centre_of_mass_offset("thin_rod", length=length)
    tensor = (parallel_axis(shape_tensor("disc", m_rotor, radius=R), m_rotor, _on_axis(d))
              + parallel_axis(shape_tensor("thin_rod", m_axle, length=length), m_axle,
                              _on_axis(rod_cm)))
    M = m_rotor + m_axle
    shown = (M, (m_rotor * d + m_axle * rod_cm) / M, tensor[:, 0, 0], tensor[:, 2, 2])
    return [{"M": M_, "l": arm, "I1": I1, "I3": I3, "g": G}
            for M_, arm, I1, I3 in zip(*(round_sig(x, SIG).tolist() for x in shown),
                                       strict=True)]


def _on_axis(z: np.ndarray) -> np.ndarray:
    """Points ``(0, 0, z)`` on the symmetry axis, m."""
    points = np.zeros((len(z), 3))
    points[:, 2] = z
    return points


def _gyroscope_text(p: Mapping[str, Any]) -> str:
    return (
        "A gyroscope rests on a post at the end of its axle (the pivot): mass "
        f"{_shown(p, 'M', 'M', 'kg')}, centre of mass {_shown(p, 'l', 'l', 'm')} from the "
        f"pivot, moments {_shown(p, 'I1', 'I_1', 'kg m²')} about the pivot and "
        f"{_shown(p, 'I3', 'I_3', 'kg m²')} about the axle; {_shown(p, 'g', 'g', 'm/s²')}."
    )


def _gyroscope(p: Mapping[str, Any]) -> Top:
    return Top("gyroscope", "A gyroscope on a post", _gyroscope_text, dict(p), p["I1"],
               p["I3"], p["M"] * p["g"] * p["l"], None, (0.2, 1.6),
               (POLE_MARGIN, math.pi / 2 + 0.4), (100.0, 400.0))


@dataclass(frozen=True)
class _Scene:
    """A scene: the draw of its random numbers from a student's generator, the shown numbers
    of many such draws at once, and its :class:`Top` from the shown numbers."""

    draw: Callable[[np.random.Generator], Any]
    shown: Callable[[list], list[dict[str, float]]]
    top: Callable[[Mapping[str, Any]], Top]


SCENES: dict[str, _Scene] = {
    "toy_top": _Scene(lambda rng: _disc_body(rng, (0.025, 0.06)), list, _toy_top),
    "gyroscope": _Scene(_gyroscope_dimensions, _gyroscope_bodies, _gyroscope),
    "hanging": _Scene(lambda rng: _disc_body(rng, (0.03, 0.07)), list, _hanging),
}
"""The three tops (a disc's shown numbers are its draw's)."""

_BODY_NAMES = ("M", "R", "l", "I1", "I3", "g")


def draw_top(rng: np.random.Generator) -> Top:
    """A random real top (toy top, gyroscope or hanging disc), moments from the shown values."""
    return draw_tops([rng])[0]


def draw_tops(rngs: Sequence[np.random.Generator]) -> list[Top]:
    """:func:`draw_top` of each generator: each student's scene and random numbers drawn in
    order, then the shown numbers of each scene's tops worked out together."""
    scenes = [drawn_scene(SCENES, rng) for rng in rngs]
    drawn = [SCENES[scene].draw(rng) for scene, rng in zip(scenes, rngs, strict=True)]
    shown: list[dict[str, float]] = [{}] * len(rngs)
    for name, scene in SCENES.items():
        rows = [i for i, s in enumerate(scenes) if s == name]
        for i, body in zip(rows, scene.shown([drawn[i] for i in rows]) if rows else (),
                           strict=True):
            shown[i] = body
    return [top_from_params({"scene": scene, **body})
            for scene, body in zip(scenes, shown, strict=True)]


def top_from_params(params: Mapping[str, Any]) -> Top:
    """The :class:`Top` of recorded parameters (the scene and its shown numbers)."""
    shown = {k: params[k] for k in ("scene", *_BODY_NAMES) if k in params}
    return SCENES[params["scene"]].top(shown)


def draw_state(rng: np.random.Generator, top: Top, precession: float, nod: float) -> State:
    """An initial state of ``top``, rounded to ``SIG`` figures.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws ``β0`` in ``top.tilt``, ``|γ̇0|`` in ``top.spin`` and the spin's sense (one
        time in four clockwise seen from above).
    top : Top
        The body.
    precession : float
        ``α̇0`` as a multiple of the fast-top precession rate ``Mgl/(I3 γ̇0)`` (R21); 0 gives
        exactly ``α̇0 = 0``.
    nod : float
        ``β̇0`` as a multiple of the nutation frequency ``I3 |γ̇0|/I1`` (R21); 0 gives exactly
        ``β̇0 = 0``.
    """
    beta0 = _r(rng.uniform(*top.tilt))
    gamma_dot0 = _r(pick(rng, (1.0, 1.0, 1.0, -1.0)) * rng.uniform(*top.spin))
    alpha_dot0 = _r(precession * top.Mgl / (top.I3 * gamma_dot0)) if precession else 0.0
    beta_dot0 = _r(nod * top.I3 * abs(gamma_dot0) / top.I1) if nod else 0.0
    return State(beta0, alpha_dot0, beta_dot0, gamma_dot0)


def state_from_params(params: Mapping[str, Any]) -> State:
    """The :class:`State` of recorded parameters."""
    return State(*(params[n] for n in STATE_NAMES))


def state_args(top: Top, state: State) -> tuple[float, ...]:
    """``(I1, I3, Mgl, beta0, alpha_dot0, beta_dot0, gamma_dot0)`` for :mod:`solver.heavy_top`."""
    return (top.I1, top.I3, top.Mgl, *state.values())


def state_text(state: State) -> str:
    """The sentence giving the initial state, naming each value's Python name."""
    shown = ", ".join(
        f"${s} = {latex_sig(v, SIG)}$ {STATE_UNITS[n]} (`{n}`)"
        for s, n, v in zip(_STATE_SYMBOLS, STATE_NAMES, state.values(), strict=True)
    )
    return f"At $t = 0$: {shown}."


def variant_params(top: Top, state: State, **extra: float) -> dict[str, Any]:
    """The recorded parameters: the scene and body's, the state's, then ``extra``."""
    return {**top.params, **dict(zip(STATE_NAMES, state.values(), strict=True)), **extra}


def mistaken_states(top: Top, state: State) -> dict[str, tuple[float, ...]]:
    """Solver arguments of the moment and angle mistakes that apply to this top.

    ``I1_about_cm`` (scenes where the student shifts ``I1``), ``I1_I3_swapped`` (only if the
    swapped moments are still a rigid body's about its tip, ``I1 ≤ 2 I3``, which the solver
    requires; for the constants of motion :func:`_swapped_constants` writes the swap out),
    ``degree_mode`` (``β0`` read as degrees) and, when ``α̇0 ≠ 0``, ``omega3_is_gamma_dot``
    (``γ̇0`` taken for ``ω3 = γ̇0 + α̇0 cos β0``, so ``p_γ = I3 γ̇0``).
    """
    args = state_args(top, state)
    mistaken = {}
    if top.I1_cm is not None:
        mistaken["I1_about_cm"] = (top.I1_cm, *args[1:])
    if top.I1 <= 2 * top.I3:
        mistaken["I1_I3_swapped"] = (top.I3, top.I1, *args[2:])
    mistaken["degree_mode"] = (*args[:3], math.radians(state.beta0), *args[4:])
    if state.alpha_dot0 != 0.0:  # p_γ = I3 γ̇0: the state whose ω3 = γ̇' + α̇0 cos β0 is γ̇0
        spin_only = state.gamma_dot0 - state.alpha_dot0 * math.cos(state.beta0)
        mistaken["omega3_is_gamma_dot"] = (*args[:6], spin_only)
    return mistaken


def motion_within_limits(top: Top, beta1: float, beta2: float) -> bool:
    """Turning points inside the scene's limits (clear of the poles, the table, the horizontal
    for the hanging disc) and at least ``MIN_NUTATION`` apart."""
    low, high = top.limits
    return low <= beta1 and beta2 <= high and beta2 - beta1 >= MIN_NUTATION


def well_conditioned(value: float, *terms: float) -> bool:
    """``value`` is not a small difference of the larger ``terms`` it is the sum of."""
    return abs(value) >= MIN_CONDITION * sum(abs(t) for t in terms)


def select_mistakes(
    key: float, primary: dict[str, float], secondary: dict[str, float], *,
    rtol: float = RTOL, atol: float = 0.0, feedback: dict[str, str] | None = None,
) -> tuple[Mistake, ...] | None:
    """The known mistakes of one answer, or None if the draw must be rejected.

    ``primary`` mistakes are the ones the answer is about (``p_α`` without ``p_γ cos β``, β1
    and β2 exchanged …): each must lie ``MARGIN`` tolerances from the key and from the others,
    else the draw is rejected (None). ``secondary`` ones propagate from an earlier step (a
    moment or an angle mistake): each is kept, in order, only if it lies ``MARGIN`` tolerances
    from the key and from every mistake kept so far; otherwise it hardly changes *this* answer
    in this variant (e.g. ``I1`` about the centre of mass barely moves ``E'`` of a fast top,
    whose energy is mostly potential) and the grader could not name it reliably. Feedback from
    ``feedback`` (default :data:`FEEDBACK`).

    "Apart" means ``|x − y| > MARGIN (atol + rtol max(|x|, |y|))``: wider than the grader's
    test ``|x − m| ≤ atol + rtol |m|`` around either value, so each kept mistake is named by
    the grader even with the tolerances widened ``MARGIN`` times.
    """
    feedback = FEEDBACK if feedback is None else feedback

    def apart(x: float, kept: list[tuple[str, float]]) -> bool:
        size = abs(x)
        for y in (key, *(v for _, v in kept)):
            if not abs(x - y) > MARGIN * (atol + rtol * max(size, abs(y))):
                return False
        return True

    kept: list[tuple[str, float]] = []
    for name, value in primary.items():
        if not apart(float(value), kept):
            return None
        kept.append((name, float(value)))
    for name, value in secondary.items():
        if apart(float(value), kept):
            kept.append((name, float(value)))
    return tuple(Mistake(name, value, feedback[name]) for name, value in kept)


# --------------------------------------------------------------------------------------------
# This family: p_γ, p_α, E'


def _swapped_constants(top: Top, state: State) -> tuple[float, float, float]:
    """R15/R16 with ``I1`` and ``I3`` exchanged: what a student who swaps them computes.

    Written out rather than asked of the solver: ``constants_of_motion`` rightly refuses
    ``I3 > 2 I1`` (no rigid body has it about its tip), which is what the swap gives for most
    tops, yet the student's formulas still return these numbers.
    """
    beta0, alpha_dot0, beta_dot0, gamma_dot0 = state.values()
    u, s2 = math.cos(beta0), math.sin(beta0) ** 2
    p_gamma = top.I1 * (alpha_dot0 * u + gamma_dot0)
    p_alpha = top.I3 * alpha_dot0 * s2 + p_gamma * u
    e_prime = 0.5 * top.I3 * (beta_dot0**2 + alpha_dot0**2 * s2) + top.Mgl * u
    return p_alpha, p_gamma, e_prime


def _constants_many(motions: list[tuple[Top, State]]) -> list[tuple]:
    """For each ``(top, state)``: its mistaken states' names (:func:`mistaken_states` but
    the swap, see :func:`_swapped_constants`) and ``p_α``, ``p_γ``, ``E'`` (R15, R16) of the
    key then of each mistaken state (lists of floats), all of them in one solver call."""
    names, rows = [], []
    for top, state in motions:
        mistaken = mistaken_states(top, state)
        mistaken.pop("I1_I3_swapped", None)
        names.append(tuple(mistaken))
        rows.append([state_args(top, state), *mistaken.values()])
    ends = np.cumsum([len(r) for r in rows])[:-1]
    columns = np.array([row for student in rows for row in student], dtype=float).T
    split = ([part.tolist() for part in np.split(np.atleast_1d(c), ends)]
             for c in constants_of_motion(*columns))
    return list(zip(names, *split, strict=True))


def _answers(top: Top, state: State, constants: tuple) -> tuple[Answer, ...] | None:
    """The answers from the motion's :func:`_constants_many` (None: rejected)."""
    mistaken, p_alpha, p_gamma, e_prime = constants
    pa, pg, e = p_alpha[0], p_gamma[0], e_prime[0]
    beta0, alpha_dot0, beta_dot0, gamma_dot0 = state.values()
    transverse = top.I1 * alpha_dot0 * math.sin(beta0) ** 2
    kinetic = 0.5 * top.I1 * (beta_dot0**2 + alpha_dot0**2 * math.sin(beta0) ** 2)
    if not (well_conditioned(pa, transverse, pg * math.cos(beta0))
            and well_conditioned(e, kinetic, top.Mgl * math.cos(beta0))):
        return None
    pa_swap, pg_swap, e_swap = _swapped_constants(top, state)
    pa_wrong = dict(zip(mistaken, p_alpha[1:], strict=True))
    e_wrong = dict(zip(mistaken, e_prime[1:], strict=True))
    mistakes = (
        # p_γ does not involve I1; its degree-mode error is second order in α̇0/γ̇0
        select_mistakes(pg, {"omega3_is_gamma_dot": top.I3 * gamma_dot0},
                        {"I1_I3_swapped": pg_swap}),
        select_mistakes(pa, {"missing_p_gamma_term": transverse},
                        {"I1_I3_swapped": pa_swap, **pa_wrong}),
        select_mistakes(e, {"E_not_E_prime": e + pg**2 / (2 * top.I3)},
                        {"I1_I3_swapped": e_swap, **e_wrong}),
    )
    if any(m is None for m in mistakes):
        return None
    answers = (
        Answer("p_gamma", "scalar", pg, unit="kg m^2/s", rtol=RTOL, mistakes=mistakes[0],
               description="p_γ, the momentum conjugate to γ"),
        Answer("p_alpha", "scalar", pa, unit="kg m^2/s", rtol=RTOL, mistakes=mistakes[1],
               description="p_α, the momentum conjugate to α"),
        Answer("E_prime", "scalar", e, unit="J", rtol=RTOL, mistakes=mistakes[2],
               description="E' = E − p_γ²/(2 I3)", depends_on=("p_gamma",)),
    )
    return answers


def _statement(top: Top, state: State) -> str:
    return (
        f"{top.text} {state_text(state)}\n\n"
        "1. `p_gamma`, `p_alpha`: the momenta conjugate to $\\gamma$ and $\\alpha$;\n"
        "2. `E_prime`: the reduced energy $E' = E - p_\\gamma^2/(2 I_3)$."
    )


def draw(rng: np.random.Generator) -> dict[str, Any]:
    """A real top (:func:`draw_top`) launched with a precession of either sense and a nod."""
    return draw_many([rng])[0]


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any]]:
    """:func:`draw` of each generator, the tops drawn together (:func:`draw_tops`; the batch
    form, :mod:`problems.family`)."""
    return [_launched(rng, top) for rng, top in zip(rngs, draw_tops(rngs), strict=True)]


def _launched(rng: np.random.Generator, top: Top) -> dict[str, Any]:
    """The parameters of ``top`` launched with a precession of either sense and a nod."""
    sense = pick(rng, (1.0, 1.0, -1.0))
    nod = pick(rng, (0.0, 1.0, -1.0)) * rng.uniform(0.02, 0.15)
    return variant_params(top, draw_state(rng, top, sense * rng.uniform(0.3, 2.5), nod))


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``p_gamma``, ``p_alpha`` and ``E_prime`` (R15, R16), from the shown values.

    Raises :class:`~problems.family.IllPosed` for a motion outside the scene's limits (a top
    that would hit the table, sleep or flop over), an ill-conditioned answer, or a primary
    mistake close to the key.
    """
    (found,) = answers_many([params])
    if isinstance(found, IllPosed):
        raise found
    return found


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form (:mod:`problems.family`): every top's turning points, then the
    constants of every motion inside its scene's limits, each in one solver call."""
    motions = [(top_from_params(p), state_from_params(p)) for p in many]
    beta1, beta2 = map(np.atleast_1d,
                       turning_points(*np.array([state_args(*m) for m in motions]).T))
    inside = [i for i, (top, _) in enumerate(motions)
              if motion_within_limits(top, float(beta1[i]), float(beta2[i]))]
    constants = dict(zip(inside, _constants_many([motions[i] for i in inside]) if inside
                         else (), strict=True))
    found: list[tuple[Answer, ...] | IllPosed] = []
    for i, motion in enumerate(motions):
        if i not in constants:
            found.append(IllPosed("the motion leaves the scene's limits"))
            continue
        answered = _answers(*motion, constants[i])
        found.append(IllPosed("ill-conditioned, or a mistake close to the key")
                     if answered is None else answered)
    return found


def heading(params: Mapping[str, Any]) -> str:
    return f"{top_from_params(params).title}: constants of motion"


def statement(params: Mapping[str, Any]) -> str:
    return _statement(top_from_params(params), state_from_params(params))


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``E_prime`` from the student's own ``p_gamma``, as the statement defines it:
    ``E − p_γ²/(2 I3)``, E the top's energy (R15, :func:`solver.heavy_top.constants_of_motion`)."""
    if name != "E_prime":
        raise LookupError(name)
    top, state = top_from_params(params), state_from_params(params)
    _, p_gamma, e_prime = (float(np.atleast_1d(x)[0])
                           for x in constants_of_motion(*state_args(top, state)))
    energy = e_prime + p_gamma**2 / (2 * top.I3)
    return energy - float(earlier["p_gamma"]) ** 2 / (2 * top.I3)


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's ``p_gamma`` is no ground for ``E_prime = E − p_γ²/(2 I3)`` (R15, R16):
    zero (``E'`` is then the energy ``E`` itself, the reduction left out), or a number of the
    statement copied (``γ̇0``, say), not ``p_γ = I3 (α̇ cos β + γ̇)`` worked out. None
    otherwise."""
    if name != "E_prime":
        raise LookupError(name)
    p_gamma = float(earlier["p_gamma"])
    if p_gamma == 0:
        return ("your {p_gamma} is zero, which makes {E_prime} the energy E itself: R16's "
                "reduction is left out")
    top, state = top_from_params(params), state_from_params(params)
    key = float(np.atleast_1d(constants_of_motion(*state_args(top, state))[1])[0])
    copied = statement_number(p_gamma, params, key)
    if copied is not None:
        return (f"your {{p_gamma}} is the statement's {{{copied}}}, copied, not R15's momentum "
                "worked out: {E_prime} from it shows nothing")
    return None
