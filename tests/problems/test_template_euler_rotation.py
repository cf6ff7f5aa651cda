"""Independent checks of the euler_rotation template's answers (R11, R12).

The template uses ``solver.euler_angles``. Here the references come from scipy's
``Rotation`` instead, from the displayed parameters only:

- R11: the body axes are the columns of the *active* intrinsic z-y'-z'' rotation
  ``Rotation.from_euler("ZYZ", [α, β, γ])``, so ``R`` (lab → body components) is its transpose,
  a marker's lab position is ``rot.apply(r')`` and a lab vector's body components are
  ``rot.inv().apply(F)``;
- R12: ω's body components from the motion itself: with the angles advancing at their rates,
  the body-frame rotation vector of ``rot(t−h)⁻¹ rot(t+h)`` divided by ``2h`` (a central
  difference, error O(h²|ω̈|) ≈ 1e-9 relative for h = 1e-6 s), not from R12's formula.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from problems.templates import FAMILIES, euler_rotation

SEEDS = range(40)


@pytest.fixture(scope="module")
def variants():
    return [FAMILIES[euler_rotation.NAME].generate(np.random.default_rng(seed)) for seed in SEEDS]


def _answers(variant):
    return {a.name: np.array(a.value) for a in variant.answers}


def _rotation(p, t=0.0):
    angles = [p[n] + t * p[f"{n}_dot"] for n in ("alpha", "beta", "gamma")]
    return Rotation.from_euler("ZYZ", angles)


def test_both_vector_directions_are_drawn(variants):
    assert {"r_body" in v.params for v in variants} == {True, False}


def test_rotation_matrix_and_vector_match_scipy(variants):
    for v in variants:
        p, ans = v.params, _answers(v)
        rot = _rotation(p)
        np.testing.assert_allclose(ans["R"], rot.as_matrix().T.ravel(), rtol=0, atol=1e-14)
        if "r_body" in p:
            np.testing.assert_allclose(ans["r_lab"], rot.apply(p["r_body"]), atol=1e-15)
        else:
            np.testing.assert_allclose(ans["F_body"], rot.inv().apply(p["F_lab"]), atol=1e-13)


def test_omega_body_matches_finite_rotation(variants):
    h = 1e-6
    for v in variants:
        p = v.params
        relative = _rotation(p, -h).inv() * _rotation(p, h)  # body-frame increment
        omega = relative.as_rotvec() / (2 * h)
        key = _answers(v)["omega_body"]
        np.testing.assert_allclose(key, omega, rtol=0, atol=1e-7 * np.linalg.norm(omega))
