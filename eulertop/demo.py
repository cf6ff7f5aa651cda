"""``eulertop demo``: the whole pipeline on a built-in sample class, end to end.

``eulertop demo [--out DIR] [--force] [--timeout S] [--jobs N] [--no-bench]``

1. **Generate** a real assignment (:func:`problems.generate.generate_assignment`, seed
   :data:`eulertop.sample_class.SEED`, six families) for the 24 students of
   :data:`eulertop.sample_class.CLASS`.
2. **Hand in**: each student's submission is built from their *release* notebook in this
   process (:func:`eulertop.sample_class.make_submission`); no kernel ever reads the key.
3. **Grade** with the real grader (:func:`grader.pipeline.grade_assignment`: warm kernels,
   limits, its progress display).
4. **Charts**: ``eulertop bench --quick --out DIR/bench`` in a separate process (skipped, with
   a note, when :mod:`solver.bench` cannot be imported).

It then prints one row per student (id, name, what the demo made, points, what the grader said
in words), the counts, where everything is, and a check that every answer was judged as
intended (:func:`eulertop.sample_class.intended`), listing any that was not.

The folder ``DIR`` (default ``./eulertop-demo``) is marked as a demo's by the file
:data:`MARKER`. A folder holding anything that is not a demo's is never touched, even with
``--force``; an earlier demo is replaced only with ``--force``, and then only the entries a demo
writes (:data:`ENTRIES`) are removed, each by its exact name.

Exit status: 0 when every step ran and every answer was judged as intended; 1 when a step
failed or a result was not the intended one; 2 on usage errors (nothing written).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from grader.cli import seconds_argument, whole_number_argument

DEFAULT_OUT = Path("eulertop-demo")
MARKER = ".eulertop-demo"
ROSTER, HW, SUBMISSIONS, BENCH = "roster.csv", "HW", "submissions", "bench"
ENTRIES = frozenset({MARKER, ROSTER, HW, SUBMISSIONS, BENCH})
"""Everything a demo writes into its folder (and all that ``--force`` ever removes)."""

DEFAULT_TIMEOUT = 20.0
"""Seconds for a whole notebook: the looping student's notebook runs this long."""


class FolderRefused(Exception):
    """``--out`` cannot be used; nothing was written."""


def add_demo_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop demo``."""
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, metavar="DIR",
                        help=f"folder for everything the demo writes (default: ./{DEFAULT_OUT})")
    parser.add_argument("--force", action="store_true",
                        help="replace an earlier demo in DIR (never a folder holding anything "
                             "else)")
    parser.add_argument("--timeout", type=seconds_argument, default=DEFAULT_TIMEOUT, metavar="S",
                        help="time limit for one whole notebook (default "
                             f"{DEFAULT_TIMEOUT:g} s; the looping student's runs this long)")
    parser.add_argument("--jobs", type=whole_number_argument, metavar="N",
                        help=f"submissions graded at once (default: cores, {os.cpu_count()})")
    parser.add_argument("--no-bench", action="store_true",
                        help="skip the work-precision charts (eulertop bench --quick)")


# --------------------------------------------------------------------------------------------
# the folder


def prepare_folder(out: Path, force: bool) -> None:
    """Make ``out`` ready for a demo, or raise :class:`FolderRefused` having written nothing.

    A missing or empty folder is used; an earlier demo's (marker, and nothing but
    :data:`ENTRIES`) is cleared with ``force`` — each entry removed by its exact name —; any
    other folder is refused, ``force`` or not.
    """
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise FolderRefused(f"--out {out}: exists and is not a folder")
    if out.is_dir():
        present = set(os.listdir(out))
        others = sorted(present - ENTRIES)
        if present and (MARKER not in present or others):
            what = ", ".join(others[:5]) + (" …" if len(others) > 5 else "")
            raise FolderRefused(f"--out {out}: holds files that are not an eulertop demo's "
                                f"({what}); it is never replaced, even with --force — choose "
                                "another --out")
        if present and not force:
            raise FolderRefused(f"--out {out}: holds an earlier demo; pass --force to replace "
                                "it, or choose another --out")
        for name in sorted(present - {MARKER}):
            path = out / name
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
    out.mkdir(parents=True, exist_ok=True)
    (out / MARKER).write_text("This folder was written by 'eulertop demo'; 'eulertop demo "
                              "--force' may replace it.\n", encoding="utf-8")


# --------------------------------------------------------------------------------------------
# the steps


def _step(text: str) -> None:
    print(f"\n== {text}", flush=True)


def generate(out: Path):
    """Step 1: roster and assignment; returns the generator's Summary."""
    from eulertop.sample_class import PROBLEMS, SEED, TITLE, roster_csv
    from problems.generate import generate_assignment
    from problems.roster import read_roster
    from problems.templates import FAMILIES

    (out / ROSTER).write_text(roster_csv(), encoding="utf-8")
    return generate_assignment(read_roster(out / ROSTER), out / HW, FAMILIES,
                               problems=PROBLEMS, seed=SEED, title=TITLE)


def hand_in(out: Path) -> dict:
    """Step 2: every student's submission, from their release notebook; intended outcomes."""
    from eulertop.sample_class import CLASS, intended, make_submission
    from problems.generate import student_answers

    hw, folder = out / HW, out / SUBMISSIONS
    folder.mkdir()
    key = json.loads((hw / "key.json").read_text(encoding="utf-8"))
    manifest = json.loads((hw / "assignment.json").read_text(encoding="utf-8"))
    expected = {}
    for student in CLASS:
        answers = student_answers(key, student.id)
        release = json.loads((hw / "release" / f"{student.id}.ipynb").read_text("utf-8"))
        nb = make_submission(student, release, answers,
                             manifest["students"][student.id]["questions"])
        if nb is not None:
            text = json.dumps(nb, indent=1, sort_keys=True, ensure_ascii=False) + "\n"
            (folder / f"{student.id}.ipynb").write_text(text, encoding="utf-8")
        expected[student.id] = intended(student, answers)
    return expected


def grade(out: Path, timeout: float, jobs: int | None):
    """Step 3: the real grader, with its progress display; returns its RunReport.

    Sandboxed where bubblewrap is available. The demo's submissions are notebooks the demo
    itself just wrote, not untrusted code, so without bubblewrap it grades them unsandboxed
    (records say so) rather than fail on a fresh machine; real grading refuses instead.
    """
    from grader.limits import Limits
    from grader.pipeline import grade_assignment
    from grader.progress import Progress
    from grader.sandbox import available

    sandbox = available() is not None
    if not sandbox:
        print("      note: bubblewrap (bwrap) is not installed, so the demo grades its own "
              "sample notebooks without the sandbox; `eulertop grade` on real submissions "
              "needs it (apt-get install bubblewrap)", file=sys.stderr)
    return grade_assignment(out / HW, out / SUBMISSIONS, limits=Limits(total_timeout=timeout),
                            jobs=jobs, on_plan=lambda n: Progress(n), sandbox=sandbox)


def bench(out: Path) -> tuple[bool, str]:
    """Step 4: ``eulertop bench --quick`` in its own process; (ok, a note for the report)."""
    if importlib.util.find_spec("solver.bench.cli") is None:
        return True, "charts skipped: solver.bench is not installed"
    if importlib.util.find_spec("matplotlib") is None:
        return True, "charts skipped: matplotlib is not installed"
    command = [sys.executable, "-m", "eulertop", "bench", "--quick", "--out", str(out / BENCH)]
    done = subprocess.run(command, stdout=subprocess.DEVNULL, check=False)
    if done.returncode != 0:
        return False, f"charts FAILED: '{' '.join(command[1:])}' exited with {done.returncode}"
    charts = sorted(p.name for p in (out / BENCH).glob("*.png"))
    return True, f"charts: {out / BENCH}/ ({', '.join(charts)}; summary.md)"


# --------------------------------------------------------------------------------------------
# the report


def said(result) -> str:
    """What the grader said about one student, in words (from the record only)."""
    if result.status != "graded":
        return (result.message or result.status).splitlines()[0]
    parts = list(result.execution.get("cell_errors") or [])
    for a in result.answers:
        v = a.verdict
        if v.status == "correct":
            continue
        if v.mistake:
            parts.append(f"{a.variable} {v.status}: {v.mistake} — {v.message}")
        elif v.status == "missing":
            parts.append(f"{a.variable} not set")
        else:
            parts.append(f"{a.variable} {v.status}: {v.message}")
    return "; ".join(parts) if parts else "all correct"


def _cut(text: str, width: int) -> str:
    return text if len(text) <= width else text[: width - 1] + "…"


def student_table(results: Sequence, students: Sequence) -> str:
    """One line per student: id, name, what the demo made, points, what the grader said."""
    from eulertop.sample_class import describe
    from grader.gradebook import number

    rows = [("id", "name", "made", "points", "the grader said")]
    for s, r in zip(students, results, strict=True):
        points = f"{number(r.points)}/{number(r.max_points)}"
        rows.append((s.id, s.name, describe(s), points, _cut(said(r), 110)))
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    lines = ["  ".join(c.ljust(w) for c, w in zip(row[:4], widths, strict=True)) + "  " + row[4]
             for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths) + "  " + "-" * 15)
    return "\n".join(lines)


def counts(results: Sequence, students: Sequence) -> str:
    """The class in numbers: groups made, statuses, full marks."""
    made = {g: sum(s.group == g for s in students) for g in ("correct", "wrong", "mistake",
                                                              "broken")}
    status = {}
    for r in results:
        status[r.status] = status.get(r.status, 0) + 1
    full = sum(r.status == "graded" and r.points == r.max_points for r in results)
    return (f"{len(students)} students: made " + ", ".join(f"{n} {g}" for g, n in made.items())
            + "; graded " + ", ".join(f"{n} {k}" for k, n in status.items())
            + f"; {full} with full marks")


def check(results: Sequence, expected: dict) -> list[str]:
    """Every way a record differs from the intended outcome, as ``"id: what"`` lines."""
    from eulertop.sample_class import mismatches

    lines = []
    for r in results:
        verdicts = {a.variable: a.verdict for a in r.answers}
        lines += [f"{r.student_id}: {m}" for m in
                  mismatches(expected[r.student_id], r.status, verdicts)]
    return lines


def report(out: Path, run, expected: dict, bench_note: str) -> bool:
    """Print the table, counts, locations and the check; True when all was as intended."""
    from eulertop.sample_class import CLASS

    by_id = {r.student_id: r for r in run.results}
    results = [by_id[s.id] for s in CLASS]
    print(student_table(results, CLASS))
    print("\n" + counts(results, CLASS))
    graded = out / HW / "graded"
    print(f"\ngradebook:      {graded / 'grades.csv'}")
    print(f"feedback pages: {graded / 'feedback'}/<id>.html")
    print(f"results:        {graded / 'results'}/<id>.json")
    print(f"submissions:    {out / SUBMISSIONS}/<id>.ipynb  (assignment: {out / HW}/)")
    print(bench_note)
    problems = check(results, expected)
    if problems:
        print(f"\nNOT as intended ({len(problems)}):")
        print("\n".join(f"  {p}" for p in problems))
        return False
    n = sum(len(e.answers) for e in expected.values())
    print(f"\ncheck: all {n} answers of {len(CLASS)} students were judged as intended")
    return True


# --------------------------------------------------------------------------------------------


def run_demo(args: argparse.Namespace) -> int:
    """Run ``eulertop demo`` (module docstring); the exit status."""
    out: Path = args.out
    try:
        prepare_folder(out, args.force)
    except FolderRefused as e:
        print(f"eulertop demo: {e}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    _step(f"1/4 generating the assignment for a sample class of 24 in {out / HW}")
    summary = generate(out)
    print(f"generated {len(summary.students)} students × {len(summary.problems)} questions "
          f"({', '.join(summary.problems)}), seed {summary.seed}")
    _step(f"2/4 making the submissions in {out / SUBMISSIONS} from each release notebook")
    expected = hand_in(out)
    print(f"{len(list((out / SUBMISSIONS).glob('*.ipynb')))} notebooks handed in")
    _step(f"3/4 grading (time limit {args.timeout:g} s per notebook; progress below)")
    from grader.assignment import UsageError

    try:
        run = grade(out, args.timeout, args.jobs)
    except UsageError as e:
        print(f"eulertop demo: grading failed: {e}", file=sys.stderr)
        return 1
    ok, note = True, "charts skipped (--no-bench)"
    if not args.no_bench:
        _step(f"4/4 work-precision charts: eulertop bench --quick --out {out / BENCH}")
        ok, note = bench(out)
    _step(f"the class, graded ({time.perf_counter() - start:.0f} s in all)")
    as_intended = report(out, run, expected, note)
    return 0 if ok and as_intended else 1
