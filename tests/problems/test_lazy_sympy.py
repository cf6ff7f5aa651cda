"""``eulertop check`` reads numbers without importing sympy (most of a second of start-up)."""

from __future__ import annotations

import subprocess
import sys

CHECK_PATH = """
import sys
import grader.check, grader.extract, problems.answers, problems.notebook, problems.expressions
from problems.answers import Answer, check_spec, grade
assert "sympy" not in sys.modules, "importing the check path loaded sympy"
print(check_spec({"name": "T", "kind": "scalar", "unit": "J"}, 1.5).status)
print(check_spec({"name": "v", "kind": "vector", "length": 2}, [1, "2"]).status)
print(grade(Answer("b", "boolean", True), True).status)
assert "sympy" not in sys.modules, "reading a number loaded sympy"
print(check_spec({"name": "e", "kind": "expression", "symbols": ["x"]}, "x**2").status)
print("sympy" in sys.modules)
"""


def test_numbers_are_read_without_sympy_and_expressions_load_it():
    out = subprocess.run([sys.executable, "-c", CHECK_PATH], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["correct", "invalid", "correct", "correct", "True"]


def test_a_sympy_value_is_still_read_once_sympy_is_loaded():
    import sympy

    from problems.answers import Answer, check_form, grade

    assert check_form(Answer("x", "scalar", 0.5), sympy.Rational(1, 2)).status == "correct"
    assert grade(Answer("x", "scalar", 0.5), sympy.Rational(1, 2)).status == "correct"
    assert check_form(Answer("v", "vector", [1.0, 2.0]), sympy.Matrix([1, 2])).status == "correct"
    assert check_form(Answer("b", "boolean", True), sympy.true).status == "correct"
    verdict = check_form(Answer("x", "scalar", 0.5), sympy.Symbol("y") + 1)
    assert verdict.status == "invalid" and "an expression in y" in verdict.message
