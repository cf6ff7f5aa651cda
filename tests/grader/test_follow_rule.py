"""Follow-through credit by the marker's rule (issue 30): credit where the earlier values are a
genuine attempt, none for a physics-free submission, and no key change that takes it away.

The rule is exercised through :meth:`grader.follow_through.FollowThrough.apply`, the one entry
of grading and rescoring, on variants of the nine built-in families with a chain, and on a
graded class (fake execution stage: each submission's answers are the literals its code cell
assigns). What a student submits is built here from the key's values, its known mistakes and
the statements' definitions (the family's ``follow`` only computes the later answer a student
who worked it out from their own value would write).
"""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from grader.compare import KeyAnswer, compare
from grader.follow_through import FollowThrough
from grader.pipeline import grade_assignment
from grader.rescore import rescore
from grader.results import StudentResult, read_result
from problems.answers import Answer, Mistake
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute, literal_notebook

CHAIN_FAMILIES = ("sleeping_top", "symmetric_free_top", "heavy_top_constants",
                  "inertia_tensor", "energy_momentum", "euler_rotation", "steady_precession",
                  "motion_type", "symbolic_derivation")
DEGENERATE_BY_DESIGN = {  # named mistakes whose value leaves nothing to work out (docstrings)
    ("inertia_tensor", "parallel_axis_forgotten"),  # a box about its centre: no products
    ("energy_momentum", "untilted"),  # L along the axle: parallel to ω, angle 0
    ("steady_precession", "fast_top"), ("steady_precession", "exact"),  # slow == slow_approx
}


def _plain(value):
    return value.tolist() if hasattr(value, "tolist") else value


@pytest.fixture(scope="module")
def follow() -> Iterator[FollowThrough]:
    """One follow-through (one worker) for this module's students, registered as they come."""
    f = FollowThrough({}, {})
    yield f
    f.close()


def _graded(follow: FollowThrough, family: str, variant, submitted: dict,
            answers: tuple[Answer, ...] | None = None) -> StudentResult:
    """``submitted`` (answer name → value) compared with ``variant``'s key (or ``answers``)
    and credited, as one question of a student of its own."""
    sid = f"s{len(follow.students)}"
    follow.students[sid] = {"questions": [{"family": family, "parameters": variant.parameters,
                                           "params": variant.params,
                                           "param_units": variant.param_units}]}
    expected = [KeyAnswer(f"q1_{a.name}", 1, a) for a in answers or variant.answers]
    compared = compare(expected, {f"q1_{n}": v for n, v in submitted.items()})
    record = StudentResult(sid, "graded", "", compared, sum(a.verdict.points for a in compared),
                           sum(k.answer.points for k in expected), None, "sha256:x", {}, False,
                           "")
    return follow.apply(record, expected)


def _verdicts(record: StudentResult) -> dict:
    return {a.name: a.verdict for a in record.answers}


def _variants(family: str, count: int = 12) -> Iterator:
    for seed in range(count):
        yield seed, FAMILIES[family].generate(np.random.default_rng(seed))


def _with(variant, changed: dict) -> tuple[dict, list[str]] | None:
    """The key's values with ``changed`` (earlier answers), every later answer that depends on
    one of them recomputed from them; and those later answers' names. None when a
    recomputation leaves the physics (raises) or gives the key's own later answer back."""
    family = FAMILIES[variant.family]
    values = {a.name: a.value for a in variant.answers} | changed
    later = [a for a in variant.answers if set(a.depends_on) & set(changed)]
    for a in later:
        try:
            values[a.name] = _plain(family.follow(a.name, variant.parameters,
                                                  {n: values[n] for n in a.depends_on}))
        except (ValueError, ZeroDivisionError):
            return None
        if compare([KeyAnswer("x", 1, a)], {"x": values[a.name]})[0].verdict.status \
                == "correct":
            return None
    return (values, [a.name for a in later]) if later else None


# -- genuine attempts earn it


def _named_mistakes(variant) -> Iterator[dict]:
    """Each known mistake of an earlier answer (as the key lists it), one at a time."""
    earlier = {n for a in variant.answers for n in a.depends_on}
    for a in variant.answers:
        if a.name in earlier:
            for m in a.mistakes:
                if (variant.family, m.name) not in DEGENERATE_BY_DESIGN:
                    yield {a.name: m.value}


def _plausible(variant, off: float = 0.05) -> Iterator[dict]:
    """Wrong earlier values a student might reach, no known mistake: ``off`` (5 %) off the
    key's (a vector: one component off by that much of the largest; an expression: a factor;
    a rotation: turned by that much more, in rad), and, where the later answer is a boolean or
    a choice, what changes it: the critical spin across the given one, a rate's sign."""
    key = {a.name: a.value for a in variant.answers}
    p = variant.parameters
    if variant.family == "sleeping_top":  # the given spin on the other side of the student's
        yield {"omega3_c": p["omega3"] * (1 + off if p["omega3"] >= key["omega3_c"] else 1 - off)}
        return
    if variant.family == "motion_type":  # a turning point's rate of the other sign
        yield {"alpha_dot2": -(1 + off) * key["alpha_dot2"]}
        return
    if variant.family == "euler_rotation":  # a rotation turned a little more about ê3
        c, s = math.cos(off), math.sin(off)
        turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        yield {"R": (turn @ np.reshape(key["R"], (3, 3))).ravel().tolist()}
        return
    for name in sorted({n for a in variant.answers for n in a.depends_on}):
        value = key[name]
        if isinstance(value, str):
            yield {name: f"{1 + off}*({value})"}
        elif isinstance(value, list):
            out = list(value)
            out[1] += off * max(abs(v) for v in value)
            yield {name: out}
        else:
            yield {name: value * (1 + off)}


@pytest.mark.parametrize("family", CHAIN_FAMILIES)
@pytest.mark.parametrize("attempt", [_named_mistakes, _plausible], ids=["named", "plausible"])
def test_genuine_wrong_attempts_earn_follow_through(follow, family, attempt: Callable):
    credited = 0
    for seed, variant in _variants(family):
        for changed in attempt(variant):
            made = _with(variant, changed)
            if made is None:
                continue
            values, later = made
            verdicts = _verdicts(_graded(follow, family, variant, values))
            for name in later:
                v = verdicts[name]
                assert (v.status, v.points) == ("follows", v.max_points), (seed, changed,
                                                                           v.message)
                assert "follows from your q1_" in v.message
                credited += 1
    assert credited >= 3, f"{family}: only {credited} later answers tried"


# -- no key change lowers the credit


def _widened(answer: Answer, rtol: float) -> Answer:
    """``answer`` with the tolerance ``rtol``, as ``eulertop key set --rtol`` leaves it (the
    known mistakes it now accepts dropped)."""
    wide = Answer(**{**answer.to_dict(), "rtol": rtol, "mistakes": ()})
    kept = tuple(m for m in answer.mistakes
                 if compare([KeyAnswer("x", 1, wide)], {"x": m.value})[0].verdict.status
                 != "correct")
    return Answer(**{**answer.to_dict(), "rtol": rtol,
                     "mistakes": tuple(Mistake(**m.__dict__) for m in kept)})


RTOLS = (3e-3, 0.01, 0.03, 0.08, 0.2)


@pytest.mark.parametrize("family", CHAIN_FAMILIES)
def test_widening_an_earlier_tolerance_never_lowers_the_later_points(follow, family):
    """Earlier values a little off (:func:`_plausible`: 2 %, and 1e-4, right already) with the
    later answer worked out from them; the earlier answers' tolerances widened step by step
    (which turns them right at some step): the later answer's points and the total never go
    down."""
    tried = 0
    for seed, variant in _variants(family, 8):
        for off in (0.02, 1e-4):
            for changed in _plausible(variant, off):
                made = _with(variant, changed)
                if made is None:
                    continue
                values, later = made
                before = _graded(follow, family, variant, values)
                for rtol in RTOLS:
                    answers = tuple(_widened(a, rtol) if a.name in changed else a
                                    for a in variant.answers)
                    after = _graded(follow, family, variant, values, answers)
                    for name in later:
                        assert _verdicts(after)[name].points >= \
                            _verdicts(before)[name].points, \
                            (seed, off, rtol, _verdicts(after)[name].message)
                    assert after.points >= before.points
                    before = after
                tried += 1
    assert tried >= 3


def _scaled(value, factor: float):
    return [x * factor for x in value] if isinstance(value, list) else value * factor


# -- a physics-free submission earns nothing


def _physics_free(family: str, key: dict, params: dict) -> dict:
    """One fixed rule per family, the same for every student, that needs no physics: products
    of inertia 0 with the moments and axis read off the diagonal; R = identity with the given
    vector copied; both precession rates 0 with "cusps"; ω3c = 0 with "stable"; ω3 copied for
    Ω; L along ω with angle 0; slow = slow_approx with error 0; p_γ = 0 with E' = E; a given
    symbol for the expression with its number."""
    if family == "inertia_tensor":
        diag = key["I_diag"]
        axis = [0.0, 0.0, 0.0]
        axis[int(np.argmax(diag))] = 1.0
        return {"I_diag": diag, "I_offdiag": [0.0, 0.0, 0.0], "moments": sorted(diag),
                "axis_max": axis}
    if family == "euler_rotation":
        copied = {"r_lab": "r_body", "F_body": "F_lab"}
        return {"R": np.eye(3).ravel().tolist()} | {
            later: params[given] for later, given in copied.items() if later in key}
    if family == "motion_type":
        return {"alpha_dot1": 0.0, "alpha_dot2": 0.0, "motion": "cusps"}
    if family == "sleeping_top":
        return {"omega3_c": 0.0, "stable": True}
    if family == "symmetric_free_top":
        return {"Omega": params["omega0"][2], "T_body": 2 * math.pi / params["omega0"][2]}
    if family == "energy_momentum":
        omega = params["omega"]
        return {"L": omega if isinstance(omega, list) else [0.0, 0.0, omega], "angle": 0.0}
    if family == "steady_precession":
        return {"slow": 1.0, "slow_approx": 1.0, "slow_error": 0.0}
    if family == "heavy_top_constants":  # E' = E: the reduction left out
        return {"p_gamma": 0.0, "E_prime": FAMILIES[family].follow("E_prime", params,
                                                                   {"p_gamma": 0.0})}
    expression = next(n for n in key if n.endswith("_expr"))
    symbol = next(n for n, v in params.items() if not isinstance(v, str))
    return {expression: symbol, expression.removesuffix("_expr"): params[symbol]}


STUDENTS = ("ann", "ben", "cy", "dee", "eve", "fay")


def _submission(hw: Path, sid: str) -> str:
    manifest = json.loads((hw / "assignment.json").read_text())
    key = json.loads((hw / "key.json").read_text())
    answers = {}
    for question, entry in zip(manifest["students"][sid]["questions"],
                               key["students"][sid]["questions"], strict=True):
        values = {a["name"]: a["value"] for a in entry["answers"]}
        rule = _physics_free(question["family"], values, question["parameters"])
        answers |= {f"q{question['question']}_{n}": v for n, v in rule.items()}
    return literal_notebook(answers)


@pytest.fixture(scope="module")
def gamed(tmp_path_factory) -> Path:
    """A graded class, one question per family with a chain, every student submitting the
    physics-free rule."""
    root = tmp_path_factory.mktemp("gamed")
    hw, subs = root / "HW", root / "subs"
    roster = Roster(("id", "name"), tuple({"id": s, "name": s} for s in STUDENTS))
    generate_assignment(roster, hw, FAMILIES, problems=list(CHAIN_FAMILIES), seed=30)
    subs.mkdir()
    for sid in STUDENTS:
        (subs / f"{sid}.ipynb").write_text(_submission(hw, sid))
    grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=2)
    return hw


def _chained(hw: Path, sid: str) -> dict:
    """The later answers of ``sid``'s record, by variable."""
    key = json.loads((hw / "key.json").read_text())
    later = {f"q{q['question']}_{a['name']}" for q in key["students"][sid]["questions"]
             for a in q["answers"] if a.get("depends_on")}
    record = read_result(hw / "graded" / "results" / f"{sid}.json")
    return {a.variable: a.verdict for a in record.answers if a.variable in later}


def test_a_physics_free_submission_earns_no_follow_through(gamed, tmp_path):
    copy = Path(shutil.copytree(gamed, tmp_path / "HW"))
    rescore(copy)
    for hw in (gamed, copy):  # as graded, and rescored
        explained = 0
        for sid in STUDENTS:
            for variable, v in _chained(hw, sid).items():
                assert v.status != "follows", (sid, variable, v.message)
                if v.status == "wrong":
                    assert v.points == 0
                    explained += "; no follow-through: your q" in v.message \
                        or "; no follow-through: q" in v.message
        assert explained >= len(STUDENTS) * 4  # the refusals say why, where it mattered


def test_the_refusal_names_the_variables(gamed):
    messages = [v.message for sid in STUDENTS for v in _chained(gamed, sid).values()]
    assert any(m.endswith("no follow-through: your q4_I_offdiag is zero, which makes "
                          "q4_moments a copy of your diagonal (R4)") for m in messages)
    assert any("no follow-through: your q6_R is the identity matrix, which makes q6_" in m
               for m in messages)
    assert not any("{" in m or "}" in m for m in messages)
