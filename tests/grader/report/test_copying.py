"""The chance of a copied-looking match, checked by simulation against the class's spread."""

from __future__ import annotations

import math

import numpy as np
import pytest

from grader.report.copying import chance, expected_pairs


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
