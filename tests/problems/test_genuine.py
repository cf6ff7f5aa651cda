"""The default degenerate cases of follow-through credit (issue 30, :mod:`problems.genuine`),
each directly: the earlier answer zero, the identity, far from the key, a number copied from
the statement; the later answer then zero or a copy; and what spares a value (the key's own,
one its comparison recognises). The values are written out here, not computed by the module."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import pytest

from problems.answers import Answer, Mistake
from problems.family import Family
from problems.genuine import Given, default_reason, named, same_as_key, statement_number

OMEGA = Answer("Omega", "scalar", 2.0, unit="rad/s",
               mistakes=(Mistake("hz", 2.0 / (2 * math.pi), "in Hz"),
                         Mistake("degrees", math.degrees(2.0), "in degrees")))
PERIOD = Answer("T", "scalar", math.pi, unit="s", depends_on=("Omega",))
PARAMS = {"omega3": 40.0, "I1": 0.25, "t": 0.75, "body": "coin", "r": [0.1, 0.2, 0.3]}
UNITS = {"omega3": "rad/s", "I1": "kg m^2", "t": "s", "r": "m"}


def _reason(value, followed=None, params=PARAMS, others=()):
    """The default reason for ``T`` when the student's Omega is ``value``."""
    followed = 2 * math.pi / abs(value) if followed is None and value else followed
    return default_reason(PERIOD, [Given(OMEGA, value)], followed, params, others, UNITS)


# -- the earlier answer


@pytest.mark.parametrize("value", [0.0, 0, 1e-15, -0.0])
def test_zero_is_degenerate(value):
    assert _reason(value, followed=1.0) == "your {Omega} is zero, which leaves nothing to " \
                                          "work out for {T}"


def test_zero_where_the_key_is_zero_is_the_key():
    key = Answer("a", "vector", [0.0, 0.0, 0.0], atol=1e-3)
    later = Answer("b", "scalar", 1.0, depends_on=("a",))
    assert default_reason(later, [Given(key, [0.0, 0.0, 0.0])], 1.0, {}, ()) is None


def test_the_identity_is_degenerate_where_the_key_is_not():
    turned = [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]  # 90° about z
    R = Answer("R", "vector", turned)
    later = Answer("r_lab", "vector", [-0.2, 0.1, 0.3], unit="m", depends_on=("R",))
    identity = np.eye(3).ravel().tolist()
    reason = default_reason(later, [Given(R, identity)], [0.1, 0.2, 0.3], PARAMS, (), UNITS)
    assert reason == "your {R} is the identity matrix, which leaves nothing to work out for " \
                     "{r_lab}"
    near = (np.eye(3).ravel() * (1 + 1e-14)).tolist()  # a computed identity, 1e-14 off
    assert default_reason(later, [Given(R, near)], [0.1, 0.2, 0.3], PARAMS, (), UNITS) \
        .startswith("your {R} is the identity")
    key_identity = Answer("R", "vector", identity)
    later_same = Answer("r_lab", "vector", [0.1, 0.2, 0.3], unit="m", depends_on=("R",))
    assert default_reason(later_same, [Given(key_identity, identity)], [0.1, 0.2, 0.3],
                          PARAMS, (), UNITS) is None


@pytest.mark.parametrize(("value", "far"), [(20.5, True), (19.5, False), (0.195, True),
                                            (0.205, False), (-25.0, True), (-2.4, False)])
def test_far_means_a_factor_of_ten_in_size(value, far):
    reason = _reason(value)
    assert (reason is not None and "more than a factor of 10" in reason) == far, reason


def test_a_named_mistake_is_spared_however_far():
    degrees = math.degrees(2.0)  # 114.6: far from 2.0, but the listed mistake "degrees"
    assert _reason(degrees) is None
    assert _reason(degrees * 1.01) is not None  # not the mistake: far


def test_an_accepted_value_is_spared():
    accepting = Answer("Omega", "scalar", 2.0, unit="rad/s", accepted=(40.0,))
    later = Answer("T", "scalar", math.pi, unit="s", depends_on=("Omega",))
    given = [Given(accepting, 40.0)]  # also the statement's omega3, and 20 times the key
    assert default_reason(later, given, 2 * math.pi / 40.0, PARAMS, (), UNITS) is None
    plain = [Given(Answer("Omega", "scalar", 2.0, unit="rad/s"), 40.0)]
    assert default_reason(later, plain, 2 * math.pi / 40.0, PARAMS, (), UNITS) is not None


def test_a_number_of_the_statement_copied_is_degenerate():
    key = Answer("Omega", "scalar", 2.5, unit="rad/s")  # within a factor 10 of 0.75 and 0.25
    later = Answer("T", "scalar", 2 * math.pi / 2.5, unit="s", depends_on=("Omega",))
    for name in ("t", "I1"):
        reason = default_reason(later, [Given(key, PARAMS[name])], 2 * math.pi / PARAMS[name],
                                PARAMS, (), UNITS)
        assert reason == f"your {{Omega}} is {{{name}}}, copied from the statement, not " \
                         "worked out"
    reason = default_reason(later, [Given(key, 0.3)], 2 * math.pi / 0.3, PARAMS, (), UNITS)
    assert reason == "your {Omega} is an entry of {r}, copied from the statement, not worked out"
    assert default_reason(later, [Given(key, 0.76)], 2 * math.pi / 0.76, PARAMS, (),
                          UNITS) is None  # near t, not t


def test_a_copy_the_key_makes_too_is_no_copy():
    key = Answer("Omega", "scalar", 0.75, unit="rad/s", rtol=1e-3)  # the key is t's number
    later = Answer("T", "scalar", 2 * math.pi / 0.75, unit="s", depends_on=("Omega",))
    # a student's 0.75 is the key's own: judged against the key, never here; 0.7505 is right
    assert same_as_key(Given(key, 0.75))
    assert default_reason(later, [Given(key, 0.7505)], 2 * math.pi / 0.7505, PARAMS, (),
                          UNITS) is None


# -- the later answer


def test_a_later_answer_recomputed_to_zero_is_degenerate():
    slow = Answer("slow", "scalar", 1.0, unit="rad/s")
    error = Answer("slow_error", "scalar", -0.05, depends_on=("slow",))
    assert default_reason(error, [Given(slow, 1.2)], 0.0, {}, ()) == \
        "{slow_error} from your values is zero: nothing is left to work out"
    assert default_reason(error, [Given(slow, 1.2)], 1e-4, {}, ()) is None  # small, not zero


def test_a_later_answer_that_copies_a_given_number_in_its_unit():
    R = Answer("R", "vector", [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    later = Answer("r_lab", "vector", [-0.2, 0.1, 0.3], unit="m", depends_on=("R",))
    flipped = [0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]  # not a rotation; a reordering
    reason = default_reason(later, [Given(R, flipped)], [0.2, 0.1, 0.3], PARAMS, (), UNITS)
    assert reason == "{r_lab} from your values is {r} of the statement: a copy, not worked out"
    other_unit = {**UNITS, "r": "N"}
    assert default_reason(later, [Given(R, flipped)], [0.2, 0.1, 0.3], PARAMS, (),
                          other_unit) is None
    off = [0.2 * (1 + 2e-3), 0.1, 0.3]  # beyond COPY_RTOL of r
    assert default_reason(later, [Given(R, flipped)], off, PARAMS, (), UNITS) is None


def test_a_later_answer_that_copies_another_answer():
    diag = Answer("I_diag", "vector", [3.0, 1.0, 2.0], unit="kg m^2")
    products = Answer("I_offdiag", "vector", [-0.5, 0.25, 0.1], unit="kg m^2")
    moments = Answer("moments", "vector", [0.8, 2.1, 3.1], unit="kg m^2",
                     depends_on=("I_diag", "I_offdiag"))
    mine = [3.0, 1.1, 2.0]
    earlier = [Given(diag, mine), Given(products, [-0.5, 0.2, 0.1])]
    others = [*earlier, Given(moments, [1.1, 2.0, 3.0])]
    reason = default_reason(moments, earlier, [1.1, 2.0, 3.0005], {}, others)
    assert reason == "{moments} from your values is your {I_diag}: a copy, not worked out"
    assert default_reason(moments, earlier, [1.0, 2.2, 3.1], {}, others) is None


# -- the key's own values, and the helpers


@pytest.mark.parametrize(("answer", "value", "same"), [
    (OMEGA, 2.0, True), (OMEGA, 2.0 * (1 + 1e-13), True), (OMEGA, 2.0 * (1 + 1e-9), False),
    (Answer("b", "boolean", True), True, True), (Answer("b", "boolean", True), False, False),
    (Answer("c", "choice", "loops", options=("waves", "loops")), " LOOPS", True),
    (Answer("e", "expression", "2*x", symbols=("x",)), "x*2", True),
    (Answer("e", "expression", "2*x", symbols=("x",)), "x*2.001", False),
])
def test_same_as_key(answer, value, same):
    assert same_as_key(Given(answer, value)) is same


def test_statement_number_and_named():
    assert statement_number(0.75, PARAMS) == "t"
    assert statement_number([0.3, 0.1, 0.2], PARAMS) == "r"
    assert statement_number(0.2, PARAMS) == "r"  # an entry of a vector
    assert statement_number(0.75, PARAMS, key=0.75) is None
    assert statement_number(0.7500001, PARAMS) is None
    assert named("your {R} is the identity, so {r_lab} is {r_body}", 3, ["R", "r_lab"]) == \
        "your q3_R is the identity, so q3_r_lab is {r_body}"


class _Module:
    NAME, TITLE, SUMMARY = "bad_reason", "A family", "one line"
    PARAMETERS: ClassVar[dict] = {}

    @staticmethod
    def answers(params):
        return ()

    @staticmethod
    def statement(params):
        return "text"

    @staticmethod
    def degenerate(name, params, earlier):
        return earlier["a"]  # whatever it was given: not always a reason


def test_a_family_s_degenerate_must_answer_text_or_none():
    family = Family(_Module())
    assert family.degenerate("b", {}, {"a": None}) is None
    assert family.degenerate("b", {}, {"a": "your {a} is zero"}) == "your {a} is zero"
    with pytest.raises(TypeError, match="degenerate\\(\\) must return a reason"):
        family.degenerate("b", {}, {"a": 3.0})
