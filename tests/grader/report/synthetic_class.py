"""A synthetic class for the class report's tests: real variants, real grading, planted patterns.

The assignment is made by the real generator (:func:`problems.generate.generate_assignment`);
every student's notebook is written here, with answers derived from the student's *own* key
and some working code of their own; the class is graded by the real pipeline
(:func:`grader.pipeline.grade_assignment`) with an execution stage that reads the answer
variables' literal values instead of starting a kernel (:class:`LiteralExecute`, as in
``test_pipeline.py``), so the comparison stage gives the verdicts and the pipeline's last step
writes ``report.html``.

An honest student has an ability ``a`` (uniform in [0, 1]); on an answer of difficulty ``d``
they are right with probability ``1 / (1 + exp(-10 (a - d)))``, and otherwise make one of the
answer's known mistakes, an arbitrary error (the key times ``exp(N(0, 0.6))``), hand in a
string (invalid) or nothing. Correct numbers carry a relative noise of 1e-5. Their working code
is drawn from a vocabulary (names, operations, comments), so no two honest notebooks share
much of it — as no two real ones do.

Planted, with :data:`PLANTED` (none in an honest class):

* ``hard``: question 3 (turning points) has difficulty 0.75 — only strong students get it;
* ``broken``: the key of ``q4_omega3_c`` is wrong by a factor 3/2 (a template bug), so every
  student who computes the right value is marked wrong;
* ``slip``: a third of the class doubles ``q2_p_gamma`` (a factor 2 the template does not know);
* three copying pairs: ``answers`` (the copier types the source's answers into their own
  notebook), ``notebook`` (the copier hands in the source's notebook as it is) and ``wrong``
  (the copier copies the source's four wrong answers and does the rest alone);
* the last student hands in a file that is not a notebook (failed), the one before nothing.

Run as a script to write the README's example report and its screenshot::

    python -m tests.grader.report.synthetic_class docs/report
"""

from __future__ import annotations

import ast
import json
import math
import shutil
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from grader.pipeline import grade_assignment
from problems.generate import generate_assignment, json_text, key_hash, student_answers
from problems.roster import Roster
from problems.templates import FAMILIES

PROBLEMS = ("energy_momentum", "heavy_top_constants", "turning_points", "sleeping_top")
HARD_QUESTION = 3
BROKEN = "q4_omega3_c"
BROKEN_FACTOR = 1.5
SLIP = "q2_p_gamma"
EASY, HARD = 0.15, 0.75
NOISE = 1e-5
COPIED_WRONG = ("q1_T", "q2_p_alpha", "q2_E_prime", "q3_V_eff")
"""The answers the source of the ``wrong`` pair gets wrong, and its copier copies."""

PLANTED = {"answers": ("s011", "s004"), "notebook": ("s023", "s017"),
           "wrong": ("s035", "s029")}
"""Copying pairs: name → (copier, source)."""


@dataclass(frozen=True)
class FakeExecution:
    status: str
    message: str
    answers: dict
    cell_errors: tuple = ()
    duration: float = 0.0
    output_truncated: bool = False
    sandboxed: bool = False


class LiteralExecute:
    """``execute(path, variables, limits)`` reading each answer variable's literal value."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.calls = 0

    def __call__(self, path, variables, limits) -> FakeExecution:
        with self.lock:
            self.calls += 1
        nb = json.loads(Path(path).read_text(encoding="utf-8"))
        answers = dict.fromkeys(variables)
        for cell in nb["cells"]:
            if cell["cell_type"] != "code":
                continue
            for node in ast.parse("".join(cell["source"])).body:
                if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name) \
                        and node.targets[0].id in answers:
                    try:
                        answers[node.targets[0].id] = ast.literal_eval(node.value)
                    except ValueError:
                        pass  # working code, not a literal: the variable stays as it was
        return FakeExecution("ok", "", answers)


@dataclass
class SyntheticClass:
    """What :func:`build_class` made, and what was planted where."""

    hw: Path
    submissions: Path
    graded: Path
    ids: tuple[str, ...]
    planted: bool
    slip_students: tuple[str, ...] = ()
    true_values: dict = field(default_factory=dict)  # id -> {variable: value before the bug}


# ------------------------------------------------------------------------------------------
# answers


def literal_notebook(answers: dict[str, Any]) -> str:
    """A notebook of one code cell giving each answer variable its value as a literal: what
    :class:`LiteralExecute` reads back."""
    import nbformat

    code = "\n".join(f"{name} = {value!r}" for name, value in answers.items())
    return nbformat.writes(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)]))


def followed_from_a_slip(manifest: dict, key: dict, sid: str,
                         factor: float = 1.2) -> tuple[dict[str, Any], int]:
    """``sid``'s answers by variable, from a loaded ``assignment.json`` and ``key.json``: the
    key's, but the first (numeric) answer of each follow-through chain ``factor`` times the key
    and the later ones worked out from it by the family's ``follow`` — what earns
    follow-through credit; and how many later ones."""
    answers, chained = {}, 0
    for question, entry in zip(manifest["students"][sid]["questions"],
                               key["students"][sid]["questions"], strict=True):
        values = {a["name"]: a["value"] for a in entry["answers"]}
        k = question["question"]
        answers |= {f"q{k}_{n}": v for n, v in values.items()}
        for a in entry["answers"]:
            first = (a.get("depends_on") or [None])[0]
            if first is None or not isinstance(values[first], float):
                continue
            earlier = dict(values, **{first: values[first] * factor})
            value = FAMILIES[question["family"]].follow(
                a["name"], question["parameters"], {d: earlier[d] for d in a["depends_on"]})
            answers[f"q{k}_{first}"] = earlier[first]
            answers[f"q{k}_{a['name']}"] = np.asarray(value).tolist()
            chained += 1
    return answers, chained


def _noisy(value: Any, rng: np.random.Generator) -> Any:
    if isinstance(value, list):
        return [float(v * (1 + NOISE * rng.standard_normal())) for v in value]
    return float(value * (1 + NOISE * rng.standard_normal()))


def _scaled(value: Any, factor: float) -> Any:
    return [float(v * factor) for v in value] if isinstance(value, list) else float(value * factor)


def _arbitrary(answer, rng: np.random.Generator) -> Any:
    """An arbitrary wrong value: the key times exp(N(0, 0.6)), at least 5 % off."""
    if answer.kind == "boolean":
        return not answer.value
    while True:
        factor = math.exp(rng.normal(0, 0.6))
        if abs(math.log(factor)) > 0.05:
            return _scaled(answer.value, factor)


def honest_answer(answer, true_value: Any, ability: float, difficulty: float,
                  rng: np.random.Generator) -> Any:
    """What an honest student of ``ability`` hands in (module docstring)."""
    if rng.random() < 1 / (1 + math.exp(-10 * (ability - difficulty))):
        return _noisy(true_value, rng) if answer.kind != "boolean" else true_value
    roll = rng.random()
    if roll < 0.4 and answer.mistakes:
        return answer.mistakes[rng.integers(len(answer.mistakes))].value
    if roll < 0.75:
        return _arbitrary(answer, rng)
    return "see my working above" if roll < 0.85 else None


def class_answers(keys: dict, true_values: dict, planted: bool,
                  rng: np.random.Generator) -> tuple[dict, tuple[str, ...]]:
    """Every student's submitted values, and the students planted with the slip."""
    ids = list(keys)
    submitted, slip = {}, []
    involved = {s for pair in PLANTED.values() for s in pair} if planted else set()
    for i, sid in enumerate(ids):
        ability = rng.random()
        values = {}
        for variable, answer in keys[sid].items():
            hard = int(variable[1:variable.index("_")]) == HARD_QUESTION and planted
            values[variable] = honest_answer(answer, true_values[sid][variable], ability,
                                             HARD if hard else EASY, rng)
        if planted and i % 3 == 0 and sid not in involved:
            values[SLIP] = _scaled(_noisy(true_values[sid][SLIP], rng), 2.0)
            slip.append(sid)
        submitted[sid] = values
    if planted:
        _plant_copies(keys, true_values, submitted, rng)
    return submitted, tuple(slip)


def _plant_copies(keys, true_values, submitted, rng) -> None:
    for name, (copier, source) in PLANTED.items():
        src = submitted[source]
        if name in ("answers", "notebook"):
            src.update({v: _noisy(true_values[source][v], rng) for v in src
                        if keys[source][v].kind != "boolean"})  # a good student to copy from
            submitted[copier] = dict(src)
        else:
            for v in COPIED_WRONG:
                src[v] = _arbitrary(keys[source][v], rng)
            own = {v: _noisy(true_values[copier][v], rng) if keys[copier][v].kind != "boolean"
                   else true_values[copier][v] for v in keys[copier]}
            own.update({v: src[v] for v in COPIED_WRONG})
            submitted[copier] = own


# ------------------------------------------------------------------------------------------
# notebooks

WORDS = ("omega", "inertia", "spin", "tilt", "energy", "mom", "torque", "rate", "axis", "beta",
         "theta", "phi", "psi", "nu", "kin", "pot", "ang", "lever", "mass", "grav", "alpha",
         "gamma", "prec", "nut", "comp", "vec", "res", "tmp", "val", "step", "part", "term",
         "num", "den", "ratio", "root", "lhs", "rhs", "coef", "sq", "half", "tot", "base",
         "ell", "arm", "moment", "tensor", "proj", "dotp", "crossp", "norm", "unit", "eff",
         "turn", "lo", "hi", "mid", "guess", "sol", "fun")
FUNCS = ("np.sqrt", "np.sin", "np.cos", "np.abs", "np.arccos", "np.tan", "np.exp", "float")
OPS = ("+", "-", "*", "/")
COMMENTS = ("from the lecture notes", "check units", "energy conservation", "I think this is",
            "see eq. 5", "body frame", "lab frame", "careful with the sign", "TODO check",
            "works now", "from Goldstein", "small angle?", "use radians", "per the hint",
            "numerically", "quick check", "the tricky part", "as in the tutorial")


def working_code(rng: np.random.Generator, params: list[str]) -> str:
    """A few lines of a student's own calculation (drawn at random; never executed)."""
    names: list[str] = []
    lines = []
    for _ in range(rng.integers(3, 8)):
        name = f"{WORDS[rng.integers(len(WORDS))]}{rng.choice(['', '_', '2', '_a', 'x', '1'])}"
        pool = names + params
        a = pool[rng.integers(len(pool))] if pool else "1.0"
        b = pool[rng.integers(len(pool))] if pool else "2.0"
        c = f"{rng.uniform(0.1, 9):.3g}"
        form = rng.integers(4)
        expr = (f"{FUNCS[rng.integers(len(FUNCS))]}({a}) {OPS[rng.integers(4)]} {b}",
                f"({a} {OPS[rng.integers(4)]} {c}) {OPS[rng.integers(4)]} {b}",
                f"{a} {OPS[rng.integers(4)]} {FUNCS[rng.integers(len(FUNCS))]}({b} * {c})",
                f"{c} * {a}")[form]
        comment = f"  # {COMMENTS[rng.integers(len(COMMENTS))]}" if rng.random() < 0.3 else ""
        lines.append(f"{name} = {expr}{comment}")
        names.append(name)
    return "\n".join(lines)


def student_notebook(release: dict, values: dict, rng: np.random.Generator) -> dict:
    """The release notebook with working cells and the answers filled in."""
    nb = json.loads(json.dumps(release))
    params = []
    cells = []
    for cell in nb["cells"]:
        src = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        if cell["cell_type"] == "code" and cell.get("id") == "parameters":
            params = [line.split("=")[0].strip() for line in src.splitlines()
                      if line.startswith("q") and "=" in line]
        if cell["cell_type"] == "code" and str(cell.get("id", "")).endswith("-answer"):
            cells.append({"cell_type": "code", "id": f"{cell['id']}-work", "metadata": {},
                          "source": "import numpy as np\n" + working_code(rng, params),
                          "outputs": [], "execution_count": None})
            cell["source"] = "\n".join(
                f"{line.split('=')[0].strip()} = {values[line.split('=')[0].strip()]!r}"
                if line.split("=")[0].strip() in values else line for line in src.splitlines())
        cells.append(cell)
    nb["cells"] = cells
    return nb


# ------------------------------------------------------------------------------------------
# the class


def _break_key(hw: Path) -> None:
    """Multiply the key of :data:`BROKEN` by :data:`BROKEN_FACTOR` (a template bug)."""
    key = json.loads((hw / "key.json").read_text())
    question, name = int(BROKEN[1:BROKEN.index("_")]), BROKEN[BROKEN.index("_") + 1:]
    for entry in key["students"].values():
        for q in entry["questions"]:
            for a in q["answers"]:
                if q["question"] == question and a["name"] == name:
                    a["value"] *= BROKEN_FACTOR
        entry["hash"] = key_hash(entry["questions"])
    (hw / "key.json").write_text(json_text(key))


def build_class(folder: Path, n: int, *, planted: bool, seed: int = 16) -> SyntheticClass:
    """Generate, hand in and grade a class of ``n`` (module docstring); ``report.html`` is
    written by the grading run into ``folder/HW/graded``."""
    folder = Path(folder)
    ids = tuple(f"s{i:03d}" for i in range(1, n + 1))
    roster = Roster(("id", "name"), tuple({"id": s, "name": f"Student {s[1:]}"} for s in ids))
    hw = folder / "HW"
    generate_assignment(roster, hw, FAMILIES, problems=list(PROBLEMS), seed=seed,
                        title="Synthetic class" + (" (planted patterns)" if planted else ""))
    key = json.loads((hw / "key.json").read_text())
    true_values = {s: {v: a.value for v, a in student_answers(key, s).items()} for s in ids}
    if planted:
        _break_key(hw)
        key = json.loads((hw / "key.json").read_text())
    keys = {s: student_answers(key, s) for s in ids}
    rng = np.random.default_rng(seed)
    submitted, slip = class_answers(keys, true_values, planted, rng)
    subs = folder / "submissions"
    subs.mkdir(parents=True)
    notebooks = {}
    for sid in ids:
        release = json.loads((hw / "release" / f"{sid}.ipynb").read_text())
        notebooks[sid] = student_notebook(release, submitted[sid], rng)
    if planted:
        copier, source = PLANTED["notebook"]
        notebooks[copier] = notebooks[source]
    for sid, nb in notebooks.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb, indent=1))
    if planted:  # the last two hand in nothing and a file that is not a notebook
        (subs / f"{ids[-2]}.ipynb").unlink()
        (subs / f"{ids[-1]}.ipynb").write_text("{not a notebook")
    grade_assignment(hw, subs, limits="literal", execute=LiteralExecute(), jobs=2)
    return SyntheticClass(hw, subs, hw / "graded", ids, planted, slip, true_values)


CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--hide-scrollbars")


def chromium() -> str | None:
    """Debian's ``chromium`` (installed by ``.ci/run``), or None."""
    return shutil.which("chromium") or shutil.which("chromium-browser")


def screenshot(page: Path, png: Path, profile: Path, size: str = "1200,2600") -> None:
    """Render ``page`` in headless Chromium into ``png``."""
    subprocess.run([chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={profile}",
                    f"--window-size={size}", f"--screenshot={png}", page.resolve().as_uri()],
                   check=True, capture_output=True, timeout=120)


def sections_only(page: str, first: str, last: str) -> str:
    """The page with only the sections from ``<h2 id=first>`` to before ``<h2 id=last>``
    (for a screenshot of the middle of the page)."""
    start, head_end = page.index('<h2 id="look">'), page.index(f'<h2 id="{first}">')
    return page[:start] + page[head_end:page.index(f'<h2 id="{last}">')] + \
        page[page.index("<script>"):]


def main(argv: list[str]) -> int:
    """``python -m tests.grader.report.synthetic_class DIR``: the example report and its
    screenshot."""
    import tempfile

    out = Path(argv[0] if argv else "docs/report")
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        made = build_class(Path(tmp), 60, planted=True)
        for name in ("report.html", "report.csv", "report_items.csv"):
            shutil.copy(made.graded / name, out / name)
        screenshot(out / "report.html", out / "report.png", Path(tmp) / "profile")
        middle = Path(tmp) / "middle.html"
        middle.write_text(sections_only((out / "report.html").read_text(encoding="utf-8"),
                                        "slips", "students"), encoding="utf-8")
        screenshot(middle, out / "report_copying.png", Path(tmp) / "profile", size="1200,1500")
    print(f"wrote {out}/report.html, report.csv, report_items.csv, report.png, "
          "report_copying.png")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
