"""The lecture's derivations redone in sympy: R11 → R12 → R13 → R14 → R15 → R16 → R17, R19, R21.

Every expression here is *derived*, not typed in: the body angular velocity comes from the
rotation matrix of R11 (``[ω]× = −Ṙ Rᵀ``), the kinetic energy from those components, the
heavy-top Lagrangian from that energy with ``I1 = I2``, the momenta and the energy from the
Lagrangian, and so on down to the cubic ``f(u)`` and the steady-precession quadratic. The
numeric solver implements the closed forms stated on ``docs/physics/index.md``; these
derivations are the independent reference its tests are checked against, and problem templates
use them (through :data:`SYMBOLS`) for expression answers.

All functions are pure and cached: they take no arguments and return sympy expressions (immutable)
in the symbols of :data:`SYMBOLS`. The first call of the chain costs about a second of sympy.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from types import MappingProxyType

import sympy as sp

__all__ = [
    "SYMBOLS",
    "conjugate_momenta",
    "cubic_f_expr",
    "effective_potential_expr",
    "energy_expr",
    "heavy_top_lagrangian",
    "kinetic_energy_euler_expr",
    "omega_body_expr",
    "rotation_matrix_expr",
    "sleeping_top_expansion",
    "steady_precession_condition",
]

# Assumptions: moments of inertia, M, g, l, M g l and B = 2Mgl/I1 are positive (sympy can then
# take square roots and cancel signs); angles, rates, momenta and energies are merely real
# (rates and momenta take either sign, and E' may be negative for a top below the horizontal).
_POSITIVE = ("I1", "I2", "I3", "Mgl", "M", "g", "l", "B")
_REAL = (
    "alpha", "beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot",
    "p_alpha", "p_gamma", "E_prime", "omega1", "omega2", "omega3", "u", "a", "b", "A",
)

SYMBOLS: Mapping[str, sp.Symbol] = MappingProxyType(
    {name: sp.Symbol(name, positive=True) for name in _POSITIVE}
    | {name: sp.Symbol(name, real=True) for name in _REAL}
)
"""The named symbols of every expression in this module, read-only.

Names (``docs/physics/`` notation): ``I1 I2 I3`` principal moments (``I1`` about the tip for the
heavy top), ``Mgl M g l``, Euler angles ``alpha beta gamma`` and their rates ``alpha_dot beta_dot
gamma_dot`` (R11, R12), momenta ``p_alpha p_gamma`` and ``E_prime`` (R15, R16), body angular
velocity ``omega1 omega2 omega3``, and R17's ``u = cos β``, ``a = p_γ/I1``, ``b = p_α/I1``,
``A = 2E'/I1``, ``B = 2Mgl/I1``.

``I1 I2 I3 Mgl M g l B`` are declared positive, all others real. Because a sympy symbol's
identity includes its assumptions, parse expressions with these very symbols:
``sympy.parse_expr(text, local_dict=dict(SYMBOLS))`` (``parse_expr`` wants a real ``dict``;
without it ``gamma`` and ``beta`` would also parse as sympy's special functions).
"""

_S = SYMBOLS  # short alias inside the derivations
_HALF = sp.Rational(1, 2)
_VELOCITIES = ("alpha_dot", "beta_dot", "gamma_dot")


def _rot_z(angle: sp.Expr) -> sp.Matrix:
    """Passive rotation by ``angle`` about z: the ``R_α`` / ``R_γ`` of R11."""
    c, s = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def _rot_y(angle: sp.Expr) -> sp.Matrix:
    """Passive rotation by ``angle`` about y: the ``R_β`` of R11."""
    c, s = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[c, 0, -s], [0, 1, 0], [s, 0, c]])


def _euler_matrix(alpha: sp.Expr, beta: sp.Expr, gamma: sp.Expr) -> sp.Matrix:
    return _rot_z(gamma) * _rot_y(beta) * _rot_z(alpha)


def _tidy(expr: sp.Expr) -> sp.Expr:
    """Simplify term by term in the moments (cheap, unlike ``simplify`` on the whole sum)."""
    moments = [_S["I1"], _S["I2"], _S["I3"]]
    parts = sp.collect(sp.expand(expr), moments, evaluate=False)
    return sp.Add(*(k * sp.factor(sp.trigsimp(v)) for k, v in parts.items()))


@cache
def rotation_matrix_expr() -> sp.ImmutableMatrix:
    """The rotation matrix ``R = R_γ R_β R_α`` of R11 (3×3), with ``V' = R V``.

    Rows are the body axes ``ê1, ê2, ê3`` in inertial components; angles in radians.
    """
    return sp.ImmutableMatrix(_euler_matrix(_S["alpha"], _S["beta"], _S["gamma"]))


@cache
def omega_body_expr() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """Body-frame angular velocity ``(ω1, ω2, ω3)`` from the Euler-angle rates (R12), in rad/s.

    Derived from R11: with the angles functions of time, an inertially fixed vector has body
    components ``V' = R V`` that change as ``dV'/dt = Ṙ Rᵀ V'``, while R6 says they change as
    ``−ω × V'``; so the skew matrix ``[ω]× = −Ṙ Rᵀ`` and ``ω1 = [ω]×[2,1]``,
    ``ω2 = [ω]×[0,2]``, ``ω3 = [ω]×[1,0]``.

    Returns
    -------
    tuple of 3 sympy.Expr
        In ``beta gamma alpha_dot beta_dot gamma_dot`` (independent of ``alpha``).
    """
    t = sp.Symbol("t", real=True)
    names = ("alpha", "beta", "gamma")
    angles = {name: sp.Function(name, real=True)(t) for name in names}
    R = _euler_matrix(*angles.values())
    skew = -(R.diff(t) * R.T)
    rates = {angles[n].diff(t): _S[n + "_dot"] for n in names}
    plain = {angles[n]: _S[n] for n in names}
    # Rates before angles: substituting the angles first would turn the derivatives into 0.
    comps = (skew[2, 1], skew[0, 2], skew[1, 0])
    comps = (c.subs(rates).subs(plain) for c in comps)
    # The expanded components are polynomials in sines and cosines whose only simplification
    # is sin² + cos² = 1: applying it directly gives what trigsimp gives (the same expression,
    # tests/solver/test_symbolic.py), in a fifth of the time (trigsimp took 1.8 s, most of
    # 'eulertop generate's start-up).
    x = sp.Wild("x")
    return tuple(sp.factor_terms(sp.expand(sp.expand(c).replace(sp.sin(x)**2,
                                                                1 - sp.cos(x)**2)))
                 for c in comps)


@cache
def kinetic_energy_euler_expr() -> sp.Expr:
    """Rotational kinetic energy ``T = ½ Σ I_i ω_i²`` (R3) with R12's components: R13, in J.

    Symbols ``I1 I2 I3 beta gamma alpha_dot beta_dot gamma_dot``.
    """
    moments = (_S["I1"], _S["I2"], _S["I3"])
    return sp.Add(*(_HALF * m * w**2 for m, w in zip(moments, omega_body_expr(), strict=True)))


@cache
def heavy_top_lagrangian() -> sp.Expr:
    """Heavy symmetric top Lagrangian ``L = T − V`` (R14), in J.

    ``T`` is R13 with ``I1 = I2`` (``I1`` about the fixed tip), ``V = M g l cos β`` with ``β``
    from the upward vertical. Symbols ``I1 I3 Mgl beta alpha_dot beta_dot gamma_dot``.
    """
    T = kinetic_energy_euler_expr().subs(_S["I2"], _S["I1"])
    return _tidy(T) - _S["Mgl"] * sp.cos(_S["beta"])


def conjugate_momenta() -> dict[str, sp.Expr]:
    """Momenta conjugate to the cyclic angles, ``∂L/∂α̇`` and ``∂L/∂γ̇`` (R15), in J s.

    Returns
    -------
    dict
        ``{"p_alpha": ..., "p_gamma": ...}`` in the velocities (not in each other; R15's
        ``p_α = I1 α̇ sin²β + p_γ cos β`` follows by substitution). A fresh dict per call;
        the expressions themselves are immutable.
    """
    p_alpha, p_gamma = _momenta()
    return {"p_alpha": p_alpha, "p_gamma": p_gamma}


@cache
def _momenta() -> tuple[sp.Expr, sp.Expr]:
    L = heavy_top_lagrangian()
    return tuple(sp.factor_terms(sp.expand(sp.diff(L, _S[v]))) for v in ("alpha_dot", "gamma_dot"))


@cache
def energy_expr() -> sp.Expr:
    """Energy by Legendre transform, ``E = Σ q̇ ∂L/∂q̇ − L`` over ``α̇ β̇ γ̇`` (R15), in J.

    Expressed in the velocities (``I1 I3 Mgl beta alpha_dot beta_dot gamma_dot``); it equals
    ``T + M g l cos β`` because ``L`` is quadratic in the velocities. R15's form in
    ``p_α, p_γ, β̇`` follows by substituting :func:`conjugate_momenta`.
    """
    L = heavy_top_lagrangian()
    h = sp.Add(*(_S[v] * sp.diff(L, _S[v]) for v in _VELOCITIES)) - L
    return _tidy(h)


@cache
def _rates_from_momenta() -> dict[sp.Symbol, sp.Expr]:
    """``α̇, γ̇`` in terms of ``p_α, p_γ, β`` (inverting the linear map of R15)."""
    p = conjugate_momenta()
    eqs = [sp.Eq(_S["p_alpha"], p["p_alpha"]), sp.Eq(_S["p_gamma"], p["p_gamma"])]
    (solution,) = sp.solve(eqs, [_S["alpha_dot"], _S["gamma_dot"]], dict=True)
    return solution


@cache
def effective_potential_expr() -> sp.Expr:
    """Effective potential ``V_eff(β)`` of the heavy top (R16), in J.

    Derived as ``E' = E − p_γ²/(2 I3)`` with ``α̇, γ̇`` eliminated in favour of ``p_α, p_γ``
    (:func:`energy_expr`, :func:`conjugate_momenta`); what remains besides ``½ I1 β̇²`` is
    ``V_eff``. Symbols ``I1 Mgl beta p_alpha p_gamma``; singular at ``sin β = 0`` unless
    ``p_α = ±p_γ`` (see :func:`sleeping_top_expansion`).

    Examples
    --------
    >>> import sympy
    >>> effective_potential_expr()
    Mgl*cos(beta) + (-p_alpha + p_gamma*cos(beta))**2/(2*I1*sin(beta)**2)

    An answer typed as text is compared in the same symbols:

    >>> text = "(p_alpha - p_gamma*cos(beta))**2/(2*I1*sin(beta)**2) + Mgl*cos(beta)"
    >>> answer = sympy.parse_expr(text, local_dict=dict(SYMBOLS))
    >>> sympy.simplify(answer - effective_potential_expr())
    0
    """
    E = energy_expr().subs(_rates_from_momenta())
    E_prime = E - _S["p_gamma"] ** 2 / (2 * _S["I3"])
    V = sp.expand(E_prime.subs(_S["beta_dot"], 0))
    # Only the terms with 1/sin²β need combining (a perfect square); the potential stays apart.
    kinetic, potential = V.as_independent(_S["p_alpha"], _S["p_gamma"], as_Add=True)[::-1]
    return sp.factor(sp.together(kinetic)) + potential


@cache
def cubic_f_expr() -> sp.Expr:
    """R17: ``u̇² = f(u)`` with ``u = cos β``, a cubic polynomial in ``u``.

    From R16, ``u̇² = sin²β β̇² = (2/I1) sin²β (E' − V_eff)``; with ``a = p_γ/I1``,
    ``b = p_α/I1``, ``A = 2E'/I1``, ``B = 2Mgl/I1`` this becomes
    ``(1 − u²)(A − B u) − (b − a u)²``. Returned expanded in powers of ``u`` (symbols
    ``u a b A B``); the leading coefficient is ``B``.
    """
    I1, beta, u = _S["I1"], _S["beta"], _S["u"]
    udot2 = 2 * sp.sin(beta) ** 2 * (_S["E_prime"] - effective_potential_expr()) / I1
    scaled = {
        _S["p_gamma"]: I1 * _S["a"],
        _S["p_alpha"]: I1 * _S["b"],
        _S["E_prime"]: I1 * _S["A"] / 2,
        _S["Mgl"]: I1 * _S["B"] / 2,
    }
    # sin β only appears squared, so sin → √(1 − u²) is exact for every β.
    in_u = udot2.subs(scaled).subs(sp.sin(beta), sp.sqrt(1 - u**2)).subs(sp.cos(beta), u)
    f = sp.expand(sp.cancel(in_u))
    if f.has(beta) or not f.is_polynomial(u):  # would mean V_eff was not a function of cos β
        raise ArithmeticError(f"R17 derivation did not reduce to a polynomial in u: {f}")
    return sp.collect(f, u)


@cache
def sleeping_top_expansion() -> tuple[sp.Expr, sp.Expr]:
    """R19: ``V_eff`` at ``p_α = p_γ`` expanded about ``β = 0`` to ``O(β⁴)``.

    ``V_eff ≈ c0 + c2 β²`` (odd powers vanish): ``c0 = M g l`` and
    ``c2 = p_γ²/(8 I1) − M g l/2``. The vertical (sleeping) top is stable iff ``c2 ≥ 0``,
    i.e. ``p_γ² ≥ 4 M g l I1``.

    Returns
    -------
    (c0, c2) : tuple of sympy.Expr
        The ``β⁰`` and ``β²`` coefficients, in J and J/rad² (symbols ``I1 Mgl p_gamma``).
    """
    beta = _S["beta"]
    V = effective_potential_expr().subs(_S["p_alpha"], _S["p_gamma"])
    series = sp.expand(sp.series(V, beta, 0, 4).removeO())
    return series.coeff(beta, 0), series.coeff(beta, 2)


@cache
def steady_precession_condition() -> sp.Expr:
    """R21: steady precession ``∂V_eff/∂β = 0`` as a quadratic ``q(α̇) = 0``.

    ``p_α`` is eliminated in favour of the precession rate through R15
    (``p_α = I1 α̇ sin²β + p_γ cos β`` from :func:`conjugate_momenta`), and the overall factor
    ``−sin β`` of ``∂V_eff/∂β`` (whose zero is the vertical top of R19) divided out, leaving
    ``q = I1 cos β α̇² − p_γ α̇ + M g l``, a polynomial in ``alpha_dot`` with coefficients in
    ``I1 Mgl beta p_gamma``.

    Examples
    --------
    >>> steady_precession_condition()
    I1*alpha_dot**2*cos(beta) + Mgl - alpha_dot*p_gamma
    """
    beta, alpha_dot = _S["beta"], _S["alpha_dot"]
    p = conjugate_momenta()
    (gamma_dot,) = sp.solve(sp.Eq(_S["p_gamma"], p["p_gamma"]), _S["gamma_dot"])
    p_alpha = sp.expand(p["p_alpha"].subs(_S["gamma_dot"], gamma_dot))
    dV = sp.diff(effective_potential_expr(), beta).subs(_S["p_alpha"], p_alpha)
    q = sp.cancel(dV / -sp.sin(beta))
    return sp.collect(sp.expand(sp.trigsimp(q)), alpha_dot)
