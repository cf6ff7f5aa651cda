"""Benchmark ``eulertop generate``: 300 students × all 14 families, notebooks and key.

Uses the registered templates in catalogue order, repeated when there are fewer than asked.
Prints the machine and its load, the median wall time of a few full runs with ``--jobs``
worker processes (default: one per core; target: under 5 s on the 2-core machine, issue 17)
and, from one extra pass in this process, how much CPU the templates alone take.

Run from the repository root (or after ``pip install -e .``):
``PYTHONPATH=. python benchmarks/bench_generate.py [--students 300] [--questions 14]
[--runs 3] [--jobs N]``
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from problems.generate import generate_assignment, student_variants
from problems.roster import Roster
from problems.templates import FAMILIES

TARGET_S = 5.0


def machine() -> str:
    """One line describing where the numbers were measured."""
    return (f"{platform.machine()} {platform.processor() or ''} {os.cpu_count()} cores, "
            f"Python {platform.python_version()}, numpy {np.__version__}, {platform.system()}")


def _cpu() -> float:
    """CPU seconds of this process and its finished children (the generator's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=300)
    parser.add_argument("--questions", type=int, default=14)
    parser.add_argument("--jobs", type=int, default=None,
                        help="worker processes (default: one per core)")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args(argv)
    if not FAMILIES:
        print("bench_generate: no problem families are registered "
              "(problems.templates.CATALOGUE is empty): nothing to measure", file=sys.stderr)
        return 1
    names = list(FAMILIES)
    problems = tuple((names * args.questions)[: args.questions])
    roster = Roster(columns=("id", "name"), rows=tuple(
        {"id": f"s{i:04d}", "name": f"Student {i}"} for i in range(args.students)))

    times, cpus = [], []
    for run in range(args.runs):
        with tempfile.TemporaryDirectory() as folder:
            start, cpu = time.perf_counter(), _cpu()
            generate_assignment(roster, Path(folder) / "HW", FAMILIES, problems=problems,
                                seed=run, title="benchmark", jobs=args.jobs)
            times.append(time.perf_counter() - start)
            cpus.append(_cpu() - cpu)
    start = time.perf_counter()
    for sid in roster.ids:
        student_variants(FAMILIES, problems, 0, sid)
    templates_s = time.perf_counter() - start

    median = statistics.median(times)
    print(f"machine: {machine()}; load average {os.getloadavg()[0]:.1f} at the end")
    print(f"problems: {', '.join(problems)}")
    print(f"generate {args.students} students × {args.questions} questions, "
          f"jobs {args.jobs or os.cpu_count()}: median {median:.2f} s "
          f"over {args.runs} runs (min {min(times):.2f}, max {max(times):.2f}); "
          f"templates alone {templates_s:.2f} s; target < {TARGET_S:.0f} s: "
          f"{'met' if median < TARGET_S else 'MISSED'}")
    print(f"CPU (this process and its workers, user + system): median "
          f"{statistics.median(cpus):.2f} s per run — on a machine with cores to spare, wall "
          f"time approaches CPU / jobs plus the start-up each worker repeats")
    return 0


if __name__ == "__main__":
    sys.exit(main())
