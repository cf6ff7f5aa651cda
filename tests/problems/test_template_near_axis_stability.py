"""Independent checks of the near-axis stability template (R9).

References: the eigenvalues of the Jacobian of Euler's equations (R7, differentiated by sympy
here) at the steady spin — imaginary pairs for a stable axis (the oscillation frequency), a real
positive one for an unstable axis (the growth rate); the rule "the intermediate moment is the
unstable one"; and, for a stable spin, the wobble period measured on scipy's DOP853 integration
of the nonlinear equations from the displayed ω(0), which must agree with R9 to the template's
``LINEAR_RTOL``. None of this calls the solver.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from problems.templates import FAMILIES
from problems.templates import near_axis_stability as template

SEEDS = range(16)

_W = sp.symbols("w1:4")
_I = sp.symbols("I1:4", positive=True)
_EULER = sp.Matrix([(_I[1] - _I[2]) * _W[1] * _W[2] / _I[0],
                    (_I[2] - _I[0]) * _W[2] * _W[0] / _I[1],
                    (_I[0] - _I[1]) * _W[0] * _W[1] / _I[2]])
JACOBIAN = sp.lambdify((_W, _I), _EULER.jacobian(_W), "numpy")
RHS = sp.lambdify((_W, _I), _EULER, "numpy")


@pytest.fixture(params=SEEDS, ids=[f"seed{s}" for s in SEEDS])
def variant(request):
    return FAMILIES[template.NAME].generate(np.random.default_rng(request.param))


def moments(variant) -> tuple[float, float, float]:
    return tuple(variant.params[k] for k in ("I1", "I2", "I3"))


def spin_axis(variant) -> int:
    return int(np.argmax(np.abs(variant.params["omega0"]))) + 1


def eigenvalues(variant, axis: int, spin: float) -> np.ndarray:
    w = [0.0, 0.0, 0.0]
    w[axis - 1] = spin
    return np.linalg.eigvals(np.array(JACOBIAN(w, moments(variant)), dtype=float))


def test_stability_of_each_axis_from_the_jacobian(variant):
    for axis in (1, 2, 3):
        growth = eigenvalues(variant, axis, 1.0).real.max()
        assert variant.answer(f"stable{axis}").value == (growth < 1e-9)


def test_only_the_intermediate_moment_is_unstable(variant):
    middle = int(np.argsort(moments(variant))[1]) + 1
    for axis in (1, 2, 3):
        assert variant.answer(f"stable{axis}").value == (axis != middle)


def test_rate_is_the_jacobian_eigenvalue(variant):
    axis = spin_axis(variant)
    lam = eigenvalues(variant, axis, variant.params["omega0"][axis - 1])
    rate = variant.answer("rate")
    assert rate.unit == "1/s"  # the same unit stable or not: the unit must not tell which
    if variant.answer(f"stable{axis}").value:
        assert_allclose(rate.value, np.abs(lam.imag).max(), rtol=1e-10)
    else:
        assert_allclose(rate.value, lam.real.max(), rtol=1e-10)


def _stable_variants(n: int = 12) -> list:
    """The first ``n`` variants (over seeds 0, 1, …) whose spin is about a stable axis."""
    found = []
    for seed in range(200):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        if v.answer(f"stable{spin_axis(v)}").value:
            found.append(v)
        if len(found) == n:
            return found
    raise AssertionError("too few stable spins drawn")


@pytest.mark.parametrize("variant", _stable_variants(), ids=[f"stable{i}" for i in range(12)])
def test_stable_wobble_is_in_the_linear_regime(variant):
    """The nonlinear wobble's period (crossings of a small component) matches 2π/rate."""
    axis = spin_axis(variant)
    rate = variant.answer("rate").value
    other = axis % 3  # index of the next axis in cyclic order (0-based)
    w0 = np.array(variant.params["omega0"])

    def crossing(t, w):
        return w[other]

    crossing.direction = 1.0
    sol = solve_ivp(lambda t, w: np.ravel(RHS(w, moments(variant))), (0.0, 3.2 * 2 * math.pi
                    / rate), w0, method="DOP853", rtol=1e-11, atol=1e-12, events=crossing)
    up = sol.t_events[0]
    assert len(up) >= 3
    assert_allclose(np.diff(up), 2 * math.pi / rate, rtol=template.LINEAR_RTOL)


def test_draws_are_well_posed_and_varied():
    axes, labels_sorted, bodies = set(), set(), set()
    for seed in range(60):
        v = FAMILIES[template.NAME].generate(np.random.default_rng(seed))
        m = np.array(moments(v))
        gaps = np.abs(m[:, None] - m[None, :])[np.triu_indices(3, 1)]
        assert gaps.min() >= template.MIN_GAP * m.max()
        w = np.abs(v.params["omega0"])
        axis = spin_axis(v)
        assert np.delete(w, axis - 1).max() <= 1.01 * template.WOBBLE[1] * w[axis - 1]
        axes.add(axis)
        labels_sorted.add(bool(np.all(np.diff(m) > 0)))
        bodies.add(v.statement.split(" (")[0])
    assert axes == {1, 2, 3}
    assert labels_sorted == {True, False}  # the moments are not always given in order
    assert len(bodies) == 5
