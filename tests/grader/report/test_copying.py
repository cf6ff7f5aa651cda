"""The chance of a copied-looking match, checked by simulation against the class's spread."""

from __future__ import annotations

import math

import numpy as np
import pytest

from grader.report import load_class
from grader.report.classdata import numeric, submitted_values
from grader.report.copying import Match, _item_matches, _offsets, chance, expected_pairs


@pytest.mark.parametrize("spread", ["uniform", "lognormal"])
def test_chance_estimates_how_often_a_random_value_lands_within_the_tolerance(spread):
    rng = np.random.default_rng(3)
    draw = (lambda k: rng.uniform(1, 10, k)) if spread == "uniform" else \
        (lambda k: rng.lognormal(1, 0.5, k))
    keys = draw(400)
    x = 5.5 if spread == "uniform" else math.e  # the middle of each spread
    tol = 1e-3 * x
    estimate = chance(np.array([x]), keys[:, None], tol, None)
    # simulation: fresh values from the same spread, how many land within tol of x
    fresh = draw(2_000_000)
    observed = np.mean(np.abs(fresh - x) <= tol)
    assert estimate == pytest.approx(observed, rel=0.5)


def test_values_many_students_share_make_a_match_likely():
    keys = np.r_[np.zeros(50), np.linspace(1, 10, 150)][:, None]
    assert chance(np.array([0.0]), keys, 1e-6, None) > 0.2


def test_identical_variants_give_no_evidence():
    keys = np.full((100, 1), 3.0)
    assert chance(np.array([3.0]), keys, 3e-3, None) >= 0.99


def test_angles_are_compared_modulo_their_period():
    keys = np.linspace(0, 2 * np.pi, 500, endpoint=False)[:, None]
    near_zero = chance(np.array([1e-4]), keys, 1e-3, 2 * np.pi)
    middle = chance(np.array([np.pi]), keys, 1e-3, 2 * np.pi)
    assert near_zero == pytest.approx(middle)


def test_expected_pairs_counts_pairs_of_students_and_choices_of_answers():
    assert expected_pairs(1e-9, 10, 5, 2) == pytest.approx(45 * 10 * 1e-9)
    assert expected_pairs(1.0, 2, 1, 1) == 1
    assert math.isfinite(expected_pairs(1e-300, 300, 40, 20))


def test_a_vector_on_one_axis_counts_as_one_number():
    # keys spread in 3-D, wrong answers [0, 0, z] (a known mistake) along one axis: matching
    # such a value is as likely as matching a single number
    rng = np.random.default_rng(5)
    keys = rng.uniform(1, 10, (200, 3))
    on_axis = np.c_[np.zeros((100, 2)), rng.uniform(1, 10, 100)]
    reference = np.r_[keys, on_axis]
    p3 = chance(np.array([0.0, 0.0, 5.5]), reference, 5.5e-3, None)
    p1 = chance(np.array([5.5]), reference[:, 2:], 5.5e-3, None)
    assert p3 == pytest.approx(p1)


def _matches_by_definition(data, item) -> list:
    """Every match on ``item`` as the module docstring defines them, one pair at a time: each
    chance weighed against the class's other values, gathered afresh for the pair."""
    answers = {s: data.keys[s][item.variable] for s in data.graded
               if item.variable in data.keys[s]}
    keys = {s: numeric(a.value) for s, a in answers.items()}
    wrong = {s: x for s, (a, _, x) in submitted_values(data, item).items()
             if a.verdict.status in ("wrong", "follows")}
    found = []
    for s, x in wrong.items():
        a = answers.get(s)
        if a is None or keys[s] is None or keys[s].shape != x.shape:
            continue

        def near(u, v, tol, period=a.period):
            return bool(np.linalg.norm(_offsets(u, v[None, :], period)) <= tol)

        def others(*pools, pair, shape=x.shape):
            rows = [v for pool in pools for t, v in pool.items()
                    if t not in pair and v is not None and v.shape == shape]
            return np.array(rows).reshape(len(rows), *shape)

        for t, k in keys.items():
            if k is None or k.shape != x.shape or t == s:
                continue
            tol_t = answers[t].atol + answers[t].rtol * np.linalg.norm(k)
            if near(x, k, tol_t) and not near(keys[s], k, tol_t):
                found.append(Match(item.variable, "key", s, t, x.tolist(), k.tolist(),
                                   chance(x, others(keys, pair=(s, t)), tol_t, a.period)))
        tol = a.atol + a.rtol * float(np.linalg.norm(x))
        for t, y in wrong.items():
            if t <= s or keys.get(t) is None or keys[t].shape != x.shape:
                continue
            tol_t = answers[t].atol + answers[t].rtol * np.linalg.norm(keys[t])
            if near(y, x, tol) and not near(keys[s], keys[t], tol_t):
                found.append(Match(item.variable, "wrong", s, t, x.tolist(), y.tolist(),
                                   chance(x, others(keys, wrong, pair=(s, t)), tol, a.period)))
    return found


def test_the_matches_are_those_the_definition_gives(planted_class):
    """_item_matches weighs each student's value against the class once for all its matches;
    on the planted class (copies, shared slips, honest work) it finds every match, with every
    chance, that taking the pairs one at a time does."""
    from grader.report.classdata import NUMERIC_KINDS

    data = load_class(planted_class.made.hw, planted_class.made.graded)
    checked = 0
    for item in data.items:
        if item.kind in NUMERIC_KINDS:
            fast = _item_matches(data, item)
            assert sorted(fast, key=repr) == sorted(_matches_by_definition(data, item), key=repr)
            checked += len(fast)
    assert checked > 20
