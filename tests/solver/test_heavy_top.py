"""Heavy symmetric top (R14–R21): every quantity against independent references.

References: mpmath at 40 digits built from the *original* definitions of R15–R17 (the expanded
cubic solved by ``mpmath.polyroots``, the R20 integrals by ``mpmath.quad`` after the
substitution ``u = u1 + (u2 − u1)(1 − cos θ)/2`` that removes the end singularities,
``mpmath.findroot`` on ``V_eff(β) = E'``), and the equations of motion of the R14 Lagrangian
(derived here with sympy, integrated with DOP853).
"""

from __future__ import annotations

import functools

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from solver.heavy_top import (
    constants_of_motion,
    cos_beta,
    cubic_roots,
    effective_potential,
    mean_precession_rate,
    motion_type,
    nutation_period,
    precession_rate,
    solve_heavy_top,
    spin_rate,
    steady_precession_rates,
    turning_points,
)
from solver.parameters import ParameterError

mp.mp.dps = 40
TOL = 1e-10  # relative; angles absolute

# A toy top: I1 (about the tip) 2e-4 kg m², I3 1e-4 kg m², Mgl 0.02 J, critical spin 40 rad/s.
TOY = (2.0e-4, 1.0e-4, 0.02)


def _steady(beta0: float, omega3: float, which: int, rel: float = 0.0, beta_dot0: float = 0.0):
    """A state precessing at the slow (0) or fast (1) steady rate, optionally nudged."""
    rates = steady_precession_rates(*TOY, beta0, TOY[1] * omega3)
    ad = float(rates[which]) * (1.0 + rel)
    return (*TOY, beta0, ad, beta_dot0, omega3 - float(rates[which]) * np.cos(beta0))


CASES = {
    "generic_loops": (3.0e-3, 2.0e-3, 0.3, 1.1, -2.0, 1.5, 80.0),
    "generic_waves": (5.0e-3, 4.0e-3, 0.2, 0.8, 2.0, -0.3, 60.0),
    "released_from_rest": (*TOY, 0.5, 0.0, 0.0, 150.0),
    "hanging_loops": (*TOY, 2.5, 3.0, 0.5, 150.0),
    "hanging_from_rest": (*TOY, 3.0, 0.0, 0.0, 150.0),
    "fast_top_from_rest": (*TOY, 0.7, 0.0, 0.0, 5000.0),
    "fast_top_moving": (*TOY, 0.7, 0.3, 0.2, 5000.0),
    "fast_heavy_top": (1.0e-2, 1.0e-2, 0.5, 1.0, 0.0, 0.0, 5000.0),
    "near_steady_slow": _steady(0.5, 150.0, 0, rel=1e-12),
    "near_steady_fast": _steady(0.5, 150.0, 1, rel=1e-12),
    "near_steady_nudged": _steady(0.5, 150.0, 0, beta_dot0=1e-9),
    "near_steady_fast_top": _steady(0.5, 5000.0, 0, rel=1e-12),
    "sleeping_unstable_at_rest": (*TOY, 0.0, 0.0, 0.0, 30.0),
    "through_the_pole": (*TOY, 0.0, 0.0, 1.0, 30.0),
    "near_separatrix": (*TOY, 1e-3, 0.0, 0.0, 30.0),
    "near_separatrix_moving": (*TOY, 1e-3, 0.0, 1e-4, 30.0),
    "nearly_sleeping_stable": (*TOY, 1e-4, 0.0, 0.0, 150.0),
    "pendulum_through_bottom": (*TOY, 1.0, 0.0, 0.0, 0.0),
    # Simo & Wong (1991), as restated in the Solfec validation suite (parmes/parmes,
    # solfec/validation/heavy_symmetrical_top.rst): J = diag(5, 5, 1) about the fixed point,
    # M g l = 20·1·1, initial rotation exp(skew([0.05, 0, 0])) (tilt 0.05 rad), body angular
    # velocity W(0) = (0, 0, 50), i.e. α̇0 = β̇0 = 0, γ̇0 = 50.
    "simo_wong_1991": (5.0, 1.0, 20.0, 0.05, 0.0, 0.0, 50.0),
}

EXPECTED_MOTION = {
    "released_from_rest": "cusps",
    "hanging_from_rest": "cusps",
    "fast_top_from_rest": "cusps",
    "fast_heavy_top": "cusps",
    "simo_wong_1991": "cusps",
    "near_separatrix": "cusps",
    "nearly_sleeping_stable": "cusps",
    "pendulum_through_bottom": "cusps",
}


@functools.cache
def reference(case: str) -> dict:
    """Everything from R15–R17/R20 in mpmath at 40 digits, from the original definitions."""
    I1, I3, Mgl, b0, ad, bd, gd = (mp.mpf(x) for x in CASES[case])
    c, s = mp.cos(b0), mp.sin(b0)
    pg = I3 * (ad * c + gd)  # R15
    pa = I1 * ad * s**2 + pg * c
    centrifugal = 0 if s == 0 else (pa - pg * c) ** 2 / (2 * I1 * s**2)
    e_prime = I1 * bd**2 / 2 + centrifugal + Mgl * c  # R16
    a, b, A, B = pg / I1, pa / I1, 2 * e_prime / I1, 2 * Mgl / I1  # R17
    roots = mp.polyroots([B, -A - a**2, -B + 2 * a * b, A - b**2], maxsteps=400, extraprec=400)
    u1, u2, u3 = sorted(mp.re(r) for r in roots)

    def rate(u):  # R18; a pole the top reaches (b = ±a) is not 0/0
        if b == a == 0:
            return mp.mpf(0)
        if b == a:
            return a / (1 + u)
        if b == -a:
            return -a / (1 - u)
        return (b - a * u) / ((1 - u) * (1 + u))

    ref = {
        "p_alpha": pa,
        "p_gamma": pg,
        "E_prime": e_prime,
        "u": (u1, u2, u3),
        "a": a,
        "b": b,
        "beta1": mp.acos(min(u2, 1)),
        "beta2": mp.acos(max(u1, -1)),
        "rate1": rate(u2),
        "rate2": rate(u1),
        "E": e_prime + pg**2 / (2 * I3),
    }
    if u2 - u1 > mp.mpf(10) ** -25 and u3 - u2 > mp.mpf(10) ** -30:

        def u_of(th):  # (u − u1)(u2 − u) = ((u2 − u1) sin θ / 2)², du = that root dθ
            return u1 + (u2 - u1) * (1 - mp.cos(th)) / 2

        nodes = mp.linspace(0, mp.pi, 9)
        period = 2 * mp.quad(lambda th: 1 / mp.sqrt(B * (u3 - u_of(th))), nodes)
        angle = 2 * mp.quad(lambda th: rate(u_of(th)) / mp.sqrt(B * (u3 - u_of(th))), nodes)
        ref.update(T=period, dalpha=angle, mean=angle / period)
    return ref


def _close(x, ref, scale=None):
    ref = float(ref)
    scale = abs(ref) if scale is None else max(abs(ref), scale)
    return abs(float(x) - ref) <= TOL * scale


@pytest.fixture(params=sorted(CASES))
def case(request):
    return request.param


def test_constants_of_motion(case):
    pa, pg, e = constants_of_motion(*CASES[case])
    ref = reference(case)
    assert _close(pa, ref["p_alpha"], 1e-300) and _close(pg, ref["p_gamma"], 1e-300)
    assert _close(e, ref["E_prime"])


def test_turning_points(case):
    beta1, beta2 = turning_points(*CASES[case])
    ref = reference(case)
    assert abs(beta1 - float(ref["beta1"])) <= TOL
    assert abs(beta2 - float(ref["beta2"])) <= TOL
    u = cubic_roots(*CASES[case])
    for got, want in zip(u, ref["u"], strict=True):
        assert abs(got - float(want)) <= TOL * max(1.0, abs(float(want)))


@pytest.mark.parametrize(
    "name",
    ["generic_loops", "hanging_loops", "fast_top_moving", "near_steady_nudged", "simo_wong_1991"],
)
def test_turning_points_solve_the_effective_potential(name):
    """R17 as stated: V_eff(β_i) = E', by mpmath.findroot on R16 (not on the cubic)."""
    I1, _, Mgl, *_ = (mp.mpf(x) for x in CASES[name])
    ref = reference(name)
    pa, pg, e = ref["p_alpha"], ref["p_gamma"], ref["E_prime"]

    def excess(beta):
        return (pa - pg * mp.cos(beta)) ** 2 / (2 * I1 * mp.sin(beta) ** 2) + Mgl * mp.cos(beta) - e

    for got in turning_points(*CASES[name]):
        root = mp.findroot(excess, mp.mpf(got))
        assert abs(got - float(root)) <= TOL


def test_rates_at_turning_points(case):
    """α̇ at β1, β2 (R18), relative to the size of the terms it is made of."""
    out = solve_heavy_top(*CASES[case])
    ref = reference(case)
    if out["motion"] == "sleeping":
        assert out["alpha_dot_beta1"] is None and out["alpha_dot_beta2"] is None
        return
    for key, u in (("rate1", ref["u"][1]), ("rate2", ref["u"][0])):
        terms = (abs(ref["b"]) + abs(ref["a"] * u)) / max(1 - u * u, mp.mpf(10) ** -30)
        got = out["alpha_dot_beta1" if key == "rate1" else "alpha_dot_beta2"]
        assert _close(got, ref[key], 1e-6 * float(terms))


def test_nutation_period_and_mean_precession(case):
    ref = reference(case)
    period = nutation_period(*CASES[case])
    mean = mean_precession_rate(*CASES[case])
    if "T" not in ref:  # steady or sleeping: no nutation
        assert np.isnan(period) or np.isinf(period)
        return
    assert _close(period, ref["T"])
    # ⟨α̇⟩ can be a small difference of forward and backward precession (loops): scale by the
    # largest |α̇| on the path.
    assert _close(mean, ref["mean"], 1e-6 * max(abs(float(ref["rate1"])), abs(float(ref["rate2"]))))


def test_motion_type(case):
    """Cusps where physics says so (released from rest); else the signs of α̇ at u1, u2 in
    mpmath decide loops (opposite) or waves (R18); a 1e-12 nudge off steady is not steady."""
    got = motion_type(*CASES[case])
    ref = reference(case)
    if case in EXPECTED_MOTION:
        want = EXPECTED_MOTION[case]
    elif case == "sleeping_unstable_at_rest" or ref["u"][1] == 1:
        want = "waves"  # falls from / passes the vertical, α̇ = (b − a u)/(1 − u²) one-signed
    else:
        want = "loops" if ref["rate1"] * ref["rate2"] < 0 else "waves"
    assert got == want


@pytest.mark.parametrize(
    ("state", "want"),
    [
        ((*TOY, 0.0, 0.0, 0.0, 150.0), "sleeping"),
        ((*TOY, 0.0, 3.0, 0.0, 37.0 + 3.0), "sleeping"),  # ω3 = α̇ + γ̇ = 40: critical, stable
        ((*TOY, 0.0, 0.0, 0.0, 39.0), "waves"),  # unstable: falls away, α̇ one-signed
        (_steady(0.5, 150.0, 0), "steady"),
        (_steady(0.5, 150.0, 1), "steady"),
        (_steady(2.0, 150.0, 0), "steady"),
        (_steady(2.9, 150.0, 1), "steady"),  # hanging, fast (retrograde) precession
        ((*TOY, 0.5, 0.0, 0.0, 0.0), "cusps"),  # released from rest, not spinning
    ],
)
def test_motion_type_special_states(state, want):
    assert motion_type(*state) == want


def test_simo_wong_energy():
    """Simo & Wong's quoted Hamiltonian H = ½·50² + 20 Λ33(0) ≈ 1269.975 (R15 energy E)."""
    _, pg, e_prime = constants_of_motion(*CASES["simo_wong_1991"])
    assert abs(e_prime + pg**2 / (2 * 1.0) - 1269.975) < 1e-3
    assert solve_heavy_top(*CASES["simo_wong_1991"])["sleeping_stable"]


@functools.cache
def _equations_of_motion():
    """β̈, α̈, γ̈ from the Euler–Lagrange equations of the R14 Lagrangian (sympy)."""
    t = sp.Symbol("t")
    I1, I3, Mgl = sp.symbols("I1 I3 Mgl", positive=True)
    al, be, ga = (sp.Function(n)(t) for n in ("alpha", "beta", "gamma"))
    lag = (
        I1 / 2 * (al.diff(t) ** 2 * sp.sin(be) ** 2 + be.diff(t) ** 2)
        + I3 / 2 * (al.diff(t) * sp.cos(be) + ga.diff(t)) ** 2
        - Mgl * sp.cos(be)
    )
    coords = (al, be, ga)
    eqs = [sp.diff(lag.diff(q.diff(t)), t) - lag.diff(q) for q in coords]
    acc = sp.symbols("acc0:3")
    vel = sp.symbols("v0:3")
    pos = sp.symbols("q0:3")
    subs = {q.diff(t, 2): a for q, a in zip(coords, acc, strict=True)}
    subs |= {q.diff(t): v for q, v in zip(coords, vel, strict=True)}
    eqs = [e.subs(subs).subs(dict(zip(coords, pos, strict=True))) for e in eqs]
    sol = sp.solve(eqs, acc, dict=True)[0]
    return sp.lambdify((pos, vel, I1, I3, Mgl), [sp.simplify(sol[a]) for a in acc], "numpy")


@pytest.mark.parametrize(
    "name", ["generic_loops", "hanging_loops", "released_from_rest", "generic_waves"]
)
def test_against_the_equations_of_motion(name):
    """Integrate R14 for one period: β returns, α advances by Δα, β's extrema are β1, β2."""
    state = CASES[name]
    I1, I3, Mgl, b0, ad, bd, gd = state
    accel = _equations_of_motion()
    period = float(nutation_period(*state))

    def rhs(_, y):
        return [*y[3:], *accel(y[:3], y[3:], I1, I3, Mgl)]

    sol = solve_ivp(
        rhs,
        (0.0, period),
        [0.0, b0, 0.0, ad, bd, gd],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        dense_output=True,
    )
    assert abs(sol.y[1, -1] - b0) < 1e-8
    assert abs(sol.y[0, -1] - float(mean_precession_rate(*state)) * period) < 1e-8
    t = np.linspace(0.0, period, 2001)
    beta_t = sol.sol(t)[1]
    beta1, beta2 = turning_points(*state)
    assert abs(beta_t.min() - beta1) < 1e-6 and abs(beta_t.max() - beta2) < 1e-6  # sampling
    assert np.max(np.abs(cos_beta(t, *state) - np.cos(beta_t))) < 1e-8


def test_cos_beta_phase_and_direction():
    state = CASES["generic_loops"]  # β̇0 = +1.5: β grows, u = cos β falls
    u0 = cos_beta(0.0, *state)
    assert abs(u0 - np.cos(state[3])) < 1e-14
    flipped = (*state[:5], -state[5], state[6])
    assert cos_beta(1e-5, *state) < u0 < cos_beta(1e-5, *flipped)
    # Constant for steady precession and for a sleeping top.
    t = np.linspace(0.0, 1.0, 5)
    assert np.all(cos_beta(t, *_steady(0.5, 150.0, 0)) == np.cos(0.5))
    assert np.all(cos_beta(t, *TOY, 0.0, 0.0, 0.0, 150.0) == 1.0)


def test_precession_rate_is_stable_near_the_vertical():
    """α̇ at β = 1e-7 with p_α = p_γ: the textbook form loses all digits, R18's rewrite none."""
    I1, pg, beta = 2.0e-4, 0.015, 1e-7
    want = float(mp.mpf(pg) / (I1 * (1 + mp.cos(mp.mpf(beta)))))  # (b − a cos β)/sin²β, b = a
    naive = (pg - pg * np.cos(beta)) / (I1 * np.sin(beta) ** 2)
    assert abs(naive / want - 1) > 1e-3
    assert abs(precession_rate(beta, I1, pg, pg) / want - 1) < 1e-14
    assert precession_rate(0.0, I1, pg, pg) == pytest.approx(pg / (2 * I1), rel=1e-15)


@pytest.mark.parametrize("beta", [0.3, 1.2, 2.9])
def test_effective_potential_and_spin_rate(beta):
    I1, I3, Mgl, pa, pg = 2.0e-4, 1.0e-4, 0.02, 0.009, 0.015
    b = mp.mpf(beta)
    v = (pa - pg * mp.cos(b)) ** 2 / (2 * I1 * mp.sin(b) ** 2) + Mgl * mp.cos(b)
    assert _close(effective_potential(beta, I1, Mgl, pa, pg), v)
    rate = (pa - pg * mp.cos(b)) / (I1 * mp.sin(b) ** 2)
    assert _close(spin_rate(beta, I1, I3, pa, pg), mp.mpf(pg) / I3 - rate * mp.cos(b))
    assert effective_potential(0.0, I1, Mgl, pg, pg) == pytest.approx(Mgl, rel=1e-15)


def test_solve_heavy_top_dict():
    out = solve_heavy_top(*CASES["released_from_rest"])
    assert list(out) == [
        "p_alpha",
        "p_gamma",
        "E_prime",
        "beta1",
        "beta2",
        "alpha_dot_beta1",
        "alpha_dot_beta2",
        "nutation_period",
        "mean_precession_rate",
        "motion",
        "sleeping_stable",
        "omega3_critical",
        "steady_precession_rates",
        "undefined",
    ]
    assert out["undefined"] == {}
    assert all(type(out[k]) is float for k in ("p_alpha", "beta1", "nutation_period"))
    assert out["motion"] == "cusps" and out["sleeping_stable"] is True
    assert out["omega3_critical"] == pytest.approx(40.0, rel=1e-15)
    assert out["alpha_dot_beta1"] == 0.0  # released from rest at β1: exactly zero
    assert isinstance(out["steady_precession_rates"], list)
    sleeping = solve_heavy_top(*TOY, 0.0, 0.0, 0.0, 150.0)
    assert sleeping["beta1"] == sleeping["beta2"] == 0.0
    # the limit: period of an infinitesimal nutation about the vertical, 2π I1/√(p_γ² − 4 I1 Mgl)
    pg = TOY[1] * 150.0
    assert sleeping["nutation_period"] == pytest.approx(
        2 * np.pi * TOY[0] / np.sqrt(pg**2 - 4 * TOY[0] * TOY[2]), rel=1e-13)
    assert sleeping["mean_precession_rate"] is None
    assert set(sleeping["undefined"]) == {"alpha_dot_beta1", "alpha_dot_beta2",
                                          "mean_precession_rate"}
    assert "vertical" in sleeping["undefined"]["mean_precession_rate"]
    state = _steady(0.5, 150.0, 0)
    steady = solve_heavy_top(*state)
    assert steady["motion"] == "steady"
    # the limit: 2π/√(B (u3 − u0)), u3 = (A + a²)/B − 2 u0 for the double root u0 (Vieta, mpmath)
    ref = reference_of(state)
    u3 = (ref["A"] + ref["a"] ** 2) / ref["B"] - 2 * mp.cos(mp.mpf(state[3]))
    assert _close(steady["nutation_period"], 2 * mp.pi / mp.sqrt(ref["B"] * (u3 - mp.cos(
        mp.mpf(state[3])))))
    assert steady["mean_precession_rate"] == pytest.approx(
        steady["steady_precession_rates"][0], rel=1e-12
    )
    unstable = solve_heavy_top(*TOY, 0.0, 0.0, 0.0, 30.0)
    assert unstable["beta1"] == 0.0 and unstable["beta2"] > 0.5
    assert unstable["steady_precession_rates"] is None
    assert unstable["nutation_period"] is None and "asymptotically" in unstable["undefined"][
        "nutation_period"]
    assert "real" in unstable["undefined"]["steady_precession_rates"]


def reference_of(state) -> dict:
    """a, A, B of R17 in mpmath from an arbitrary state."""
    I1, I3, Mgl, b0, ad, bd, gd = (mp.mpf(x) for x in state)
    c, s = mp.cos(b0), mp.sin(b0)
    pg = I3 * (ad * c + gd)
    e_prime = I1 * (bd**2 + ad**2 * s**2) / 2 + Mgl * c
    return {"a": pg / I1, "A": 2 * e_prime / I1, "B": 2 * Mgl / I1}


def test_vectorised_over_states():
    I1 = np.array([[2.0e-4], [3.0e-3]])
    gd = np.array([150.0, 80.0, 5000.0])
    beta1, beta2 = turning_points(I1, 1.0e-4, 0.02, 0.5, 0.3, 0.1, gd)
    assert beta1.shape == beta2.shape == (2, 3)
    for i in range(2):
        for j in range(3):
            one = solve_heavy_top(float(I1[i, 0]), 1.0e-4, 0.02, 0.5, 0.3, 0.1, float(gd[j]))
            assert beta1[i, j] == one["beta1"] and beta2[i, j] == one["beta2"]
    kinds = motion_type(I1, 1.0e-4, 0.02, 0.5, 0.3, 0.1, gd)
    assert kinds.shape == (2, 3)
    period = nutation_period(2.0e-4, 1.0e-4, 0.02, [0.0, 0.5], 0.0, 0.0, 150.0)
    assert np.all(np.isfinite(period))  # sleeping (β0 = 0): the limit of small nutation


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"Mgl": 0.0}, "Mgl"),
        ({"beta0": -0.1}, "beta0"),
        ({"beta0": 3.2}, "beta0"),
        ({"I1": -1.0}, "I1"),
        ({"I3": 5e-4}, "I3"),  # I3 > 2 I1: no rigid body
        ({"gamma_dot0": float("nan")}, "gamma_dot0"),
        ({"alpha_dot0": "fast"}, "alpha_dot0"),
    ],
)
def test_bad_input_names_the_parameter(kwargs, name):
    state = (
        dict(
            zip(
                ("I1", "I3", "Mgl", "beta0", "alpha_dot0", "beta_dot0", "gamma_dot0"),
                CASES["released_from_rest"],
                strict=True,
            )
        )
        | kwargs
    )
    with pytest.raises(ParameterError) as err:
        solve_heavy_top(**state)
    assert err.value.parameter == name
    with pytest.raises(ParameterError):
        turning_points(**state)


def test_nutation_pass_equals_the_single_quantity_functions():
    """`nutation` (one pass over the cubic) agrees with the three one-quantity calls."""
    from solver.heavy_top import mean_precession_rate, nutation, nutation_period, turning_points

    rng = np.random.default_rng(11)
    n = 200
    I1 = rng.uniform(1e-4, 1e-3, n)
    state = (
        I1,
        I1 * rng.uniform(0.2, 1.8, n),
        rng.uniform(0.01, 0.3, n),
        rng.uniform(0.0, 3.0, n),
        rng.normal(0, 3, n),
        rng.normal(0, 1, n) * (rng.random(n) < 0.5),
        rng.uniform(20, 3000, n),
    )
    out = nutation(*state)
    beta1, beta2 = turning_points(*state)
    np.testing.assert_array_equal(out["beta1"], beta1)
    np.testing.assert_array_equal(out["beta2"], beta2)
    np.testing.assert_array_equal(out["nutation_period"], nutation_period(*state))
    np.testing.assert_array_equal(out["mean_precession_rate"], mean_precession_rate(*state))
