"""No text of a question depends on the answer it asks for (issue 13), over every family.

For each family, :data:`N_VARIANTS` variants are drawn and every number in their text is
masked (``#``). What remains is the words. Two tests:

1. *What is asked* — the statement's numbered questions, every answer's public spec (name,
   kind, unit, description, options, symbols, points) and the line saying how it is compared —
   is, once masked, **the same text in every variant** with the same answer names. So it
   carries no information at all, about a categorical answer or anything else. (Families that
   ask for different quantities in different variants, such as ``symbolic_derivation``, are
   compared within each set of answer names.)
2. *The whole text* (the scene described, too) carries no more information about any
   categorical (boolean or choice) answer than chance: the mutual information between the
   masked text and the answer is no larger than the 99th percentile of its distribution with
   the answers shuffled across variants (a permutation test, seeded). Two families are exempt
   from 2, for a reason of physics that the third test checks: their scene names the body's
   axes by its geometry ("along its width"), and geometry decides stability — which is the
   lesson (the tennis-racket theorem), not a leak.
3. For those two families, the masked scene predicts the answer exactly as the physics does:
   the axis named along a box's width is its intermediate one, in every variant.
"""

from __future__ import annotations

import math
import re
from collections import Counter, defaultdict

import numpy as np
import pytest

from problems.answers import comparison_rule
from problems.notebook import comparison_line
from problems.templates import FAMILIES

N_VARIANTS = 200
N_PERMUTATIONS = 400
GEOMETRY_DECIDES = {"near_axis_stability", "asymmetric_free_top"}
"""Families whose scene names body axes by geometry, which decides the categorical answers."""

_NUMBER = re.compile(r"[-−+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


_SCIENTIFIC = re.compile(r"#\s*\\times\s*#\^\{#\}")


def mask(text: str) -> str:
    """``text`` with every number (sign, digits, decimals, exponents, and LaTeX's
    ``1.2 \\times 10^{-3}``) replaced by ``#``."""
    return _SCIENTIFIC.sub("#", _NUMBER.sub("#", text))


_variants: dict[str, list] = {}


def variants(family: str) -> list:
    """:data:`N_VARIANTS` variants of ``family`` (seeds 0, 1, …), drawn once per session."""
    if family not in _variants:
        module = FAMILIES[family]
        _variants[family] = [module.generate(np.random.default_rng(seed))
                             for seed in range(N_VARIANTS)]
    return _variants[family]


def asked_text(variant) -> str:
    """What the question asks, masked: its numbered items and each answer's public text."""
    items = [line for line in variant.statement.splitlines() if re.match(r"\d+\. ", line)]
    specs = [
        repr((a.name, a.kind, a.unit, a.description, a.options, a.symbols, a.points,
              comparison_rule(a)))
        for a in variant.answers
    ]
    return mask("\n".join([*items, *specs, comparison_line(variant.answers, 1)]))


def whole_text(variant) -> str:
    """Everything a student reads about this question, masked."""
    return asked_text(variant) + "\n" + mask(variant.statement)


def mutual_information(xs: list, ys: list) -> float:
    """Plug-in mutual information (nats) of two discrete samples of equal length."""
    n = len(xs)
    joint, px, py = Counter(zip(xs, ys, strict=True)), Counter(xs), Counter(ys)
    return sum(c / n * math.log(c * n / (px[x] * py[y])) for (x, y), c in joint.items())


def categorical(family: str) -> list[str]:
    return sorted({a.name for v in variants(family) for a in v.answers
                   if a.kind in ("boolean", "choice")})


def test_mutual_information_of_a_copy_and_of_independent_samples():
    """The estimator itself: a text that is the answer carries H(answer); a constant, none."""
    ys = [True, False] * 50
    assert mutual_information(ys, ys) == pytest.approx(math.log(2))
    assert mutual_information(["same"] * 100, ys) == 0.0


@pytest.mark.parametrize("family", list(FAMILIES))
def test_what_is_asked_is_the_same_text_in_every_variant(family):
    by_names = defaultdict(set)
    for v in variants(family):
        by_names[tuple(a.name for a in v.answers)].add(asked_text(v))
    differing = {names: texts for names, texts in by_names.items() if len(texts) > 1}
    assert differing == {}


def _has_categorical(family: str, seeds: range = range(5)) -> bool:
    module = FAMILIES[family]
    return any(a.kind in ("boolean", "choice")
               for s in seeds for a in module.generate(np.random.default_rng(s)).answers)


WITH_CATEGORICAL = tuple(f for f in FAMILIES if _has_categorical(f))
"""Families asking for a boolean or a choice (checked over all the variants below)."""


@pytest.mark.parametrize("family", [f for f in WITH_CATEGORICAL if f not in GEOMETRY_DECIDES])
def test_the_whole_text_says_no_more_about_a_categorical_answer_than_chance(family):
    rng = np.random.default_rng(13)
    texts = [whole_text(v) for v in variants(family)]
    for name in categorical(family):
        answers = [v.answer(name).value for v in variants(family)]
        assert len(set(answers)) > 1, f"{name}: every variant has the same answer"
        observed = mutual_information(texts, answers)
        null = [mutual_information(texts, list(rng.permutation(answers)))
                for _ in range(N_PERMUTATIONS)]
        assert observed <= np.quantile(null, 0.99), (name, observed, np.quantile(null, 0.99))


def test_families_with_categorical_answers_are_all_covered():
    """Every family with a boolean or choice answer in any of the variants is in one of the
    two tests above."""
    assert {f for f in FAMILIES if categorical(f)} == set(WITH_CATEGORICAL)
    assert set(WITH_CATEGORICAL) >= GEOMETRY_DECIDES
    assert set(WITH_CATEGORICAL) - GEOMETRY_DECIDES  # the permutation test has work to do


@pytest.mark.parametrize("family", sorted(GEOMETRY_DECIDES))
def test_where_geometry_decides_the_words_predict_the_answer_as_physics_does(family):
    """A box's width axis is its intermediate one (I_width = m(a² + c²)/12 lies between the
    others for a > b > c); the scene names it, and the answer follows from the moments."""
    seen = 0
    for v in variants(family):
        if "uniform box" not in v.statement:
            continue
        named = re.search(r"\\hat e_(\d)\$ along its width", v.statement)
        moments = [v.params[f"I{k}"] for k in (1, 2, 3)]
        middle = int(np.argsort(moments)[1]) + 1
        assert named is not None and int(named.group(1)) == middle
        if family == "near_axis_stability":
            assert [v.answer(f"stable{k}").value for k in (1, 2, 3)] == \
                [k != middle for k in (1, 2, 3)]
        seen += 1
    assert seen >= 20


def test_the_old_near_axis_leak_would_be_caught():
    """Before issue 13 the ``rate`` answer's unit and description told a stable spin (rad/s,
    "angular frequency of the wobble") from an unstable one (1/s, "growth rate"): rebuilt
    that way, both tests above flag it."""
    from dataclasses import replace

    leaky = []
    for v in variants("near_axis_stability"):
        axis = int(re.search(r"spun mainly about \$\\hat e_(\d)", v.statement).group(1))
        stable = v.answer(f"stable{axis}").value
        rate = replace(v.answer("rate"), unit="rad/s" if stable else "1/s",
                       description="angular frequency of the wobble" if stable
                       else "growth rate of the deviation")
        leaky.append((replace(v, answers=(*v.answers[:3], rate)), stable))
    assert len({asked_text(v) for v, _ in leaky}) == 2
    texts = [asked_text(v) for v, _ in leaky]
    spun_stable = [stable for _, stable in leaky]
    assert mutual_information(texts, spun_stable) == pytest.approx(
        mutual_information(spun_stable, spun_stable))  # the text tells it completely
