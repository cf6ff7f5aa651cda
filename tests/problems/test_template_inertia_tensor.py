"""Independent checks of the inertia_tensor template's answers (R2, R4).

The template builds its tensor with ``solver.inertia`` (R2's sum for point masses, the box's
closed form plus the parallel-axis theorem for a box about a corner) and diagonalises it with
``numpy.linalg.eigh``. Here the same answers come by other routes, from the displayed
parameters only:

- point masses: the tensor's columns are ``L = Σ m r × (e_k × r)`` for ``ω = e_k`` (R5's
  definition, not R2's formula);
- box about a corner: the textbook closed form ``I_xx = M (b² + c²)/3``, ``I_xy = −M a b/4``
  (the tensor of a uniform box about a vertex, integrated directly);
- principal moments: the roots of the characteristic cubic ``λ³ − I₁λ² + I₂λ − I₃`` (tensor
  invariants) by mpmath at 40 digits; the axis: the eigen-equation ``I n = λ_max n`` itself.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from problems.templates import FAMILIES, inertia_tensor

SEEDS = range(40)


def _variant(seed):
    return FAMILIES[inertia_tensor.NAME].generate(np.random.default_rng(seed))


def _answers(variant):
    return {a.name: np.array(a.value) for a in variant.answers}


def _tensor_from_parts(diag, off):
    xy, xz, yz = off
    return np.array([[diag[0], xy, xz], [xy, diag[1], yz], [xz, yz, diag[2]]])


def _reference_tensor(params):
    if "M" in params:  # uniform box a × b × c about its corner
        M, a, b, c = (params[k] for k in "Mabc")
        return M * np.array([
            [(b**2 + c**2) / 3, -a * b / 4, -a * c / 4],
            [-a * b / 4, (a**2 + c**2) / 3, -b * c / 4],
            [-a * c / 4, -b * c / 4, (a**2 + b**2) / 3],
        ])
    n = sum(name.startswith("m") for name in params)
    columns = []
    for e in np.eye(3):  # L for ω = e, from L = Σ m r × (ω × r)
        columns.append(sum(params[f"m{k}"] * np.cross(params[f"r{k}"],
                                                      np.cross(e, params[f"r{k}"]))
                           for k in range(1, n + 1)))
    return np.array(columns).T


@pytest.fixture(scope="module")
def variants():
    return [_variant(seed) for seed in SEEDS]


def test_both_scenes_are_drawn(variants):
    scenes = {"M" in v.params for v in variants}
    assert scenes == {True, False}


def test_tensor_matches_independent_construction(variants):
    for v in variants:
        ans = _answers(v)
        reference = _reference_tensor(v.params)
        key = _tensor_from_parts(ans["I_diag"], ans["I_offdiag"])
        np.testing.assert_allclose(key, reference, rtol=0, atol=1e-13 * np.abs(reference).max())


@mp.workdps(40)
def _characteristic_roots(tensor):
    t = mp.matrix(tensor.tolist())
    trace = t[0, 0] + t[1, 1] + t[2, 2]
    minors = sum(t[i, i] * t[j, j] - t[i, j] ** 2 for i, j in ((0, 1), (0, 2), (1, 2)))
    roots = mp.polyroots([1, -trace, minors, -mp.det(t)], maxsteps=200, extraprec=200)
    return sorted(float(mp.re(r)) for r in roots)


def test_principal_moments_are_roots_of_the_characteristic_cubic(variants):
    for v in variants:
        reference = _characteristic_roots(_reference_tensor(v.params))
        np.testing.assert_allclose(_answers(v)["moments"], reference, rtol=1e-10)


def test_axis_solves_the_eigen_equation_with_the_stated_sign(variants):
    for v in variants:
        ans = _answers(v)
        tensor = _reference_tensor(v.params)
        n, largest = ans["axis_max"], ans["moments"][2]
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-14)
        assert n[2] > 0
        assert np.linalg.norm(tensor @ n - largest * n) < 1e-12 * largest


def test_box_about_corner_textbook_case():
    # A cube of side s about a vertex: I_xx = 2/3 M s², I_xy = −M s²/4, and principal moments
    # M s² (11/12, 11/12, 1/6) (the body diagonal is the axis of the smallest).
    params = {"M": 1.0, "a": 1.0, "b": 1.0, "c": 1.0}
    moments = np.linalg.eigvalsh(_reference_tensor(params))
    np.testing.assert_allclose(moments, [1 / 6, 11 / 12, 11 / 12], rtol=1e-14)


def test_statement_states_the_sign_of_the_products_and_the_key_follows_it():
    """Issue 13: "I_xy = −Σ m x y" is in every statement, and the point-mass key is exactly
    that sum (written out here from the displayed masses and positions)."""
    import re

    checked = 0
    for seed in range(40):
        v = FAMILIES[inertia_tensor.NAME].generate(np.random.default_rng(seed))
        assert re.search(r"minus sign, \$I_\{xy\} = -\\sum m\\,x y\$", v.statement)
        masses = sorted(k for k in v.params if re.fullmatch(r"m\d+", k))
        if not masses:
            continue  # the box about its corner
        r = np.array([v.params[f"r{k[1:]}"] for k in masses])
        m = np.array([v.params[k] for k in masses])
        products = [-np.sum(m * r[:, i] * r[:, j]) for i, j in ((0, 1), (0, 2), (1, 2))]
        np.testing.assert_allclose(v.answer("I_offdiag").value, products, rtol=1e-12,
                                   atol=1e-15)
        checked += 1
    assert checked >= 5
