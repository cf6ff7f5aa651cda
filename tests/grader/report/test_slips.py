"""Common wrong answers: each named relation recognised from a student's own key; shared
ratios found only when unlikely by chance (checked by simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from grader.report.slips import (
    RELATIONS,
    WINDOW,
    chance_groups,
    cluster,
    named_relation,
    nice_name,
)
from problems.answers import Answer

SCALAR = Answer("w", "scalar", 2.37, rtol=1e-3)
ANGLE = Answer("b", "angle", 0.61, rtol=1e-3)
VECTOR = Answer("L", "vector", [1.3, -0.4, 2.2], rtol=1e-3)


@pytest.mark.parametrize(("answer", "wrong", "name"), [
    (SCALAR, -2.37, "sign"),
    (SCALAR, 4.74, "factor_2"),
    (SCALAR, 1.185, "half"),
    (SCALAR, 2.37 * 180 / math.pi, "degrees"),
    (SCALAR, 2.37 * math.pi / 180, "radians_twice"),
    (SCALAR, 2.37 * 2 * math.pi, "times_2pi"),
    (SCALAR, 2.37 / (2 * math.pi), "over_2pi"),
    (SCALAR, 1 / 2.37, "reciprocal"),
    (SCALAR, 2.37**2, "squared"),
    (SCALAR, math.sqrt(2.37), "square_root"),
    (ANGLE, math.pi - 0.61, "supplement"),
    (ANGLE, math.pi / 2 - 0.61, "complement"),
    (ANGLE, 0.61 + math.pi, "plus_pi"),
    (VECTOR, [-0.4, 1.3, 2.2], "swap_x_y"),
    (VECTOR, [2.2, -0.4, 1.3], "swap_x_z"),
    (VECTOR, [1.3, 2.2, -0.4], "swap_y_z"),
    (VECTOR, [1.3, 0.4, 2.2], "sign_y"),
])
def test_a_wrong_value_is_related_to_the_students_own_key(answer, wrong, name):
    x = np.atleast_1d(np.asarray(wrong, dtype=float)) * (1 + 3e-4)  # within the tolerance
    v = np.atleast_1d(np.asarray(answer.value, dtype=float))
    rel = named_relation(answer, x, v)
    assert rel is not None and rel.name == name


def test_an_arbitrary_error_has_no_named_relation():
    assert named_relation(SCALAR, np.array([2.37 * 1.37]), np.array([2.37])) is None


def test_relation_names_are_unique_and_usable_as_mistake_names():
    names = [r.name for r in RELATIONS]
    assert len(set(names)) == len(names)
    assert all(n.isidentifier() for n in names)


def test_nice_ratio_names():
    assert nice_name(1.5003, 1e-3) == "3/2"
    assert nice_name(1.37, 1e-3) is None


def test_cluster_groups_span_at_most_the_width():
    values = [0.0, 0.004, 0.008, 0.012, 5.0]
    groups = cluster(values, 0.01)
    assert all(max(values[i] for i in g) - min(values[i] for i in g) <= 0.01 for g in groups)
    assert sorted(len(g) for g in groups) == [1, 1, 3]


def test_chance_groups_bounds_the_simulated_rate_of_chance_triples():
    # n values uniform on [0, 1): how often do some 3 fall within a window? (simulation,
    # independent of the formula, which counts expected groups and so bounds that rate)
    rng = np.random.default_rng(7)
    n, width, trials = 20, 0.01, 4000
    hits = sum(any(len(g) >= 3 for g in cluster(list(rng.random(n)), width))
               for _ in range(trials))
    rate = hits / trials
    local = round((n - 1) * WINDOW * width)  # others within WINDOW widths, on average
    bound = chance_groups(n, 3, local)
    assert rate <= bound
    assert rate > bound / 4  # and is not wildly pessimistic
