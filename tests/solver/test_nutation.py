"""The cubic of R17 about u0 = cos β0 (solver.nutation): derivation, stability, robustness.

References: a sympy derivation of the expansion coefficients from R15–R17, and
``mpmath.polyroots`` at 40 digits on the cubic assembled from the original definitions.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
import sympy as sp

from solver.heavy_top import constants_of_motion, steady_precession_rates
from solver.nutation import nutation_cubic

mp.mp.dps = 40

STATES = [
    (2.0e-4, 1.0e-4, 0.02, 0.5, 0.3, 0.7, 150.0),
    (3.0e-3, 2.0e-3, 0.3, 2.4, -2.0, 1.5, 80.0),
    (2.0e-4, 1.0e-4, 0.02, 0.7, 0.3, 0.2, 5000.0),
    (1.0e-2, 1.0e-2, 0.5, 1.0, 0.0, 0.0, 5000.0),
]


def _mp_roots(state):
    """Roots of f(u) = (1 − u²)(A − B u) − (b − a u)² from R15–R17, 40 digits."""
    I1, I3, Mgl, b0, ad, bd, gd = (mp.mpf(x) for x in state)
    c, s = mp.cos(b0), mp.sin(b0)
    pg = I3 * (ad * c + gd)
    pa = I1 * ad * s**2 + pg * c
    e = I1 * bd**2 / 2 + (pa - pg * c) ** 2 / (2 * I1 * s**2) + Mgl * c
    a, b, A, B = pg / I1, pa / I1, 2 * e / I1, 2 * Mgl / I1
    roots = mp.polyroots([B, -A - a**2, -B + 2 * a * b, A - b**2], maxsteps=400, extraprec=400)
    return sorted(mp.re(r) for r in roots)


def test_expansion_coefficients_derived_with_sympy():
    """f(u0 + w) = B w³ + c2 w² + c1 w + c0 with the docstring's c0, c1, c2 (symbolically),
    and the implementation's numbers equal them (40-digit evaluation)."""
    I1, I3, Mgl = sp.symbols("I1 I3 Mgl", positive=True)
    beta, ad, bd, gd, w = sp.symbols("beta alpha_dot beta_dot gamma_dot w", real=True)
    u0, s2 = sp.cos(beta), sp.sin(beta) ** 2
    p_gamma = I3 * (ad * u0 + gd)  # R15
    p_alpha = I1 * ad * s2 + p_gamma * u0
    e_prime = I1 * bd**2 / 2 + (p_alpha - p_gamma * u0) ** 2 / (2 * I1 * s2) + Mgl * u0  # R16
    a, b, A, B = p_gamma / I1, p_alpha / I1, 2 * e_prime / I1, 2 * Mgl / I1
    u = u0 + w
    f = sp.expand((1 - u**2) * (A - B * u) - (b - a * u) ** 2)  # R17
    P, Q = bd**2 + ad**2 * s2, ad * s2
    claimed = {0: s2 * bd**2, 1: -B * s2 - 2 * u0 * P + 2 * a * Q, 2: 2 * u0 * B - P - a**2, 3: B}
    for k, ck in claimed.items():
        assert sp.simplify(sp.trigsimp(f.coeff(w, k) - ck)) == 0, k

    coeffs = [sp.lambdify((I1, I3, Mgl, beta, ad, bd, gd), claimed[k], "mpmath") for k in range(3)]
    for state in STATES:
        cubic = nutation_cubic(*(np.atleast_1d(x).astype(float) for x in state))
        for k, got in enumerate((cubic.c0, cubic.c1, cubic.c2)):
            want = coeffs[k](*(mp.mpf(x) for x in state))
            scale = max(abs(want), abs(coeffs[2](*(mp.mpf(x) for x in state))) * 1e-6)
            assert abs(float(got[0]) - want) <= 1e-13 * scale


HARD = {
    # a fast top (ω3 = 5000 rad/s): the expanded coefficients cancel catastrophically
    "fast_top_moving": (2.0e-4, 1.0e-4, 0.02, 0.7, 0.3, 0.2, 5000.0),
    "fast_top_from_rest": (2.0e-4, 1.0e-4, 0.02, 0.7, 0.0, 0.0, 5000.0),
    "fast_heavy_top": (1.0e-2, 1.0e-2, 0.5, 1.0, 0.0, 0.0, 5000.0),
}
# within 1e-12 of steady precession: a near-double root (slow rate at β0 = 0.5, ω3 = 150)
_SLOW = float(steady_precession_rates(2.0e-4, 1.0e-4, 0.02, 0.5, 1.0e-4 * 150.0)[0])
HARD["near_steady"] = (2.0e-4, 1.0e-4, 0.02, 0.5, _SLOW * (1 + 1e-12), 0.0,
                       150.0 - _SLOW * np.cos(0.5))


def _errors(u_got, u_ref):
    """(relative error of the nutation width u2 − u1, absolute error of u1 and u2)."""
    width = float(u_ref[1] - u_ref[0])
    rel_width = abs((u_got[1] - u_got[0]) / width - 1)
    return rel_width, max(abs(u_got[k] - float(u_ref[k])) for k in range(2))


@pytest.mark.parametrize("name", sorted(HARD))
def test_np_roots_is_not_good_enough(name):
    """np.roots on the expanded cubic against ours, both against mpmath.

    Fast tops: the nutation width u2 − u1 (which Δα and ⟨α̇⟩ are proportional to) — np.roots
    gets it to 1e-8 … 1e-5, ours to rounding. Near steady: the turning points themselves —
    np.roots splits the near-double root by ~√ε (or returns complex roots), ours to ~ε.
    """
    state = HARD[name]
    u_ref = _mp_roots(state)
    pa, pg, e = constants_of_motion(*state)
    I1, Mgl = state[0], state[2]
    a, b, A, B = pg / I1, pa / I1, 2 * e / I1, 2 * Mgl / I1
    naive = np.sort(np.roots([B, -A - a * a, -B + 2 * a * b, A - b * b]).real)
    cubic = nutation_cubic(*(np.atleast_1d(x).astype(float) for x in state))
    naive_width, naive_abs = _errors(naive, u_ref)
    _, ours_abs = _errors(cubic.u[0], u_ref)
    # our width straight from the offsets w = u − u0 (adding u0 first would round it)
    ours_width = abs((cubic.w[0, 1] - cubic.w[0, 0]) / float(u_ref[1] - u_ref[0]) - 1)
    if name == "near_steady":
        assert naive_abs > 1e-9  # measured 2e-8: fails the 1e-10 target
        assert ours_abs < 1e-15
        # The width itself (9e-15) is ill-conditioned: rounding c1's terms sets it, ~1e-4.
        assert ours_width < 1e-3
    else:
        assert naive_width > 1e-9  # measured 7e-9 … 3e-5: fails the 1e-10 target
        assert ours_width < 1e-14
        assert ours_abs < 1e-15


def test_roots_are_ordered_and_solve_the_cubic():
    """1000 random tops (fast and slow, moving or not): −1 ≤ u1 ≤ u0 ≤ u2 ≤ 1 ≤ u3, and a
    sample of them against mpmath to 1e-10 (u3 relative)."""
    rng = np.random.default_rng(20240917)
    n = 1000
    I1 = 10 ** rng.uniform(-4, -2, n)
    state = (I1, I1 * rng.uniform(0.1, 1.9, n), 10 ** rng.uniform(-3, 0, n),
             rng.uniform(0, np.pi, n), rng.normal(0, 5, n),
             rng.normal(0, 2, n) * (rng.random(n) < 0.7),
             rng.normal(0, 1, n) * 10 ** rng.uniform(0, 3.7, n))
    cubic = nutation_cubic(*state)
    u = cubic.u
    assert np.all(u[:, 0] >= -1) and np.all(u[:, 1] <= 1) and np.all(u[:, 2] >= 1)
    assert np.all(cubic.w[:, 0] <= 0) and np.all(cubic.w[:, 1] >= 0)
    for i in range(0, n, 50):
        want = _mp_roots([x[i] for x in state])
        for k in range(3):
            assert abs(u[i, k] - float(want[k])) <= 1e-10 * max(1.0, abs(float(want[k])))


def _cubics(n, seed):
    """The coefficients ``B, c0 > 0, c1, c2`` of ``n`` random moving tops' cubics, and ``1 − u0``
    (fast and slow tops, near and far from the poles)."""
    rng = np.random.default_rng(seed)
    I1 = 10 ** rng.uniform(-4, -2, n)
    state = (I1, I1 * rng.uniform(0.1, 1.9, n), 10 ** rng.uniform(-3, 0, n),
             rng.uniform(1e-6, np.pi - 1e-6, n), rng.normal(0, 5, n), rng.normal(0, 2, n),
             rng.normal(0, 1, n) * 10 ** rng.uniform(0, 3.7, n))
    cubic = nutation_cubic(*state)
    return cubic.B, cubic.c0, cubic.c1, cubic.c2, cubic.one_minus_u0


@pytest.mark.parametrize("fallback", [False, True])
def test_newton_starts_above_the_largest_root_and_finds_it(fallback, monkeypatch):
    """For 200 random cubics, the start (the raised trigonometric root, or Fujiwara's bound
    where that is not provably above) lies above the largest root of the float coefficients
    (mpmath, 40 digits), and Newton from it finds that root to 1e-14 relative."""
    from solver import nutation

    B, c0, c1, c2, hm = _cubics(200, 20261127)
    if fallback:  # as if the trigonometric root were never provably above the largest one
        monkeypatch.setattr(nutation.np, "arccos", lambda x: np.full_like(x, np.nan))
    start = nutation._start_above_w3(B, c0, c1, c2, hm)
    monkeypatch.undo()
    w3 = nutation._newton_from_above(B, c0, c1, c2, start.copy())
    for i in range(200):
        coefficients = [mp.mpf(float(x[i])) for x in (B, c2, c1, c0)]
        largest = max(mp.re(r) for r in mp.polyroots(coefficients, maxsteps=400, extraprec=400))
        assert start[i] >= largest
        assert abs(w3[i] - float(largest)) <= 1e-14 * abs(float(largest))
