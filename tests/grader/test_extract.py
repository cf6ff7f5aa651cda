"""Extraction: the kernel-side converter (run here, in-process, exactly as shipped to the
kernel) and the grader's reading of untrusted replies. References: the values themselves
(plain JSON expected by hand), and hostile replies that must never raise."""

from __future__ import annotations

import builtins
import fractions
import json
import math
import os
import time

import mpmath
import numpy as np
import pytest
import sympy

from grader.extract import (
    ANSWER_SECONDS,
    INVALID,
    MAX_ELEMENTS,
    extraction_request,
    invalid_reason,
    parse_answers,
)

x, t = sympy.symbols("x t")

CONVERSIONS = [
    (None, None),
    (True, True),
    (np.bool_(False), False),
    (sympy.true, True),
    (3, 3),
    (np.int32(-4), -4),
    (10**16, 1e16),
    (2.5, 2.5),
    (np.float32(0.5), 0.5),
    (fractions.Fraction(1, 4), 0.25),
    (mpmath.mpf("0.125"), 0.125),
    (sympy.Rational(3, 8), 0.375),
    (sympy.sqrt(2) * 0, 0.0),
    ("loops", "loops"),
    ([1, 2.5, "a", None, True], [1, 2.5, "a", None, True]),
    ((1.0, np.float64(2.0)), [1.0, 2.0]),
    (np.array([[1, 2], [3, 4]]), [[1, 2], [3, 4]]),
    (np.array(7.5), 7.5),
    (sympy.Matrix([[1], [2]]), [1.0, 2.0]),
    (sympy.Matrix([[1, 2], [3, 4]]), [[1.0, 2.0], [3.0, 4.0]]),
    (x**2 * sympy.sin(t), "x**2*sin(t)"),
    ({"a": 1}, {INVALID: "a dict"}),
    ({1, 2}, {INVALID: "a set"}),
    (b"1.0", {INVALID: "bytes"}),
    (len, {INVALID: "a function (call it to get the value)"}),
    (3 + 4j, {INVALID: "the complex number 3+4j"}),
    (np.array([1j]), {INVALID: "an array of complex numbers"}),
    (sympy.I + 1, {INVALID: "the complex number 1 + I"}),
    (sympy.Eq(x, 1), {INVALID: "the sympy object Equality, not an expression"}),
    (10**400, {INVALID: "an integer too large for a float"}),
    ("s" * 10_001, {INVALID: "a string of 10001 characters"}),
    (np.zeros(MAX_ELEMENTS + 1), {INVALID: f"an array of {MAX_ELEMENTS + 1} elements (more "
                                           f"than {MAX_ELEMENTS})"}),
    ([[[[[1.0]]]]], {INVALID: "a list whose element 1 is a list whose element 1 is a list whose "
                              "element 1 is a list whose element 1 is a list nested more than 4 "
                              "deep"}),
    ([[0.0] * 6000, [0.0] * 6000], {INVALID: "a list whose element 2 is a list whose element "
                                             "4001 is more than 10000 numbers"}),
    (object(), {INVALID: "a value of type object"}),
]


def _in_kernel_namespace(values: dict) -> dict:
    """Run the extraction code as the kernel would, in a namespace shadowing what it could use."""
    names = tuple(values)
    request = extraction_request(names)
    namespace = {"__builtins__": builtins, **values, "json": None, "print": None, "float": str,
                 "list": dict, "isinstance": None, "exec": None, "__import__": None}
    exec(request.code, namespace)
    text = namespace[request.user_expressions["answers"]]
    reply = {"status": "ok", "user_expressions": {"answers": {
        "status": "ok", "data": {"text/plain": repr(text)}, "metadata": {}}}}
    answers, problem = parse_answers(reply, names)
    assert problem is None
    return answers


@pytest.mark.parametrize("value, expected", CONVERSIONS,
                         ids=[f"{i}-{type(v).__name__}" for i, (v, _) in enumerate(CONVERSIONS)])
def test_values_become_plain_json_or_a_marker(value, expected):
    got = _in_kernel_namespace({"q1_a": value})["q1_a"]
    assert got == expected
    assert type(got) is type(expected)
    json.dumps(got, allow_nan=False)  # plain JSON


@pytest.mark.parametrize("value, check", [(float("nan"), math.isnan),
                                          (np.float64("-inf"), lambda v: v == -math.inf),
                                          (sympy.oo, lambda v: v == math.inf)])
def test_non_finite_numbers_are_kept_for_the_comparison_to_report(value, check):
    got = _in_kernel_namespace({"q1_a": value})["q1_a"]
    assert isinstance(got, float) and check(got)


def test_unset_names_are_none_and_only_declared_names_come_back():
    request = extraction_request(("q1_a", "q1_b"))
    namespace = {"__builtins__": builtins, "q1_a": 1.0, "q9_secret": 2.0}
    exec(request.code, namespace)
    reply = {"status": "ok", "user_expressions": {"answers": {"data": {
        "text/plain": repr(namespace[request.user_expressions["answers"]])}}}}
    assert parse_answers(reply, ("q1_a", "q1_b")) == ({"q1_a": 1.0, "q1_b": None}, None)


def test_each_request_has_a_fresh_nonce():
    first, second = extraction_request(("q1_a",)), extraction_request(("q1_a",))
    assert first.user_expressions != second.user_expressions
    assert first.code != second.code


@pytest.mark.parametrize("names", [("q1 a",), ("import os",), ("class",), (1,)])
def test_variable_names_must_be_identifiers(names):
    with pytest.raises(ValueError, match="must be Python identifiers"):
        extraction_request(names)


def _reply(text_plain) -> dict:
    return {"status": "ok", "user_expressions": {"answers": {"data": {"text/plain": text_plain}}}}


FORGED = [
    ("error reply", {"status": "error", "ename": "NameError", "evalue": "name 'exec' x"},
     "the grader's extraction raised NameError: name 'exec' x"),
    ("no expressions", {"status": "ok"}, "the kernel returned no answers"),
    ("not a reply", ["a"], "the kernel's reply is malformed"),
    ("not a str repr", _reply("42"), "not the grader's answer text"),
    ("code, not a literal", _reply("__import__('os').system('true')"),
     "not the grader's answer text"),
    ("not JSON", _reply(repr("{'q1_a': 1}")), "the kernel's reply is not JSON"),
    ("JSON list", _reply(repr("[1, 2]")), "not a JSON object"),
    ("deep JSON", _reply(repr("[" * 100_000 + "]" * 100_000)), "not JSON"),
    ("huge int", _reply(repr('{"q1_a": ' + "9" * 5000 + "}")), "not JSON"),
]


@pytest.mark.parametrize("name, reply, message", FORGED, ids=[f[0] for f in FORGED])
def test_unreadable_replies_give_no_answers_and_say_why(name, reply, message):
    answers, problem = parse_answers(reply, ("q1_a",))
    assert answers == {}
    assert problem.startswith("the notebook ran, but its answers could not be read: ")
    assert message in problem


def test_forged_contents_are_filtered_to_declared_plain_values():
    forged = json.dumps({"q1_a": {"nested": "dict"}, "q1_b": [1, [2, [3, [4, [5]]]]],
                         "q1_c": {INVALID: "x" * 1000}, "q1_d": 10**20, "q1_e": [0.0] * 20_000,
                         "q1_f": "ok", "q9_other": 1.0})
    answers, problem = parse_answers(_reply(repr(forged)), ("q1_a", "q1_b", "q1_c", "q1_d",
                                                            "q1_e", "q1_f", "q1_g"))
    assert problem is None
    unreadable = {INVALID: "a value the grader could not read"}
    assert answers == {"q1_a": unreadable, "q1_b": unreadable, "q1_c": {INVALID: "x" * 200},
                       "q1_d": unreadable, "q1_e": unreadable, "q1_f": "ok", "q1_g": None}


def test_invalid_reason_recognises_only_well_formed_markers():
    assert invalid_reason({INVALID: "a dict"}) == "a dict"
    for value in ({INVALID: 3}, {INVALID: "a", "b": 1}, "a dict", None, [INVALID]):
        assert invalid_reason(value) is None


# -- each answer read on its own, with a time bound (issue 30); in this process, as the kernel
# -- would: the readers are child processes of this one


class _Hangs(float):
    def __float__(self):
        # catches everything, as a hostile loop would: only a kill ends it — or, here, 30 s
        # (far over ANSWER_SECONDS), so that a reader without a time bound fails, not hangs
        end = time.monotonic() + 30
        while time.monotonic() < end:
            try:
                while time.monotonic() < end:
                    pass
            except BaseException:
                pass
        return 2.0


class _Raises(float):
    def __float__(self):
        raise ValueError("no")


class _Exits(float):
    def __float__(self):
        os._exit(0)


class _NoComparing(type):
    """A metaclass whose comparisons run code: a type checked by ``==`` or ``in`` would run it."""

    def __eq__(cls, other):
        raise RuntimeError("the student's metaclass ran")

    __hash__ = type.__hash__


def test_each_answer_is_read_on_its_own_within_its_time(monkeypatch):
    values = {"q1_a": 1.5, "q1_b": _Hangs(2.0), "q1_c": [_Raises(3.0)], "q1_d": _Exits(4.0),
              "q1_e": sympy.Rational(1, 4), "q1_f": _NoComparing("F", (float,), {})(6.0),
              "q1_g": np.arange(2.0)}
    before, start = set(_children()), time.monotonic()
    got = _in_kernel_namespace(values)
    assert time.monotonic() - start < ANSWER_SECONDS + 2
    assert got == {
        "q1_a": 1.5,
        "q1_b": {INVALID: "could not be read: its value did not convert within 2 s (a loop "
                          "that does not end?)"},
        "q1_c": {INVALID: "could not be read: reading it raised ValueError"},
        "q1_d": {INVALID: "could not be read: reading it ended the process"},
        "q1_e": 0.25, "q1_f": 6.0, "q1_g": [0.0, 1.0]}
    assert set(_children()) <= before  # every reader killed and reaped


def test_plain_values_are_read_without_a_child_and_without_one_all_are_read(monkeypatch):
    forks = []
    real = os.fork
    monkeypatch.setattr(os, "fork", lambda: forks.append(1) or real())
    plain = {"q1_a": 1.5, "q1_b": [1, 2.5, "x", None, True], "q1_c": np.float32(0.5),
             "q1_d": np.array([[1, 2], [3, 4]])}
    assert _in_kernel_namespace(plain) == {"q1_a": 1.5, "q1_b": [1, 2.5, "x", None, True],
                                           "q1_c": 0.5, "q1_d": [[1, 2], [3, 4]]}
    assert forks == []  # nothing of the student's runs when these are read
    assert _in_kernel_namespace({"q1_a": sympy.Rational(1, 2)}) == {"q1_a": 0.5}
    assert forks == [1]

    def no_process():
        raise BlockingIOError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(os, "fork", no_process)  # a kernel at its process limit
    assert _in_kernel_namespace({"q1_a": sympy.Rational(1, 2), "q1_b": [_Raises(1.0)]}) == {
        "q1_a": 0.5, "q1_b": {INVALID: "could not be read: reading it raised ValueError"}}


def _children() -> list[int]:
    """Processes whose parent is this one, zombies included (a reader never reaped)."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            stat = open(f"/proc/{pid}/stat").read()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == os.getpid():
            found.append(int(pid))
    return found
