"""Variant: JSON round trip, checks on what templates return, and the public answer spec."""

from __future__ import annotations

import json

import numpy as np
import pytest

from problems.answers import Answer, Mistake
from problems.variant import Variant, answer_spec, plain_number_tree, variable_name

ANSWERS = (
    Answer("T", "scalar", 1.25, unit="J", mistakes=(Mistake("half", 0.625, "factor 2"),)),
    Answer("L", "vector", [0.5, -1.0, 2.0], unit="kg m^2/s"),
    Answer("kind", "choice", "loops", options=("waves", "loops", "cusps")),
    Answer("V", "expression", "p**2/(2*I1)", symbols=("p", "I1")),
)


def make(**changes) -> Variant:
    fields = dict(family="fam", title="A top", params={"I1": 0.002, "ω3": 120.0},
                  param_units={"I1": "kg m^2"}, statement="$I_1$ …", answers=ANSWERS)
    return Variant(**{**fields, **changes})


def test_round_trip_through_json_text():
    variant = make()
    assert Variant.from_dict(json.loads(json.dumps(variant.to_dict()))) == variant


def test_numpy_parameters_become_plain_floats():
    variant = make(params={"I1": np.float32(0.5), "r": np.array([1, 2, 3]), "n": np.int64(2)})
    assert variant.params == {"I1": 0.5, "r": [1.0, 2.0, 3.0], "n": 2.0}
    assert all(type(v) in (float, list) for v in variant.params.values())
    json.dumps(variant.to_dict(), allow_nan=False)  # plain JSON, or this raises


@pytest.mark.parametrize(
    ("changes", "fragment"),
    [
        ({"params": {"2x": 1.0}}, "Python identifiers"),
        ({"params": {"lambda": 1.0}}, "Python identifiers"),
        ({"param_units": {"I9": "kg"}}, "unknown parameters ['I9']"),
        ({"params": {"I1": float("nan")}}, "'I1': must be finite"),
        ({"params": {"I1": "0.2"}}, "'I1': expected a number"),
        ({"params": {"I1": True}}, "'I1': expected a number"),
        ({"answers": ()}, "no answers"),
        ({"answers": (ANSWERS[0], ANSWERS[0])}, "duplicate answer names"),
    ],
)
def test_template_mistakes_are_refused(changes, fragment):
    with pytest.raises(ValueError, match="variant of 'fam'") as info:
        make(**changes)
    assert fragment in str(info.value)


def test_public_spec_has_form_but_no_values():
    variant = make()
    public = variant.public_dict(3)
    assert [a["variable"] for a in public["answers"]] == ["q3_T", "q3_L", "q3_kind", "q3_V"]
    text = json.dumps(public)
    for forbidden in ('"value"', '"mistakes"', "0.625", "p**2/(2*I1)", "-1.0"):
        assert forbidden not in text
    spec = {a["name"]: a for a in public["answers"]}
    assert spec["L"]["length"] == 3 and spec["T"]["length"] is None
    assert spec["kind"]["options"] == ["waves", "loops", "cusps"]
    assert spec["V"]["symbols"] == ["p", "I1"]
    assert public["params"] == variant.params and public["statement"] == variant.statement


@pytest.mark.parametrize("answer", ANSWERS)
def test_answer_spec_keys(answer):
    assert set(answer_spec(answer, 1)) == {
        "variable", "name", "kind", "unit", "length", "options", "symbols", "period", "points",
        "description",
    }


def test_variable_name_and_number_tree():
    assert variable_name(12, "beta1") == "q12_beta1"
    assert plain_number_tree([[1, 2.5], (np.float64(3),)], "x") == [[1.0, 2.5], [3.0]]
    with pytest.raises(ValueError, match="x: must be finite"):
        plain_number_tree([1.0, float("inf")], "x")
