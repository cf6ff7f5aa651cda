"""Independent checks of the motion_type template's answers (R18).

The template's numbers come from ``solver.heavy_top.solve_heavy_top`` (turning points from the
nutation cubic, α̇ from R18's formula, the figure from its signs). Here the top is integrated
instead: Newton–Euler equations for the symmetry axis ``e3`` and the angular momentum ``L`` about
the fixed point, in the lab frame (no Euler angles, no conserved quantities used),

    de3/dt = ω × e3 = (L × e3)/I1,      dL/dt = l e3 × (−M g ẑ) = Mgl ẑ × e3,

started from the shown Euler angles and rates (R12: ω = α̇ ẑ + β̇ ê_N + γ̇ e3 with α0 = 0), with
scipy's DOP853 at rtol 1e-10 over one nutation period (until ``d(e3·ẑ)/dt`` has vanished three
times). Along the path ``α̇ = (e3x ė3y − e3y ė3x)/(e3x² + e3y²)``:

- at the turning points (the events) it must equal ``alpha_dot1`` (smallest tilt) and
  ``alpha_dot2`` (largest tilt);
- its signs along the whole path must give the figure: both signs for loops, one sign and never
  near zero for waves, one sign and zero at the upper turning point for cusps.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from problems.answers import grade
from problems.templates import FAMILIES
from problems.templates import motion_type as template
from problems.templates.heavy_top_constants import MARGIN

SEEDS = range(24)
RTOL = 1e-10


@pytest.fixture(scope="module")
def variants():
    return [FAMILIES[template.NAME].generate(np.random.default_rng(seed)) for seed in SEEDS]


def top(p: dict) -> tuple[float, float, float]:
    """``(I1 about the tip, I3, Mgl)`` from R2 (thin disc on a light axle), typed in."""
    Mgl = p["M"] * p["g"] * p["l"]
    if "I1" in p:
        return p["I1"], p["I3"], Mgl
    return p["M"] * p["R"] ** 2 / 4 + p["M"] * p["l"] ** 2, p["M"] * p["R"] ** 2 / 2, Mgl


def initial(p: dict, I1: float, I3: float) -> np.ndarray:
    """``(e3, L)`` at t = 0 from the Euler angles (α0 = 0) and their rates."""
    b = p["beta0"]
    e3 = np.array([math.sin(b), 0.0, math.cos(b)])
    # R11: β turns about the line of nodes, the y axis when α = 0 (it tilts e3 towards +x)
    omega = p["alpha_dot0"] * np.array([0.0, 0.0, 1.0]) + p["beta_dot0"] * np.array(
        [0.0, 1.0, 0.0]) + p["gamma_dot0"] * e3
    L = I1 * omega + (I3 - I1) * np.dot(omega, e3) * e3
    return np.concatenate([e3, L])


def rhs(I1: float, Mgl: float):
    z = np.array([0.0, 0.0, 1.0])

    def f(t, y):
        e3, L = y[:3], y[3:]
        return np.concatenate([np.cross(L, e3) / I1, Mgl * np.cross(z, e3)])

    return f


def precession(y: np.ndarray, I1: float) -> np.ndarray:
    """α̇ of the axis e3 (azimuth rate about z), for states y of shape (6, n)."""
    e3, L = y[:3], y[3:]
    de3 = np.cross(L, e3, axis=0) / I1
    return (e3[0] * de3[1] - e3[1] * de3[0]) / (e3[0] ** 2 + e3[1] ** 2)


@pytest.fixture(scope="module")
def paths(variants):
    """One nutation period of each variant: (tilts at events, α̇ at events, α̇ along the path)."""
    out = []
    for v in variants:
        p = v.params
        I1, I3, Mgl = top(p)
        f = rhs(I1, Mgl)

        def turning(t, y, f=f):
            return f(t, y)[2]  # d(e3·ẑ)/dt = 0: β at an extremum

        turning.terminal = 3
        sol = solve_ivp(f, (0.0, 20.0), initial(p, I1, I3), method="DOP853", rtol=RTOL,
                        atol=1e-12, events=turning, dense_output=True)
        assert sol.status == 1, sol.message  # stopped by the events, within 20 s
        events = sol.y_events[0].T
        t = np.linspace(0.0, sol.t[-1], 4001)
        out.append((np.arccos(np.clip(events[2], -1, 1)), precession(events, I1),
                    precession(sol.sol(t), I1)))
    return out


def test_all_three_figures_occur(variants):
    assert {v.answer("motion").value for v in variants} == {"waves", "loops", "cusps"}


def test_rates_at_the_turning_points_match_the_integration(variants, paths):
    for v, (tilts, rates, _) in zip(variants, paths, strict=True):
        a1, a2 = v.answer("alpha_dot1").value, v.answer("alpha_dot2").value
        scale = max(abs(a1), abs(a2))
        upper = tilts < 0.5 * (tilts.min() + tilts.max())  # the events at β1 (highest axis)
        assert upper.any() and (~upper).any()
        np.testing.assert_allclose(rates[upper], a1, rtol=1e-6, atol=1e-7 * scale)
        np.testing.assert_allclose(rates[~upper], a2, rtol=1e-6, atol=1e-7 * scale)
        # and the turning points themselves are those of the integrated motion
        assert tilts.min() < tilts.max() - 0.019


def test_figure_matches_the_signs_of_alpha_dot_along_the_path(variants, paths):
    for v, (_, rates, along) in zip(variants, paths, strict=True):
        figure = v.answer("motion").value
        scale = np.abs(along).max()
        if figure == "loops":
            assert along.min() < -0.04 * scale and along.max() > 0.04 * scale
        elif figure == "waves":
            assert np.abs(along).min() > 0.04 * scale
            assert (along > 0).all() or (along < 0).all()
        else:  # cusps: α̇ touches zero at the top of the nod and never changes sign
            assert np.abs(rates).min() < 1e-7 * scale
            sense = np.sign(along[np.argmax(np.abs(along))])
            assert (sense * along > -1e-7 * scale).all()


def test_cusps_are_released_tops(variants):
    for v in variants:
        released = v.params["alpha_dot0"] == 0 and v.params["beta_dot0"] == 0
        assert (v.answer("motion").value == "cusps") == released
        if released:
            assert v.answer("alpha_dot1").value == 0.0


def test_mistakes_are_named_even_with_tolerances_widened_margin_times(variants):
    # select_mistakes keeps mistakes MARGIN tolerances from the key and from each other (and
    # replace() re-validates: it refuses a mistake within the widened tolerance of the key)
    for v in variants:
        for a in v.answers:
            wide = replace(a, rtol=MARGIN * a.rtol, atol=MARGIN * a.atol)
            for m in wide.mistakes:
                assert grade(wide, m.value).mistake == m.name, (a.name, m.name)


def test_rate_mistakes_exchange_and_flip_the_key(variants):
    for v in variants:
        a1, a2 = v.answer("alpha_dot1"), v.answer("alpha_dot2")
        for key, other in ((a1, a2), (a2, a1)):
            wrong = {m.name: m.value for m in key.mistakes}
            assert wrong["turning_points_exchanged"] == other.value
            assert wrong.get("sign_flipped", 0.0) == -key.value  # absent only for a cusp's 0
        figure = v.answer("motion")
        assert {m.value for m in figure.mistakes} == set(template.OPTIONS) - {figure.value}
