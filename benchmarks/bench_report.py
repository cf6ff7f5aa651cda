"""Benchmark the class report: its time, and its false and missed flags over many classes.

For each seed, an honest class (default 200 students) and a planted one (default 60) are made
by the tests' synthetic class (``tests/grader/report/synthetic_class.py``: real variants, real
grading without kernels). Printed per seed: the time of the report alone (loading the records,
every analysis, the figures and the page), what was flagged in the honest class (false
positives: pairs, near-identical code, common slips, broken answers) and, with the honest
pair closest to a flag, how far it stayed (expected chance pairs vs the threshold); and whether
every planted pattern was found in the planted class.

Run from the repository root:
``PYTHONPATH=. python benchmarks/bench_report.py [--seeds 5] [--honest 200] [--planted 60]``
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

from grader.report import build_report, load_class, write_report
from grader.report.cli import submitted_notebooks
from grader.report.copying import ALPHA
from tests.grader.report.synthetic_class import BROKEN, PLANTED, SLIP, build_class


def _report(made):
    start = time.perf_counter()
    data = load_class(made.hw, made.graded)
    report = build_report(data, submitted_notebooks(made.submissions, data.ids))
    write_report(report, made.graded / "bench.html")
    return report, time.perf_counter() - start


def honest(folder: Path, n: int, seed: int) -> str:
    report, seconds = _report(build_class(folder, n, planted=False, seed=seed))
    closest = min((p.expected for p in report.pairs), default=float("inf"))
    broken = sum("possibly broken" in s.flags for s in report.answers)
    return (f"honest {n}: report {seconds:.2f} s; flagged pairs {len(report.flagged_pairs)}, "
            f"code pairs {len(report.code)}, slip groups {len(report.slips)}, broken {broken}; "
            f"closest honest pair expects {closest:.3g} chance pairs (flag at ≤ {ALPHA})")


def planted(folder: Path, n: int, seed: int) -> str:
    made = build_class(folder, n, planted=True, seed=seed)
    report, seconds = _report(made)
    pairs = {frozenset(p.students) for p in report.flagged_pairs}
    wanted = {frozenset(p) for p in PLANTED.values()}
    slip = next((g for g in report.slips if g.variable == SLIP and g.relation == "factor_2"),
                None)
    slip_ok = slip is not None and set(slip.students) == set(made.slip_students)
    broken = any(s.label == BROKEN and "possibly broken" in s.flags for s in report.answers)
    code = [set(c.students) for c in report.code] == [set(PLANTED["notebook"])]
    return (f"planted {n}: report {seconds:.2f} s; copy pairs found {len(pairs & wanted)}/3, "
            f"extra {len(pairs - wanted)}; slip exact {slip_ok}; broken {broken}; "
            f"copied notebook only code pair {code}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--honest", type=int, default=200)
    parser.add_argument("--planted", type=int, default=60)
    args = parser.parse_args(argv)
    print(f"{platform.machine()} {os.cpu_count()} cores, Python {platform.python_version()}")
    for seed in range(1, args.seeds + 1):
        with tempfile.TemporaryDirectory() as tmp:
            print(f"seed {seed}: {honest(Path(tmp) / 'h', args.honest, seed)}", flush=True)
            print(f"seed {seed}: {planted(Path(tmp) / 'p', args.planted, seed)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
