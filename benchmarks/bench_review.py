"""Benchmark the review desk's API (issue 31, :mod:`grader.review`) on a class of ``--students``
(600): how long a review takes to land, in-process, as ``eulertop review`` calls it.

Makes an assignment of three questions with written parts (``turning_points`` and
``near_axis_stability`` with their own, and a question that is only a written part: three
written answers a student), gives every student their solutions notebook with a paragraph of
Markdown and LaTeX in each written cell, and grades the class without running a kernel (the
tests' ``LiteralExecute`` reads the answers' literals; the written answers are read from the
files as in every run). Then, in one process:

* ``ReviewSession(hw)``: loading the class (assignment, overrides, reviews, every record);
* ``written(question)`` and the first answer's HTML: what the question page needs;
* ``submit(...)`` of ``--reviews`` reviews, each committed as its own transaction (the record,
  its page, ``grades.csv``, ``answers.csv``, ``reviews.json``, the trail): the first (which
  imports what renders the page) apart, then the median and maximum of the others;
* the same with a second session submitting in between (each submit then reads what the other
  wrote: a record and ``reviews.json``);
* ``close()``: the class report rebuilt once.

Run from the repository root: ``PYTHONPATH=. python benchmarks/bench_review.py [--students 600]
[--reviews 60]``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SPEC = """
title = "Review benchmark"
seed = 31
roster = "roster.csv"

[[questions]]
family = "turning_points"
written = true

[[questions]]
family = "near_axis_stability"
written = true

[[questions]]
written = "Explain why a thrown tennis racket flips when spun about its intermediate axis."
name = "racket"
rubric = [
  { item = "Euler's equations linearised about the spin axis", points = 1 },
  { item = "the sign of Ω₁Ω₂ for the intermediate axis", points = 1 },
  { item = "exponential growth of the perturbation", points = 1 },
]
"""

TEXT = ("With $u = \\cos\\beta$ the effective potential reads $$V_\\text{eff}(u) = "
        "\\frac{(p_\\alpha - p_\\gamma u)^2}{2 I_1 (1 - u^2)} + Mgl\\,u,$$ which grows without "
        "bound as $u \\to \\pm 1$ since the numerator does not vanish there. Its derivative "
        "has one zero in $(-1, 1)$, so there is exactly one minimum. " * 3)


def build(folder: Path, students: int) -> Path:
    """The assignment, the submissions (solutions with written text) and the graded class."""
    from grader.pipeline import grade_assignment
    from problems.generate import Question, generate_assignment
    from problems.roster import read_roster
    from problems.spec import check_spec, read_spec
    from problems.templates import FAMILIES
    from tests.grader.report.synthetic_class import LiteralExecute

    (folder / "roster.csv").write_text("id,name\n" + "".join(
        f"s{i:03d},Student {i}\n" for i in range(students)))
    (folder / "spec.toml").write_text(SPEC)
    spec = read_spec(folder / "spec.toml")
    check_spec(spec, FAMILIES)
    hw = folder / "HW"
    generate_assignment(read_roster(folder / "roster.csv"), hw, FAMILIES,
                        questions=[Question(q.label, q.pool, q.settings, q.written, q.title)
                                   for q in spec.questions], seed=31)
    subs = folder / "subs"
    subs.mkdir()
    for path in sorted((hw / "solutions").glob("*.ipynb")):
        nb = json.loads(path.read_text())
        for cell in nb["cells"]:
            if cell["metadata"].get("eulertop", {}).get("written"):
                cell["source"] = TEXT
        (subs / path.name).write_text(json.dumps(nb))
    grade_assignment(hw, subs, execute=LiteralExecute())
    return hw


def timed(call) -> tuple[float, object]:
    start = time.perf_counter()
    value = call()
    return time.perf_counter() - start, value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, default=600)
    parser.add_argument("--reviews", type=int, default=60)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from benchmarks.bench_grade import machine
    from grader.review import ReviewSession

    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        hw = build(Path(tmp), args.students)
        print(f"generated and graded {args.students} students (no kernel) in "
              f"{time.perf_counter() - start:.1f} s")
        seconds, desk = timed(lambda: ReviewSession(hw, grader="ta-one"))
        print(f"ReviewSession(hw): {1000 * seconds:.0f} ms")
        question = desk.questions()[0]["question"]
        seconds, answers = timed(lambda: desk.written(question))
        page, _ = timed(lambda: desk.html(answers[0]["id"]))
        print(f"written({question!r}): {len(answers)} answers in {1000 * seconds:.0f} ms; the "
              f"first one's HTML in {1000 * page:.1f} ms")
        alone = [timed(lambda a=a: desk.submit(a["id"], [0, 2], -0.25, "see R16"))[0]
                 for a in answers[:args.reviews]]
        first, alone = alone[0], alone[1:]  # the first imports the page's Markdown and MathML
        print(f"submit, one session: the first {1000 * first:.0f} ms; then median "
              f"{1000 * statistics.median(alone):.1f} ms, max {1000 * max(alone):.1f} ms over "
              f"{len(alone)} reviews")
        other = ReviewSession(hw, grader="ta-two")
        rest = answers[args.reviews:3 * args.reviews]
        both = []
        for mine, theirs in zip(rest[::2], rest[1::2], strict=False):
            other.submit(theirs["id"], [1], 0.0, "")
            both.append(timed(lambda a=mine: desk.submit(a["id"], [0], 0.0, ""))[0])
        print(f"submit, another session submitting in between: median "
              f"{1000 * statistics.median(both):.1f} ms, max {1000 * max(both):.1f} ms over "
              f"{len(both)} reviews")
        other.close()
        seconds, _ = timed(desk.close)
        print(f"close() (the class report rebuilt): {seconds:.1f} s")


if __name__ == "__main__":
    main()
