"""Independent checks of the energy_momentum template's answers (R3, R5).

The template computes ``T = ½ ω·I·ω`` and ``L = I·ω`` in the given axes with ``solver.inertia``.
Here, from the displayed parameters only:

- tumbling satellite: the tensor is diagonalised by mpmath (``eigsy``, 40 digits) and ``T`` and
  ``L`` are summed in the principal frame, ``T = ½ Σ λ_k (n_k·ω)²``, ``L = Σ λ_k (n_k·ω) n_k``
  (R3, R5 in principal axes); the angle from ``acos`` of the normalised dot product;
- askew disc: the textbook closed forms for a disc tilted by θ on its axle,
  ``T = ½ ω² (I1 sin²θ + I3 cos²θ)``, ``L = ω ((I3 − I1) sin θ cos θ, 0, I1 sin²θ + I3 cos²θ)``
  with ``I1 = MR²/4``, ``I3 = MR²/2``, and ``tan φ = L_x / L_z``;
- for both, the identity ``L·ω = 2T`` between the key's own answers.
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

from problems.templates import FAMILIES, energy_momentum

SEEDS = range(40)


@pytest.fixture(scope="module")
def variants():
    return [FAMILIES[energy_momentum.NAME].generate(np.random.default_rng(seed)) for seed in SEEDS]


def _answers(variant):
    return {a.name: a.value for a in variant.answers}


@mp.workdps(40)
def _satellite_reference(tensor, omega):
    values, vectors = mp.eigsy(mp.matrix(tensor))
    w = mp.matrix(omega)
    T, L = mp.mpf(0), mp.matrix(3, 1)
    for k in range(3):
        n = vectors[:, k]
        component = sum(n[i] * w[i] for i in range(3))
        T += values[k] * component**2 / 2
        L += values[k] * component * n
    cos_angle = sum(L[i] * w[i] for i in range(3)) / (mp.norm(L) * mp.norm(w))
    return float(T), [float(x) for x in L], float(mp.acos(cos_angle))


def _disc_reference(M, R, theta, omega):
    I1, I3 = M * R**2 / 4, M * R**2 / 2
    s, c = math.sin(theta), math.cos(theta)
    L = [omega * (I3 - I1) * s * c, 0.0, omega * (I1 * s**2 + I3 * c**2)]
    return 0.5 * omega**2 * (I1 * s**2 + I3 * c**2), L, math.atan2(L[0], L[2])


def test_both_scenes_are_drawn(variants):
    assert {"I" in v.params for v in variants} == {True, False}


def test_answers_match_independent_references(variants):
    for v in variants:
        p, ans = v.params, _answers(v)
        if "I" in p:
            T, L, angle = _satellite_reference(p["I"], p["omega"])
        else:
            T, L, angle = _disc_reference(p["M"], p["R"], p["theta"], p["omega"])
        assert ans["T"] == pytest.approx(T, rel=1e-12)
        np.testing.assert_allclose(ans["L"], L, rtol=0, atol=1e-12 * np.linalg.norm(L))
        assert ans["angle"] == pytest.approx(angle, rel=1e-10)


def test_L_dot_omega_is_twice_T(variants):
    for v in variants:
        ans = _answers(v)
        omega = v.params["omega"]
        omega = omega if isinstance(omega, list) else [0.0, 0.0, omega]
        assert np.dot(ans["L"], omega) == pytest.approx(2 * ans["T"], rel=1e-12)


def test_disc_reference_small_tilt_limit():
    # For a small tilt the angle between L and ω is (I3 − I1)/I3 · θ = θ/2 for a thin disc.
    theta = 1e-4
    assert _disc_reference(1.0, 0.1, theta, 100.0)[2] == pytest.approx(theta / 2, rel=1e-6)
