"""The demo's sample class: 24 students, what each hands in, and how each should be graded.

``eulertop demo`` (:mod:`eulertop.demo`) generates a real assignment for :data:`CLASS`, then
makes every student's submission here, *in the instructor's process*, from that student's
release notebook and the key's values — no kernel ever reads ``key.json``. Each student follows
a :class:`Student` plan, and :func:`intended` says what the grader should make of it, answer by
answer, so that the demo can check that every answer was judged as intended.

The class
---------
* 13 correct, in three styles a real class shows: ``numpy`` (``np.array`` vectors, angles
  typed in degrees through ``np.deg2rad``), ``plain`` (Python literals) and ``sympy``
  (``sp.Matrix``, ``sp.Float``, the expression built from ``sp.symbols`` — for some students
  expanded into a form different from the key's). Numbers carry a relative noise of about
  1e-5 and are typed to 7 significant figures, as a student copies them from a calculation.
* 3 wrong: two arithmetic slips (a factor on one answer, chosen so that it is outside the
  tolerance *and* matches none of the answer's known mistakes) and one angle typed as the string
  ``"… rad"`` (invalid, not wrong).
* 3 typical mistakes — ``degrees``, ``I1_I3_swapped``, ``missing_factor_2`` — each using the
  key's own :class:`problems.answers.Mistake` value for every answer that lists the mistake.
* 5 broken: a ``NameError`` in a working cell (that question's answers are never set); a
  bisection loop that never ends (the whole-notebook time limit stops it); an empty notebook;
  one answer left unset; one student who hands nothing in.
"""

from __future__ import annotations

import copy
import hashlib
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy

from problems.answers import Answer, grade
from problems.expressions import parse_expression

SEED = 711
"""The demo assignment's seed (the lecture's number): the same class gets the same variants."""

PROBLEMS: tuple[str, ...] = (
    "inertia_tensor",
    "energy_momentum",
    "euler_kinetic_energy",
    "heavy_top_constants",
    "turning_points",
    "sleeping_top",
)
"""Six families, from the inertia tensor to the sleeping top (every answer kind appears)."""

TITLE = "PHY 711 · Lecture 24 · eulertop demo"

NOISE = 1e-5
"""Relative noise of a correct student's numbers (well inside the key's rtol of 1e-3)."""

FIGURES = 7
"""Significant figures a student types."""

SLIP_FACTORS = (1.05, 0.95, 1.1, 0.9, 1.2, 0.8, 1.5, 0.6)
"""Arithmetic slips tried in turn; the first that matches no known mistake is used."""

PLANS = ("correct", "slip", "string_angle", "mistake", "name_error", "endless_loop", "empty",
         "unset", "absent")

GROUPS = {"correct": "correct", "slip": "wrong", "string_angle": "wrong", "mistake": "mistake",
          "name_error": "broken", "endless_loop": "broken", "empty": "broken",
          "unset": "broken", "absent": "broken"}
"""Each plan's group, for the demo's counts."""


@dataclass(frozen=True)
class Student:
    """One student of the sample class and the submission the demo makes for them.

    Attributes
    ----------
    id, name : str
        Roster id (also the submission's file name) and full name.
    plan : str
        One of :data:`PLANS`.
    style : str
        ``"numpy"``, ``"plain"`` or ``"sympy"``: how the numbers are written.
    mistake : str
        For ``plan == "mistake"``: the :class:`~problems.answers.Mistake` name made.
    question : int
        For plans aimed at one question (``slip``, ``string_angle``, ``name_error``,
        ``endless_loop``, ``unset``): which one.
    expand : bool
        ``sympy`` style: write the expression expanded (a different form from the key's).
    """

    id: str
    name: str
    plan: str = "correct"
    style: str = "plain"
    mistake: str = ""
    question: int = 0
    expand: bool = False

    @property
    def email(self) -> str:
        return f"{self.id}@example.edu"

    @property
    def group(self) -> str:
        return GROUPS[self.plan]


CLASS: tuple[Student, ...] = (
    Student("aiko", "Aiko Tanaka", style="numpy"),
    Student("amara", "Amara Okafor"),
    Student("bilal", "Bilal Chaudhry", "mistake", mistake="degrees"),
    Student("camille", "Camille Dubois", style="sympy"),
    Student("chen", "Chen Wei", style="numpy"),
    Student("dagny", "Dagny Solberg", "name_error", style="numpy", question=4),
    Student("diego", "Diego Hernández"),
    Student("elif", "Elif Yılmaz", "slip", style="numpy", question=4),
    Student("farah", "Farah Haddad", style="sympy", expand=True),
    Student("giulia", "Giulia Romano", style="numpy"),
    Student("hamid", "Hamid Karimi", "endless_loop", style="numpy", question=5),
    Student("ines", "Inês Carvalho"),
    Student("jonas", "Jonas Becker", "mistake", mistake="I1_I3_swapped"),
    Student("kavya", "Kavya Iyer", style="sympy"),
    Student("lars", "Lars Nyström", "empty"),
    Student("mei", "Mei Ling Tan", style="numpy"),
    Student("nadia", "Nadia Kowalska", "string_angle", question=5),
    Student("oluwaseun", "Oluwaseun Adeyemi"),
    Student("priya", "Priya Raman", "mistake", mistake="missing_factor_2"),
    Student("rafael", "Rafael Costa", style="sympy", expand=True),
    Student("sofia", "Sofía Morales", "unset", question=2),
    Student("tomasz", "Tomasz Wiśniewski", "slip", question=6),
    Student("yusuf", "Yusuf Demir", style="numpy"),
    Student("zanele", "Zanele Dlamini", "absent"),
)
"""The sample class, in roster order."""


@dataclass(frozen=True)
class Intended:
    """What the grader should make of one student's submission.

    Attributes
    ----------
    status : str
        The record's status: ``"graded"``, ``"failed"`` or ``"missing"``.
    answers : dict
        Variable → ``(verdict status, mistake name or None, feedback or None)``; the feedback is
        the key's own text for a known mistake, None where any message will do.
    """

    status: str
    answers: dict[str, tuple[str, str | None, str | None]] = field(default_factory=dict)


def roster_csv(students: tuple[Student, ...] = CLASS) -> str:
    """The class list as the CSV ``eulertop generate --roster`` reads (id, name, email), written
    like every CSV of the project (:func:`grader.gradebook.gradebook_csv`)."""
    from grader.gradebook import gradebook_csv

    return gradebook_csv([["id", "name", "email"], *([s.id, s.name, s.email] for s in students)])


def describe(student: Student) -> str:
    """What the demo made for ``student``, in a few words (the demo's table)."""
    return {
        "correct": f"correct ({student.style}{', expanded' if student.expand else ''})",
        "slip": f"arithmetic slip in question {student.question}",
        "string_angle": f"angle typed as a string (question {student.question})",
        "mistake": f"typical mistake: {student.mistake}",
        "name_error": f"NameError in a working cell (question {student.question})",
        "endless_loop": f"bisection that never ends (question {student.question})",
        "empty": "empty notebook",
        "unset": f"one answer left unset (question {student.question})",
        "absent": "handed nothing in",
    }[student.plan]


# --------------------------------------------------------------------------------------------
# which answers a plan touches


def _question(variable: str) -> int:
    return int(variable[1:].split("_", 1)[0])


def _target(student: Student, key: Mapping[str, Answer]) -> str:
    """The one variable a plan aimed at a question changes (first of the right kind)."""
    kinds = {"slip": ("scalar",), "string_angle": ("angle",)}.get(student.plan)
    for variable, answer in key.items():
        if _question(variable) == student.question and (kinds is None or answer.kind in kinds):
            return variable
    raise ValueError(f"{student.id}: question {student.question} has no answer for plan "
                     f"{student.plan!r}")


def _mistake_of(answer: Answer, name: str):
    return next((m for m in answer.mistakes if m.name == name), None)


def slip_value(answer: Answer) -> float:
    """A slip on a scalar answer: off by a factor, wrong, and no known mistake.

    Checked with the grader's own comparison (:func:`problems.answers.grade`).
    """
    for factor in SLIP_FACTORS:
        value = typed(answer.value * factor)
        verdict = grade(answer, value)
        if verdict.status == "wrong" and verdict.mistake is None:
            return value
    raise ValueError(f"{answer.name}: every slip factor matches a known mistake")


def intended(student: Student, key: Mapping[str, Answer]) -> Intended:
    """What the grader should conclude for ``student``, given their key (variable → Answer)."""
    if student.plan == "absent":
        return Intended("missing", {v: ("missing", None, None) for v in key})
    if student.plan == "empty":  # nothing read, nothing given (fail closed)
        return Intended("failed", {v: ("missing", None, None) for v in key})
    if student.plan == "endless_loop":  # time ran out in its loop: what was set before counts
        return Intended("graded", {v: ("correct" if _question(v) < student.question else
                                       "missing", None, None) for v in key})
    answers = {v: ("correct", None, None) for v in key}
    if student.plan == "mistake":
        for v, a in key.items():
            m = _mistake_of(a, student.mistake)
            if m is not None:
                answers[v] = ("wrong", m.name, m.feedback)
    elif student.plan == "name_error":
        answers.update({v: ("missing", None, None) for v in key
                        if _question(v) == student.question})
    elif student.plan in ("slip", "string_angle", "unset"):
        status = {"slip": "wrong", "string_angle": "invalid", "unset": "missing"}[student.plan]
        answers[_target(student, key)] = (status, None, None)
    return Intended("graded", answers)


def mismatches(expect: Intended, status: str, verdicts: Mapping[str, Any]) -> list[str]:
    """How a record differs from what was intended; empty when it is exactly as intended.

    ``verdicts`` maps each variable to its :class:`problems.answers.Verdict`.
    """
    out = [f"status {status}, intended {expect.status}"] if status != expect.status else []
    for variable, (want, mistake, feedback) in expect.answers.items():
        v = verdicts.get(variable)
        if v is None:
            out.append(f"{variable}: no verdict")
        elif (v.status, v.mistake) != (want, mistake):
            got = v.status + (f" ({v.mistake})" if v.mistake else "")
            out.append(f"{variable}: {got}, intended {want}" + (f" ({mistake})" if mistake else ""))
        elif feedback is not None and v.message != feedback:
            out.append(f"{variable}: feedback differs from the key's for {mistake}")
    return out


# --------------------------------------------------------------------------------------------
# writing values the way a student would


def typed(x: float) -> float:
    """``x`` as a student types it: :data:`FIGURES` significant figures."""
    return float(f"{x:.{FIGURES}g}")


def _noisy(value: Any, rng: np.random.Generator) -> Any:
    if isinstance(value, list):
        return [_noisy(v, rng) for v in value]
    return typed(value * (1.0 + NOISE * rng.standard_normal()))


def _number_code(x: float, kind: str, style: str) -> str:
    if kind == "angle" and style == "numpy":
        return f"np.deg2rad({typed(math.degrees(x))!r})"
    if kind == "angle" and style == "sympy":
        return f"{typed(x / math.pi)!r}*sp.pi"
    if style == "sympy":
        return f"sp.Float('{x!r}')"
    return repr(x)


def _expression_code(text: str, answer: Answer, student: Student) -> str:
    if student.style != "sympy":
        return repr(text)
    expr = parse_expression(text, answer.symbols)
    return str(sympy.expand(expr) if student.expand else expr)


def value_code(value: Any, answer: Answer, student: Student) -> str:
    """Python source for ``value`` as an answer of ``answer``'s kind, in ``student``'s style."""
    if value is None or isinstance(value, bool):
        return repr(value)
    if answer.kind == "expression":
        return _expression_code(value, answer, student)
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, list):
        inner = ", ".join(_number_code(x, "scalar", "plain") for x in value)
        wrap = {"numpy": "np.array([{}])", "sympy": "sp.Matrix([{}])"}.get(student.style, "[{}]")
        return wrap.format(inner)
    return _number_code(value, answer.kind, student.style)


def _rng(student: Student) -> np.random.Generator:
    # Seeded from the id (not hash(), which changes per process): the same files every run.
    digest = hashlib.sha256(f"eulertop-demo:{student.id}".encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "big"))


def answer_values(student: Student, key: Mapping[str, Answer]) -> dict[str, str]:
    """Variable → the Python source the student writes after ``=`` (``"None"`` when unset)."""
    rng = _rng(student)
    code = {}
    for variable, a in key.items():
        value = a.value if a.kind in ("boolean", "choice", "expression") else _noisy(a.value, rng)
        mistake = _mistake_of(a, student.mistake) if student.plan == "mistake" else None
        if mistake is not None:
            value = mistake.value if isinstance(mistake.value, str | bool) else \
                _exact(mistake.value)
        code[variable] = value_code(value, a, student)
    if student.plan in ("slip", "string_angle", "unset"):
        target = _target(student, key)
        code[target] = {
            "slip": lambda: value_code(slip_value(key[target]), key[target], student),
            "string_angle": lambda: repr(f"{typed(key[target].value):.4f} rad"),
            "unset": lambda: "None",
        }[student.plan]()
    return code


def _exact(value: Any) -> Any:
    """A mistake's value typed to :data:`FIGURES` figures (no noise: it *is* the mistake)."""
    if isinstance(value, list):
        return [_exact(v) for v in value]
    return typed(value)


# --------------------------------------------------------------------------------------------
# the notebook


_ANSWER_LINE = re.compile(r"^(q\d+_\w+) = None(\s+#.*)?$")


def _code_cell(cell_id: str, source: str) -> dict:
    return {"cell_type": "code", "id": cell_id, "metadata": {}, "execution_count": None,
            "outputs": [], "source": source.splitlines(keepends=True)}


def _setup_source(student: Student, key: Mapping[str, Answer]) -> str:
    if student.style == "numpy":
        return "import numpy as np"
    if student.style != "sympy":
        return "import math"
    symbols = sorted({s for a in key.values() if a.kind == "expression" for s in a.symbols})
    lines = ["import sympy as sp", "from sympy import cos, sin, sqrt"]
    if symbols:
        lines.append(f"{', '.join(symbols)} = sp.symbols({' '.join(symbols)!r})")
    return "\n".join(lines)


def _working_cell(student: Student, question: int, params: Mapping[str, float]) -> str | None:
    """A working cell before question ``question``'s answers, when the plan has one."""
    if student.question != question:
        return None
    if student.plan == "name_error":
        # The student forgot the question prefix of the parameters: a NameError.
        first = next(iter(params))
        return (f"# working: question {question}\nscale = {first} * 1.0  # forgot the "
                f"q{question}_ prefix\nfirst_answer = scale")
    if student.plan == "endless_loop":
        # Bisection with a tolerance below the spacing of floats near 0.5: once lo and hi are
        # neighbouring floats, mid is one of them and hi - lo never shrinks. Never ends.
        return (f"# working: question {question}, bisection for a turning point\n"
                "f = lambda b: np.cos(b) - 0.5\nlo, hi = 0.0, 1.5\n"
                "while hi - lo > 1e-18:\n    mid = 0.5 * (lo + hi)\n"
                "    if f(lo) * f(mid) <= 0:\n        hi = mid\n    else:\n        lo = mid\n"
                "first_answer = mid")
    return None


def _answer_source(cell: dict, code: Mapping[str, str], student: Student, question: int) -> str:
    lines = []
    for line in "".join(cell["source"]).splitlines():
        m = _ANSWER_LINE.match(line)
        if m and m.group(1) in code:
            value = code[m.group(1)]
            if student.plan == "name_error" and student.question == question and not lines:
                value = "first_answer"  # uses the working cell that raised
            line = f"{m.group(1)} = {value}{m.group(2) or ''}"
        lines.append(line)
    return "\n".join(lines)


def make_submission(
    student: Student,
    release: Mapping[str, Any],
    key: Mapping[str, Answer],
    questions: list[Mapping[str, Any]],
) -> dict | None:
    """The notebook ``student`` hands in, built from their release notebook; None if absent.

    Parameters
    ----------
    release : mapping
        The student's ``release/<id>.ipynb``, as loaded JSON.
    key : mapping
        Variable → :class:`~problems.answers.Answer` (:func:`problems.generate.student_answers`).
    questions : list of mapping
        The student's public questions (``assignment.json``; only ``params`` is read).
    """
    if student.plan == "absent":
        return None
    nb = copy.deepcopy(dict(release))
    if student.plan == "empty":
        nb["cells"] = []
        return nb
    code = answer_values(student, key)
    cells = []
    for cell in nb["cells"]:
        role = cell.get("metadata", {}).get("eulertop", {}).get("role")
        question = cell.get("metadata", {}).get("eulertop", {}).get("question")
        if role == "answer":
            work = _working_cell(student, question, questions[question - 1]["params"])
            if work is not None:
                cells.append(_code_cell(f"q{question}-work", work))
            cell = {**cell, "source": _answer_source(cell, code, student, question)
                    .splitlines(keepends=True)}
        cells.append(cell)
        if role == "parameters":
            cells.append(_code_cell("setup", _setup_source(student, key)))
    nb["cells"] = cells
    return nb
