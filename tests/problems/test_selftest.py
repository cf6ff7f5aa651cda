"""`eulertop problems test`: a sound family passes every check; each way a family can be wrong is
caught by its own check, with the seed that reproduces it; every built-in family passes (this is
how CI runs the command over them)."""

from __future__ import annotations

import math
import types
from pathlib import Path

import numpy as np
import pytest

import problems.selftest as selftest
from eulertop import family_example
from eulertop.cli import main
from grader.selftest_run import grade_solutions
from problems.answers import Answer, Mistake
from problems.family import Family, Parameter
from problems.family_files import load_family_file
from problems.rounding import latex_sig
from problems.selftest import CHECKS, leaked_values, misprinted, printed_for, readings, self_test
from problems.templates import FAMILIES

from .family_sources import pendulum, write_family


def self_test_graded(family, seeds, **options):
    """The self-test as `eulertop problems test` runs it: its solutions notebook run and
    graded by the grader (handed in as the front end does)."""
    return self_test(family, seeds, grade_solutions=grade_solutions, **options)


SEEDS = range(12)


def falling(**changes) -> Family:
    """A sound family (a ball dropped from h: t = √(2h/g)), with ``changes`` to break it."""
    params = {"h": Parameter(unit="m", low=1.0, high=20.0),
              "g": Parameter(unit="m/s^2", low=9.81, high=9.81)}

    def answers(p):
        t = math.sqrt(2 * p["h"] / p["g"])
        return (Answer("t", "scalar", t, unit="s", description="time of the fall",
                       mistakes=(Mistake("missing_2", math.sqrt(p["h"] / p["g"]),
                                         "h = g t²/2: the 2 is missing."),)),)

    def statement(p):
        return (f"A ball is dropped from $h = {p['h']:g}$ m (`h`); $g = {p['g']:g}$ m/s² "
                "(`g`).\n\n1. `t`: how long it falls.")

    attributes = dict(NAME="falling", TITLE="A dropped ball", SUMMARY="free fall (test)",
                      PARAMETERS=params, answers=answers, statement=statement)
    return Family(types.SimpleNamespace(**{**attributes, **changes}), origin="test")


def failures(report, check: str) -> tuple[int, tuple[str, ...]]:
    result = next(c for c in report.checks if c.name == check)
    return result.failed, result.failures


def only_failing(report) -> set[str]:
    return {c.name for c in report.checks if c.failed}


def test_a_sound_family_passes_every_check():
    report = self_test_graded(falling(), SEEDS)
    assert report.passed, [c for c in report.checks if c.failed]
    assert [c.name for c in report.checks] == list(CHECKS)
    assert all(c.passed == len(SEEDS) for c in report.checks)
    assert "sandboxed" in report.checks[-1].note


def test_the_worked_example_and_an_outside_file_pass_as_written(tmp_path):
    assert self_test_graded(load_family_file(Path(family_example.__file__)), range(40)).passed
    path = write_family(tmp_path, "pendulum.py", pendulum())
    assert self_test_graded(load_family_file(path), range(40)).passed


def test_a_draw_from_global_randomness_is_caught():
    import random

    def draw(rng):
        return {"h": round(random.uniform(1.0, 20.0), 1), "g": 9.81}

    report = self_test_graded(falling(draw=draw), SEEDS)
    count, shown = failures(report, "same seed, same variant")
    assert count > 0 and shown[0].startswith("seed 0: drawn twice, the variants differ")


def test_a_statement_using_what_the_draw_left_behind_is_caught():
    """The statement reads a module variable the draw set, not the parameters: the key cannot
    be recomputed from the recorded parameters."""
    left = {}

    def draw(rng):
        left["where"] = ["a bridge", "a tower"][int(rng.integers(2))]
        return {"h": round(rng.uniform(1.0, 20.0), 1), "g": 9.81}

    def statement(p):
        return f"A ball is dropped from {left['where']}, $h = {p['h']:g}$ m (`h`), (`g`)."

    report = self_test_graded(falling(draw=draw, statement=statement), range(20))
    count, shown = failures(report, "key recomputed from its parameters")
    assert count > 0 and "'statement' differs" in shown[0]
    assert only_failing(report) == {"key recomputed from its parameters"}


def test_an_answer_written_in_the_statement_is_caught():
    def statement(p):
        t = math.sqrt(2 * p["h"] / p["g"])
        return (f"A ball is dropped from $h = {p['h']:g}$ m (`h`), $g$ (`g`) = {p['g']}; "
                f"it lands after about {t:.3g} s.")

    report = self_test_graded(falling(statement=statement), SEEDS)
    count, shown = failures(report, "no answer value in the statement")
    assert count == len(SEEDS)
    assert "answer 't' =" in shown[0] and "written in the statement" in shown[0]


def test_leaks_are_readings_of_the_answer_not_parameters_or_list_numbers():
    assert {1.23, 1.235, 1.2, 1.0, 1.2346} <= readings(1.23456)
    v = falling().generate(np.random.default_rng(0))
    assert leaked_values(v) == []
    assert 0.0 not in readings(0.0004)  # zero is never a reading


PRINTED = "parameters printed as in the cell"


def test_a_parameter_printed_with_fewer_digits_than_its_cell_is_caught():
    """The issue's case: the cell (and the key) has h = 12.3, the statement prints 12 — a
    student using the printed number is 2.4 % off a 0.1 % tolerance. Run without the grader:
    only this check and the sandbox's (not run) fail."""
    def statement(p):
        return (f"A ball is dropped from $h = {p['h']:.2g}$ m (`h`); $g = {p['g']:g}$ m/s² "
                "(`g`).\n\n1. `t`: how long it falls.")

    seeds = range(20)
    report = self_test(falling(statement=statement), seeds)
    drawn = {s: falling().generate(np.random.default_rng(s)).parameters["h"] for s in seeds}
    shortened = [s for s, h in drawn.items() if float(f"{h:.2g}") != h]
    count, shown = failures(report, PRINTED)
    assert count == len(shortened) > 0
    first, h = shortened[0], drawn[shortened[0]]
    assert shown[0] == (f"seed {first}: parameter h is printed as '{h:.2g}' but the parameter "
                        f"cell holds {h!r}")
    assert only_failing(report) == {PRINTED, CHECKS[-1]}


def tiny_marker(shown_figures: int) -> Family:
    """A family whose vector parameter prints in LaTeX powers of ten (``4.2 \\times 10^{-5}``)
    with ``shown_figures`` figures, followed by its unit; the cell holds 3."""
    def statement(p):
        r = ",\\ ".join(latex_sig(x, shown_figures) for x in p["r"])
        return f"A marker sits at $\\mathbf r = ({r})$ m (`r`).\n\n1. `s`: its mean coordinate."

    return Family(types.SimpleNamespace(
        NAME="marker", TITLE="A marker", SUMMARY="a vector parameter (test)",
        PARAMETERS={"r": Parameter(unit="m", low=1e-5, high=9e-5, shape=(3,), figures=3)},
        answers=lambda p: (Answer("s", "scalar", sum(p["r"]) / 3, unit="m"),),
        statement=statement), origin="test")


@pytest.mark.parametrize("seed", range(4))
def test_each_component_of_a_vector_in_latex_is_compared_with_the_cell(seed):
    variant = tiny_marker(2).generate(np.random.default_rng(seed))
    r = variant.parameters["r"]
    expected = [f"parameter r[{k}] is printed as {latex_sig(x, 2)!r} but the parameter cell "
                f"holds {x!r}" for k, x in enumerate(r) if float(f"{x:.1e}") != x]
    assert expected and misprinted(tiny_marker(2), variant) == expected
    assert misprinted(tiny_marker(3), tiny_marker(3).generate(np.random.default_rng(seed))) == []


def test_fixed_numbers_near_a_parameter_are_not_taken_for_it():
    """12, 10 and the list's 1. and 2. are roundings of h = 12.3 but do not change with it."""
    def statement(p):
        return (f"1. A ball is dropped from $h = {p['h']:g}$ m (`h`), off a 12 m wall 10 m "
                f"from the road; $g = {p['g']:g}$ m/s² (`g`).\n\n2. `t`: how long it falls.")

    family = falling(draw=lambda rng: {"h": 12.3, "g": 9.81}, statement=statement)
    variant = family.generate(np.random.default_rng(0))
    assert [p.text for p in printed_for(family, variant.parameters, "h")] == ["12.3"]
    assert misprinted(family, variant) == []


def test_a_parameter_rounded_to_a_whole_number_is_caught():
    family = falling(draw=lambda rng: {"h": 3.04, "g": 9.81},
                     statement=lambda p: f"1. Dropped from {round(p['h'])} m (`h`), g (`g`).")
    assert misprinted(family, family.generate(np.random.default_rng(0))) == [
        "parameter h is printed as '3' but the parameter cell holds 3.04"]


def test_a_statement_that_cannot_take_the_doubled_value_is_checked_with_it_halved():
    def statement(p):
        if p["h"] > 20:
            raise ValueError("too high a drop")
        return f"Dropped from $h = {p['h']:.2g}$ m (`h`); g (`g`)."

    family = falling(draw=lambda rng: {"h": 12.3, "g": 9.81}, statement=statement)
    variant = family.generate(np.random.default_rng(0))
    assert misprinted(family, variant) == [
        "parameter h is printed as '12' but the parameter cell holds 12.3"]

    def only_as_drawn(p):
        if p["h"] != 12.3:
            raise ValueError("not the drop this statement was written for")
        return f"Dropped from $h = {p['h']:g}$ m (`h`); g (`g`)."

    stubborn = falling(draw=lambda rng: {"h": 12.3, "g": 9.81}, statement=only_as_drawn)
    with pytest.raises(ValueError, match="cannot be rendered with h doubled or halved"):
        misprinted(stubborn, stubborn.generate(np.random.default_rng(0)))


def test_two_mistakes_the_grader_cannot_tell_apart_are_caught():
    def answers(p):
        t = math.sqrt(2 * p["h"] / p["g"])
        return (Answer("t", "scalar", t, unit="s", mistakes=(
            Mistake("double", 2 * t, "twice"), Mistake("also_double", 2 * t, "twice again"))),)

    report = self_test_graded(falling(answers=answers), SEEDS)
    count, shown = failures(report, "known mistakes outside the tolerance")
    assert count == len(SEEDS) and "'also_double' is graded wrong as 'double'" in shown[0]


@pytest.mark.parametrize(("changes", "fragment"), [
    ({"draw": lambda rng: {"h": 50.0, "g": 9.81}}, "parameter h: 50.0 is outside [1.0, 20.0]"),
    ({"draw": lambda rng: {"h": 2.0, "g": 9.81, "x": 1.0}}, "not declared in PARAMETERS"),
    ({"draw": lambda rng: None, "MAX_ATTEMPTS": 5}, "no acceptable draw in 5 attempts"),
    ({"answers": lambda p: (Answer("t", "scalar", p["x"]),)}, "answers() raised KeyError"),
    ({"answers": lambda p: (Answer("t", "scalar", 1.0,
                                   mistakes=(Mistake("close", 1.0001, "?"),)),)},
     "answers() raised ParameterError"),
    ({"statement": lambda p: 1 / 0}, "statement() raised ZeroDivisionError"),
    ({"statement": lambda p: None}, "statement() must return text, got None"),
])
def test_a_draw_that_is_neither_well_posed_nor_rejected_is_caught(changes, fragment):
    report = self_test_graded(falling(**changes), range(3))
    count, shown = failures(report, "draws well posed or rejected")
    assert count == 3 and shown[0].startswith("seed 0: ") and fragment in shown[0], shown


def test_a_typed_tolerance_is_caught():
    def statement(p):
        return "A ball is dropped from $h$ (`h`), $g$ (`g`); answer to a 1 % tolerance."

    count, shown = failures(self_test_graded(falling(statement=statement), SEEDS),
                            "every tolerance stated in the notebook")
    assert count == len(SEEDS) and "types a tolerance" in shown[0]


def _chained(degenerate) -> Family:
    """The dropped ball asking, after t, the speed v = g t from the student's own t."""
    from problems.family import follows_from

    def answers(p):
        t = math.sqrt(2 * p["h"] / p["g"])
        return (Answer("t", "scalar", t, unit="s"),
                follows_from(Answer("v", "scalar", p["g"] * t, unit="m/s"), "t"))

    def statement(p):
        return (f"A ball is dropped from $h = {p['h']:g}$ m (`h`); $g = {p['g']:g}$ m/s² "
                "(`g`).\n\n1. `t`: how long it falls;\n2. `v`: its speed then, from your t.")

    return falling(answers=answers, statement=statement, degenerate=degenerate,
                   follow=lambda name, p, earlier: p["g"] * earlier["t"])


def test_a_degenerate_that_refuses_the_key_s_own_values_is_caught():
    check = "follow-through gives back the key"
    sound = _chained(lambda name, p, earlier: "your {t} is zero" if earlier["t"] == 0 else None)
    assert failures(self_test(sound, range(3)), check)[0] == 0
    refusing = _chained(lambda name, p, earlier: "your {t} is a guess")
    count, shown = failures(self_test(refusing, range(3)), check)
    assert count == 3
    assert shown[0] == "seed 0: degenerate('v') calls the key's own values degenerate: your " \
                       "{t} is a guess"


def test_a_slow_family_is_caught(monkeypatch):
    monkeypatch.setattr(selftest, "MAX_SECONDS", 0.0)
    count, shown = failures(self_test_graded(falling(), range(3)), "time per variant")
    assert count == 3 and shown[0].startswith("seed 0: took ")


def test_a_solutions_notebook_that_loses_marks_is_caught_with_its_seed(monkeypatch):
    """The sandboxed run really compares: tamper with the second question's answer cell."""
    real = selftest.build_notebook

    def tampered(*args, **kwargs):
        nb = real(*args, **kwargs)
        if kwargs.get("solutions"):  # the notebook that runs, not the one read for its words
            cell = next(c for c in nb["cells"] if c["id"] == "q2-answer")
            cell["source"] = ["q2_t = -1.0\n"]
        return nb

    monkeypatch.setattr(selftest, "build_notebook", tampered)
    report = self_test_graded(falling(), [4, 5, 6])
    count, shown = failures(report, "solutions get full marks (sandbox)")
    assert count == 1 and shown[0].startswith("seed 5: q2_t: wrong")
    assert only_failing(report) == {"solutions get full marks (sandbox)"}


def test_the_command_prints_a_table_and_exits_1_naming_the_seed(tmp_path, capsys):
    """A family written outside the package whose statement gives the period away."""
    leak = ("f\"2. `T`: its period for small swings, about "
            "{2 * math.pi * math.sqrt(2 * p['L'] / (3 * p['g'])):.3g} s.\"")
    source = pendulum("leaky").replace('"2. `T`: its period for small swings."', leak)
    assert leak in source
    path = write_family(tmp_path, "leaky.py", source)
    assert main(["problems", "test", str(path), "--seeds", "5"]) == 1
    out = capsys.readouterr().out
    assert out.startswith(f"eulertop problems test leaky ({path}): 5 seed(s)")
    row = next(line for line in out.splitlines()
               if line.startswith("no answer value in the statement"))
    assert row.split()[-2:] == ["0", "5"]
    assert "FAILED no answer value in the statement: 5 time(s)" in out
    assert "  seed 0: answer 'T' = " in out


def test_the_command_names_a_parameter_printed_otherwise_than_its_cell(tmp_path, capsys):
    """An instructor's own file printing L with two figures while the cell holds three."""
    source = pendulum("shortened").replace("{p['L']:g}", "{p['L']:.2g}")
    assert "{p['L']:.2g}" in source
    path = write_family(tmp_path, "shortened.py", source)
    assert main(["problems", "test", str(path), "--seeds", "5"]) == 1
    out = capsys.readouterr().out
    family = load_family_file(path)
    lengths = {s: family.generate(np.random.default_rng(s)).parameters["L"] for s in range(5)}
    first, L = next((s, L) for s, L in lengths.items() if float(f"{L:.2g}") != L)
    assert (f"  seed {first}: parameter L is printed as '{L:.2g}' but the parameter cell holds "
            f"{L!r}") in out.splitlines()
    assert f"FAILED {PRINTED}:" in out


def test_the_command_refuses_an_unknown_family(capsys):
    assert main(["problems", "test", "no_such_family"]) == 2
    assert "unknown family 'no_such_family'" in capsys.readouterr().err


@pytest.mark.parametrize("name", list(FAMILIES))
def test_every_built_in_family_passes_the_command(name, capsys):
    """What CI runs: `eulertop problems test NAME` (100 seeds; every solution in the sandbox)."""
    assert main(["problems", "test", name]) == 0, capsys.readouterr().out
    out = capsys.readouterr().out
    assert out.splitlines()[0] == f"eulertop problems test {name} (built-in): 100 seed(s)"
    assert out.rstrip().endswith("all checks passed")
    assert "sandboxed" in out


def test_without_a_grader_the_full_marks_check_fails_as_not_run():
    """``problems/`` cannot run a notebook itself (the grader is a floor above it): without the
    grader handed in, the sandbox check is never counted as passed."""
    report = self_test(falling(), range(3))
    check = next(c for c in report.checks if c.name == CHECKS[-1])
    assert not report.passed and check.failed and "not run" in " ".join(check.failures)
