"""``eulertop problems test``: the checks every family must pass, for any family.

Each check runs over the seeds given (``numpy.random.default_rng(seed)`` per variant, as
``tests/problems/test_templates.py`` does for the built-ins) and records, for a failure, the
seed that reproduces it and what failed:

``draws well posed or rejected``
    Every draw either is rejected (``draw`` returns None or raises
    :class:`~problems.family.IllPosed`, or ``answers`` raises it) or gives parameters that are
    all declared, plain JSON and within their declared ranges and figures, answers and a
    statement, without any other exception; a seed that finds no acceptable draw fails.
``same seed, same variant``
    Drawing the seed again gives the same variant, to the last bit of its JSON.
``key recomputed from its parameters``
    ``answers`` and ``statement`` of the recorded parameters, read back from JSON, give the
    same variant — recomputed after every seed has been drawn, so that nothing a draw left
    behind (a module variable) can stand in for a parameter: drawing and answering are kept
    apart, and a key can be recomputed later from what the assignment recorded.
``answers finite and JSON-able``
    Each answer's record is plain JSON without NaN or infinities and reads back equal; the key
    itself is graded correct.
``known mistakes outside the tolerance``
    Each known mistake's value is graded wrong, and recognised by its own name.
``no answer value in the statement``
    No number in the statement that is not one of the parameters equals an answer value
    rounded to 2–6 significant figures or to 0–6 decimals (zero, and whole numbers below 10 —
    list numbers, "π/2" — are not counted).
``every tolerance stated in the notebook``
    The question's cell in the student's notebook says how each answer is compared (its own
    tolerance), and the statement never types a tolerance itself.
``time per variant``
    Drawing a variant takes at most :data:`MAX_SECONDS`.
``follow-through gives back the key``
    An answer that declares ``depends_on`` names other answers of its question, and the
    family's ``follow`` given the recorded parameters and the key's values of those answers
    recomputes it to within its own tolerance (the consistency follow-through credit relies
    on: a student whose earlier answers are right is judged as by the key); the family's
    ``degenerate``, where it has one, calls those values no degenerate case. A family without
    such answers passes it trivially.
``parameters printed as in the cell``
    Every number the statement (and the question's title) prints for a parameter is that
    parameter's value exactly as the parameter cell holds it (the key is computed from it): a
    statement that prints θ = 0.316 as ``0.32`` sends a student 1.3 % off. Where a parameter
    is printed is found by rendering the statement again with that one number (one component
    of a vector) doubled, or halved where doubling fails: a printed number that changes, and
    whose digits are a rounding of the parameter, is a print of it — a fixed number of the text
    (``0.5 m``, a list's ``2.``) never is, however close.
``solutions get full marks (sandbox)``
    One solutions notebook holding the variants of the first ``sandbox_seeds`` seeds as its
    questions is run as a submission and compared with their key by ``grade`` — the grader's
    :func:`grader.selftest_run.grade_solutions` (in the sandbox where this machine has one),
    handed in by the front end (``problems/`` sits below ``grader/``): every answer must be
    correct. Without ``grade`` the check fails, saying it was not run.
"""

from __future__ import annotations

import json
import math
import re
import tempfile
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from difflib import SequenceMatcher
from pathlib import Path

import numpy as np

from problems.answers import Answer, comparison_rule, grade
from problems.family import Family, IllPosed
from problems.notebook import build_notebook, notebook_text
from problems.rounding import round_sig
from problems.variant import Variant, variable_name

MAX_SECONDS = 5.0
"""The longest a variant may take to draw (a class of 300 × 14 questions is generated in
minutes, not hours)."""
SHOWN_FAILURES = 3
"""Failures listed per check (the count says how many there were)."""

CHECKS = (
    "draws well posed or rejected",
    "same seed, same variant",
    "key recomputed from its parameters",
    "answers finite and JSON-able",
    "known mistakes outside the tolerance",
    "no answer value in the statement",
    "every tolerance stated in the notebook",
    "time per variant",
    "follow-through gives back the key",
    "parameters printed as in the cell",
    "solutions get full marks (sandbox)",
)


@dataclass(frozen=True)
class CheckResult:
    """One check over all seeds.

    Attributes
    ----------
    name : str
        One of :data:`CHECKS`.
    passed, failed : int
        Seeds (or variants) that passed and failed it.
    failures : tuple of str
        The first :data:`SHOWN_FAILURES` failures, each ``"seed S: what failed"``.
    note : str
        What else the table says (the time taken, the isolation used).
    """

    name: str
    passed: int
    failed: int
    failures: tuple[str, ...] = ()
    note: str = ""


@dataclass(frozen=True)
class Report:
    """A family's self-test: its checks, in :data:`CHECKS` order."""

    family: str
    seeds: tuple[int, ...]
    checks: tuple[CheckResult, ...]

    @property
    def passed(self) -> bool:
        return all(c.failed == 0 for c in self.checks)


class _Tally:
    """Counts of one check while it runs."""

    def __init__(self, name: str) -> None:
        self.name, self.passed, self.failed, self.failures = name, 0, 0, []

    def record(self, seed: int, problem: str | None) -> None:
        if problem is None:
            self.passed += 1
            return
        self.failed += 1
        if len(self.failures) < SHOWN_FAILURES:
            self.failures.append(f"seed {seed}: {problem}")

    def result(self, note: str = "") -> CheckResult:
        return CheckResult(self.name, self.passed, self.failed, tuple(self.failures), note)


def self_test(family: Family, seeds: Iterable[int], sandbox_seeds: int | None = None,
              grade_solutions: GradeSolutions | None = None) -> Report:
    """Run every check of :data:`CHECKS` on ``family`` over ``seeds``.

    ``sandbox_seeds``: how many of the seeds (the first ones) the full-marks check runs (one
    notebook); default all. ``grade_solutions``: what runs that notebook and compares it with
    its key (:data:`GradeSolutions`; the grader's, handed in by the front end).
    """
    seeds = tuple(seeds)
    family.prepare()
    tallies = {name: _Tally(name) for name in CHECKS}
    variants: dict[int, Variant] = {}
    times = []
    for seed in seeds:
        variant, problem = drawn_variant(family, seed)
        tallies[CHECKS[0]].record(seed, problem)
        if variant is None:
            continue
        variants[seed] = variant
        start = time.perf_counter()
        try:
            again = family.generate(np.random.default_rng(seed))
        except Exception as e:  # drawn once, failing the second time: not the same variant
            again = f"{type(e).__name__}: {e}"
        times.append(time.perf_counter() - start)
        tallies[CHECKS[1]].record(seed, _safely(_same, variant, again))
        tallies[CHECKS[3]].record(seed, _safely(_answers_problem, variant))
        tallies[CHECKS[4]].record(seed, _safely(_mistakes_problem, variant))
        tallies[CHECKS[5]].record(seed, _safely(lambda v: _first(leaked_values(v)), variant))
        tallies[CHECKS[6]].record(seed, _safely(_tolerance_problem, family, variant))
        slow = times[-1] > MAX_SECONDS
        tallies[CHECKS[7]].record(seed, f"took {times[-1]:.2f} s" if slow else None)
    for seed, variant in variants.items():  # after every draw: no state of its own draw left
        tallies[CHECKS[2]].record(seed, _safely(_recomputed, family, variant))
        tallies[CHECKS[8]].record(seed, _safely(_follow_problem, family, variant))
        tallies[CHECKS[9]].record(seed, _safely(lambda f, v: _first(misprinted(f, v)),
                                                family, variant))
    timing = f"max {max(times):.3f} s, mean {sum(times) / len(times):.3f} s" if times else ""
    checks = [tallies[name].result(timing if name == CHECKS[7] else "") for name in CHECKS[:-1]]
    chosen = dict(list(variants.items())[:sandbox_seeds])
    checks.append(full_marks(family, chosen, grade_solutions) if chosen else
                  CheckResult(CHECKS[-1], 0, 1, ("no variant to run",)))
    return Report(family.name, seeds, tuple(checks))


def drawn_variant(family: Family, seed: int) -> tuple[Variant | None, str | None]:
    """The seed's variant, drawn as :meth:`Family.generate` draws it, checking each step; or
    None and what went wrong."""
    rng = np.random.default_rng(seed)
    declared = family.parameters
    for attempt in range(1, family.max_attempts + 1):
        step = "draw()"
        try:
            params = family.draw(rng)
            if params is None:
                continue
            step = "the drawn parameters"
            params = family.recorded(params)
            bad = [f"{n}: {p}" for n, v in params.items() if (p := declared[n].problem(v))]
            if bad:
                return None, f"draw {attempt}: parameter {bad[0]}"
            step = "answers()"
            answers = family.answers(params)
            step = "statement()"
            return family.variant(params, answers), None
        except IllPosed:
            continue
        except Exception as e:
            return None, f"draw {attempt}: {step} raised {type(e).__name__}: {e}"
    return None, f"no acceptable draw in {family.max_attempts} attempts"


def _first(problems: Iterable[str | None]) -> str | None:
    return next((p for p in problems if p is not None), None)


def _safely(check: Callable[..., str | None], *args: object) -> str | None:
    """``check(*args)``, or what it raised as the failure (a family's values the check could
    not handle fail the check; they never stop the run)."""
    try:
        return check(*args)
    except Exception as e:
        return f"the check failed on this variant: {type(e).__name__}: {e}"


def _answers_problem(variant: Variant) -> str | None:
    return _first(_answer_problem(a) for a in variant.answers)


def _mistakes_problem(variant: Variant) -> str | None:
    return _first(_mistake_problem(a) for a in variant.answers)


def _json(variant: Variant) -> str:
    return json.dumps(variant.to_dict(), sort_keys=True, allow_nan=False)


def _same(variant: Variant, again: Variant | str) -> str | None:
    if isinstance(again, str):
        return f"drawn again, the seed failed: {again}"
    if _json(variant) == _json(again):
        return None
    first = next(k for k, v in variant.to_dict().items() if again.to_dict().get(k) != v)
    return f"drawn twice, the variants differ in {first!r}"


def _recomputed(family: Family, variant: Variant) -> str | None:
    recorded = json.loads(json.dumps(variant.parameters))
    try:
        again = family.variant(recorded)
    except Exception as e:
        return f"answers/statement of the recorded parameters raised {type(e).__name__}: {e}"
    if _json(again) != _json(variant):
        first = next(k for k, v in variant.to_dict().items() if again.to_dict().get(k) != v)
        return f"recomputed from its recorded parameters, {first!r} differs"
    return None


def _follow_problem(family: Family, variant: Variant) -> str | None:
    names = {a.name for a in variant.answers}
    recorded = json.loads(json.dumps(variant.parameters))
    key = {a.name: a.value for a in variant.answers}
    for answer in variant.answers:
        if not answer.depends_on:
            continue
        unknown = [n for n in answer.depends_on if n not in names or n == answer.name]
        if unknown:
            return f"answer {answer.name!r} depends on {', '.join(map(repr, unknown))}, " \
                   "not another answer of its question"
        try:
            value = family.follow(answer.name, recorded, {n: key[n] for n in answer.depends_on})
        except Exception as e:
            return f"follow({answer.name!r}) from the key raised {type(e).__name__}: {e}"
        verdict = grade(answer, value.tolist() if hasattr(value, "tolist") else value)
        if verdict.status != "correct":
            return f"follow({answer.name!r}) from the key's own values is graded " \
                   f"{verdict.status}: {verdict.message}"
        try:
            reason = family.degenerate(answer.name, recorded,
                                       {n: key[n] for n in answer.depends_on})
        except Exception as e:
            return f"degenerate({answer.name!r}) of the key raised {type(e).__name__}: {e}"
        if reason is not None:
            return f"degenerate({answer.name!r}) calls the key's own values degenerate: {reason}"
    return None


def _answer_problem(answer: Answer) -> str | None:
    try:
        text = json.dumps(answer.to_dict(), allow_nan=False)
    except (TypeError, ValueError) as e:
        return f"answer {answer.name!r} is not plain JSON: {e}"
    if Answer.from_dict(json.loads(text)) != answer:
        return f"answer {answer.name!r} does not read back from JSON unchanged"
    verdict = grade(answer, answer.value)
    if verdict.status != "correct":
        return f"answer {answer.name!r}: the key itself is graded {verdict.status}"
    return None


def _mistake_problem(answer: Answer) -> str | None:
    for m in answer.mistakes:
        verdict = grade(answer, m.value)
        if (verdict.status, verdict.mistake) != ("wrong", m.name):
            return (f"answer {answer.name!r}: mistake {m.name!r} is graded {verdict.status}"
                    + (f" as {verdict.mistake!r}" if verdict.mistake else ""))
    return None


_NUMBER = re.compile(
    r"(?<![\w.])10\^\{(-?\d+)\}"  # 10^{-7}
    r"|(?<![\w.^{])(\d+(?:\.\d*)?(?:e[+-]?\d+)?)(?:\s*\\times\s*10\^\{(-?\d+)\})?"
)


@dataclass(frozen=True)
class Printed:
    """One number as a text writes it: its ``text``, its magnitude ``value`` and half the
    unit of its last digit, ``half_unit`` (``0.32``: 0.005; ``1230``: 5)."""

    text: str
    value: float
    half_unit: float

    def rounds(self, x: float) -> bool:
        """Whether these digits are ``|x|`` rounded to the figures shown (a tie, ``0.125`` as
        ``0.12``, included: the margin is for the binary error of ``value`` and ``half_unit``)."""
        return abs(abs(x) - self.value) <= self.half_unit * (1 + 1e-9)


def _printed(match: re.Match) -> Printed:
    power, mantissa, exponent = match.groups()
    if power:
        return Printed(match.group(0), float(f"1e{power}"), 0.5 * 10.0 ** int(power))
    digits, _, e_notation = mantissa.partition("e")
    whole, _, fraction = digits.partition(".")
    last_digit = -len(fraction) if fraction else len(whole) - len(whole.rstrip("0") or "0")
    scale = int(e_notation or 0) + int(exponent or 0)
    return Printed(match.group(0), float(f"{digits}e{scale}"),
                   0.5 * 10.0 ** (last_digit + scale))


def printed_numbers(text: str) -> list[Printed]:
    r"""The numbers written in ``text``, in order: ``0.05``, ``1.2e-5``,
    ``1.2 \times 10^{-5}``, ``10^{-7}`` (digits inside names such as ``r1`` or ``m_1`` are not
    numbers; a sign is not part of one).

    Examples
    --------
    >>> [(p.text, p.value, p.half_unit) for p in printed_numbers("$m_1 = 0.32$ kg, 1230")]
    [('0.32', 0.32, 0.005), ('1230', 1230.0, 5.0)]
    """
    return [_printed(m) for m in _NUMBER.finditer(text)]


def numbers_in(text: str) -> set[float]:
    """Magnitudes of the numbers written in ``text`` (:func:`printed_numbers`).

    Examples
    --------
    >>> sorted(numbers_in(r"$m_1 = 0.05$ kg (`r1`), $I = 1.2 \\times 10^{-5}$, 3e5"))
    [1.2e-05, 0.05, 300000.0]
    """
    return {p.value for p in printed_numbers(text)}


def _leaves(value: object) -> list[float]:
    if isinstance(value, list):
        return [x for v in value for x in _leaves(v)]
    return [value] if isinstance(value, float | int) and not isinstance(value, bool) else []


def readings(x: float) -> set[float]:
    """What a student could read as ``|x|``: rounded to 2–6 significant figures, or to 0–6
    decimals (zero excluded)."""
    x = abs(x)
    found = {round_sig(x, k) for k in range(2, 7)} | {round(x, d) for d in range(7)}
    return {r for r in found if r != 0}


def leaked_values(variant: Variant) -> list[str]:
    """Answer values written in the statement (module docstring), one message each."""
    given = {abs(x) for v in variant.parameters.values() for x in _leaves(v)}
    shown = {x for x in numbers_in(variant.statement)
             if x not in given and not (x < 10 and x == int(x))}
    leaks = []
    for answer in variant.answers:
        if answer.kind not in ("scalar", "angle", "vector"):
            continue
        for x in _leaves(answer.value):
            hits = sorted(shown & readings(x)) if math.isfinite(x) and x != 0 else []
            if hits:
                leaks.append(f"answer {answer.name!r} = {x!r} is written in the statement as "
                             f"{hits[0]:g}")
    return leaks


def _numeric_leaves(value: object, path: tuple[int, ...] = ()
                    ) -> list[tuple[tuple[int, ...], float]]:
    """The numbers of a parameter's value (a number, a vector, a matrix), each with its
    index."""
    if isinstance(value, list):
        return [leaf for k, v in enumerate(value) for leaf in _numeric_leaves(v, (*path, k))]
    is_number = isinstance(value, float | int) and not isinstance(value, bool)
    return [(path, float(value))] if is_number else []


def _replaced(value: object, path: tuple[int, ...], new: float) -> object:
    """``value`` with its number at ``path`` replaced by ``new``."""
    if not path:
        return new
    return [_replaced(v, path[1:], new) if k == path[0] else v for k, v in enumerate(value)]


def _shown_text(family: Family, params: dict) -> str:
    """What the student reads of the question: its title and its statement."""
    return family.heading(params) + "\n\n" + family.statement(params)


def _changed(before: list[Printed], after: list[Printed]) -> list[Printed]:
    """The numbers of ``before`` that ``after`` writes otherwise at the same place (numbers
    added or dropped, a wording that changed with the value, are not paired)."""
    matcher = SequenceMatcher(None, [p.text for p in before], [p.text for p in after],
                              autojunk=False)
    return [before[i] for tag, i1, i2, j1, j2 in matcher.get_opcodes()
            if tag == "replace" and i2 - i1 == j2 - j1 for i in range(i1, i2)]


def printed_for(family: Family, params: dict, name: str, path: tuple[int, ...] = ()
                ) -> list[Printed]:
    """What the question's text prints for the number at ``path`` of parameter ``name``: the
    numbers that change when it alone is doubled (halved, where the family cannot render it
    doubled) and whose digits are a rounding of it.

    Raises
    ------
    ValueError
        The family renders the question neither with it doubled nor halved.
    """
    x = dict(_numeric_leaves(params[name]))[path]
    before = printed_numbers(_shown_text(family, params))
    for factor in (2.0, 0.5):
        try:
            changed = {**params, name: _replaced(params[name], path, x * factor)}
            after = printed_numbers(_shown_text(family, changed))
        except Exception:  # a value the family's text cannot take: try the other
            continue
        return [p for p in _changed(before, after) if p.rounds(x)]
    raise ValueError(f"the statement cannot be rendered with {name} doubled or halved, so "
                     "where it prints the parameter cannot be found")


def misprinted(family: Family, variant: Variant) -> list[str]:
    """Parameters the question's text prints otherwise than as the parameter cell holds them
    (the value the key is computed from), one message each."""
    problems = []
    for name, value in variant.parameters.items():
        for path, x in _numeric_leaves(value):
            if x == 0:
                continue  # nothing to double, and no rounding of it but 0 itself
            label = name + "".join(f"[{k}]" for k in path)
            where = "the parameter cell holds" if name in variant.params else "the key uses"
            problems += [f"parameter {label} is printed as {p.text!r} but {where} {x!r}"
                         for p in printed_for(family, variant.parameters, name, path)
                         if p.value != abs(x)]
    return problems


def _tolerance_problem(family: Family, variant: Variant) -> str | None:
    if re.search(r"toleran", variant.statement, re.I):
        return "the statement types a tolerance (the notebook states each one itself)"
    nb = build_notebook("self-test", {"id": "selftest"}, [variant],
                        families={family.name: family})
    cell = next(c for c in nb["cells"] if c["id"] == "q1-statement")
    compared = "".join(cell["source"]).rsplit("\n\n", 1)[-1]
    for answer in variant.answers:
        if f"`{variable_name(1, answer.name)}`" not in compared \
                or comparison_rule(answer) not in compared:
            return f"the notebook does not say how {variable_name(1, answer.name)} is compared"
    return None


@dataclass(frozen=True)
class SolutionsRun:
    """What ``grade`` (:func:`full_marks`) tells of the solutions notebook it ran: its
    execution's status and message, each answer's verdict as ``(question, variable, status,
    message)``, whether it ran sandboxed, and how long it took (s)."""

    status: str
    message: str
    verdicts: tuple[tuple[int, str, str, str], ...]
    sandboxed: bool
    duration: float


GradeSolutions = Callable[[Path, dict, float], SolutionsRun]
"""``grade(notebook, key_entry, seconds) -> SolutionsRun``: run the notebook as a submission
within ``seconds`` and compare it with the key entry (``key.json``'s form for one student)."""


def full_marks(family: Family, variants: dict[int, Variant],
               grade_solutions: GradeSolutions | None = None) -> CheckResult:
    """Run one solutions notebook of ``variants`` (seed → variant, one question each) as a
    submission and compare it with their key (``grade_solutions``); every answer must be
    correct."""
    from problems.generate import key_entry

    seeds, chosen = list(variants), list(variants.values())
    if grade_solutions is None:
        return CheckResult(CHECKS[-1], 0, len(seeds), ("not run: no grader was given to run "
                                                      "the solutions notebook",))
    tally = _Tally(CHECKS[-1])
    nb = build_notebook(f"{family.name} self-test", {"id": "selftest"}, chosen,
                        solutions=True, families={family.name: family})
    with tempfile.TemporaryDirectory(prefix="eulertop-selftest-") as folder:
        path = Path(folder) / "selftest.ipynb"
        path.write_text(notebook_text(nb), encoding="utf-8")
        run = grade_solutions(path, key_entry(chosen), 120 + 2 * len(chosen))
    if run.status != "ok":
        return CheckResult(CHECKS[-1], 0, len(seeds),
                           (f"seeds {seeds[0]}–{seeds[-1]}: the solutions notebook did not run: "
                            f"{run.status}: {run.message}",))
    for k, seed in enumerate(seeds, start=1):
        wrong = [v for v in run.verdicts if v[0] == k and v[2] != "correct"]
        tally.record(seed, None if not wrong else
                     f"{wrong[0][1]}: {wrong[0][2]}: {wrong[0][3]}")
    where = "sandboxed" if run.sandboxed else "NOT sandboxed (no sandbox on this machine)"
    return tally.result(f"{where}, {run.duration:.1f} s")


def report_lines(report: Report) -> list[str]:
    """The table of a report, then each failure with its seed."""
    width = max(len(c.name) for c in report.checks)
    lines = [f"{'check':<{width}}  {'passed':>6}  {'failed':>6}  ",
             f"{'-' * width}  {'-' * 6}  {'-' * 6}  "]
    for c in report.checks:
        lines.append(f"{c.name:<{width}}  {c.passed:>6}  {c.failed:>6}  {c.note}".rstrip())
    failed = [c for c in report.checks if c.failed]
    for c in failed:
        lines.append(f"FAILED {c.name}: {c.failed} time(s)")
        lines.extend(f"  {f}" for f in c.failures)
    lines.append("all checks passed" if not failed else
                 f"{len(failed)} check(s) failed; a seed reproduces its variant: "
                 "eulertop problems preview NAME --seed S")
    return lines
