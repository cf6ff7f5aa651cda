"""Benchmark ``eulertop generate``: 300 students × all 14 families, notebooks and key.

Uses the registered templates in catalogue order, repeated when there are fewer than asked.
Each run is a fresh Python process, as ``eulertop generate`` is: the templates' one-time work
(sympy derivations, done once before the worker processes fork) is paid in every run, never
carried over from an earlier one. Prints the machine and its load average before and after,
and the median over the runs of

- ``generate``: the call ``generate_assignment`` alone (target: under 5 s on the 2-core machine
  with one worker process per core, issue 17);
- ``whole process``: interpreter start-up, imports and the call — what a user of
  ``eulertop generate`` waits for;
- ``CPU``: user + system seconds of that process and its worker processes.

``--breakdown`` adds one pass in one process that says where the CPU goes: the templates'
one-time work, drawing the variants, writing the notebooks, and the manifest and key entries.

Run from the repository root (or after ``pip install -e .``):
``PYTHONPATH=. python benchmarks/bench_generate.py [--students 300] [--questions 14]
[--runs 3] [--jobs N] [--breakdown]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

TARGET_S = 5.0
ROOT = Path(__file__).resolve().parent.parent


def machine() -> str:
    """One line describing where the numbers were measured."""
    import numpy as np

    return (f"{platform.machine()} {platform.processor() or ''} {os.cpu_count()} cores, "
            f"Python {platform.python_version()}, numpy {np.__version__}, {platform.system()}")


def _cpu() -> float:
    """CPU seconds of this process and its finished children (the generator's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _setup(students: int, questions: int) -> tuple:
    from problems.roster import Roster
    from problems.templates import FAMILIES

    names = list(FAMILIES)
    problems = tuple((names * questions)[:questions])
    roster = Roster(columns=("id", "name"), rows=tuple(
        {"id": f"s{i:04d}", "name": f"Student {i}"} for i in range(students)))
    return FAMILIES, problems, roster


def child(students: int, questions: int, jobs: int | None, seed: int, out: str) -> None:
    """One timed run, in a fresh process: print its times as one JSON line."""
    imports = time.perf_counter()
    from problems.generate import generate_assignment

    families, problems, roster = _setup(students, questions)
    imports = time.perf_counter() - imports
    start, cpu = time.perf_counter(), _cpu()
    generate_assignment(roster, Path(out), families, problems=problems, seed=seed,
                        title="benchmark", jobs=jobs)
    print(json.dumps({"generate": time.perf_counter() - start, "cpu_generate": _cpu() - cpu,
                      "cpu": _cpu(), "imports": imports, "problems": problems}))


def breakdown(students: int, questions: int) -> dict[str, float]:
    """CPU seconds of each part of generation, in this process (no files written)."""
    from problems.generate import (
        CompactJSON,
        key_entry,
        manifest_entry,
        prepare_families,
        student_variants,
    )
    from problems.notebook import build_notebooks, notebook_text

    families, problems, roster = _setup(students, questions)
    clock = time.process_time
    parts, start = {}, clock()
    prepare_families(families, problems)
    parts["one-time template work"], start = clock() - start, clock()
    drawn = [student_variants(families, problems, 0, row["id"]) for row in roster.rows]
    parts["drawing the variants"], start = clock() - start, clock()
    for row, variants in zip(roster.rows, drawn, strict=True):
        memo: dict = {}
        for notebook in build_notebooks("benchmark", row, variants):
            notebook_text(notebook, validate=False, memo=memo)
    parts["building and encoding the notebooks"], start = clock() - start, clock()
    for variants in drawn:
        CompactJSON.of(manifest_entry(variants, 0)), CompactJSON.of(key_entry(variants))
    parts["manifest and key entries"] = clock() - start
    return parts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=300)
    parser.add_argument("--questions", type=int, default=14)
    parser.add_argument("--jobs", type=int, default=None,
                        help="worker processes (default: one per core)")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--breakdown", action="store_true",
                        help="also say where the CPU goes (one more pass, in one process)")
    parser.add_argument("--child", metavar="OUT", help=argparse.SUPPRESS)
    parser.add_argument("--seed", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.students, args.questions, args.jobs, args.seed, args.child)
        return 0
    from problems.templates import FAMILIES

    if not FAMILIES:
        print("bench_generate: no problem families are registered "
              "(problems.templates.CATALOGUE is empty): nothing to measure", file=sys.stderr)
        return 1

    import tempfile

    load_before = os.getloadavg()[0]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)}
    runs = []
    for run in range(args.runs):
        with tempfile.TemporaryDirectory() as folder:
            command = [sys.executable, str(Path(__file__).resolve()), "--child",
                       str(Path(folder) / "HW"), "--seed", str(run), "--students",
                       str(args.students), "--questions", str(args.questions)]
            if args.jobs is not None:
                command += ["--jobs", str(args.jobs)]
            start = time.perf_counter()
            done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
            result = json.loads(done.stdout.splitlines()[-1])
            result["whole"] = time.perf_counter() - start
            runs.append(result)

    def median(key: str) -> float:
        return statistics.median(r[key] for r in runs)

    generate = [r["generate"] for r in runs]
    jobs = args.jobs or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                         else os.cpu_count())
    print(f"machine: {machine()}; load average {load_before:.1f} before, "
          f"{os.getloadavg()[0]:.1f} after")
    print(f"problems: {', '.join(runs[0]['problems'])}")
    verdict = ""
    if (args.students, args.questions) == (300, 14):  # the class size the target is set for
        verdict = (f"; target < {TARGET_S:.0f} s: "
                   f"{'met' if median('generate') < TARGET_S else 'MISSED'}")
    print(f"generate {args.students} students × {args.questions} questions, jobs {jobs}, "
          f"a fresh process per run: median {median('generate'):.2f} s over {args.runs} runs "
          f"(min {min(generate):.2f}, max {max(generate):.2f}){verdict}")
    print(f"whole process (start-up, imports {median('imports'):.2f} s, generate): median "
          f"{median('whole'):.2f} s")
    print(f"CPU (user + system, the process and its workers): median {median('cpu'):.2f} s per "
          f"run, of which generate {median('cpu_generate'):.2f} s")
    if args.breakdown:
        parts = breakdown(args.students, args.questions)
        print("where the CPU goes (one process, CPU s): " + "; ".join(
            f"{name} {seconds:.2f}" for name, seconds in parts.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
