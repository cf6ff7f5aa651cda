"""Sympy derivations against the forms stated in docs/physics/; the numeric solver against them.

Two kinds of test:

* derived == stated: every expression of ``solver.symbolic`` is derived (from R11's rotation
  matrix onwards); the reference is the result as ``docs/physics/`` states it, typed here as text
  and parsed with :data:`SYMBOLS`, so a typo in either shows up as a difference. Structural
  identities (R orthogonal, energy conservation along the Euler–Lagrange equations, odd terms of
  the sleeping-top series) back them up.
* numeric == symbolic: the numeric solver (``solver.euler_angles``, ``solver.heavy_top``),
  which implements the stated closed forms in numpy, is evaluated on arrays of random points and
  compared with the derivations evaluated pointwise by mpmath at 40 digits, to 1e-10 relative
  (the accuracy target of ``solver/API.md``). These import the solver modules inside the test, so
  that a missing module fails only its own tests.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp
from sympy.parsing.sympy_parser import parse_expr

from solver import symbolic
from solver.symbolic import SYMBOLS

S = SYMBOLS
RTOL = 1e-10  # solver/API.md accuracy target
N_POINTS = 16


def stated(text: str) -> sp.Expr:
    """A formula as typed from docs/physics/, in the module's symbols."""
    return parse_expr(text, local_dict=dict(SYMBOLS))


def assert_equivalent(derived: sp.Expr, reference: sp.Expr) -> None:
    """Symbolic identity: the difference simplifies to exactly 0 (expressions here are small)."""
    difference = sp.simplify(sp.expand(derived - reference))
    assert difference == 0, f"derived {derived}\n   stated {reference}\n   differ by {difference}"


def mp_reference(expr: sp.Expr, names: list[str], columns: list[np.ndarray],
                 *, complex_to_nan: bool = False) -> np.ndarray:
    """Evaluate ``expr`` at each point (one value per column entry) in mpmath at 40 digits.

    A non-real value raises, unless ``complex_to_nan`` (then it becomes NaN, as in the solver).
    """
    f = sp.lambdify([S[n] for n in names], expr, modules="mpmath")
    with mpmath.workdps(40):
        values = [f(*(mpmath.mpf(float(c)) for c in point)) for point in zip(*columns, strict=True)]
        if complex_to_nan:
            values = [np.nan if mpmath.im(v) != 0 else mpmath.re(v) for v in values]
        return np.array([float(v) for v in values])


def assert_matches(numeric: np.ndarray, reference: np.ndarray) -> None:
    # atol guards components that happen to be near 0 at a random point (ω1 = ω2 = 0 etc.).
    scale = np.max(np.abs(reference))
    np.testing.assert_allclose(numeric, reference, rtol=RTOL, atol=RTOL * scale)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240611)


@pytest.fixture
def euler_state(rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Random Euler angles, rates and principal moments (moments obey the triangle inequality)."""
    u = lambda lo, hi: rng.uniform(lo, hi, N_POINTS)  # noqa: E731
    return {
        "alpha": u(-np.pi, np.pi), "beta": u(0.05, np.pi - 0.05), "gamma": u(-np.pi, np.pi),
        "alpha_dot": u(-5, 5), "beta_dot": u(-5, 5), "gamma_dot": u(-20, 20),
        "I1": u(1, 2), "I2": u(1, 2), "I3": u(1, 2),
    }


@pytest.fixture
def top_state(rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Random heavy-top states: I1 about the tip, I3 <= 2 I1, β0 away from 0 and π."""
    u = lambda lo, hi: rng.uniform(lo, hi, N_POINTS)  # noqa: E731
    return {
        "I1": u(1, 2), "I3": u(0.5, 1.5), "Mgl": u(0.5, 3), "beta": u(0.1, np.pi - 0.1),
        "alpha_dot": u(-3, 3), "beta_dot": u(-3, 3), "gamma_dot": u(-30, 30),
    }


# --- derived == stated (docs/physics/) ---------------------------------------------------------

R12_OMEGA = (
    "-alpha_dot*sin(beta)*cos(gamma) + beta_dot*sin(gamma)",
    "alpha_dot*sin(beta)*sin(gamma) + beta_dot*cos(gamma)",
    "alpha_dot*cos(beta) + gamma_dot",
)


def test_rotation_matrix_is_proper_orthogonal_R11():
    R = sp.Matrix(symbolic.rotation_matrix_expr())
    assert (R * R.T).applyfunc(sp.trigsimp) == sp.eye(3)
    assert sp.trigsimp(R.det()) == 1


@pytest.mark.parametrize("component", [0, 1, 2])
def test_omega_body_is_R12(component: int):
    assert_equivalent(symbolic.omega_body_expr()[component], stated(R12_OMEGA[component]))


def test_omega_body_is_sum_of_rotation_axes_R12():
    """Second route to R12: ω = α̇ ẑ + β̇ ê'2 + γ̇ ê3, each axis's body components read off R11
    (``ẑ`` is R applied to (0, 0, 1), ``ê'2`` is R_γ applied to (0, 1, 0))."""
    R = sp.Matrix(symbolic.rotation_matrix_expr())
    c, s = sp.cos(S["gamma"]), sp.sin(S["gamma"])
    R_gamma = sp.Matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])  # typed from R11
    omega = (S["alpha_dot"] * R[:, 2] + S["beta_dot"] * R_gamma[:, 1]
             + S["gamma_dot"] * sp.Matrix([0, 0, 1]))
    for derived, reference in zip(symbolic.omega_body_expr(), omega, strict=True):
        assert_equivalent(derived, reference)


def test_kinetic_energy_is_R13():
    reference = " + ".join(
        f"I{i}*({w})**2/2" for i, w in zip((1, 2, 3), R12_OMEGA, strict=True))
    assert_equivalent(symbolic.kinetic_energy_euler_expr(), stated(reference))


def test_kinetic_energy_symmetric_top_is_R13():
    T = symbolic.kinetic_energy_euler_expr().subs(S["I2"], S["I1"])
    reference = ("I1*(alpha_dot**2*sin(beta)**2 + beta_dot**2)/2"
                 " + I3*(alpha_dot*cos(beta) + gamma_dot)**2/2")
    assert_equivalent(T, stated(reference))


def test_lagrangian_is_R14():
    reference = ("I1*(alpha_dot**2*sin(beta)**2 + beta_dot**2)/2"
                 " + I3*(alpha_dot*cos(beta) + gamma_dot)**2/2 - Mgl*cos(beta)")
    assert_equivalent(symbolic.heavy_top_lagrangian(), stated(reference))


def test_momenta_are_R15():
    p = symbolic.conjugate_momenta()
    assert set(p) == {"p_alpha", "p_gamma"}
    p_gamma = stated("I3*(alpha_dot*cos(beta) + gamma_dot)")
    assert_equivalent(p["p_gamma"], p_gamma)
    # R15 states p_α in terms of p_γ: p_α = I1 α̇ sin²β + p_γ cos β.
    p_alpha = stated("I1*alpha_dot*sin(beta)**2 + p_gamma*cos(beta)").subs(S["p_gamma"], p_gamma)
    assert_equivalent(p["p_alpha"], p_alpha)


def in_velocities(expr: sp.Expr) -> sp.Expr:
    """Replace p_α, p_γ by their R15 velocity forms (typed from docs/physics/)."""
    p_gamma = stated("I3*(alpha_dot*cos(beta) + gamma_dot)")
    p_alpha = stated("I1*alpha_dot*sin(beta)**2 + p_gamma*cos(beta)").subs(S["p_gamma"], p_gamma)
    return expr.subs({S["p_alpha"]: p_alpha, S["p_gamma"]: p_gamma})


def test_energy_is_R15():
    reference = stated("I1*beta_dot**2/2 + p_gamma**2/(2*I3)"
                       " + (p_alpha - p_gamma*cos(beta))**2/(2*I1*sin(beta)**2) + Mgl*cos(beta)")
    assert_equivalent(symbolic.energy_expr(), in_velocities(reference))


def test_energy_is_conserved_along_euler_lagrange_motion():
    """Noether / Jacobi: dE/dt = Σ q̇ (d/dt ∂L/∂q̇ − ∂L/∂q) for any path, so E is conserved on
    solutions of the Euler–Lagrange equations of R14."""
    t = sp.Symbol("t", real=True)
    names = ("alpha", "beta", "gamma")
    q = {n: sp.Function(n, real=True)(t) for n in names}
    on_path = {S[n + "_dot"]: q[n].diff(t) for n in names} | {S[n]: q[n] for n in names}
    L = symbolic.heavy_top_lagrangian().subs(on_path)
    E = symbolic.energy_expr().subs(on_path)
    euler_lagrange = sum(
        q[n].diff(t) * (L.diff(q[n].diff(t)).diff(t) - L.diff(q[n])) for n in names)
    assert sp.simplify(sp.expand(E.diff(t) - euler_lagrange)) == 0


def test_alpha_and_gamma_are_cyclic_R15():
    L = symbolic.heavy_top_lagrangian()
    assert not L.has(S["alpha"]) and not L.has(S["gamma"])


def test_effective_potential_is_R16():
    reference = "(p_alpha - p_gamma*cos(beta))**2/(2*I1*sin(beta)**2) + Mgl*cos(beta)"
    assert_equivalent(symbolic.effective_potential_expr(), stated(reference))


def test_reduced_energy_is_beta_kinetic_plus_effective_potential_R16():
    """E' = E − p_γ²/(2 I3) = ½ I1 β̇² + V_eff(β), everything in velocities."""
    p_gamma = symbolic.conjugate_momenta()["p_gamma"]
    E_prime = symbolic.energy_expr() - p_gamma**2 / (2 * S["I3"])
    rest = E_prime - in_velocities(symbolic.effective_potential_expr())
    assert_equivalent(rest, stated("I1*beta_dot**2/2"))


def test_cubic_is_R17():
    f = symbolic.cubic_f_expr()
    assert_equivalent(f, stated("(1 - u**2)*(A - B*u) - (b - a*u)**2"))
    poly = sp.Poly(f, S["u"])
    assert poly.degree() == 3 and poly.LC() == S["B"]  # f = B (u − u1)(u − u2)(u − u3)


def test_cubic_is_udot_squared_at_random_states(top_state: dict[str, np.ndarray]):
    """u̇² = sin²β β̇² computed directly from a state, against f(cos β) from its constants."""
    I1, I3, Mgl, beta, ad, bd, gd = (top_state[k] for k in
                                     ("I1", "I3", "Mgl", "beta", "alpha_dot", "beta_dot",
                                      "gamma_dot"))
    p_gamma = I3 * (ad * np.cos(beta) + gd)  # R15
    p_alpha = I1 * ad * np.sin(beta) ** 2 + p_gamma * np.cos(beta)
    E_prime = 0.5 * I1 * (ad**2 * np.sin(beta) ** 2 + bd**2) + Mgl * np.cos(beta)
    f = mp_reference(symbolic.cubic_f_expr(), ["u", "a", "b", "A", "B"],
                     [np.cos(beta), p_gamma / I1, p_alpha / I1, 2 * E_prime / I1, 2 * Mgl / I1])
    np.testing.assert_allclose(f, (np.sin(beta) * bd) ** 2, rtol=1e-9, atol=1e-9)


def test_sleeping_top_expansion_is_R19():
    c0, c2 = symbolic.sleeping_top_expansion()
    assert_equivalent(c0, stated("Mgl"))
    assert_equivalent(c2, stated("p_gamma**2/(8*I1) - Mgl/2"))


def test_sleeping_top_criterion_R19():
    """c2 >= 0 ⇔ p_γ² >= 4 Mgl I1: c2 is increasing in p_γ² and vanishes exactly there."""
    _, c2 = symbolic.sleeping_top_expansion()
    p2 = sp.Symbol("p2", positive=True)
    c2_of_p2 = c2.subs(S["p_gamma"] ** 2, p2)
    assert sp.solve(c2_of_p2, p2) == [4 * S["Mgl"] * S["I1"]]
    assert sp.diff(c2_of_p2, p2).is_positive


@pytest.mark.parametrize("beta", ["1e-3", "1e-4", "1e-5"])
def test_sleeping_top_expansion_remainder_is_fourth_order(beta: str):
    """V_eff(β) − c0 − c2 β² = O(β⁴), checked in mpmath at 40 digits (I1 = 1.3, Mgl = 0.7,
    p_α = p_γ = 2.1): the scaled remainder stays bounded as β shrinks."""
    values = {S["I1"]: sp.Float("1.3", 40), S["Mgl"]: sp.Float("0.7", 40),
              S["p_alpha"]: sp.Float("2.1", 40), S["p_gamma"]: sp.Float("2.1", 40),
              S["beta"]: sp.Float(beta, 40)}
    c0, c2 = symbolic.sleeping_top_expansion()
    V = symbolic.effective_potential_expr()
    remainder = (V - c0 - c2 * S["beta"] ** 2).subs(values).evalf(40)
    assert abs(remainder / values[S["beta"]] ** 4) < 1.0


def test_steady_precession_condition_is_R21():
    q = symbolic.steady_precession_condition()
    assert_equivalent(q, stated("I1*cos(beta)*alpha_dot**2 - p_gamma*alpha_dot + Mgl"))
    assert sp.Poly(q, S["alpha_dot"]).degree() == 2


# --- the module's own contract ----------------------------------------------------------------

EXPECTED_SYMBOLS = {
    "omega_body_expr": "beta gamma alpha_dot beta_dot gamma_dot",
    "kinetic_energy_euler_expr": "I1 I2 I3 beta gamma alpha_dot beta_dot gamma_dot",
    "heavy_top_lagrangian": "I1 I3 Mgl beta alpha_dot beta_dot gamma_dot",
    "energy_expr": "I1 I3 Mgl beta alpha_dot beta_dot gamma_dot",
    "effective_potential_expr": "I1 Mgl beta p_alpha p_gamma",
    "cubic_f_expr": "u a b A B",
    "sleeping_top_expansion": "I1 Mgl p_gamma",
    "steady_precession_condition": "I1 Mgl beta p_gamma alpha_dot",
}


@pytest.mark.parametrize("name", sorted(EXPECTED_SYMBOLS))
def test_expressions_use_exactly_the_named_symbols(name: str):
    """Every free symbol is one of SYMBOLS (same assumptions, hence same identity)."""
    result = getattr(symbolic, name)()
    exprs = result if isinstance(result, tuple) else (result,)
    free = set().union(*(sp.sympify(e).free_symbols for e in exprs))
    assert free == {S[n] for n in EXPECTED_SYMBOLS[name].split()}


def test_results_are_cached():
    assert symbolic.effective_potential_expr() is symbolic.effective_potential_expr()
    # conjugate_momenta hands out a fresh dict: mutating it must not corrupt the cache.
    symbolic.conjugate_momenta()["p_alpha"] = sp.Integer(0)
    assert symbolic.conjugate_momenta()["p_alpha"] != 0


def test_symbols_are_read_only():
    with pytest.raises(TypeError):
        SYMBOLS["I1"] = sp.Symbol("I1")  # type: ignore[index]


# --- numeric solver == symbolic derivation ------------------------------------------------------

def test_rotation_matrix_numeric(euler_state: dict[str, np.ndarray]):
    from solver.euler_angles import rotation_matrix

    names = ["alpha", "beta", "gamma"]
    R = rotation_matrix(*(euler_state[n] for n in names))
    assert R.shape == (N_POINTS, 3, 3)
    R_sym = symbolic.rotation_matrix_expr()
    for i in range(3):
        for j in range(3):
            ref = mp_reference(R_sym[i, j], names, [euler_state[n] for n in names])
            np.testing.assert_allclose(R[:, i, j], ref, rtol=RTOL, atol=RTOL)


def test_omega_body_numeric(euler_state: dict[str, np.ndarray]):
    from solver.euler_angles import omega_body

    names = ["beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot"]
    omega = omega_body(*(euler_state[n] for n in names))
    assert omega.shape == (N_POINTS, 3)
    for k, expr in enumerate(symbolic.omega_body_expr()):
        assert_matches(omega[:, k], mp_reference(expr, names, [euler_state[n] for n in names]))


def test_kinetic_energy_euler_numeric(euler_state: dict[str, np.ndarray]):
    from solver.euler_angles import kinetic_energy_euler

    names = ["I1", "I2", "I3", "beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot"]
    T = kinetic_energy_euler(*(euler_state[n] for n in names))
    ref = mp_reference(symbolic.kinetic_energy_euler_expr(), names,
                       [euler_state[n] for n in names])
    assert_matches(T, ref)


def test_constants_of_motion_numeric(top_state: dict[str, np.ndarray]):
    from solver.heavy_top import constants_of_motion

    names = ["I1", "I3", "Mgl", "beta", "alpha_dot", "beta_dot", "gamma_dot"]
    columns = [top_state[n] for n in names]
    p_alpha, p_gamma, E_prime = constants_of_motion(*columns)
    p = symbolic.conjugate_momenta()
    E_prime_sym = symbolic.energy_expr() - p["p_gamma"] ** 2 / (2 * S["I3"])  # R16
    assert_matches(p_alpha, mp_reference(p["p_alpha"], names, columns))
    assert_matches(p_gamma, mp_reference(p["p_gamma"], names, columns))
    assert_matches(E_prime, mp_reference(E_prime_sym, names, columns))


def test_effective_potential_numeric(top_state: dict[str, np.ndarray],
                                     rng: np.random.Generator):
    from solver.heavy_top import effective_potential

    top_state = top_state | {"p_alpha": rng.uniform(-5, 5, N_POINTS),
                             "p_gamma": rng.uniform(-5, 5, N_POINTS)}
    names = ["beta", "I1", "Mgl", "p_alpha", "p_gamma"]
    columns = [top_state[n] for n in names]
    V = effective_potential(*columns)
    assert_matches(V, mp_reference(symbolic.effective_potential_expr(), names, columns))


def positive_root_of_c2() -> sp.Expr:
    """p_γ at which the β² coefficient of R19 vanishes (the positive root)."""
    _, c2 = symbolic.sleeping_top_expansion()
    roots = [r for r in sp.solve(c2, S["p_gamma"]) if r.is_positive]
    assert len(roots) == 1
    return roots[0]


def test_critical_spin_numeric(top_state: dict[str, np.ndarray]):
    from solver.heavy_top import critical_spin

    names = ["I1", "I3", "Mgl"]
    columns = [top_state[n] for n in names]
    omega3 = positive_root_of_c2() / S["I3"]  # p_γ = I3 ω3 (R15)
    assert_matches(critical_spin(*columns), mp_reference(omega3, names, columns))


@pytest.mark.parametrize("factor", [0.5, 0.999, 1.001, 3.0])
def test_sleeping_top_stable_numeric(top_state: dict[str, np.ndarray], factor: float):
    """Stable iff the β² coefficient c2 of R19 is >= 0 at p_γ = I3 ω3."""
    from solver.heavy_top import sleeping_top_stable

    names = ["I1", "I3", "Mgl"]
    columns = [top_state[n] for n in names]
    omega3 = factor * mp_reference(positive_root_of_c2() / S["I3"], names, columns)
    _, c2 = symbolic.sleeping_top_expansion()
    c2_values = mp_reference(c2, ["I1", "Mgl", "p_gamma"],
                             [top_state["I1"], top_state["Mgl"], top_state["I3"] * omega3])
    stable = sleeping_top_stable(*columns, omega3)
    np.testing.assert_array_equal(stable, c2_values >= 0)


@pytest.mark.parametrize("regime", ["upper", "lower"])
def test_steady_precession_rates_numeric(top_state: dict[str, np.ndarray],
                                         rng: np.random.Generator, regime: str):
    """Both rates are the roots of the derived R21 quadratic; NaN exactly where they are complex.

    Upper hemisphere (cos β0 > 0, p_γ > 0): real roots both positive, slow < fast, or complex.
    Lower hemisphere (cos β0 < 0): always real, compared as an unordered pair.
    """
    from solver.heavy_top import steady_precession_rates

    beta0 = rng.uniform(0.1, 1.4, N_POINTS)
    if regime == "lower":
        beta0 = np.pi - beta0
    # p_γ spread around the threshold √(4 I1 Mgl cos β0) so both real and complex cases occur.
    threshold = np.sqrt(4 * top_state["I1"] * top_state["Mgl"] * np.abs(np.cos(beta0)))
    columns = {"I1": top_state["I1"], "Mgl": top_state["Mgl"], "beta": beta0,
               "p_gamma": threshold * rng.uniform(0.5, 3.0, N_POINTS)}
    q = symbolic.steady_precession_condition()
    discriminant = sp.discriminant(q, S["alpha_dot"])
    real = mp_reference(discriminant, list(columns), list(columns.values())) >= 0
    roots = sp.solve(q, S["alpha_dot"])
    assert len(roots) == 2
    ref = np.sort([mp_reference(r, list(columns), list(columns.values()), complex_to_nan=True)
                   for r in roots], axis=0)

    slow, fast = steady_precession_rates(top_state["I1"], top_state["I3"], top_state["Mgl"],
                                         beta0, columns["p_gamma"])
    if regime == "upper":
        assert 0 < real.sum() < N_POINTS  # the draw covers both cases
        np.testing.assert_array_equal(np.isnan(slow), ~real)
        np.testing.assert_array_equal(np.isnan(fast), ~real)
        assert_matches(slow[real], ref[0][real])
        assert_matches(fast[real], ref[1][real])
    else:
        assert real.all()
        assert_matches(np.sort([slow, fast], axis=0), ref)


def test_omega_body_is_the_expression_trigsimp_gives():
    """The cheap sin² + cos² = 1 reduction gives structurally the expression sympy's trigsimp
    gives (the generated statements and keys print it, so it must not change shape)."""
    t = sp.Symbol("t", real=True)
    angles = [sp.Function(n, real=True)(t) for n in ("alpha", "beta", "gamma")]
    R = symbolic._euler_matrix(*angles)
    skew = -(R.diff(t) * R.T)
    rates = {a.diff(t): symbolic.SYMBOLS[f"{n}_dot"]
             for a, n in zip(angles, ("alpha", "beta", "gamma"), strict=True)}
    plain = {a: symbolic.SYMBOLS[n] for a, n in zip(angles, ("alpha", "beta", "gamma"),
                                                     strict=True)}
    for c, derived in zip((skew[2, 1], skew[0, 2], skew[1, 0]), symbolic.omega_body_expr(),
                          strict=True):
        by_trigsimp = sp.factor_terms(sp.trigsimp(sp.expand(c.subs(rates).subs(plain))))
        assert sp.srepr(derived) == sp.srepr(by_trigsimp)
