"""Kinetic energy and angular momentum for a given ω and inertia tensor; the angle between L and ω.

Two scenes, drawn at random:

``tumbling_satellite``
    A small satellite's inertia tensor in its body axes (from a spec sheet: principal moments of
    5–60 kg m², axes turned at random, entries shown to 4 significant figures, so the products of
    inertia do not vanish) and its tumbling rate ω (components up to 0.3 rad/s).
``askew_disc``
    A grinding wheel or saw blade, a uniform thin disc (R2) mounted on an axle through its centre
    with its symmetry axis tilted by θ from the axle, spinning at ω about the axle. Its tensor in
    the axle frame is the disc's principal tensor turned by θ about y.

Answers (R3, R5): ``T = ½ ω·I·ω``, ``L = I·ω`` and the angle between ``L`` and ``ω``, in
``[0, π/2)`` (``L·ω = 2T > 0``). Known mistakes: the missing ½ in T, products of inertia ignored,
L assumed parallel to ω, the angle in degrees, the disc's tilt θ given for the angle of L.

Tolerance: ``rtol = 1e-3`` (vectors by norm). The parameters are exact inputs with 3–4 figures,
so a student keeping 4 figures in the working is inside it; the angle is a smooth function of
them (no cancellation: draws with an angle below 0.03 rad are rejected, where the relative error
of a hand computation of a small angle from nearly parallel vectors would grow).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from problems.answers import Answer, Mistake
from problems.family import (
    IllPosed,
    Parameter,
    batch_of_one,
    drawn_scene,
    redrawn_many_until_well_posed,
    redrawn_until_well_posed,
    remembered,
    stacked_apart,
    stacked_dots,
    stacked_norms,
)
from problems.genuine import SAME
from problems.rounding import format_sig, latex_sig, round_sig
from solver.inertia import angular_momentum, kinetic_energy, shape_tensor
from solver.parameters import principal_moments

NAME = "energy_momentum"
TITLE = "Kinetic energy and angular momentum"
SUMMARY = "T and L for a given ω and inertia tensor; the angle between L and ω"
RESULTS = ("R3", "R5")
CONVENTIONS = ('inertia',)
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""

RTOL = 1e-3
MIN_ANGLE = 0.03  # rad; below it the angle between L and ω is a small difference of directions
SEPARATION = 5.0  # key and mistakes at least this many tolerances apart
MAX_TRIES = 200

# Discs: (radius range m, mass range kg, spin range rad/s).
DISCS = {
    "grinding wheel": ((0.075, 0.1), (0.5, 1.5), (200.0, 350.0)),
    "circular saw blade": ((0.09, 0.125), (0.3, 0.8), (400.0, 520.0)),
}

_HALF = "T = ½ ω·I·ω (R3): the factor ½ is missing."
_DEGREES = "The angle is asked in radians; this is the angle in degrees."


def _angle(u: np.ndarray, v: np.ndarray) -> float:
    """The angle between two vectors, in rad (atan2 form: accurate for small angles too)."""
    return float(_angles(u, v))


def _angles(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The angles between stacked vectors (..., 3), in rad: :func:`_angle` of each pair."""
    return np.arctan2(stacked_norms(np.cross(u, v)), stacked_dots(u, v))


def _answer(name, kind, key, mistakes, unit, description) -> Answer:
    return Answer(  # Answer converts numpy values to plain JSON
        name, kind, key, unit=unit, rtol=RTOL, description=description,
        mistakes=tuple(Mistake(n, v, f) for n, v, f in mistakes),
    )


def _built(specs: tuple) -> tuple[Answer, ...]:
    """T, L and the angle from :func:`_answers`' arguments of :func:`_answer`."""
    T, L, angle = (_answer(*spec) for spec in specs)
    return T, L, angle.following("L")


def _answers(tensor: np.ndarray, omega: np.ndarray, T_naive: np.ndarray, L_naive: np.ndarray,
             naive: tuple[str, str, str], extra_angle: dict[str, tuple] | None = None
             ) -> list[tuple | None]:
    """For stacked tensors (n, 3, 3) and angular velocities (n, 3), the arguments of
    :func:`_answer` for T (J, R3), L (kg m²/s, R5) and the angle between them (rad), with
    their mistakes (None: an angle below ``MIN_ANGLE``, or a mistake within SEPARATION
    tolerances of its key or another); ``naive = (name, feedback on T, feedback on L)`` is
    the simplification that gave ``T_naive`` (n,) and ``L_naive`` (n, 3), ``extra_angle``
    maps another mistaken angle to its values (n,) and feedback."""
    T = kinetic_energy(tensor, omega)
    L = angular_momentum(tensor, omega)
    angle = _angles(L, omega)
    wrong_angle = {"degrees": (np.degrees(angle), _DEGREES), **(extra_angle or {})}
    name, T_feedback, L_feedback = naive
    kept = ~(angle < MIN_ANGLE) & _apart(np.stack([T, 2 * T, T_naive], axis=-1)) \
        & _apart(np.stack([L, L_naive], axis=-2)) \
        & _apart(np.stack([angle, *(v for v, _ in wrong_angle.values())], axis=-1))
    return [(
        ("T", "scalar", float(T[i]), [("missing_half", 2 * float(T[i]), _HALF),
                                      (name, float(T_naive[i]), T_feedback)],
         "J", "kinetic energy"),
        ("L", "vector", L[i], [(name, L_naive[i], L_feedback)], "kg m^2/s",
         "angular momentum (same axes as ω)"),
        ("angle", "angle", float(angle[i]),
         [(n, v[i], feedback) for n, (v, feedback) in wrong_angle.items()],
         "rad", "angle between L and ω"),
    ) if kept[i] else None for i in range(len(kept))]


def _apart(values: np.ndarray) -> np.ndarray:
    """Whether, for each student, the key ``values[..., 0, :]`` (or ``values[..., 0]``, a
    number) and the mistakes after it lie SEPARATION tolerances apart (vectors by norm)."""
    values = values[..., None] if values.ndim == 2 else values  # numbers: vectors of one
    return stacked_apart(values, SEPARATION * RTOL * stacked_norms(values[..., 0, :]))


def _physical_moments(moments: np.ndarray) -> bool:
    """Principal moments (3,) a rigid body can have (R4)."""
    try:
        principal_moments(*moments)
    except ValueError:
        return False
    return True


def _physical_many(moments: np.ndarray) -> np.ndarray:
    """:func:`_physical_moments` of each row of ``moments`` (n, 3): all checked at once when
    all are a body's (the drawn tensors), else row by row."""
    try:
        principal_moments(*moments.T)
    except ValueError:
        return np.array([_physical_moments(m) for m in moments], dtype=bool)
    return np.ones(len(moments), dtype=bool)


def _physical(tensor: np.ndarray) -> bool:
    """Still a physical inertia tensor after the rounding (R4)."""
    return _physical_moments(np.linalg.eigvalsh(tensor))


def _satellite_answers(many: list[Mapping[str, Any]]) -> list[tuple | IllPosed | None]:
    """:func:`_answers` of satellites (stacked), or the IllPosed of a tensor that is not a
    body's or of too slow a tumble."""
    tensor, omega = (np.array([params[n] for params in many]) for n in ("I", "omega"))
    kept = _physical_many(np.linalg.eigvalsh(tensor)) & (stacked_norms(omega) >= 0.1)
    rows = np.flatnonzero(kept)
    tensor, omega = tensor[rows], omega[rows]
    diag = np.zeros_like(tensor)  # products of inertia left out
    diag[:, _AXES, _AXES] = tensor[:, _AXES, _AXES]
    found: list = [IllPosed("no physical tensor, or too slow a tumble") for _ in many]
    for i, specs in zip(rows, _answers(tensor, omega, kinetic_energy(diag, omega),
                                       angular_momentum(diag, omega), _PRODUCTS_IGNORED),
                        strict=True):
        found[i] = specs
    return found


_AXES = np.arange(3)
_PRODUCTS_IGNORED = (
    "products_ignored",
    "The products of inertia (off-diagonal entries) matter: the body axes are not principal "
    "axes, so T = ½ ω·I·ω with the full tensor (R3).",
    "The products of inertia (off-diagonal entries) matter: the body axes are not principal "
    "axes, so L = I·ω with the full tensor (R5).",
)


def _tumbling_satellite(rng: np.random.Generator) -> dict[str, Any] | None:
    """A satellite's tensor (principal moments turned at random, 4 figures) and its ω."""
    moments = np.sort(rng.uniform(5.0, 60.0, size=3))
    if moments[2] >= moments[0] + moments[1] or np.min(np.diff(moments)) < 2.0:
        return None  # not a physical body, or a nearly symmetric one (small products)
    Q = Rotation.random(rng=rng).as_matrix()
    upper = round_sig(np.triu(Q @ np.diag(moments) @ Q.T), 4)
    tensor = upper + np.triu(upper, 1).T
    if not _physical(tensor):
        return None
    omega = round_sig(rng.uniform(-0.3, 0.3, size=3), 3)
    if np.linalg.norm(omega) < 0.1:
        return None
    return {"scene": "tumbling_satellite", "I": tensor.tolist(), "omega": omega.tolist()}


_ASK = ("Find the kinetic energy $T$, the angular momentum $\\mathbf L$ about the centre of "
        "mass (along the same axes as $\\boldsymbol\\omega$), and the angle between "
        "$\\mathbf L$ and $\\boldsymbol\\omega$ (from 0 to π).")


def _satellite_statement(params: Mapping[str, Any]) -> str:
    tensor, omega = params["I"], params["omega"]
    rows = " \\\\ ".join(" & ".join(latex_sig(x, 4) for x in row) for row in tensor)
    return (
        "A small satellite tumbles after its attitude control failed. In its body axes, its "
        "inertia tensor about the centre of mass is (`I`)\n\n"
        f"$$\\mathsf I = \\begin{{pmatrix}} {rows} \\end{{pmatrix}}\\ \\mathrm{{kg\\,m^2}},$$"
        "\n\nand its angular velocity is "
        f"$\\boldsymbol\\omega = ({', '.join(format_sig(w, 3) for w in omega)})$ rad/s "
        f"(`omega`).\n\n{_ASK}"
    )


def _askew_disc(rng: np.random.Generator) -> dict[str, Any]:
    """A grinding wheel or saw blade: its mass, radius, tilt and spin, rounded."""
    kind = list(DISCS)[int(rng.integers(len(DISCS)))]
    radius_range, mass_range, spin_range = DISCS[kind]
    M, R = round_sig(rng.uniform(*mass_range), 3), round_sig(rng.uniform(*radius_range), 3)
    theta = round_sig(rng.uniform(0.12, 0.4), 3)
    w = round_sig(rng.uniform(*spin_range), 3)
    return {"scene": "askew_disc", "disc": kind, "M": M, "R": R, "theta": theta, "omega": w}


def _disc_answers(many: list[Mapping[str, Any]]) -> list[tuple | None]:
    """:func:`_answers` of discs askew (stacked)."""
    M, R, theta, w = (np.array([params[n] for params in many])
                      for n in ("M", "R", "theta", "omega"))
    disc = shape_tensor("disc", M, radius=R)  # principal: symmetry axis along z
    tilt = Rotation.from_euler("y", theta[:, None]).as_matrix()  # axes (sin θ, 0, cos θ)
    tensor = tilt @ disc @ np.swapaxes(tilt, -1, -2)
    omega = np.zeros((len(many), 3))
    omega[:, 2] = w
    I3 = disc[:, 2, 2]
    # ½ I3 ω² as one student's scalars give it (a float's ** is not numpy's square)
    T_naive = np.array([0.5 * i3 * params["omega"] ** 2 for i3, params in zip(I3, many,
                                                                              strict=True)])
    return _answers(tensor, omega, T_naive, I3[:, None] * omega, _UNTILTED, extra_angle={
        "tilt_angle": (theta, "θ is the angle between the disc's axis and ω; the question "
                       "asks for the angle between L and ω, which is smaller.")})


_UNTILTED = (
    "untilted",
    "½ I3 ω² would hold for an untilted disc. Tilted, its moment about the axle is "
    "I_zz = I1 sin²θ + I3 cos²θ, with I1 = MR²/4 the moment about a diameter (R3).",
    "The disc's axis is tilted from the axle, so L = I·ω is not along ω: in the axle frame "
    "the tensor has a product of inertia I_xz ≠ 0 (R5).",
)


def _disc_statement(params: Mapping[str, Any]) -> str:
    M, R, theta, w = (params[n] for n in ("M", "R", "theta", "omega"))
    return (
        f"A {params['disc']}, a uniform thin disc of mass $M = {latex_sig(M, 3)}$ kg (`M`) and "
        f"radius $R = {latex_sig(R, 3)}$ m (`R`), is mounted askew: its axle passes through its "
        f"centre at the angle $\\theta = {latex_sig(theta, 3)}$ rad (`theta`) to its symmetry "
        f"axis, and spins at $\\omega = {latex_sig(w, 3)}$ rad/s (`omega`). Take $z$ along the "
        "axle and the symmetry axis along $(\\sin\\theta, 0, \\cos\\theta)$ at this "
        f"instant.\n\n{_ASK}"
    )


SCENES = {
    "tumbling_satellite": (_tumbling_satellite, _satellite_answers, _satellite_statement,
                           "Energy and angular momentum of a tumbling satellite"),
    "askew_disc": (_askew_disc, _disc_answers, _disc_statement, "A {disc} mounted askew"),
}
"""Scene → (its draw, answers, statement, title)."""

PARAMETERS: dict[str, Parameter] = {
    "scene": Parameter(choices=tuple(SCENES), description="a satellite, or a disc askew"),
    "disc": Parameter(choices=tuple(DISCS), description="the disc's object"),
    "I": Parameter(unit="kg m^2", shape=(3, 3), figures=4, description="inertia tensor"),
    "M": Parameter(unit="kg", description="mass of the disc"),
    "R": Parameter(unit="m", description="radius of the disc"),
    "theta": Parameter(unit="rad", description="tilt of the disc on its axle"),
    "omega": Parameter(unit="rad/s", shape=None,
                       description="angular velocity (a vector), or the axle's spin"),
}


def draw(rng: np.random.Generator) -> dict[str, Any] | None:
    """A scene of :data:`SCENES`, then draws of it until one is well posed (at most
    ``MAX_TRIES``)."""
    return redrawn_until_well_posed(SCENES[drawn_scene(SCENES, rng)][0], _specs, rng, MAX_TRIES)


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any] | None]:
    """:func:`draw` of each generator, each round's tries tested together (the batch form,
    :mod:`problems.family`)."""
    return redrawn_many_until_well_posed([SCENES[drawn_scene(SCENES, rng)][0] for rng in rngs],
                                         _specs_many, rngs, MAX_TRIES)


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``T`` (J), ``L`` (kg m²/s, vector) and ``angle`` (rad) between L and ω, R3, R5.

    Raises :class:`~problems.family.IllPosed` for an angle below ``MIN_ANGLE`` or a known
    mistake close to the key.
    """
    return _built(_specs(params))


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form: the tensors, T, L and the angles of all at once."""
    return [found if isinstance(found, IllPosed) else _built(found)
            for found in _specs_many(many)]


@remembered  # the draw's accepted try, then answers() of the same parameters
def _specs(params: Mapping[str, Any]) -> tuple:
    """What :func:`answers` builds its answers from; IllPosed where it rejects them (the
    draw's test of each try, which builds none)."""
    return batch_of_one(_specs_many, params)


def _specs_many(many: list[Mapping[str, Any]]) -> list[tuple | IllPosed]:
    """:func:`_specs` of each parameter set (an IllPosed where rejected), the scenes alike
    stacked and worked out together."""
    alike: dict[str, list[int]] = {}
    for i, params in enumerate(many):
        alike.setdefault(params["scene"], []).append(i)
    found: list = [None] * len(many)
    for scene, rows in alike.items():
        for i, specs in zip(rows, SCENES[scene][1]([many[i] for i in rows]), strict=True):
            found[i] = (IllPosed("too small an angle, or a mistake close to the key")
                        if specs is None else specs)
    return found


def heading(params: Mapping[str, Any]) -> str:
    return SCENES[params["scene"]][3].format(disc=params.get("disc"))


def statement(params: Mapping[str, Any]) -> str:
    return SCENES[params["scene"]][2](params)


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``angle`` between the student's own ``L`` and the given ω (along the axle, for the disc
    askew)."""
    if name != "angle":
        raise LookupError(name)
    return _angle(np.array(earlier["L"], dtype=float), _omega_vector(params))


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's ``L`` leaves nothing to work out for ``angle`` (R5: ``L = I·ω`` is
    along ω only when ω is along a principal axis, which no draw is): ``L`` zero, or parallel
    (or antiparallel) to the given ω — ω itself copied, or ``L = I ω`` with a scalar ``I`` —
    which makes the angle 0 (or π) with nothing computed. None otherwise."""
    if name != "angle":
        raise LookupError(name)
    L, omega = np.array(earlier["L"], dtype=float), _omega_vector(params)
    if not np.any(L):
        return "your {L} is zero: there is no angle {angle} to find (R5)"
    if np.linalg.norm(np.cross(L, omega)) <= SAME * np.linalg.norm(L) * np.linalg.norm(omega):
        return ("your {L} is parallel to ω, which makes {angle} zero with nothing of R5 worked "
                "out (L = I·ω turns away from ω)")
    return None


def _omega_vector(params: Mapping[str, Any]) -> np.ndarray:
    """ω as a vector: given, or along the axle (z) for the disc askew."""
    omega = params["omega"]
    return np.array(omega if params["scene"] == "tumbling_satellite" else [0.0, 0.0, omega],
                    dtype=float)
