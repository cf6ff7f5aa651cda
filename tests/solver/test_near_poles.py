"""Issue 12's four defects, each against the independent mpmath reference
(solver.bench.mp_reference).

1. a hanging, barely spinning top near the lower pole: β1 was NaN (a signed gap), the batch died;
2. the planar pendulum (p_α = p_γ = 0): poles are exact roots; over the top there is no turning
   point (label "revolves", not "cusps");
3. ⟨α̇⟩ of a fast top looping near a pole: the two Π terms of R20 cancelled ~10⁸-fold;
4. valid batch lines answered with errors.

The reference itself is checked here against direct mpmath quadrature of R20's integrals.
"""

from __future__ import annotations

import io
import json
import math
import sys

import mpmath as mp
import numpy as np
import pytest

from eulertop.cli import main
from solver.bench.mp_reference import reference
from solver.heavy_top import solve_heavy_top, solve_heavy_top_many

HANGING = (1.0, 0.5, 1.0, 3.1415, 2.0, 0.01, 1.9999999914153124)
PENDULUM_SWING = (2e-4, 1e-4, 0.02, 2.0, 0.0, 0.0, 0.0)
PENDULUM_OVER = (2e-4, 1e-4, 0.02, 0.3, 0.0, -12.0, 0.0)
FAST_NEAR_POLE = (0.02, 0.01, 0.2, 1e-5, 0.0, 1.0, 1e5)


def _quadrature(state):
    """T and ⟨α̇⟩ by mpmath quadrature of R20's integrals, u = u1 + g(1 − cos θ)/2, with break
    points clustered where the integrand peaks (θ → π when u2 is near the upper pole)."""
    with mp.workdps(60):
        I1, I3, Mgl, b0, ad, bd, gd = (mp.mpf(x) for x in state)
        c, s = mp.cos(b0), mp.sin(b0)
        pg = I3 * (ad * c + gd)
        pa = I1 * ad * s**2 + pg * c
        e = I1 * (bd**2 + ad**2 * s**2) / 2 + Mgl * c
        a, b, A, B = pg / I1, pa / I1, 2 * e / I1, 2 * Mgl / I1
        roots = mp.polyroots([B, -(A + a * a), 2 * a * b - B, A - b * b], maxsteps=200,
                             extraprec=400)
        u1, u2, u3 = sorted(mp.re(r) for r in roots)

        def u_of(th):
            return u1 + (u2 - u1) * (1 - mp.cos(th)) / 2

        def rate(u):
            return (b - a * u) / ((1 - u) * (1 + u))

        points = [mp.mpf(0)] + [mp.pi - mp.pi * mp.mpf(2) ** -k for k in range(1, 40)] + [mp.pi]
        points = sorted(set(points))
        period = 2 * mp.quad(lambda th: 1 / mp.sqrt(B * (u3 - u_of(th))), points)
        angle = 2 * mp.quad(lambda th: rate(u_of(th)) / mp.sqrt(B * (u3 - u_of(th))), points)
        return period, angle / period


GENERIC = (3e-3, 2e-3, 0.3, 1.1, -2.0, 1.5, 80.0)


@pytest.mark.parametrize("state", [HANGING, FAST_NEAR_POLE, GENERIC])
def test_reference_agrees_with_direct_quadrature(state):
    period, mean = _quadrature(state)
    ref = reference(state)
    assert abs(ref.period / period - 1) < 1e-25
    assert abs(ref.mean_rate / mean - 1) < 1e-20


def test_hanging_top_near_the_lower_pole_is_finite_and_right():
    """Defect 1: β1 = 3.1315904661014646, T = 3.14161229724823 (the issue's numbers)."""
    out = solve_heavy_top(*HANGING)
    ref = reference(HANGING)
    assert abs(out["beta1"] - float(ref.beta1)) < 1e-12
    assert abs(out["beta2"] - float(ref.beta2)) < 1e-12
    assert abs(out["nutation_period"] / float(ref.period) - 1) < 1e-12
    assert abs(out["mean_precession_rate"] / float(ref.mean_rate) - 1) < 1e-10
    assert out["motion"] == ref.label == "waves"
    assert out["beta1"] == pytest.approx(3.1315904661014646, abs=1e-15)


def test_hanging_tops_near_the_pole_never_nan():
    """A sweep of hanging, barely spinning tops (p_γ ≈ 0, u near −1): every field finite."""
    rng = np.random.default_rng(12)
    n = 2000
    b0 = np.pi - 10 ** rng.uniform(-8, -1, n)
    ad = rng.uniform(-3, 3, n)
    gd = -ad * np.cos(b0) * (1 + rng.normal(0, 1e-9, n))
    bd = rng.uniform(-0.1, 0.1, n)
    table = solve_heavy_top_many(1.0, 0.5, 1.0, b0, ad, bd, gd)
    for key in ("beta1", "beta2", "nutation_period", "mean_precession_rate"):
        assert np.all(np.isfinite(table[key])), key
    for i in range(0, n, 100):
        ref = reference((1.0, 0.5, 1.0, b0[i], ad[i], bd[i], gd[i]))
        assert abs(table["beta1"][i] - float(ref.beta1)) < 1e-10
        assert abs(table["beta2"][i] - float(ref.beta2)) < 1e-10
        assert abs(table["nutation_period"][i] / float(ref.period) - 1) < 1e-10


def test_pendulum_swings_to_the_bottom_exactly():
    """Defect 2a: β2 is π exactly (u1 = −1 is an exact root of (1 − u²)(A − Bu))."""
    out = solve_heavy_top(*PENDULUM_SWING)
    assert out["beta2"] == math.pi and out["beta1"] == 2.0
    assert out["motion"] == reference(PENDULUM_SWING).label == "cusps"


def test_pendulum_over_the_top_revolves():
    """Defect 2b: β̇² = A − Bu > 0 all the way round (axis speed > 11 rad/s): no turning point,
    β spans [0, π], label "revolves"."""
    out = solve_heavy_top(*PENDULUM_OVER)
    ref = reference(PENDULUM_OVER)
    assert out["beta1"] == 0.0 and out["beta2"] == math.pi
    assert out["motion"] == ref.label == "revolves"
    assert abs(out["nutation_period"] / float(ref.period) - 1) < 1e-13
    assert out["mean_precession_rate"] == 0.0


def test_fast_top_looping_near_the_pole_mean_precession():
    """Defect 3: the truth 2.0000000072e-4 (the solver gave 1.999999889e-4)."""
    out = solve_heavy_top(*FAST_NEAR_POLE)
    ref = reference(FAST_NEAR_POLE)
    assert abs(out["mean_precession_rate"] / float(ref.mean_rate) - 1) < 1e-12
    assert out["motion"] == ref.label == "loops"


def _batch(lines, monkeypatch, capsys):
    monkeypatch.setattr(sys, "stdin", io.StringIO("".join(line + "\n" for line in lines)))
    status = main(["solve", "--batch", "-"])
    out = capsys.readouterr()
    return status, [json.loads(line) for line in out.out.splitlines()], out.err


def test_batch_answers_the_issue_line_and_survives_garbage(monkeypatch, capsys):
    """Defects 1 and 4: one output line per input line, in order; bad lines get errors."""
    keys = ("I1", "I3", "Mgl", "beta0", "alpha_dot0", "beta_dot0", "gamma_dot0")
    good = json.dumps({"scene": "heavy-top", **dict(zip(keys, HANGING, strict=True))})
    lines = [good, "", "{", "[]", '{"scene": ["heavy-top"]}', '{"scene": "heavy-top"}',
             json.dumps({"scene": "heavy-top", **dict(zip(keys, PENDULUM_OVER, strict=True))}),
             good]
    status, answers, err = _batch(lines, monkeypatch, capsys)
    assert status == 1 and "Traceback" not in err
    assert len(answers) == len(lines)
    assert answers[0]["beta1"] == pytest.approx(3.1315904661014646, abs=1e-15)
    assert answers[0] == answers[-1]
    assert all("error" in answers[i] for i in range(1, 6))
    assert "line 2" in answers[1]["error"] and "blank" in answers[1]["error"]
    assert answers[6]["motion"] == "revolves"


def test_batch_of_hard_valid_lines_has_no_errors(monkeypatch, capsys):
    """Defect 4: 2,600 valid lines from the hard regions, each answered without an error."""
    rng = np.random.default_rng(4)
    n = 2600
    b0 = np.where(rng.random(n) < 0.5, np.pi - 10 ** rng.uniform(-9, -1, n),
                  10 ** rng.uniform(-9, -1, n))
    ad = rng.uniform(-3, 3, n)
    gd = np.where(rng.random(n) < 0.5, -ad * np.cos(b0), 10 ** rng.uniform(-2, 5, n))
    lines = [json.dumps({"scene": "heavy-top", "I1": 0.02, "I3": 0.01, "Mgl": 0.2,
                         "beta0": float(b), "alpha_dot0": float(x),
                         "beta_dot0": float(y), "gamma_dot0": float(g)})
             for b, x, y, g in zip(b0, ad, rng.normal(0, 1, n) * (rng.random(n) < 0.7), gd,
                                   strict=True)]
    status, answers, _ = _batch(lines, monkeypatch, capsys)
    assert len(answers) == n
    assert [a for a in answers if "error" in a] == []
    assert status == 0


def test_batch_help_documents_exit_status(capsys):
    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "Exit status: 0" in text and "1: at least one line" in text and "2: usage" in text
