"""Tests of solver/inertia.py (R2–R5).

References, none of them the code under test:
- standard shapes: the density integrated directly with ``scipy.integrate.cubature`` in
  spherical/cylindrical coordinates (mass, centre of mass, then the tensor about that centre);
- point masses: a hand-derived dumbbell, rotation covariance ``I' = Q I Qᵀ``, and the definitions
  ``L = Σ m r × (ω × r)``, ``T = ½ Σ m |ω × r|²`` (R5, R3) evaluated with ``numpy.cross``;
- principal axes: ``mpmath.eigsy`` at 40 digits, and the reconstruction ``A diag(m) Aᵀ``.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
from scipy.integrate import cubature
from scipy.spatial.transform import Rotation

from solver.inertia import (
    SHAPES,
    angular_momentum,
    centre_of_mass_offset,
    kinetic_energy,
    parallel_axis,
    point_mass_tensor,
    principal_axes,
    shape_tensor,
    solve_inertia,
)
from solver.parameters import ParameterError

RTOL = 1e-10
TWO_PI = 2 * np.pi


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240524)


@pytest.fixture
def cloud(rng):
    """An irregular body of 7 point masses, and a random angular velocity."""
    return rng.uniform(0.5, 2.0, 7), rng.normal(size=(7, 3)), rng.normal(size=3)


# --- standard shapes against direct integration of the density --------------------------------
#
# Each body is parametrised over a box of coordinates u, with the pivot of
# centre_of_mass_offset at the origin and the symmetry axis along +z: position(u) -> (npts, 3),
# weight(u) = the volume (area, length) element. The density is uniform.

def _spherical(u, radius):  # (rho, theta, phi), the centre at (0, 0, R): the pivot on the surface
    rho, th, ph = u.T
    pos = np.stack((rho * np.sin(th) * np.cos(ph), rho * np.sin(th) * np.sin(ph),
                    radius + rho * np.cos(th)), axis=-1)
    return pos, rho**2 * np.sin(th)


def _shell(u, radius):  # (theta, phi) on the sphere of the given radius, centre (0, 0, R)
    th, ph = u.T
    return _spherical(np.stack((np.full_like(th, radius), th, ph), axis=-1), radius)[0], np.sin(th)


def _cylindrical(u):  # (r, phi, z)
    r, ph, z = u.T
    return np.stack((r * np.cos(ph), r * np.sin(ph), z), axis=-1), r


def _wall(u, radius):  # (phi, z) on the lateral surface
    ph, z = u.T
    return np.stack((radius * np.cos(ph), radius * np.sin(ph), z), axis=-1), np.ones_like(z)


def _disc(u):  # (r, phi) in the plane z = 0
    r, ph = u.T
    return np.stack((r * np.cos(ph), r * np.sin(ph), np.zeros_like(r)), axis=-1), r


def _rod(u):  # (z,) along the axis
    z = u[:, 0]
    zero = np.zeros_like(z)
    return np.stack((zero, zero, z), axis=-1), np.ones_like(z)


def _cone(u, radius, height):  # (s, phi, z), apex at the origin: r = s R z / h, dr = R z/h ds
    s, ph, z = u.T
    rmax = radius * z / height
    r = s * rmax
    return np.stack((r * np.cos(ph), r * np.sin(ph), z), axis=-1), r * rmax


def _cartesian(u):
    return u, np.ones(len(u))


R0, H0, L0, ABC = 0.37, 1.3, 2.1, (0.3, 0.5, 0.7)
INTEGRATION_CASES = {
    "solid_sphere": ({"radius": R0}, lambda u: _spherical(u, R0), [0, 0, 0], [R0, np.pi, TWO_PI]),
    "hollow_sphere": ({"radius": R0}, lambda u: _shell(u, R0), [0, 0], [np.pi, TWO_PI]),
    "solid_cylinder": ({"radius": R0, "height": H0}, _cylindrical, [0, 0, 0], [R0, TWO_PI, H0]),
    "hollow_cylinder": ({"radius": R0, "height": H0}, lambda u: _wall(u, R0), [0, 0],
                        [TWO_PI, H0]),
    "disc": ({"radius": R0}, _disc, [0, 0], [R0, TWO_PI]),
    "thin_rod": ({"length": L0}, _rod, [0], [L0]),
    "box": (dict(zip("abc", ABC, strict=True)), _cartesian,
            [-ABC[0] / 2, -ABC[1] / 2, 0], [ABC[0] / 2, ABC[1] / 2, ABC[2]]),
    "solid_cone": ({"radius": R0, "height": H0}, lambda u: _cone(u, R0, H0), [0, 0, 0],
                   [1, TWO_PI, H0]),
}


def _integrate(body, lower, upper, integrand):
    def f(u):
        pos, weight = body(u)
        return weight.reshape(-1, *([1] * (integrand(pos).ndim - 1))) * integrand(pos)

    res = cubature(f, lower, upper, rtol=1e-13, atol=1e-13)
    assert res.status == "converged"
    return res.estimate


@pytest.fixture(scope="module", params=sorted(INTEGRATION_CASES))
def integrated_shape(request):
    """(shape, dims, mass, CM from the pivot, tensor about the CM) by direct integration."""
    name = request.param
    dims, body, lower, upper = INTEGRATION_CASES[name]
    mass = 2.5
    volume = _integrate(body, lower, upper, lambda p: np.ones(len(p)))
    centre = _integrate(body, lower, upper, lambda p: p) / volume
    # Tensor about the integrated centre of mass, straight from the definition (R2).
    rel = lambda p: p - centre  # noqa: E731
    tensor = _integrate(
        body, lower, upper,
        lambda p: (np.einsum("ni,ni->n", rel(p), rel(p))[:, None, None] * np.eye(3)
                   - np.einsum("ni,nj->nij", rel(p), rel(p))),
    ) * mass / volume
    return name, dims, mass, centre, tensor


def test_every_shape_has_an_integration_case():
    assert set(INTEGRATION_CASES) == set(SHAPES)
    for name, (dims, *_rest) in INTEGRATION_CASES.items():
        assert tuple(dims) == SHAPES[name]


def test_shape_tensor_matches_integrated_density(integrated_shape):
    name, dims, mass, _, reference = integrated_shape
    scale = np.max(np.abs(reference))
    np.testing.assert_allclose(shape_tensor(name, mass, **dims), reference, rtol=RTOL,
                               atol=RTOL * scale)


def test_centre_of_mass_offset_matches_integrated_centre(integrated_shape):
    name, dims, _, centre, _ = integrated_shape
    # The pivot is at the origin and the centre of mass on the +z axis.
    np.testing.assert_allclose(centre[:2], 0.0, atol=1e-12)
    np.testing.assert_allclose(centre_of_mass_offset(name, **dims), centre[2], rtol=RTOL,
                               atol=1e-14)


def test_tensor_about_the_pivot_via_parallel_axis(integrated_shape):
    """The tensor about the pivot (a heavy top's tip, R14) integrated directly from the pivot."""
    name, dims, mass, _, _ = integrated_shape
    _, body, lower, upper = INTEGRATION_CASES[name]
    volume = _integrate(body, lower, upper, lambda p: np.ones(len(p)))
    about_pivot = _integrate(
        body, lower, upper,
        lambda p: np.einsum("ni,ni->n", p, p)[:, None, None] * np.eye(3)
        - np.einsum("ni,nj->nij", p, p),
    ) * mass / volume
    offset = centre_of_mass_offset(name, **dims)
    shifted = parallel_axis(shape_tensor(name, mass, **dims), mass, [0.0, 0.0, offset])
    np.testing.assert_allclose(shifted, about_pivot, rtol=RTOL,
                               atol=RTOL * np.max(np.abs(about_pivot)))


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_shape_tensor_vectorised_equals_loop(name, rng):
    dims = {d: rng.uniform(0.1, 2.0, size=(4, 1)) for d in SHAPES[name]}
    mass = rng.uniform(0.5, 3.0, size=5)
    stacked = shape_tensor(name, mass, **dims)
    offsets = centre_of_mass_offset(name, **dims)
    assert stacked.shape == (4, 5, 3, 3)
    assert offsets.shape == (4, 1)
    for i in range(4):
        single_dims = {d: v[i, 0] for d, v in dims.items()}
        assert offsets[i, 0] == centre_of_mass_offset(name, **single_dims)
        for j in range(5):
            np.testing.assert_array_equal(stacked[i, j], shape_tensor(name, mass[j], **single_dims))


# --- shape errors --------------------------------------------------------------------------------

def test_unknown_shape_lists_the_known_ones():
    with pytest.raises(ParameterError, match="unknown shape 'torus'") as info:
        shape_tensor("torus", 1.0, radius=1.0)
    assert info.value.parameter == "shape"
    for name in SHAPES:
        assert name in str(info.value)


@pytest.mark.parametrize(
    ("shape", "dims", "culprit"),
    [
        ("solid_cone", {"radius": 1.0}, "height"),
        ("solid_sphere", {"radius": 1.0, "height": 2.0}, "height"),
        ("box", {"a": 1.0, "b": 1.0, "side": 1.0}, "side"),
        ("thin_rod", {"length": -1.0}, "length"),
        ("disc", {"radius": float("nan")}, "radius"),
    ],
)
def test_bad_dimension_is_named(shape, dims, culprit):
    with pytest.raises(ParameterError) as info:
        shape_tensor(shape, 1.0, **dims)
    assert info.value.parameter == culprit
    with pytest.raises(ParameterError) as info:
        centre_of_mass_offset(shape, **dims)
    assert info.value.parameter == culprit


def test_nonpositive_mass_is_named():
    with pytest.raises(ParameterError) as info:
        shape_tensor("disc", 0.0, radius=1.0)
    assert info.value.parameter == "mass"


# --- point masses ---------------------------------------------------------------------------------

def test_point_masses_hand_derived_dumbbell():
    """m = 2 at ±(1, 1, 0): I_xx = 2·2·1, I_yy = 4, I_zz = 2·2·2, I_xy = −2·2·1·1, by hand."""
    tensor = point_mass_tensor([2.0, 2.0], [[1.0, 1.0, 0.0], [-1.0, -1.0, 0.0]])
    np.testing.assert_array_equal(tensor, [[4.0, -4.0, 0.0], [-4.0, 4.0, 0.0], [0.0, 0.0, 8.0]])
    moments, axes = principal_axes(tensor)
    # The rod axis (1, 1, 0)/√2 has moment 0; the perpendicular plane is degenerate at 8.
    np.testing.assert_allclose(moments, [0.0, 8.0, 8.0], atol=1e-14)
    np.testing.assert_allclose(np.abs(axes[:, 0]), [2**-0.5, 2**-0.5, 0.0], atol=1e-14)


def test_point_masses_rotation_covariance(cloud):
    masses, positions, _ = cloud
    q = Rotation.from_euler("zyx", [0.3, -1.1, 2.4]).as_matrix()
    rotated = point_mass_tensor(masses, positions @ q.T)
    np.testing.assert_allclose(rotated, q @ point_mass_tensor(masses, positions) @ q.T,
                               rtol=RTOL, atol=1e-13)


def test_point_masses_vectorised_equals_loop(rng):
    masses = rng.uniform(0.1, 1.0, size=(3, 1, 6))
    positions = rng.normal(size=(3, 4, 6, 3))
    stacked = point_mass_tensor(masses, positions)
    assert stacked.shape == (3, 4, 3, 3)
    for i in range(3):
        for j in range(4):
            single = point_mass_tensor(masses[i, 0], positions[i, j])
            np.testing.assert_allclose(stacked[i, j], single, rtol=1e-15, atol=1e-15)


def test_point_masses_shape_mismatch_is_named():
    with pytest.raises(ParameterError) as info:
        point_mass_tensor([1.0, 2.0, 3.0], np.zeros((2, 3)))
    assert info.value.parameter == "masses"
    with pytest.raises(ParameterError) as info:
        point_mass_tensor([1.0, 2.0], np.zeros((2, 2)))
    assert info.value.parameter == "positions"


# --- parallel axis --------------------------------------------------------------------------------

@pytest.mark.parametrize("d", [[0.0, 0.0, 1.5], [0.3, -0.7, 2.0], [-4.0, 1.0, 0.0]])
def test_parallel_axis_equals_displaced_point_masses(cloud, d):
    masses, positions, _ = cloud
    centred = positions - masses @ positions / masses.sum()
    i_cm = point_mass_tensor(masses, centred)
    np.testing.assert_allclose(parallel_axis(i_cm, masses.sum(), d),
                               point_mass_tensor(masses, centred + d), rtol=RTOL, atol=1e-12)


def test_parallel_axis_rejects_asymmetric_tensor():
    with pytest.raises(ParameterError) as info:
        parallel_axis([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 1.0, [0, 0, 1])
    assert info.value.parameter == "tensor_cm"


# --- principal axes -------------------------------------------------------------------------------

@pytest.fixture(params=["cloud", "symmetric_top", "sphere", "rod"])
def tensor(request, cloud):
    masses, positions, _ = cloud
    return {
        "cloud": point_mass_tensor(masses, positions),
        "symmetric_top": shape_tensor("solid_cone", 1.3, radius=0.4, height=0.9),
        "sphere": shape_tensor("solid_sphere", 2.0, radius=0.5),
        "rod": point_mass_tensor([1.0, 1.0], [[0.2, 0.3, 0.6], [-0.2, -0.3, -0.6]]),
    }[request.param]


def test_principal_axes_reconstruct_the_tensor(tensor):
    moments, axes = principal_axes(tensor)
    assert np.all(np.diff(moments) >= 0)
    np.testing.assert_allclose(np.linalg.det(axes), 1.0, rtol=1e-14)
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(axes @ np.diag(moments) @ axes.T, tensor, rtol=1e-13,
                               atol=1e-14 * np.max(np.abs(tensor)))


def test_principal_moments_match_mpmath(tensor):
    with mp.workdps(40):
        eigenvalues = mp.eigsy(mp.matrix(tensor.tolist()))[0]
        reference = np.array(sorted(float(e) for e in eigenvalues))
    np.testing.assert_allclose(principal_axes(tensor)[0], reference, rtol=1e-13,
                               atol=1e-14 * np.max(np.abs(tensor)))


def test_principal_axes_of_a_stack(rng):
    """Stacks: right-handed everywhere, although eigh returns either handedness per element."""
    tensors = point_mass_tensor(rng.uniform(0.1, 1.0, (50, 5)), rng.normal(size=(50, 5, 3)))
    moments, axes = principal_axes(tensors)
    np.testing.assert_allclose(np.linalg.det(axes), 1.0, rtol=1e-13)
    for k in range(50):
        single_moments, single_axes = principal_axes(tensors[k])
        np.testing.assert_allclose(moments[k], single_moments, rtol=1e-14)
        np.testing.assert_allclose(axes[k], single_axes, atol=1e-13)


# --- kinetic energy and angular momentum ----------------------------------------------------------

def test_angular_momentum_and_energy_from_the_definitions(cloud):
    """L = Σ m r × (ω × r) (R5) and T = ½ Σ m |ω × r|² (R3), summed over the points directly."""
    masses, positions, omega = cloud
    velocities = np.cross(omega, positions)
    tensor = point_mass_tensor(masses, positions)
    np.testing.assert_allclose(angular_momentum(tensor, omega),
                               masses @ np.cross(positions, velocities), rtol=RTOL)
    np.testing.assert_allclose(kinetic_energy(tensor, omega),
                               0.5 * masses @ np.sum(velocities**2, axis=-1), rtol=RTOL)


def test_energy_is_half_omega_dot_l_and_l_not_parallel(cloud):
    masses, positions, omega = cloud
    tensor = point_mass_tensor(masses, positions)
    ell = angular_momentum(tensor, omega)
    np.testing.assert_allclose(kinetic_energy(tensor, omega), 0.5 * omega @ ell, rtol=1e-14)
    sine = np.linalg.norm(np.cross(ell, omega)) / (np.linalg.norm(ell) * np.linalg.norm(omega))
    assert sine > 0.05  # an irregular body: L is not along ω
    # ... except along a principal axis, where L = I_k ω.
    moments, axes = principal_axes(tensor)
    for k in range(3):
        np.testing.assert_allclose(angular_momentum(tensor, 2.0 * axes[:, k]),
                                   2.0 * moments[k] * axes[:, k], rtol=1e-12, atol=1e-12)


def test_energy_and_momentum_vectorised_equal_loop(rng):
    tensors = point_mass_tensor(rng.uniform(0.1, 1.0, (6, 4)), rng.normal(size=(6, 4, 3)))
    omegas = rng.normal(size=(2, 6, 3))
    energies, momenta = kinetic_energy(tensors, omegas), angular_momentum(tensors, omegas)
    assert energies.shape == (2, 6) and momenta.shape == (2, 6, 3)
    for i in range(2):
        for j in range(6):
            np.testing.assert_allclose(energies[i, j], kinetic_energy(tensors[j], omegas[i, j]),
                                       rtol=1e-15)
            np.testing.assert_allclose(momenta[i, j], angular_momentum(tensors[j], omegas[i, j]),
                                       rtol=1e-15)


# --- solve_inertia --------------------------------------------------------------------------------

def test_solve_inertia_point_masses(cloud):
    masses, positions, _ = cloud
    result = solve_inertia(masses=masses, positions=positions)
    assert set(result) == {"tensor", "principal_moments", "principal_axes"}
    np.testing.assert_array_equal(result["tensor"], point_mass_tensor(masses, positions))
    axes, moments = result["principal_axes"], result["principal_moments"]
    np.testing.assert_allclose(axes @ np.diag(moments) @ axes.T, result["tensor"], atol=1e-13)


def test_solve_inertia_shape():
    """A box's moments M(b² + c²)/12 … sorted ascending, edges along the principal axes."""
    result = solve_inertia(shape="box", mass=12.0, a=1.0, b=2.0, c=3.0)
    np.testing.assert_allclose(result["principal_moments"], [5.0, 10.0, 13.0], rtol=1e-15)
    # Ascending: I_zz = 5 (axis z) first, I_xx = 13 (axis x) last.
    np.testing.assert_allclose(np.abs(result["principal_axes"]), np.eye(3)[:, ::-1], atol=0)


@pytest.mark.parametrize(
    ("kwargs", "culprit"),
    [
        ({}, "masses"),
        ({"masses": [1.0]}, "positions"),
        ({"positions": [[1.0, 0.0, 0.0]]}, "masses"),
        ({"shape": "disc", "radius": 1.0}, "mass"),
        ({"mass": 1.0, "radius": 1.0}, "shape"),
        ({"masses": [1.0], "positions": [[1.0, 0.0, 0.0]], "shape": "disc"}, "shape"),
        ({"masses": [1.0], "positions": [[1.0, 0.0, 0.0]], "radius": 1.0}, "radius"),
    ],
)
def test_solve_inertia_incomplete_or_conflicting(kwargs, culprit):
    with pytest.raises(ParameterError) as info:
        solve_inertia(**kwargs)
    assert info.value.parameter == culprit
