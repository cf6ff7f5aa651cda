"""The family contract: Parameter, the default draw, Family's checks, rejection, recomputing a key
from recorded parameters, and what an assignment's settings change (problems/family.py,
problems/settings.py)."""

from __future__ import annotations

import gc
import json
import math
import types

import numpy as np
import pytest

from eulertop_base import ParameterError
from problems.answers import Answer, Mistake
from problems.family import (
    Family,
    FamilyError,
    IllPosed,
    Parameter,
    batch_of_one,
    distinguishable,
    draw_parameters,
    drawn_scene,
    redrawn_many_until_well_posed,
    redrawn_until_well_posed,
    reject_unless,
    remembered,
    stacked_apart,
    stacked_distinguishable,
    stacked_dots,
    stacked_norms,
)
from problems.rounding import round_sig
from problems.settings import AnswerSetting, ParameterSetting, QuestionSettings
from problems.templates import FAMILIES

# --------------------------------------------------------------------------------------------
# Parameter


def test_a_parameter_draws_in_its_range_rounded_to_its_figures():
    p = Parameter(unit="m", low=0.2, high=2.0, figures=3)
    rng = np.random.default_rng(1)
    values = [p.draw(rng) for _ in range(500)]
    assert all(0.2 <= v <= 2.0 and round_sig(v, 3) == v for v in values)
    assert min(values) < 0.4 and max(values) > 1.8  # the whole range, not a corner of it
    assert p.draw(np.random.default_rng(7)) == p.draw(np.random.default_rng(7))


def test_a_vector_parameter_and_a_choice():
    vector = Parameter(unit="m", low=-1.0, high=1.0, figures=2, shape=(3,))
    value = vector.draw(np.random.default_rng(0))
    assert isinstance(value, list) and len(value) == 3
    assert all(round_sig(x, 2) == x for x in value)
    choice = Parameter(choices=("disc", "cone"))
    drawn = {choice.draw(np.random.default_rng(s)) for s in range(40)}
    assert drawn == {"disc", "cone"}
    assert choice.is_choice and choice.settable and not choice.in_cell


@pytest.mark.parametrize(("kwargs", "fragment"), [
    ({"low": 1.0}, "both low and high"),
    ({"low": 2.0, "high": 1.0}, "low <= high"),
    ({"low": 0.0, "high": math.inf}, "finite"),
    ({"figures": 0}, "figures"),
    ({"choices": ("a",), "low": 0.0, "high": 1.0}, "no range"),
    ({"choices": ("a", "")}, "non-empty"),
])
def test_bad_parameters_are_refused(kwargs, fragment):
    with pytest.raises(ValueError, match=fragment):
        Parameter(**kwargs)


@pytest.mark.parametrize(("value", "fragment"), [
    (0.1, "outside [0.2, 2.0]"),
    (0.7512, "more than 3 significant figures"),
    ([0.5, 0.6], "shape"),
    ("0.5", "expected a number"),
    (float("nan"), "finite"),
])
def test_what_is_wrong_with_a_value(value, fragment):
    p = Parameter(unit="m", low=0.2, high=2.0, figures=3)
    assert fragment in p.problem(value)
    assert p.problem(0.75) is None


def test_a_derived_parameter_is_not_settable():
    derived = Parameter(unit="kg m^2", figures=4)
    assert not derived.settable and derived.in_cell
    with pytest.raises(ValueError, match="no range"):
        derived.draw(np.random.default_rng(0))


def test_the_default_draw_draws_each_parameter_in_order():
    params = {"L": Parameter(low=1.0, high=2.0), "n": Parameter(choices=("a", "b"))}
    a, b = np.random.default_rng(3), np.random.default_rng(3)
    drawn = draw_parameters(a, params)
    assert list(drawn) == ["L", "n"]
    assert drawn["L"] == round_sig(b.uniform(1.0, 2.0), 3)  # the same stream, in order
    assert drawn["n"] == ("a", "b")[int(b.integers(2))]


# --------------------------------------------------------------------------------------------
# A family


def family(**changes) -> Family:
    """A falling-ball family (t = √(2h/g)) kept as a namespace, with ``changes``."""
    def answers(p):
        t = math.sqrt(2 * p["h"] / p["g"])
        return (Answer("t", "scalar", t, unit="s",
                       mistakes=(Mistake("no_root", 2 * p["h"] / p["g"], "a square root"),)),)

    attributes = dict(
        NAME="drop", TITLE="A dropped ball", SUMMARY="free fall: the time to fall h",
        PARAMETERS={"h": Parameter(unit="m", low=1.0, high=20.0),
                    "g": Parameter(unit="m/s^2", low=9.81, high=9.81),
                    "where": Parameter(choices=("a bridge", "a tower"))},
        answers=answers,
        statement=lambda p: f"A ball falls from {p['where']}, $h = {p['h']}$ m (`h`), "
                            f"$g = {p['g']}$ m/s² (`g`).\n\n1. `t`: the time of the fall.",
    )
    return Family(types.SimpleNamespace(**{**attributes, **changes}), origin="test")


def test_a_variant_has_the_cell_parameters_and_records_them_all():
    v = family().generate(np.random.default_rng(5))
    assert list(v.params) == ["h", "g"]  # the label is not a cell variable
    assert v.param_units == {"h": "m", "g": "m/s^2"}
    assert set(v.parameters) == {"h", "g", "where"}
    assert v.answers[0].value == pytest.approx(math.sqrt(2 * v.params["h"] / 9.81), rel=1e-15)
    assert v.title == "A dropped ball"


def test_a_key_is_recomputed_from_the_recorded_parameters():
    """The recorded parameters, through JSON, give the same variant: drawing is apart."""
    for name, found in FAMILIES.items():
        v = found.generate(np.random.default_rng(11))
        recorded = json.loads(json.dumps(v.to_dict()))["parameters"]
        assert found.variant(recorded) == v, name


def test_rejected_draws_are_drawn_again_from_the_same_generator():
    seen = []

    def draw(rng):
        h = round_sig(rng.uniform(1.0, 20.0), 3)
        seen.append(h)
        if len(seen) == 1:
            return None  # rejected by draw
        return {"h": h, "g": 9.81, "where": "a tower"}

    def answers(p):
        if len(seen) == 2:
            raise IllPosed("rejected by answers")
        return (Answer("t", "scalar", math.sqrt(2 * p["h"] / p["g"]), unit="s"),)

    v = family(draw=draw, answers=answers).generate(np.random.default_rng(0))
    assert len(seen) == 3 and v.params["h"] == seen[2]
    rng = np.random.default_rng(0)
    assert [round_sig(rng.uniform(1.0, 20.0), 3) for _ in range(3)] == seen


@pytest.mark.parametrize("seed", range(5))
def test_a_scene_is_drawn_by_one_integer_of_the_generator(seed):
    scenes = {"rod": None, "disc": None, "box": None}
    rng, twin = np.random.default_rng(seed), np.random.default_rng(seed)
    assert drawn_scene(scenes, rng) == ["rod", "disc", "box"][int(twin.integers(3))]
    assert rng.random() == twin.random()  # the next draw is the same: one integer was used


def test_a_batch_form_of_one_gives_its_result_or_raises_its_rejection():
    rejection = IllPosed("a mistake close to the key")

    def many(params):
        return [rejection if p["h"] < 0 else p["h"] * 2 for p in params]

    assert batch_of_one(many, {"h": 1.5}) == 3.0
    with pytest.raises(IllPosed) as raised:
        batch_of_one(many, {"h": -1.0})
    assert raised.value is rejection


def test_no_acceptable_draw_is_an_error_naming_the_family():
    with pytest.raises(RuntimeError, match="drop: no acceptable draw in 7 attempts"):
        family(draw=lambda rng: None, MAX_ATTEMPTS=7).generate(np.random.default_rng(0))


def test_distinguishable_rejects_a_mistake_close_to_the_key():
    def close():
        return (Answer("t", "scalar", 1.0, mistakes=(Mistake("near", 1.004, "?"),)),)

    with pytest.raises(IllPosed):
        distinguishable(close, 5.0)
    far = distinguishable(lambda: (Answer("t", "scalar", 1.0,
                                          mistakes=(Mistake("far", 2.0, "?"),)),), 5.0)
    assert far[0].mistakes[0].name == "far"


@pytest.mark.parametrize(("changes", "fragment"), [
    ({"answers": None}, "must be a function"),
    ({"NAME": "has space"}, "NAME must be a Python identifier"),
    ({"TITLE": "two\nlines"}, "TITLE must be one line"),
    ({"PARAMETERS": {"h": 1.0}}, "must be a Parameter"),
    ({"PARAMETERS": {"2h": Parameter(low=1.0, high=2.0)}}, "not a Python identifier"),
    ({"PARAMETERS": {"I1": Parameter(unit="kg m^2")}}, "neither a range nor choices"),
])
def test_a_broken_contract_is_a_family_error(changes, fragment):
    with pytest.raises(FamilyError, match=fragment):
        family(**changes)


def test_missing_names_are_listed():
    module = types.SimpleNamespace(NAME="x", TITLE="t", SUMMARY="s")
    with pytest.raises(FamilyError, match="must define PARAMETERS, answers, statement"):
        Family(module)


def test_undeclared_or_bad_drawn_parameters_are_refused():
    with pytest.raises(ValueError, match=r"not declared in PARAMETERS: \['x'\]"):
        family(draw=lambda rng: {"h": 1.0, "g": 9.81, "where": "a tower", "x": 1.0}) \
            .generate(np.random.default_rng(0))
    with pytest.raises(ValueError, match="'where' must be one of"):
        family(draw=lambda rng: {"h": 1.0, "g": 9.81, "where": "a cliff"}) \
            .generate(np.random.default_rng(0))


# --------------------------------------------------------------------------------------------
# What an assignment's settings change


def test_a_fixed_parameter_a_range_and_a_narrowed_choice():
    settings = QuestionSettings(parameters={
        "h": ParameterSetting(low=5.0, high=6.0),
        "g": ParameterSetting(value=9.81),
        "where": ParameterSetting(choices=("a tower",)),
    })
    variants = [family().generate(np.random.default_rng(s), settings) for s in range(60)]
    assert all(5.0 <= v.params["h"] <= 6.0 for v in variants)
    assert {v.parameters["where"] for v in variants} == {"a tower"}
    for v in variants:  # the key follows the values shown
        assert v.answers[0].value == pytest.approx(math.sqrt(2 * v.params["h"] / 9.81),
                                                   rel=1e-15)


def test_a_narrowed_label_excludes_draws_without_it_and_a_missing_number_is_left_out():
    """``box`` narrows inertia_tensor to boxes (point masses have none); ``h`` fixed for a
    sleeping top applies to the tops that have a thickness and leaves the disc alone."""
    boxes = QuestionSettings(parameters={"box": ParameterSetting(choices=("book",))})
    found = [FAMILIES["inertia_tensor"].generate(np.random.default_rng(s), boxes)
             for s in range(10)]
    assert {(v.parameters["scene"], v.parameters["box"]) for v in found} == {
        ("box_corner", "book")}
    thick = QuestionSettings(parameters={"h": ParameterSetting(value=0.03)})
    tops = [FAMILIES["sleeping_top"].generate(np.random.default_rng(s), thick)
            for s in range(30)]
    assert {v.parameters["top"] for v in tops} == {"disc", "solid_cylinder", "solid_cone"}
    assert all(v.params.get("h", 0.03) == 0.03 for v in tops)
    assert all("h" not in v.params for v in tops if v.parameters["top"] == "disc")


def test_answer_settings_points_and_tolerances():
    answers = (Answer("a", "scalar", 1.0, points=1.0),
               Answer("b", "scalar", 2.0, points=0.5, mistakes=(Mistake("x2", 4.0, "?"),)),
               Answer("c", "scalar", 3.0, points=2.0, mistakes=(Mistake("near", 3.03, "?"),)))
    settings = QuestionSettings(points=7.0, answers={"c": AnswerSetting(points=4.0, rtol=0.02)})
    a, b, c = settings.adjust_answers(answers)
    assert (a.points, b.points, c.points) == pytest.approx((2.0, 1.0, 4.0))  # 3 spread 2:1
    assert c.rtol == 0.02 and c.mistakes == ()  # 3.03 is now right: its feedback is dropped
    assert b.mistakes == answers[1].mistakes and b.rtol == answers[1].rtol


def test_settings_round_trip_through_the_manifest():
    settings = QuestionSettings(points=4.0, answers={"T": AnswerSetting(points=2.0, rtol=5e-3)},
                                parameters={"L": ParameterSetting(value=0.75),
                                            "m": ParameterSetting(low=0.2, high=0.5),
                                            "top": ParameterSetting(choices=("disc",))})
    again = QuestionSettings.from_dict(json.loads(json.dumps(settings.to_dict())))
    assert again == settings


def test_what_a_family_returns_is_checked_and_named():
    with pytest.raises(TypeError, match="statement\\(\\) must return text, got 3"):
        family(statement=lambda p: 3).generate(np.random.default_rng(0))
    with pytest.raises(TypeError, match="answers\\(\\) must return Answer records"):
        family(answers=lambda p: (1.0,)).generate(np.random.default_rng(0))
    with pytest.raises(FamilyError, match=r"CONVENTIONS \['tennis'\] are not topics"):
        family(CONVENTIONS=("tennis",))


# --------------------------------------------------------------------------------------------
# The batch form (issue 34)


def _batch_drop(seen: list) -> Family:
    """The falling ball with a batch form whose draw rejects every third student's first try
    and whose answers reject every draw with h < 5 m, counting its calls in ``seen``."""
    tries: dict[int, int] = {}

    def draw(rng):
        h = round_sig(rng.uniform(1.0, 20.0), 3)
        tries[id(rng)] = tries.get(id(rng), 0) + 1
        return None if tries[id(rng)] == 1 and h > 13.0 else {"h": h, "g": 9.81,
                                                              "where": "a tower"}

    def answers(p):
        if p["h"] < 5.0:
            raise IllPosed("too low")
        return family().module.answers(p)

    def draw_many(rngs):
        seen.append(("draw_many", len(rngs)))
        return [draw(rng) for rng in rngs]

    def answers_many(many):
        seen.append(("answers_many", len(many)))
        found = []
        for p in many:
            try:
                found.append(answers(p))
            except IllPosed as e:
                found.append(e)
        return found

    return family(draw=draw, answers=answers, draw_many=draw_many, answers_many=answers_many)


def test_a_batch_form_gives_each_student_the_variant_drawn_alone():
    """30 students drawn together, rejections by draw and by answers redrawn from each one's
    own generator in rounds, equal those drawn one at a time — with settings too."""
    settings = QuestionSettings(parameters={"h": ParameterSetting(low=2.0, high=19.0)})
    for given in (None, settings):
        seen: list = []
        batch = _batch_drop(seen)
        together = batch.generate_many([np.random.default_rng(s) for s in range(30)], given)
        alone = [_batch_drop([]).generate(np.random.default_rng(s), given) for s in range(30)]
        assert [v.to_dict() for v in together] == [v.to_dict() for v in alone]
        assert batch.batched and seen[0] == ("draw_many", 30)
        assert len(seen) > 2 and seen[-1][1] < 30  # later rounds: only the rejected again


def test_generate_many_without_a_batch_form_draws_one_at_a_time():
    plain = family()
    assert not plain.batched
    together = plain.generate_many([np.random.default_rng(s) for s in range(5)])
    assert together == [plain.generate(np.random.default_rng(s)) for s in range(5)]


def test_a_batch_form_that_loses_a_student_is_refused():
    short = family(answers_many=lambda many: [family().module.answers(p) for p in many[1:]])
    with pytest.raises(TypeError, match=r"answers_many\(\) must return one element per student "
                                        r"\(3\), got 2"):
        short.generate_many([np.random.default_rng(s) for s in range(3)])


@pytest.mark.parametrize("name", [n for n, f in FAMILIES.items() if f.batched])
def test_a_built_in_batch_form_gives_the_variants_drawn_alone(name):
    """Each built-in family with a batch form: 60 students together, bit for bit the
    variants of one at a time (the solver called on all of them at once)."""
    found = FAMILIES[name]
    together = found.generate_many([np.random.default_rng([7, s]) for s in range(60)])
    alone = [found.generate(np.random.default_rng([7, s])) for s in range(60)]
    assert [v.to_dict() for v in together] == [v.to_dict() for v in alone]


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_a_class_drawn_at_once_leaves_nothing_for_the_cycle_collector(name):
    """A rejected draw's IllPosed is kept without its traceback, whose frames hold the batch:
    40 students drawn with the collector off are freed by reference counting alone (with the
    tracebacks, each batch of 150 left ~60 000 objects that a collection had to walk). Drawn
    twice: the first time may leave cycles once (sympy's caches filling)."""
    found = FAMILIES[name]
    found.generate_many([np.random.default_rng([11, s]) for s in range(40)])
    gc.collect()
    gc.disable()
    try:
        drawn = found.generate_many([np.random.default_rng([11, s]) for s in range(40)])
        assert len(drawn) == 40
        del drawn
        assert gc.collect() == 0
    finally:
        gc.enable()


def test_a_batch_drawn_question_keeps_the_written_parts_its_settings_ask_for():
    """turning_points has a batch form and a written part: drawn together for 12 students with
    ``written = true``, each variant equals the one drawn alone, written part included."""
    from problems.templates import FAMILIES

    family = FAMILIES["turning_points"]
    assert family.batched
    settings = QuestionSettings(written=True)
    together = family.generate_many([np.random.default_rng(s) for s in range(12)], settings)
    alone = [family.generate(np.random.default_rng(s), settings) for s in range(12)]
    assert [v.to_dict() for v in together] == [v.to_dict() for v in alone]
    assert all(any(a.kind == "written" for a in v.answers) for v in together)


def test_redrawn_together_draws_what_each_student_draws_alone():
    """A round of tries for the whole class (issue 34) gives each student the draw it gets
    alone — a draw rejected at once (None), or by the test, or never accepted within the
    tries (None) — and leaves each generator where drawing alone leaves it."""

    def draw_once(rng):
        x = float(rng.uniform())
        return None if x < 0.3 else {"x": x}

    def posed(params):
        reject_unless(params["x"] > 0.8, "too small")

    def posed_many(many):
        return [IllPosed("too small") if p["x"] <= 0.8 else None for p in many]

    alone_rngs = [np.random.default_rng([5, s]) for s in range(200)]
    together_rngs = [np.random.default_rng([5, s]) for s in range(200)]
    alone = [redrawn_until_well_posed(draw_once, posed, rng, 4) for rng in alone_rngs]
    together = redrawn_many_until_well_posed([draw_once] * 200, posed_many, together_rngs, 4)
    assert together == alone
    assert None in alone and any(p is not None for p in alone)  # both ends exercised
    assert [r.uniform() for r in together_rngs] == [r.uniform() for r in alone_rngs]


def test_stacked_products_are_numpy_s_of_each_vector_bit_for_bit():
    """stacked_dots and stacked_norms equal numpy.dot and numpy.linalg.norm of each vector
    exactly (an einsum sum would not), and stacked_apart tests every pair."""
    rng = np.random.default_rng(3)
    u, v = rng.normal(size=(500, 3)) * 1e3, rng.normal(size=(500, 3))
    assert stacked_dots(u, v).tolist() == [float(np.dot(a, b)) for a, b in zip(u, v, strict=True)]
    assert stacked_norms(u).tolist() == [float(np.linalg.norm(a)) for a in u]
    values = np.array([[[1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0]],
                       [[1.0, 0, 0], [3.0, 0, 0], [1.5, 0, 0]]])
    assert stacked_apart(values, np.array([0.9, 0.9])).tolist() == [True, False]


def test_stacked_distinguishable_is_the_verdict_of_the_answer_built():
    """stacked_distinguishable gives, row by row, mistakes_distinguishable's verdict on the
    scalar answer built from the row (key first, then its mistakes; an answer that refuses a
    mistake next to its key rejected alike), values set on the edge of the widened tolerances
    included."""
    from problems.answers import mistakes_distinguishable

    rng = np.random.default_rng(5)
    key = rng.uniform(0.5, 2.0, 3000)
    signs = rng.choice([-1.0, 1.0], (3000, 4))
    values = np.concatenate([key[:, None], key[:, None] * (1 + signs * rng.uniform(0, 0.06,
                                                                                   (3000, 4)))],
                            axis=1)
    values[::3, 2] = values[::3, 1] + 0.005 * np.abs(values[::3, 1])  # on the edge
    expected = []
    for row in values.tolist():
        try:
            answer = Answer("x", "scalar", row[0], rtol=1e-3, mistakes=tuple(
                Mistake(f"m{k}", v, "why") for k, v in enumerate(row[1:])))
        except ParameterError:
            expected.append(False)
        else:
            expected.append(mistakes_distinguishable(answer, 5.0))
    assert stacked_distinguishable(values, 5.0 * 1e-3).tolist() == expected
    assert 0 < sum(expected) < len(expected)  # both verdicts exercised


@pytest.mark.parametrize("name", ["asymmetric_free_top", "near_axis_stability"])
def test_a_class_drawn_at_once_keeps_each_student_s_variant(name):
    """A family drawing the class at once (draw_many and answers_many: the bodies, the solver
    and the test of the mistakes stacked): 600 students in batches of 32, bit for bit the
    variants drawn one at a time, each generator left where drawing alone leaves it."""
    found = FAMILIES[name]
    together_rngs = [np.random.default_rng([9, s]) for s in range(600)]
    alone_rngs = [np.random.default_rng([9, s]) for s in range(600)]
    together = [v for k in range(0, 600, 32)
                for v in found.generate_many(together_rngs[k:k + 32])]
    alone = [found.generate(rng) for rng in alone_rngs]
    assert [v.to_dict() for v in together] == [v.to_dict() for v in alone]
    assert [r.uniform() for r in together_rngs] == [r.uniform() for r in alone_rngs]


def test_remembered_works_again_for_other_parameters_only():
    """A draw's accepted try and answers() share one computation (issue 34): equal parameters
    get the remembered result; any other value, type or sign of zero is worked out again, and
    a rejection (IllPosed) is not remembered."""
    calls = []

    def work(params):
        calls.append(dict(params))
        if params["x"] == 2.0:
            raise IllPosed("rejected")
        return [params["x"], params.get("v")]

    once = remembered(work)
    first = once({"x": 1.0, "v": [0.0, 1.0]})
    assert once({"x": 1.0, "v": [0.0, 1.0]}) is first and len(calls) == 1
    for other in ({"x": 1, "v": [0.0, 1.0]}, {"x": 1.0, "v": [-0.0, 1.0]},
                  {"x": 1.0, "v": (0.0, 1.0)}, {"x": 1.0}):
        assert once(other) == work(other) and once(other) is not first
    assert len(calls) == 9
    for _ in range(2):
        with pytest.raises(IllPosed):
            once({"x": 2.0})
    assert len(calls) == 11
