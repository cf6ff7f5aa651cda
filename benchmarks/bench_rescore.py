"""Benchmark ``eulertop rescore`` on a class of ``--students`` (300): how long a key fix takes to
reach the gradebook when no notebook runs again (issue 26).

Makes an assignment of every built-in family (14 questions a student) for the class, and
records of a graded class without running a kernel: each student's answers are literals in a
notebook's code cell, read back by the tests' fake execution stage (``LiteralExecute``). What
is measured is what happens after the answers are extracted: comparing them with the key,
follow-through, overrides, writing the records, ``grades.csv``, ``answers.csv``, every feedback
page and the class report. A third of the students get an earlier answer of every
follow-through chain wrong and the later one right from it (so each rescore recomputes those),
every fifth one answer 10 % off. Then, in one run:

* ``eulertop rescore HW`` as a fresh process (start-up included) after a key change (every
  scalar answer's ``rtol`` widened), the median of ``--runs`` runs, and the same with
  ``--dry-run`` (compare and count, write nothing);
* the time the first grading of the class with that fake execution stage took in-process, for
  scale (a real grading run adds every notebook's execution to it:
  ``benchmarks/bench_grade.py``).

Run from the repository root: ``PYTHONPATH=. python benchmarks/bench_rescore.py [--students 300]
[--runs 3]``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def submissions(hw: Path, folder: Path) -> int:
    """Each student's notebook (see the module docstring); how many chained answers follow
    from a wrong earlier one."""
    from tests.grader.report.synthetic_class import followed_from_a_slip, literal_notebook

    key = json.loads((hw / "key.json").read_text())
    manifest = json.loads((hw / "assignment.json").read_text())
    folder.mkdir(parents=True)
    chained = 0
    for n, (sid, entry) in enumerate(key["students"].items()):
        if n % 3 == 1:
            answers, count = followed_from_a_slip(manifest, key, sid, 1.2)
            chained += count
        else:
            answers = {f"q{k}_{a['name']}": a["value"]
                       for k, q in enumerate(entry["questions"], start=1) for a in q["answers"]}
        if n % 5 == 0:
            name = next(v for v, x in answers.items() if isinstance(x, float))
            answers[name] *= 1.1
        (folder / f"{sid}.ipynb").write_text(literal_notebook(answers))
    return chained


def widen(hw: Path, rtol: float) -> None:
    """Every scalar answer's relative tolerance set to ``rtol`` (its known mistakes kept only
    where still told apart), as ``eulertop key set`` does."""
    from dataclasses import replace

    from grader.assignment import load_assignment
    from grader.key_edit import set_answer
    from grader.results import atomic_write_text
    from problems.generate import json_text

    a = load_assignment(hw)
    names = {f"q{q['question']}_{x['name']}" for e in a.key["students"].values()
             for q in e["questions"] for x in q["answers"] if x["kind"] == "scalar"}
    for name in sorted(names):
        key, _ = set_answer(a, name, rtol=rtol)
        a = replace(a, key=key)
    atomic_write_text(hw / "key.json", json_text(a.key))


def timed(command: list[str]) -> tuple[float, str]:
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=ROOT, check=False)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed:\n{done.stdout}\n{done.stderr}")
    return seconds, done.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, default=300)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from benchmarks.bench_grade import machine
    from grader.pipeline import grade_assignment
    from problems.generate import generate_assignment
    from problems.roster import Roster
    from problems.templates import FAMILIES
    from tests.grader.report.synthetic_class import LiteralExecute

    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        hw = Path(tmp) / "HW"
        roster = Roster(("id", "name"), tuple({"id": f"s{i:03d}", "name": f"Student {i}"}
                                               for i in range(args.students)))
        start = time.perf_counter()
        generate_assignment(roster, hw, FAMILIES, seed=26)
        print(f"generated {args.students} students x {len(FAMILIES)} questions in "
              f"{time.perf_counter() - start:.1f} s")
        chained = submissions(hw, Path(tmp) / "subs")
        start = time.perf_counter()
        grade_assignment(hw, Path(tmp) / "subs", limits="LIMITS", execute=LiteralExecute())
        graded = time.perf_counter() - start
        print(f"graded (fake execution stage, in-process): {graded:.1f} s; {chained} answers "
              "follow from a wrong earlier one")
        widen(hw, 0.15)  # the 10 % slips now within it
        command = [sys.executable, "-m", "eulertop", "rescore", str(hw)]
        dry, wet = [], []
        for run in range(args.runs):
            seconds, out = timed([*command, "--dry-run"])
            dry.append(seconds)
            seconds, out = timed(command)
            wet.append(seconds)
            if run == 0:
                print("first rescore said: " + out.strip().splitlines()[-1])
        print(f"eulertop rescore, {args.students} students (fresh process, median of "
              f"{args.runs}): {statistics.median(wet):.2f} s "
              f"(runs: {', '.join(f'{s:.2f}' for s in wet)})")
        print(f"eulertop rescore --dry-run (median of {args.runs}): "
              f"{statistics.median(dry):.2f} s "
              f"(runs: {', '.join(f'{s:.2f}' for s in dry)})")
        print(f"ratio grading run (no kernels) / rescore: {graded / statistics.median(wet):.2f}")
        one_student(hw, args.runs)


def one_student(hw: Path, runs: int) -> None:
    """An override of one student (set, then taken back: each a fresh process), against its
    floor: a fresh process importing what the command imports and reading the assignment —
    and the same reading that student's key as well (``Assignment.expected``: what every
    change of a student checks first, and its comparison needs; sympy for an expression
    answer)."""
    from grader.assignment import load_assignment

    a = load_assignment(hw)
    sid = a.ids[len(a.ids) // 2]
    variable = a.expected(sid)[0].variable
    eulertop = [sys.executable, "-m", "eulertop", "override", str(hw), sid, variable]
    start = ("import sys; from grader.assignment import load_assignment; "
             "import grader.amend, grader.rescore; a = load_assignment(sys.argv[1])")
    floor = [sys.executable, "-c", start, str(hw)]
    keyed = [sys.executable, "-c", start + "; a.expected(sys.argv[2])", str(hw), sid]
    setting, taking, starting, reading = [], [], [], []
    for _ in range(runs):
        starting.append(timed(floor)[0])
        reading.append(timed(keyed)[0])
        setting.append(timed([*eulertop, "--points", "0", "--reason", "bench"])[0])
        taking.append(timed([*eulertop, "--remove"])[0])
    med = statistics.median
    print(f"eulertop override of one student (fresh process, median of {runs}): set "
          f"{med(setting):.2f} s, taken back {med(taking):.2f} s; its floor — the command's "
          f"imports and reading the assignment — {med(starting):.2f} s; ratio "
          f"{med(setting) / med(starting):.2f}; with that student's key read as well "
          f"{med(reading):.2f} s, ratio {med(setting) / med(reading):.2f}")

if __name__ == "__main__":
    main()
