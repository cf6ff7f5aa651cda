"""Inertia tensor of point masses or of a uniform box about a corner; principal moments and axes.

Two scenes, drawn at random:

``point_masses``
    Three or four small weights (20–250 g) fixed on a light rigid frame, at positions on a
    1 cm grid within 15 cm of the pivot O. Tensor about O by R2's sum.
``box_corner``
    A uniform book, smartphone or satellite solar panel (edges ``a, b, c`` along x, y, z) turning
    about one of its corners: the box's tensor about its centre of mass (R2's closed form)
    shifted to the corner by the parallel-axis theorem (R2).

Answers: the diagonal ``(I_xx, I_yy, I_zz)`` and the products ``(I_xy, I_xz, I_yz)`` of the
tensor, the principal moments in ascending order (R4), and the unit principal axis of the
largest moment (R4). An eigenvector is defined only up to sign, so the question fixes the sign:
the axis is asked *with a positive z component*, and draws whose axis lies within ~12° of the xy
plane are rejected (there the sign convention would hinge on a small, rounding-sensitive
number). Draws with the two largest moments within 5 % are rejected too: the axis of a nearly
degenerate pair is ill-conditioned (it turns by ~δI/(I3 − I2) under a change δI).

Tolerance: ``rtol = 1e-3`` on every answer (vectors by norm, see :mod:`problems.answers`). The
parameters have 2–3 significant figures but are *exact* inputs (the key is computed from the
displayed values), so a student who keeps 4 or more figures in the working lands within 1e-3;
one who rounds intermediate results to 3 figures may not, and the statement says so.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

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
    stacked_norms,
)
from problems.genuine import SAME
from problems.rounding import format_sig, latex_sig, round_sig
from solver.inertia import parallel_axis, point_mass_tensor, principal_axes, shape_tensor

NAME = "inertia_tensor"
TITLE = "Inertia tensor and principal axes"
SUMMARY = "inertia tensor of point masses or of a box about its corner; principal moments and axis"
RESULTS = ("R2", "R4")

RTOL = 1e-3
CONVENTIONS = ("inertia",)
"""Topics of :mod:`problems.conventions` stated at the top of the notebook."""
MIN_GAP = 0.05  # reject (I3 − I2)/I3 below this: the largest axis would be ill-conditioned
MIN_AXIS_Z = 0.2  # reject |n_z| below this: the sign convention n_z > 0 would be fragile
SEPARATION = 5.0  # key and mistakes at least this many tolerances apart (no overlapping balls)
MAX_TRIES = 200

# Uniform boxes (a, b, c ranges in m, mass range in kg): real objects' sizes.
BOXES = {
    "book": ((0.20, 0.30), (0.13, 0.21), (0.015, 0.05), (0.4, 1.5)),
    "smartphone": ((0.14, 0.17), (0.065, 0.08), (0.007, 0.01), (0.14, 0.22)),
    "solar panel": ((1.5, 2.5), (0.8, 1.2), (0.02, 0.04), (8.0, 20.0)),
}

_ASK = (
    "Find the inertia tensor about $O$: its diagonal $(I_{xx}, I_{yy}, I_{zz})$ and its products "
    "of inertia $(I_{xy}, I_{xz}, I_{yz})$, with their minus sign, $I_{xy} = -\\sum m\\,x y$. "
    "Then the principal moments, ascending, and the **unit** axis of the largest, with a "
    "**positive $z$ component**."
)
"""What is asked, for either scene."""


def _positive_z(v: np.ndarray) -> np.ndarray:
    """The sign convention of the question: the unit vectors ``±v`` (..., 3) with a positive
    z component."""
    return np.where(v[..., 2:] > 0, v, -v)


def _diagonal(tensors: np.ndarray) -> np.ndarray:
    """The diagonals (..., 3) of tensors (..., 3, 3)."""
    return np.diagonal(tensors, axis1=-2, axis2=-1)


def _diagonal_tensor(diagonal: np.ndarray) -> np.ndarray:
    """Tensors (..., 3, 3) with the given diagonals (..., 3) and +0.0 elsewhere (as
    ``numpy.diag`` makes them: a product of ``-0.0`` would print as such)."""
    tensors = np.zeros((*diagonal.shape, 3))
    tensors[..., _AXES, _AXES] = diagonal
    return tensors


_AXES = np.arange(3)
_PRODUCTS = (np.array([0, 0, 1]), np.array([1, 2, 2]))  # (xy, xz, yz)


def _apart(values: np.ndarray) -> np.ndarray:
    """Whether, for each student, the key ``values[..., 0, :]`` and the mistakes after it lie
    SEPARATION tolerances from one another (vectors by norm, as graded)."""
    return stacked_apart(values, SEPARATION * RTOL * stacked_norms(values[..., 0, :]))


def _vector_answer(name, key, mistakes, unit, description, depends=()) -> Answer:
    """A vector answer (kg m² or a unit vector) with its mistakes ``(name, value, feedback)``."""
    answer = Answer(
        name, "vector", np.asarray(key, dtype=float).tolist(), unit=unit, rtol=RTOL,
        description=description,
        mistakes=tuple(Mistake(n, np.asarray(v, float).tolist(), f) for n, v, f in mistakes),
    )
    return answer.following(*depends) if depends else answer


_PRODUCT_SIGN = (
    "Check the sign of the products of inertia: I_ij = −Σ m x_i x_j for i ≠ j (R2), with a "
    "minus sign."
)

_FEEDBACK = {
    "product_sign": _PRODUCT_SIGN,
    "axis_distance":
        "I_xx is Σ m (y² + z²), the squared distance *from* the x axis (R2), not Σ m x².",
    "parallel_axis_forgotten":
        "This is the tensor about the centre of mass. About the corner, add the "
        "parallel-axis term M (d² δ_ij − d_i d_j), d = (a/2, b/2, c/2) (R2).",
    "diagonal_entries":
        "These are the diagonal entries of the tensor. The principal moments are its "
        "eigenvalues (R4); they equal the diagonal entries only when the products of inertia "
        "vanish.",
    "sign_convention":
        "Right axis, wrong sign: the question asks for the unit vector with a positive z "
        "component.",
    "smallest_axis":
        "This is the axis of the *smallest* principal moment. numpy.linalg.eigh returns the "
        "eigenvalues in ascending order, so the largest moment's axis is the *last column* of "
        "the eigenvector matrix.",
}
"""Each known mistake's feedback."""

_ILL_POSED = "a nearly degenerate moment, or an axis near the xy plane"
_CLOSE = "a known mistake close to the key"


def _tensor_answers(tensor: np.ndarray, mistaken: dict[str, np.ndarray]
                    ) -> tuple[list[tuple], np.ndarray, np.ndarray]:
    """The four answers of a stack of tensors (..., 3, 3), kg m², as ``(name, key, {mistake:
    values}, unit, description, depends)``, values stacked like ``tensor``; ``mistaken`` maps
    a mistake to the tensors a student with it gets, the answers' mistakes derived from them
    by the same (correct) later steps. Also the principal moments and axes (R4)."""
    moments, axes = principal_axes(tensor)
    diag = _diagonal(tensor)
    axis = _positive_z(axes[..., 2])
    wrong_moments = {n: principal_axes(t)[0] for n, t in mistaken.items() if n != "product_sign"}
    return [
        ("I_diag", diag, {n: _diagonal(t) for n, t in mistaken.items() if n != "product_sign"},
         "kg m^2", "diagonal (I_xx, I_yy, I_zz) of the inertia tensor about O", ()),
        ("I_offdiag", tensor[..., _PRODUCTS[0], _PRODUCTS[1]],
         {n: t[..., _PRODUCTS[0], _PRODUCTS[1]] for n, t in mistaken.items()
          if n != "axis_distance"},
         "kg m^2", "products of inertia (I_xy, I_xz, I_yz) about O", ()),
        ("moments", moments, {**wrong_moments, "diagonal_entries": np.sort(diag, axis=-1)},
         "kg m^2", "principal moments about O, ascending", ("I_diag", "I_offdiag")),
        ("axis_max", axis, {"sign_convention": -axis, "smallest_axis": _positive_z(axes[..., 0])},
         "", "unit principal axis of the largest moment, z component > 0",
         ("I_diag", "I_offdiag")),
    ], moments, axes


def _well_posed(moments: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Principal moments (..., 3) and axes (..., 3, 3) of a real body, the largest moment
    well apart from the next, its axis well out of the xy plane."""
    gap = (moments[..., 2] - moments[..., 1]) / moments[..., 2]
    return (moments[..., 0] > 0) & (gap > MIN_GAP) & (np.abs(axes[..., 2, 2]) > MIN_AXIS_Z)


def _posed_specs(tensor: np.ndarray, mistaken: dict[str, np.ndarray]) -> list[list | IllPosed]:
    """For each of a stack of tensors (n, 3, 3), the arguments of :func:`_vector_answer` for
    its four answers, or the :class:`IllPosed` that rejects it: a nearly degenerate largest
    moment, an axis near the xy plane, or a known mistake within SEPARATION tolerances of the
    key or of another (every listed mistake must be recognisable)."""
    found, moments, axes = _tensor_answers(tensor, mistaken)
    posed = _well_posed(moments, axes)
    apart = np.logical_and.reduce([_apart(np.stack([key, *wrong.values()], axis=-2))
                                   for _, key, wrong, *_ in found])
    return [
        IllPosed(_ILL_POSED) if not posed[i] else IllPosed(_CLOSE) if not apart[i] else
        [(name, key[i], [(n, v[i], _FEEDBACK[n]) for n, v in wrong.items()], *rest)
         for name, key, wrong, *rest in found]
        for i in range(len(tensor))
    ]


def _point_masses(rng: np.random.Generator) -> dict[str, Any] | None:
    """Three or four weights on a 1 cm grid (None: one at the pivot, or two in one place)."""
    n = int(rng.integers(3, 5))
    masses = round_sig(rng.uniform(0.02, 0.25, size=n), 3)
    positions = round_sig(rng.integers(-15, 16, size=(n, 3)) / 100.0, 2)
    radii = np.linalg.norm(positions, axis=1)
    # a set of the rows finds two alike as numpy.unique does (no -0.0 on the grid), at a
    # thirtieth of its cost
    if np.min(radii) < 0.03 or len({tuple(r) for r in positions.tolist()}) < n:
        return None  # a weight at the pivot, or two weights in one place
    params: dict[str, Any] = {"scene": "point_masses"}
    params |= {f"m{k}": float(m) for k, m in enumerate(masses, 1)}
    return params | {f"r{k}": r.tolist() for k, r in enumerate(positions, 1)}


def _count(params: Mapping[str, Any]) -> int:
    """The number of weights of the point-mass scene (0 for the box)."""
    return sum(1 for k in range(1, MAX_WEIGHTS + 1) if f"m{k}" in params)


def _weights(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The masses and positions of the point-mass scene."""
    n = _count(params)
    masses = np.array([params[f"m{k}"] for k in range(1, n + 1)])
    return masses, np.array([params[f"r{k}"] for k in range(1, n + 1)])


def _point_mass_tensor(many: list[Mapping[str, Any]]) -> tuple[np.ndarray, dict]:
    """The tensors about O (n, 3, 3), kg m², of point-mass scenes with as many weights each
    (R2), and the tensors each mistake gives."""
    masses, positions = (np.array(x) for x in zip(*map(_weights, many), strict=True))
    tensor = point_mass_tensor(masses, positions)
    diagonal = _diagonal_tensor(_diagonal(tensor))
    squares = _diagonal_tensor(np.einsum("...p,...pi->...i", masses, positions**2))
    return tensor, {"product_sign": 2 * diagonal - tensor,
                    "axis_distance": squares + tensor - diagonal}


def _point_mass_statement(params: Mapping[str, Any]) -> str:
    masses, positions = _weights(params)
    rows = "\n".join(
        f"| {k} | $m_{k} = {latex_sig(m, 3)}$ kg (`m{k}`) | "
        f"$\\mathbf r_{k} = ({', '.join(format_sig(x, 2) for x in r)})$ m (`r{k}`) |"
        for k, (m, r) in enumerate(zip(masses, positions, strict=True), 1)
    )
    return (
        f"{len(masses)} point masses on a light rigid frame turn about a pivot $O$. Their "
        "masses, and positions from $O$ along the frame's axes $x, y, z$:\n\n"
        "| | mass | position |\n| --- | --- | --- |\n"
        f"{rows}\n\n{_ASK}"
    )


def _box_corner(rng: np.random.Generator) -> dict[str, Any]:
    """A book, smartphone or solar panel: its edges and mass, rounded."""
    kind = list(BOXES)[int(rng.integers(len(BOXES)))]
    *edges, mass_range = BOXES[kind]
    a, b, c = (round_sig(rng.uniform(*r), 3) for r in edges)
    M = round_sig(rng.uniform(*mass_range), 3)
    return {"scene": "box_corner", "box": kind, "M": M, "a": a, "b": b, "c": c}


def _box_tensor(many: list[Mapping[str, Any]]) -> tuple[np.ndarray, dict]:
    """The tensors about the corner (n, 3, 3), kg m², of box scenes: the box's about its
    centre shifted by the parallel-axis theorem (R2); and the tensors each mistake gives."""
    M, a, b, c = (np.array([params[n] for params in many]) for n in ("M", "a", "b", "c"))
    tensor_cm = shape_tensor("box", M, a=a, b=b, c=c)
    tensor = parallel_axis(tensor_cm, M, np.stack([a / 2, b / 2, c / 2], axis=-1))
    return tensor, {"parallel_axis_forgotten": tensor_cm,
                    "product_sign": 2 * _diagonal_tensor(_diagonal(tensor)) - tensor}


def _box_statement(params: Mapping[str, Any]) -> str:
    M, a, b, c = (params[n] for n in ("M", "a", "b", "c"))
    return (
        f"A {params['box']}, a uniform box of mass $M = {latex_sig(M, 3)}$ kg (`M`) with edges "
        f"$a = {latex_sig(a, 3)}$ m (`a`), $b = {latex_sig(b, 3)}$ m (`b`) and "
        f"$c = {latex_sig(c, 3)}$ m (`c`), turns about a corner $O$. Axes $x, y, z$ run from "
        "$O$ along $a, b, c$: the box fills $0 \\le x \\le a$, $0 \\le y \\le b$, "
        f"$0 \\le z \\le c$.\n\n{_ASK}"
    )


SCENES = {"point_masses": (_point_masses, _point_mass_tensor, _point_mass_statement),
          "box_corner": (_box_corner, _box_tensor, _box_statement)}
"""Scene → (its draw, its tensor and mistaken tensors, its statement)."""

MAX_WEIGHTS = 4

PARAMETERS: dict[str, Parameter] = {
    "scene": Parameter(choices=tuple(SCENES), description="point masses, or a box"),
    "box": Parameter(choices=tuple(BOXES), description="the box's object"),
    "M": Parameter(unit="kg", description="mass of the box"),
    **{e: Parameter(unit="m", description=f"edge {e} of the box") for e in "abc"},
    **{f"m{k}": Parameter(unit="kg", description=f"mass of weight {k}")
       for k in range(1, MAX_WEIGHTS + 1)},
    **{f"r{k}": Parameter(unit="m", shape=(3,), figures=2, description=f"position of weight {k}")
       for k in range(1, MAX_WEIGHTS + 1)},
}


def draw(rng: np.random.Generator) -> dict[str, Any] | None:
    """A scene of :data:`SCENES`, then draws of it until one is well posed (at most
    ``MAX_TRIES``)."""
    return redrawn_until_well_posed(SCENES[drawn_scene(SCENES, rng)][0], _posed, rng, MAX_TRIES)


def draw_many(rngs: list[np.random.Generator]) -> list[dict[str, Any] | None]:
    """:func:`draw` of each generator, each round's tries tested together (the batch form,
    :mod:`problems.family`)."""
    return redrawn_many_until_well_posed([SCENES[drawn_scene(SCENES, rng)][0] for rng in rngs],
                                         _posed_many, rngs, MAX_TRIES)


def answers(params: Mapping[str, Any]) -> tuple[Answer, ...]:
    """``I_diag``, ``I_offdiag``, ``moments`` (kg m²) and ``axis_max`` (unit vector), R2, R4.

    Raises :class:`~problems.family.IllPosed` for a nearly degenerate largest moment, an axis
    near the xy plane, or a known mistake close to the key.
    """
    return tuple(_vector_answer(*spec) for spec in _posed(params))


def answers_many(many: list[Mapping[str, Any]]) -> list[tuple[Answer, ...] | IllPosed]:
    """:func:`answers` of each parameter set (an :class:`~problems.family.IllPosed` where
    rejected) — the batch form: the tensors and their principal axes of all at once."""
    return [found if isinstance(found, IllPosed)
            else tuple(_vector_answer(*spec) for spec in found) for found in _posed_many(many)]


@remembered  # the draw's accepted try, then answers() of the same parameters
def _posed(params: Mapping[str, Any]) -> list[tuple]:
    """:func:`_posed_specs` of one scene; IllPosed where it rejects it (the draw's test of
    each try, which builds no answers)."""
    return batch_of_one(_posed_many, params)


def _posed_many(many: list[Mapping[str, Any]]) -> list[list[tuple] | IllPosed]:
    """:func:`_posed_specs` of each parameter set: the scenes alike (a box, or as many point
    masses) stacked, their tensors and principal axes worked out together."""
    alike: dict[tuple[str, int], list[int]] = {}
    for i, params in enumerate(many):
        alike.setdefault((params["scene"], _count(params)), []).append(i)
    found: list = [None] * len(many)
    for (scene, _), rows in alike.items():
        tensor, mistaken = SCENES[scene][1]([many[i] for i in rows])
        for i, specs in zip(rows, _posed_specs(tensor, mistaken), strict=True):
            found[i] = specs
    return found


def heading(params: Mapping[str, Any]) -> str:
    if params["scene"] == "point_masses":
        return "Inertia tensor of point masses"
    return f"Inertia tensor of a {params['box']} about a corner"


def statement(params: Mapping[str, Any]) -> str:
    return SCENES[params["scene"]][2](params)


def follow(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
    """``moments`` or ``axis_max`` from the student's own tensor (their diagonal and products
    of inertia, as the statement defines them): its eigenvalues ascending, or the unit axis of
    the largest with a positive z component (R4, :func:`solver.inertia.principal_axes`)."""
    (xx, yy, zz), (xy, xz, yz) = earlier["I_diag"], earlier["I_offdiag"]
    tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]], dtype=float)
    moments, axes = principal_axes(tensor)
    if name == "moments":
        return moments.tolist()
    if name == "axis_max":
        return _positive_z(axes[:, 2]).tolist()
    raise LookupError(name)


_READ_OFF = {"moments": "{moments} a copy of your diagonal",
             "axis_max": "{axis_max} a coordinate axis read off your diagonal"}


def degenerate(name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> str | None:
    """Why a student's tensor leaves nothing to work out for ``moments`` or ``axis_max`` (R4:
    the eigenvalues and eigenvectors of the tensor): products of inertia that are all zero
    where the body's are not (a diagonal tensor's eigenvalues are its diagonal, its axes the
    coordinate axes), or a diagonal that is zero. None otherwise."""
    if name not in _READ_OFF:
        raise LookupError(name)
    diag, products = (np.asarray(earlier[n], dtype=float) for n in ("I_diag", "I_offdiag"))
    tensor = SCENES[params["scene"]][1]([params])[0][0]
    key = np.array([tensor[0, 1], tensor[0, 2], tensor[1, 2]])
    if np.any(key) and np.linalg.norm(products) <= SAME * np.linalg.norm(key):
        return f"your {{I_offdiag}} is zero, which makes {_READ_OFF[name]} (R4)"
    if not np.any(diag):
        return f"your {{I_diag}} is zero: no ground for {{{name}}} (R4)"
    return None
