"""Follow-through chains of the built-in families (issue 26): each answer whose statement asks
to compute it from earlier answers declares them (``depends_on``), and the family's ``follow``
recomputes it from a student's own earlier values.

Checked here, over many seeds, against references written out from the statements' own
definitions (numpy, sympy, the R-ids) — not the families' code paths:

- from the key's own earlier values, ``follow`` gives the key back within its tolerance (a
  student whose earlier answers are right is judged as by the key);
- from perturbed earlier values, it gives what the statement's definition gives for them;
- and that differs from the key (a numeric answer), so follow-through credit is a real change;
- each family declares the earlier values that leave nothing to work out for the later answer
  (``degenerate``, issue 30), and calls neither the key's own values nor a plausible wrong
  one so.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import numpy as np
import pytest
import sympy

from problems.answers import Answer, grade
from problems.templates import FAMILIES

CHAINS = {  # (family, answer): the earlier answers its statement asks to use
    ("sleeping_top", "stable"): ("omega3_c",),
    ("symmetric_free_top", "T_body"): ("Omega",),
    ("heavy_top_constants", "E_prime"): ("p_gamma",),
    ("inertia_tensor", "moments"): ("I_diag", "I_offdiag"),
    ("inertia_tensor", "axis_max"): ("I_diag", "I_offdiag"),
    ("energy_momentum", "angle"): ("L",),
    ("euler_rotation", "F_body"): ("R",),
    ("euler_rotation", "r_lab"): ("R",),
    ("steady_precession", "slow_error"): ("slow", "slow_approx"),
    ("motion_type", "motion"): ("alpha_dot1", "alpha_dot2"),
}
SYMBOLIC = ("p_alpha", "p_gamma", "E_prime", "V_eff", "alpha_dot", "c2")  # its SUMMARY's list
CHAINS.update({("symbolic_derivation", q): (f"{q}_expr",) for q in SYMBOLIC})


def _variant(family: str, seed: int):
    return FAMILIES[family].generate(np.random.default_rng(seed))


def _answers(variant) -> dict[str, Answer]:
    return {a.name: a for a in variant.answers}


def _plain(value):
    return value.tolist() if hasattr(value, "tolist") else value


# -- the references: each statement's own definition of the later answer


def _critical_spin_rule(params, earlier):  # R19: sleeping stable when ω3 ≥ ω3c
    return params["omega3"] >= earlier["omega3_c"]


def _body_period(params, earlier):  # R8: the body cone's period 2π/|Ω|
    return 2 * math.pi / abs(earlier["Omega"])


def _reduced_energy(params, earlier, key):
    # E' = E − p_γ²/(2 I3) (R15), with I3 = p_γ/ω3 from the key's p_γ and ω3 = γ̇ + α̇ cos β
    # (R12): E' at another p_γ differs from the key's by (p_key² − p²)/(2 I3).
    omega3 = params["gamma_dot0"] + params["alpha_dot0"] * math.cos(params["beta0"])
    i3 = key["p_gamma"].value / omega3
    p, p_key = earlier["p_gamma"], key["p_gamma"].value
    return key["E_prime"].value + (p_key**2 - p**2) / (2 * i3)


def _tensor(earlier):
    (xx, yy, zz), (xy, xz, yz) = earlier["I_diag"], earlier["I_offdiag"]
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _moments(params, earlier):  # R4: the eigenvalues of the tensor, ascending
    return sorted(np.linalg.eigvals(_tensor(earlier)).real.tolist())


def _axis_max(params, earlier):  # R4: the axis of the largest moment, z component > 0
    values, vectors = np.linalg.eig(_tensor(earlier))
    axis = vectors[:, int(np.argmax(values.real))].real
    axis = axis / np.linalg.norm(axis)
    return (axis if axis[2] > 0 else -axis).tolist()


def _angle(params, earlier):  # the angle between L and ω (ω along the axle for the disc)
    omega = params["omega"]
    omega = np.array(omega if np.ndim(omega) else [0.0, 0.0, omega], dtype=float)
    L = np.array(earlier["L"], dtype=float)
    return math.acos(float(L @ omega / (np.linalg.norm(L) * np.linalg.norm(omega))))


def _force_in_body(params, earlier):  # R11: body components = R · lab components
    return (np.reshape(earlier["R"], (3, 3)) @ np.array(params["F_lab"])).tolist()


def _position_in_lab(params, earlier):  # R11: lab components = Rᵀ · body components
    return (np.reshape(earlier["R"], (3, 3)).T @ np.array(params["r_body"])).tolist()


def _relative_error(params, earlier):  # the statement: (slow_approx − slow)/slow
    return (earlier["slow_approx"] - earlier["slow"]) / earlier["slow"]


def _motion(params, earlier):  # R18: opposite signs at the turning points make loops
    a, b = earlier["alpha_dot1"], earlier["alpha_dot2"]
    return "loops" if a * b < 0 else "waves"


def _expression_value(params, earlier):  # the student's expression at the given numbers
    (text,) = earlier.values()
    names = {n: sympy.Symbol(n) for n, v in params.items() if not isinstance(v, str)}
    expr = sympy.sympify(text, locals=names)  # "beta" a symbol, not sympy's beta function
    return float(expr.subs({names[n]: params[n] for n in names}))


REFERENCES: dict[tuple[str, str], Callable] = {
    ("sleeping_top", "stable"): _critical_spin_rule,
    ("symmetric_free_top", "T_body"): _body_period,
    ("heavy_top_constants", "E_prime"): _reduced_energy,
    ("inertia_tensor", "moments"): _moments,
    ("inertia_tensor", "axis_max"): _axis_max,
    ("energy_momentum", "angle"): _angle,
    ("euler_rotation", "F_body"): _force_in_body,
    ("steady_precession", "slow_error"): _relative_error,
    ("euler_rotation", "r_lab"): _position_in_lab,
    ("motion_type", "motion"): _motion,
    **{("symbolic_derivation", q): _expression_value for q in SYMBOLIC},
}


def _perturbed(name: str, value, seed: int):
    """A wrong earlier answer a student might give: off by 20 % (a vector: one entry off by
    20 % of the largest; an expression: a factor 2; the rotation matrix: transposed, the
    classic mistake; the motion's rates: one sign flipped)."""
    if isinstance(value, str):
        return f"2*({value})"
    if name == "R":
        return np.reshape(value, (3, 3)).T.ravel().tolist()
    if isinstance(value, list):
        out = list(value)
        out[seed % len(out)] += 0.2 * max(abs(v) for v in value)
        return out
    if name == "alpha_dot2":
        return -value
    return value * 1.2


def _variants_with(family: str, answer: str, count: int = 15):
    """The first ``count`` variants (seed, variant, key) whose question asks ``answer`` (a
    family's scenes ask different ones)."""
    found = []
    for seed in range(1000):
        variant = _variant(family, seed)
        if answer in _answers(variant):
            found.append((seed, variant, _answers(variant)))
            if len(found) == count:
                break
    return found


@pytest.mark.parametrize("chain", sorted(CHAINS), ids="/".join)
def test_chains_are_declared(chain):
    family, answer = chain
    found = _variants_with(family, *chain[1:])
    assert found, f"no variant of {family} asks {answer}"
    assert {key[answer].depends_on for _, _, key in found} == {CHAINS[chain]}


def test_every_declared_chain_is_listed_here():
    """No built-in declares a chain this test does not check."""
    found = {(name, a.name) for name, fam in FAMILIES.items() for s in range(60)
             for a in fam.generate(np.random.default_rng(s)).answers if a.depends_on}
    assert found <= set(CHAINS), found - set(CHAINS)


@pytest.mark.parametrize("chain", sorted(CHAINS), ids="/".join)
def test_follow_from_the_key_gives_the_key(chain):
    family, answer = chain
    checked = 0
    for seed, variant, key in _variants_with(family, answer):
        earlier = {n: key[n].value for n in CHAINS[chain]}
        value = FAMILIES[family].follow(answer, variant.parameters, earlier)
        assert grade(key[answer], _plain(value)).status == "correct", seed
        checked += 1
    assert checked >= 12


@pytest.mark.parametrize("chain", sorted(CHAINS), ids="/".join)
def test_follow_from_wrong_earlier_answers_matches_the_definition(chain):
    family, answer = chain
    checked = differs = 0
    # motion_type: half its scenes are cusps (a rate zero), skipped below
    for seed, variant, key in _variants_with(family, answer, 30 if family == "motion_type"
                                             else 15):
        earlier = {n: key[n].value for n in CHAINS[chain]}
        first = CHAINS[chain][seed % len(CHAINS[chain])]
        if family == "motion_type":
            first = "alpha_dot2"
            rates = (abs(earlier["alpha_dot1"]), abs(earlier["alpha_dot2"]))
            if min(rates) <= 0.05 * max(rates):
                continue  # a cusp: the rule near zero is the tolerance's, not the sign's
        earlier[first] = _perturbed(first, earlier[first], seed)
        value = _plain(FAMILIES[family].follow(answer, variant.parameters, earlier))
        args = (variant.parameters, earlier) + ((key,) if family == "heavy_top_constants"
                                               else ())
        expected = REFERENCES[chain](*args)
        if isinstance(expected, bool | str):
            assert value == expected, seed
        else:
            np.testing.assert_allclose(value, expected, rtol=1e-9, atol=1e-12,
                                       err_msg=f"seed {seed}")
        checked += 1
        differs += grade(key[answer], value).status != "correct"
    assert checked >= 12
    if key[answer].kind in ("scalar", "vector", "angle"):
        assert differs == checked  # every numeric chain: the wrong start leads elsewhere
    else:
        assert differs > 0


def test_follow_outside_the_physics_raises():
    """What earns no credit: a 'rotation' matrix that is not one, a zero precession rate."""
    _, variant, key = _variants_with("euler_rotation", "F_body", 1)[0]
    skewed = list(key["R"].value)
    skewed[0] *= 1.2
    with pytest.raises(ValueError, match="rotation matrix"):
        FAMILIES["euler_rotation"].follow("F_body", variant.parameters, {"R": skewed})
    variant = _variant("symmetric_free_top", 0)
    with pytest.raises(ZeroDivisionError):
        FAMILIES["symmetric_free_top"].follow("T_body", variant.parameters, {"Omega": 0.0})


def test_follow_refuses_an_answer_without_a_chain():
    variant = _variant("sleeping_top", 0)
    with pytest.raises(LookupError):
        FAMILIES["sleeping_top"].follow("omega3_c", variant.parameters, {})
    with pytest.raises(LookupError):
        FAMILIES["turning_points"].follow("beta1", _variant("turning_points", 0).parameters,
                                          {})


def test_depends_on_round_trips_through_the_key_record():
    answer = _answers(_variant("sleeping_top", 0))["stable"]
    record = answer.to_dict()
    assert record["depends_on"] == ["omega3_c"]
    assert Answer.from_dict(record) == answer
    assert "depends_on" not in _answers(_variant("sleeping_top", 0))["omega3_c"].to_dict()


# -- each family's own degenerate cases (issue 30): earlier values that leave nothing to work
# out for the later answer, as the family's docstring declares them; written out here from the
# statements, never taken from the family's code


def _rotation(values):
    return np.reshape(values["R"], (3, 3))


DEGENERATE: dict[str, Callable] = {  # family -> (params, key values) -> [(changed, earlier)]
    "sleeping_top": lambda p, k: [("omega3_c", {"omega3_c": 0.0}),
                                  ("omega3_c", {"omega3_c": -k["omega3_c"]}),
                                  ("omega3_c", {"omega3_c": p["omega3"]})],
    "symmetric_free_top": lambda p, k: [("Omega", {"Omega": 0.0})] + (
        [("Omega", {"Omega": p["omega0"][2]})] if k["Omega"] != p["omega0"][2] else []),
    "heavy_top_constants": lambda p, k: [("p_gamma", {"p_gamma": 0.0}),
                                         ("p_gamma", {"p_gamma": p["gamma_dot0"]})],
    "inertia_tensor": lambda p, k: [("I_offdiag", {"I_offdiag": [0.0, 0.0, 0.0]}),
                                    ("I_diag", {"I_diag": [0.0, 0.0, 0.0]})],
    "energy_momentum": lambda p, k: [
        ("L", {"L": [0.0, 0.0, 0.0]}),
        *(("L", {"L": (f * _omega(p)).tolist()}) for f in (1.0, 2.5, -0.7))],
    "euler_rotation": lambda p, k: [
        ("R", {"R": np.eye(3).ravel().tolist()}),
        ("R", {"R": np.diag([-1.0, -1.0, 1.0]).ravel().tolist()}),
        ("R", {"R": [0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0]})],
    "steady_precession": lambda p, k: [
        ("slow", {"slow": 0.0}),
        ("slow", {"slow": k["slow_approx"], "slow_approx": k["slow_approx"]})],
    "motion_type": lambda p, k: [
        ("alpha_dot1", {"alpha_dot1": 0.0, "alpha_dot2": 0.0}),
        *((n, {n: 0.0}) for n in ("alpha_dot1", "alpha_dot2") if k[n] != 0)],
    "symbolic_derivation": lambda p, k: [
        (e, {e: text}) for e in k if e.endswith("_expr")
        for text in ("0", "7.5", _symbols(p)[0])],
}


def _omega(params):
    omega = params["omega"]
    return np.array(omega if np.ndim(omega) else [0.0, 0.0, omega], dtype=float)


def _symbols(params):
    """The symbols of a symbolic_derivation variant: its parameters that are numbers."""
    return [n for n, v in params.items() if not isinstance(v, str)]


@pytest.mark.parametrize("chain", sorted(CHAINS), ids="/".join)
def test_each_family_declares_its_degenerate_cases(chain):
    family, answer = chain
    names, checked = CHAINS[chain], 0
    module = FAMILIES[family].module
    assert module.degenerate.__doc__ and re.search(r"\bR\d+\b", module.degenerate.__doc__)
    for seed, variant, key in _variants_with(family, answer, 8):
        values = {n: a.value for n, a in key.items()}
        own = {n: values[n] for n in names}
        assert FAMILIES[family].degenerate(answer, variant.parameters, own) is None, seed
        first = names[seed % len(names)]
        plausible = {**own, first: _perturbed(first, own[first], seed)}
        assert FAMILIES[family].degenerate(answer, variant.parameters, plausible) is None, seed
        for changed, case in DEGENERATE[family](variant.parameters, values):
            reason = FAMILIES[family].degenerate(answer, variant.parameters, {**own, **case})
            assert reason is not None, (seed, case)
            assert f"{{{changed}}}" in reason and f"{{{answer}}}" in reason, reason
            assert re.search(r"\bR\d+\b", reason), reason
            checked += 1
    assert checked >= 8


def test_degenerate_is_asked_of_a_chained_answer_only():
    variant = _variant("sleeping_top", 0)
    with pytest.raises(LookupError):
        FAMILIES["sleeping_top"].degenerate("omega3_c", variant.parameters, {})
