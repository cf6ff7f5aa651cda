"""Item statistics against independent formulas (scipy's point-biserial coefficient)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from grader.report.items import category, item_flags, point_biserial
from problems.answers import Verdict


@pytest.mark.parametrize("seed", range(5))
def test_point_biserial_of_a_right_or_wrong_item_equals_scipys(seed):
    rng = np.random.default_rng(seed)
    rest = rng.normal(10, 3, 80)
    item = (rest + rng.normal(0, 3, 80) > 10).astype(float)
    expected = stats.pointbiserialr(item.astype(bool), rest).statistic
    assert point_biserial(item, rest) == pytest.approx(expected, rel=1e-12)


def test_point_biserial_is_undefined_when_nobody_or_everybody_is_right():
    rest = np.array([1.0, 2.0, 3.0])
    assert point_biserial(np.zeros(3), rest) is None
    assert point_biserial(np.ones(3), rest) is None


@pytest.mark.parametrize(("facility", "discrimination", "flags"), [
    (0.0, None, ("possibly broken",)),
    (0.04, 0.3, ("possibly broken",)),
    (0.3, 0.5, ("hard",)),
    (0.3, -0.2, ("hard", "negative discrimination")),
    (0.8, 0.05, ("low discrimination",)),
    (0.8, 0.5, ()),
])
def test_item_flags(facility, discrimination, flags):
    assert item_flags(facility, discrimination, 30) == flags


def test_too_few_students_flag_nothing():
    assert item_flags(0.0, None, 3) == ()


@pytest.mark.parametrize(("verdict", "name"), [
    (Verdict("correct", 1, 1, "ok"), "correct"),
    (Verdict("wrong", 0, 1, "no", mistake="degrees"), "known mistake"),
    (Verdict("wrong", 0, 1, "no"), "wrong"),
    (Verdict("invalid", 0, 1, "a string"), "invalid"),
    (Verdict("missing", 0, 1, "not set"), "unanswered"),
])
def test_each_verdict_counts_in_one_category(verdict, name):
    assert category(verdict) == name
