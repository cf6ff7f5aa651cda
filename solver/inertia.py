"""Inertia tensors, principal axes, kinetic energy and angular momentum (R2–R5).

Results of the physics page, ``docs/physics/index.md``:

- R2: the inertia tensor of point masses, ``I_ij = Σ_p m_p (δ_ij r_p² − r_pi r_pj)``, the
  closed forms of standard uniform shapes, and the parallel-axis theorem;
- R3: ``T = ½ ω·I·ω``;
- R4: principal axes = eigenvectors of ``I`` (a symmetric eigenproblem);
- R5: ``L = I·ω`` (in general not parallel to ``ω``).

All functions are vectorised: leading dimensions of the inputs broadcast, vectors carry a trailing
axis of 3 and tensors two trailing axes of 3. SI units (kg, m, rad/s).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.parameters import ParameterError, as_real, nonnegative, positive

__all__ = [
    "SHAPES",
    "angular_momentum",
    "centre_of_mass_offset",
    "kinetic_energy",
    "parallel_axis",
    "point_mass_tensor",
    "principal_axes",
    "shape_tensor",
    "solve_inertia",
]

# A tensor handed in by a user is symmetric only up to the rounding of its displayed entries.
_SYMMETRY_RTOL = 1e-9


def point_mass_tensor(masses: ArrayLike, positions: ArrayLike) -> NDArray[np.float64]:
    """Inertia tensor of point masses about the origin (R2).

    ``I_ij = Σ_p m_p (δ_ij r_p² − r_pi r_pj)``.

    Parameters
    ----------
    masses : array_like, shape (..., n)
        Masses in kg (non-negative: zero masses are allowed, so that stacks of bodies with
        different numbers of points can be padded).
    positions : array_like, shape (..., n, 3)
        Positions relative to the origin the tensor is taken about, in m.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The inertia tensor in kg m²; leading dimensions are those of ``masses`` and
        ``positions[..., 0]`` broadcast together.

    Examples
    --------
    >>> point_mass_tensor([1.0, 1.0], [[1.0, 1.0, 0.0], [-1.0, -1.0, 0.0]])
    array([[ 2., -2.,  0.],
           [-2.,  2.,  0.],
           [ 0.,  0.,  4.]])
    """
    r = as_real("positions", positions, shape_tail=(3,))
    m = nonnegative("masses", masses)
    try:
        m, r0 = np.broadcast_arrays(m, r[..., 0])
    except ValueError:
        raise ParameterError(
            "masses",
            f"shape {m.shape} does not match positions of shape {r.shape} "
            "(expected masses (..., n) with positions (..., n, 3))",
        ) from None
    r = np.broadcast_to(r, (*r0.shape, 3))
    r2 = np.einsum("...pi,...pi->...p", r, r)
    trace_part = np.einsum("...p,...p->...", m, r2)[..., None, None] * np.eye(3)
    return trace_part - np.einsum("...p,...pi,...pj->...ij", m, r, r)


def parallel_axis(
    tensor_cm: ArrayLike, mass: ArrayLike, displacement: ArrayLike
) -> NDArray[np.float64]:
    """Inertia tensor about a shifted origin, from the tensor about the centre of mass (R2).

    ``I_shifted = I_cm + M (d² δ − d d)``, where ``d`` is the position of the centre of mass
    relative to the new origin (the sign of ``d`` does not matter: it enters quadratically).

    Parameters
    ----------
    tensor_cm : array_like, shape (..., 3, 3)
        Inertia tensor about the centre of mass, kg m² (symmetric).
    mass : array_like, shape (...)
        Total mass in kg (positive).
    displacement : array_like, shape (..., 3)
        ``d``, the centre of mass relative to the new origin, in m.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The inertia tensor about the new origin, kg m².
    """
    tensor = _symmetric_tensor("tensor_cm", tensor_cm)
    m = positive("mass", mass)
    d = as_real("displacement", displacement, shape_tail=(3,))
    d2 = np.einsum("...i,...i->...", d, d)
    steiner = d2[..., None, None] * np.eye(3) - d[..., :, None] * d[..., None, :]
    return tensor + m[..., None, None] * steiner


@dataclass(frozen=True)
class _Shape:
    """A uniform body: its dimensions, principal moments about the CM, and natural pivot.

    ``moments(mass, dims)`` returns ``(I_xx, I_yy, I_zz)`` about the centre of mass (symmetry
    axis z); ``cm_offset(dims)`` is the distance from the pivot (on the z axis) to the CM.
    """

    dims: tuple[str, ...]
    moments: Callable[..., tuple[Any, Any, Any]]
    pivot: str
    cm_offset: Callable[..., Any]


def _solid_cylinder(m, d):
    side = m * (3 * d["radius"] ** 2 + d["height"] ** 2) / 12
    return side, side, m * d["radius"] ** 2 / 2


def _hollow_cylinder(m, d):
    # Thin lateral wall only (no end caps): every element is at distance R from the axis.
    side = m * (6 * d["radius"] ** 2 + d["height"] ** 2) / 12
    return side, side, m * d["radius"] ** 2


def _solid_cone(m, d):
    # About the apex the transverse moment is 3/20 M R² + 3/5 M h²; shifting by 3h/4 to the CM
    # leaves 3/20 M R² + 3/80 M h².
    side = m * (3 * d["radius"] ** 2 / 20 + 3 * d["height"] ** 2 / 80)
    return side, side, 3 * m * d["radius"] ** 2 / 10


def _box(m, d):
    a2, b2, c2 = d["a"] ** 2, d["b"] ** 2, d["c"] ** 2
    return m * (b2 + c2) / 12, m * (a2 + c2) / 12, m * (a2 + b2) / 12


def _isotropic(k):
    def moments(m, d):
        i = k * m * d["radius"] ** 2
        return i, i, i

    return moments


def _uniaxial(k_side, k_axis, dim):
    def moments(m, d):
        s = d[dim] ** 2
        return k_side * m * s, k_side * m * s, k_axis * m * s

    return moments


_SHAPE_TABLE: Mapping[str, _Shape] = MappingProxyType(
    {
        "solid_sphere": _Shape(
            ("radius",), _isotropic(2 / 5), "a point of the surface", lambda d: d["radius"]
        ),
        "hollow_sphere": _Shape(
            ("radius",), _isotropic(2 / 3), "a point of the surface", lambda d: d["radius"]
        ),
        "solid_cylinder": _Shape(
            ("radius", "height"), _solid_cylinder, "the centre of an end face",
            lambda d: d["height"] / 2,
        ),
        "hollow_cylinder": _Shape(
            ("radius", "height"), _hollow_cylinder, "the centre of an end (on the axis)",
            lambda d: d["height"] / 2,
        ),
        "disc": _Shape(
            ("radius",), _uniaxial(1 / 4, 1 / 2, "radius"), "its centre (on an axle along z)",
            lambda d: np.zeros_like(d["radius"]),
        ),
        "thin_rod": _Shape(
            ("length",), _uniaxial(1 / 12, 0.0, "length"), "one end", lambda d: d["length"] / 2
        ),
        "box": _Shape(
            ("a", "b", "c"), _box, "the centre of the face normal to −z", lambda d: d["c"] / 2
        ),
        "solid_cone": _Shape(
            ("radius", "height"), _solid_cone, "the apex", lambda d: 3 * d["height"] / 4
        ),
    }
)

#: Standard uniform shapes (R2) → the names of their dimensions (lengths in m).
SHAPES: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {name: shape.dims for name, shape in _SHAPE_TABLE.items()}
)


def shape_tensor(shape: str, mass: ArrayLike, **dims: ArrayLike) -> NDArray[np.float64]:
    """Inertia tensor of a uniform standard shape about its centre of mass (R2).

    The symmetry axis is z, so the tensor is diagonal. Shapes and dimensions (lengths in m):

    ===================  ================  =====================================================
    shape                dimensions        body
    ===================  ================  =====================================================
    ``solid_sphere``     radius            ``I = 2/5 M R²``
    ``hollow_sphere``    radius            thin spherical shell, ``I = 2/3 M R²``
    ``solid_cylinder``   radius, height    ``I_zz = M R²/2``, ``I_xx = M (3R² + h²)/12``
    ``hollow_cylinder``  radius, height    thin lateral wall, no end caps: ``I_zz = M R²``,
                                           ``I_xx = M (6R² + h²)/12``
    ``disc``             radius            thin disc in the xy plane: ``I_zz = M R²/2``,
                                           ``I_xx = M R²/4``
    ``thin_rod``         length            along z: ``I_xx = M L²/12``, ``I_zz = 0``
    ``box``              a, b, c           edges along x, y, z: ``I_xx = M (b² + c²)/12`` …
    ``solid_cone``       radius, height    ``I_zz = 3/10 M R²``, ``I_xx = 3/20 M R² + 3/80 M h²``
    ===================  ================  =====================================================

    Parameters
    ----------
    shape : str
        One of :data:`SHAPES`.
    mass : array_like
        Mass in kg (positive).
    **dims : array_like
        Exactly the dimensions :data:`SHAPES` lists for ``shape`` (positive); they broadcast
        with ``mass``.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The tensor in kg m², about the centre of mass.

    Raises
    ------
    ParameterError
        For an unknown shape (naming ``shape`` and listing the known ones), or a missing,
        extra or non-positive dimension (naming it).
    """
    spec, d = _shape_dims(shape, dims)
    m = positive("mass", mass)
    m, *values = np.broadcast_arrays(m, *d.values())
    moments = spec.moments(m, dict(zip(d, values, strict=True)))
    diag = np.stack(np.broadcast_arrays(*moments), axis=-1)
    return diag[..., :, None] * np.eye(3)


def centre_of_mass_offset(shape: str, **dims: ArrayLike) -> NDArray[np.float64]:
    """Distance from a shape's natural pivot to its centre of mass, in m (R2, R14's ``l``).

    The pivot lies on the symmetry axis z, so the tensor about it is
    ``parallel_axis(shape_tensor(...), mass, [0, 0, offset])``:

    ===================  ==============================================  ==========
    shape                pivot                                           offset
    ===================  ==============================================  ==========
    ``solid_sphere``     a point of the surface                          ``R``
    ``hollow_sphere``    a point of the surface                          ``R``
    ``solid_cylinder``   the centre of an end face                       ``h/2``
    ``hollow_cylinder``  the centre of an end (on the axis)              ``h/2``
    ``disc``             its centre (an axle along z)                    ``0``
    ``thin_rod``         one end                                         ``L/2``
    ``box``              the centre of the face normal to z              ``c/2``
    ``solid_cone``       the apex                                        ``3h/4``
    ===================  ==============================================  ==========

    Parameters and errors as for :func:`shape_tensor` (without the mass).

    Returns
    -------
    ndarray
        The offset, shape of the dimensions broadcast together.
    """
    spec, d = _shape_dims(shape, dims)
    values = np.broadcast_arrays(*d.values())
    return np.asarray(spec.cm_offset(dict(zip(d, values, strict=True))), dtype=float)


def principal_axes(tensor: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Principal moments and axes of a symmetric inertia tensor (R4).

    Solved as a symmetric eigenproblem (``numpy.linalg.eigh``). For degenerate moments (a
    symmetric top, a sphere) any orthonormal basis of the eigenspace is returned.

    Parameters
    ----------
    tensor : array_like, shape (..., 3, 3)
        Inertia tensor in kg m² (symmetric up to rounding; the symmetric part is used).

    Returns
    -------
    moments : ndarray, shape (..., 3)
        Principal moments in ascending order.
    axes : ndarray, shape (..., 3, 3)
        Unit principal axes as columns (``axes[..., :, k]`` belongs to ``moments[..., k]``),
        forming a right-handed frame: ``det(axes) = +1`` and
        ``tensor = axes @ diag(moments) @ axes.T``.
    """
    t = _symmetric_tensor("tensor", tensor)
    moments, axes = np.linalg.eigh(t)
    # eigh returns an orthonormal basis of either handedness; flipping the last axis makes it a
    # rotation without changing the eigen-decomposition.
    flip = np.where(np.linalg.det(axes) < 0, -1.0, 1.0)
    axes = axes.copy()
    axes[..., :, 2] *= flip[..., None]
    return moments, axes


def kinetic_energy(tensor: ArrayLike, omega: ArrayLike) -> NDArray[np.float64]:
    """Rotational kinetic energy ``T = ½ ω·I·ω`` in J (R3).

    Parameters
    ----------
    tensor : array_like, shape (..., 3, 3)
        Inertia tensor in kg m², in the same frame as ``omega``.
    omega : array_like, shape (..., 3)
        Angular velocity in rad/s.

    Returns
    -------
    ndarray, shape (...)
    """
    t = _symmetric_tensor("tensor", tensor)
    w = as_real("omega", omega, shape_tail=(3,))
    return 0.5 * np.einsum("...i,...ij,...j->...", w, t, w)


def angular_momentum(tensor: ArrayLike, omega: ArrayLike) -> NDArray[np.float64]:
    """Angular momentum ``L = I·ω`` in kg m²/s (R5); in general not parallel to ``ω``.

    Parameters
    ----------
    tensor : array_like, shape (..., 3, 3)
        Inertia tensor in kg m², in the same frame as ``omega``.
    omega : array_like, shape (..., 3)
        Angular velocity in rad/s.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    t = _symmetric_tensor("tensor", tensor)
    w = as_real("omega", omega, shape_tail=(3,))
    return np.einsum("...ij,...j->...i", t, w)


def solve_inertia(
    masses: ArrayLike | None = None,
    positions: ArrayLike | None = None,
    shape: str | None = None,
    mass: ArrayLike | None = None,
    **dims: ArrayLike,
) -> dict[str, NDArray[np.float64]]:
    """Inertia tensor and its principal axes, of point masses or of a standard shape (R2, R4).

    Give either ``masses`` and ``positions`` (tensor about the origin, :func:`point_mass_tensor`)
    or ``shape``, ``mass`` and its dimensions (tensor about the centre of mass,
    :func:`shape_tensor`).

    Returns
    -------
    dict
        ``"tensor"`` (..., 3, 3) kg m², ``"principal_moments"`` (..., 3) ascending, and
        ``"principal_axes"`` (..., 3, 3), axes as columns, right-handed.

    Raises
    ------
    ParameterError
        If both descriptions or neither are given, or a part of one is missing.
    """
    point_given = masses is not None or positions is not None
    shape_given = shape is not None or mass is not None or bool(dims)
    if point_given and shape_given:
        culprit = "shape" if shape is not None else "mass" if mass is not None else next(iter(dims))
        raise ParameterError(
            culprit,
            "give either point masses (masses, positions) or a shape (shape, mass, dims), "
            "not both",
        )
    if point_given:
        for name, value in (("masses", masses), ("positions", positions)):
            if value is None:
                raise ParameterError(name, "is required for point masses")
        tensor = point_mass_tensor(masses, positions)
    elif shape_given:
        for name, value in (("shape", shape), ("mass", mass)):
            if value is None:
                raise ParameterError(name, "is required for a standard shape")
        tensor = shape_tensor(shape, mass, **dims)
    else:
        raise ParameterError(
            "masses", "nothing to solve: give point masses (masses, positions) or a shape"
        )
    moments, axes = principal_axes(tensor)
    return {"tensor": tensor, "principal_moments": moments, "principal_axes": axes}


def _shape_dims(shape: str, dims: Mapping[str, ArrayLike]) -> tuple[_Shape, dict[str, Any]]:
    """Look a shape up and validate exactly its dimensions (positive), in the table's order."""
    spec = _SHAPE_TABLE.get(shape) if isinstance(shape, str) else None
    if spec is None:
        raise ParameterError(
            "shape", f"unknown shape {shape!r}; known shapes: {', '.join(SHAPES)}"
        )
    takes = f"{shape} takes {', '.join(spec.dims)}"
    for name in dims:
        if name not in spec.dims:
            raise ParameterError(name, f"is not a dimension of {takes}")
    for name in spec.dims:
        if name not in dims:
            raise ParameterError(name, f"is required: {takes}")
    return spec, {name: positive(name, dims[name]) for name in spec.dims}


def _symmetric_tensor(name: str, tensor: ArrayLike) -> NDArray[np.float64]:
    """Validate a (..., 3, 3) tensor as symmetric (up to rounding) and return its symmetric part."""
    t = as_real(name, tensor, shape_tail=(3, 3))
    t_transposed = np.swapaxes(t, -1, -2)
    scale = np.max(np.abs(t), axis=(-2, -1), keepdims=True)
    if np.any(np.abs(t - t_transposed) > _SYMMETRY_RTOL * scale):
        raise ParameterError(name, "must be a symmetric tensor")
    return 0.5 * (t + t_transposed)
