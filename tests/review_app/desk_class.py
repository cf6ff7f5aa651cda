"""A small graded class for the review desk's tests (issue 31), and the docs' screenshot.

Six students, two written parts each (``near_axis_stability``'s own and a question that is
only a written part), graded without a kernel (the literal reader of
:mod:`tests.grader.report.synthetic_class`): ada writes :data:`HOSTILE` (every way of putting
markup, script, links or requests into Markdown and LaTeX that we know of) under her
derivation; bob pastes an image; cyd leaves the family's written cell as released; eve's rate
is off by 1.5 times its tolerance, fay's rate is a word and her second stability answer is the
known mistake — the flagged view's rows.

``python -m tests.review_app.desk_class DIR`` writes the docs' screenshot of the question page
(``DIR/review.png``) and of the flagged view (``DIR/review_flagged.png``).
"""

from __future__ import annotations

import base64
import json
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from grader.pipeline import grade_assignment
from problems.generate import Question, generate_assignment
from problems.roster import read_roster
from problems.spec import check_spec, read_spec
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute

RUBRIC = (1.0, 1.0, 2.0)  # the standalone question's items, as SPEC declares them
SPEC = """
title = "Torque-free spin"
seed = 7
roster = "roster.csv"

[[questions]]
family = "near_axis_stability"
written = true

[[questions]]
written = "Show that $V_\\\\text{eff}(\\\\beta)$ has exactly one minimum between the turning \
points."
name = "veff_minimum"
title = "One minimum"
rubric = [
  { item = "$V_\\\\text{eff}$ in terms of $p_\\\\alpha$, $p_\\\\gamma$, $I_1$, $Mgl$", \
points = 1 },
  { item = "$V_\\\\text{eff} \\\\to +\\\\infty$ at both ends argued", points = 1 },
  { item = "one stationary point shown", points = 2 },
]
"""
STUDENTS = {"ada": "Ada Lovelace", "bob": "Bob Moog", "cyd": "Cyd Charisse",
            "dee": "Dee Dee Bridgewater", "eve": "Eve Curie", "fay": "Fay Kanin"}
FAMILY_WRITTEN, OWN = "q1_intermediate_axis", "q2_veff_minimum"
TEXT = ("With $u = \\cos\\beta$ the effective potential is $$V_\\text{eff}(u) = "
        "\\frac{(p_\\alpha - p_\\gamma u)^2}{2 I_1 (1 - u^2)} + Mgl\\,u,$$ which grows without "
        "bound as $u \\to \\pm 1$ since $p_\\alpha \\ne \\pm p_\\gamma$. Its derivative has one "
        "zero in $(-1, 1)$: **one minimum**.")
AXIS = ("Linearised about steady spin $\\omega_3$, Euler's equations give "
        "$$\\ddot\\omega_1 = -\\Omega_1 \\Omega_2\\, \\omega_1, \\quad "
        "\\Omega_1 = \\omega_3 \\frac{I_3 - I_2}{I_1},\\ \\Omega_2 = \\omega_3 "
        "\\frac{I_3 - I_1}{I_2}.$$ For the intermediate axis $\\Omega_1 \\Omega_2 < 0$: "
        "the perturbation grows exponentially.")
BEACON = "http://127.0.0.1:9/beacon"
"""Where a hostile answer tries to send the browser (nothing listens there)."""
HOSTILE = "\n\n".join((
    '<script>window.pwned = 1; alert("script")</script>',
    '<svg onload="alert(\'svg\')"><circle r="9"/><script>alert("svg script")</script></svg>',
    '<img src=x onerror="alert(\'img\')"> <img src="' + BEACON + '/img.png">',
    '[a link](javascript:alert("link")) and [another](' + BEACON + '/link)',
    '<a href="javascript:alert(\'raw\')" onclick="alert(\'click\')">raw anchor</a>',
    '![an image](' + BEACON + '/image.png) <' + BEACON + '/autolink>',
    '<iframe src="' + BEACON + '/frame"></iframe> <object data="' + BEACON + '/object"></object>',
    '<style>body { display: none }</style> <link rel="stylesheet" href="' + BEACON + '/css">',
    '<meta http-equiv="refresh" content="0;url=' + BEACON + '/refresh">',
    '<form action="' + BEACON + '/form"><button>send</button></form>',
    '<div onmouseover="alert(\'hover\')" style="background:url(' + BEACON + '/bg)">hover</div>',
    '$\\href{javascript:alert("href")}{x}$ and $\\href{' + BEACON + '/href}{y}$',
    '<math href="javascript:alert(\'mathml\')"><mi xlink:href="' + BEACON + '/x">m</mi></math>',
    '$\\text{<img src=x onerror=alert("text")>}$ and $a < b$ & c',
))
PNG = base64.b64encode(bytes.fromhex(
    "89504e470d0a1a0a0000000d4948445200000001000000010806000000"
    "1f15c4890000000d49444154789c6360f8cfc0f01f0005000201a5e1f3"
    "0a0000000049454e44ae426082")).decode()  # one pixel


@dataclass
class DeskClass:
    """A graded class: its assignment folder and graded folder."""

    hw: Path
    out: Path
    subs: Path


def _written_cells(nb: dict) -> dict[str, dict]:
    return {c["metadata"]["eulertop"]["written"]: c for c in nb["cells"]
            if c["metadata"].get("eulertop", {}).get("written")}


def _set_answer(nb: dict, variable: str, literal: str) -> None:
    """The code line ``variable = …`` of ``nb`` made ``variable = literal``."""
    pattern = re.compile(rf"^{variable} = [^#\n]*", re.M)
    for cell in nb["cells"]:
        source = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        if cell["cell_type"] == "code" and pattern.search(source):
            cell["source"] = pattern.sub(f"{variable} = {literal}  ", source)


def _key_value(hw: Path, sid: str, variable: str) -> float:
    key = json.loads((hw / "key.json").read_text())
    for q in key["students"][sid]["questions"]:
        for a in q["answers"]:
            if f"q{q['question']}_{a['name']}" == variable:
                return a["value"]
    raise KeyError(variable)


def _hand_in(hw: Path, subs: Path, sid: str, texts: dict, answers: dict | None = None) -> None:
    """``sid``'s solutions with its written cells holding ``texts`` (absent: as released)
    and the code answers ``answers`` (variable → literal) changed."""
    nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
    release = _written_cells(json.loads((hw / "release" / f"{sid}.ipynb").read_text()))
    for variable, cell in _written_cells(nb).items():
        text = texts.get(variable, release[variable]["source"])
        if isinstance(text, dict):
            cell["attachments"] = text["attachments"]
            text = text["text"]
        cell["source"] = text
    for variable, literal in (answers or {}).items():
        _set_answer(nb, variable, literal)
    (subs / f"{sid}.ipynb").write_text(json.dumps(nb))


def build(folder: Path) -> DeskClass:
    """Generate, hand in (module docstring) and grade the class in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "roster.csv").write_text("id,name\n" + "".join(
        f"{sid},{name}\n" for sid, name in STUDENTS.items()))
    (folder / "spec.toml").write_text(SPEC)
    spec = read_spec(folder / "spec.toml")
    check_spec(spec, FAMILIES)
    hw = folder / "HW"
    generate_assignment(read_roster(folder / "roster.csv"), hw, FAMILIES, seed=7,
                        title=spec.title,
                        questions=[Question(q.label, q.pool, q.settings, q.written, q.title)
                                   for q in spec.questions])
    subs = folder / "subs"
    subs.mkdir()
    both = {FAMILY_WRITTEN: AXIS, OWN: TEXT}
    _hand_in(hw, subs, "ada", {FAMILY_WRITTEN: AXIS, OWN: TEXT + "\n\n" + HOSTILE})
    _hand_in(hw, subs, "bob", {**both, OWN: {"text": TEXT, "attachments": {
        "sketch.png": {"image/png": PNG}}}})
    _hand_in(hw, subs, "cyd", {OWN: TEXT})
    _hand_in(hw, subs, "dee", both)
    _hand_in(hw, subs, "eve", both,
             {"q1_rate": repr(_key_value(hw, "eve", "q1_rate") * 1.0015)})
    _hand_in(hw, subs, "fay", both, {"q1_rate": '"fast"', "q1_stable2": repr(
        not _key_value(hw, "fay", "q1_stable2"))})
    grade_assignment(hw, subs, execute=LiteralExecute())
    return DeskClass(hw, hw / "graded", subs)


def main(argv: list[str]) -> int:
    """The docs' screenshots (module docstring)."""
    from tests.review_app.browser import launch, screenshots

    out = Path(argv[0] if argv else "docs/instructors")
    with tempfile.TemporaryDirectory() as tmp:
        made = build(Path(tmp))  # before the browser, whose event loop blocks asyncio.run
        with launch() as browser:
            written = screenshots(browser, made, out)
    print("wrote " + ", ".join(str(p) for p in written))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
