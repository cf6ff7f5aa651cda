"""``eulertop grade`` and ``eulertop check`` (dispatched from ``eulertop/cli.py``).

Top-level imports stay light (argparse, pathlib) so that ``eulertop --help`` is fast; the
pipeline, nbclient and the comparison are imported inside the run functions.

Exit status of ``grade``: 0 when every submission was graded (whatever the scores), 1 when
some could not be (listed on stderr), 2 on usage errors (no assignment, no key, an unreadable
folder, bad options, another run in progress) — one line, no traceback.
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
from pathlib import Path


def add_check_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop check`` (implemented in :mod:`grader.check`)."""
    from grader.check import add_check_arguments as add

    add(parser)


def run_check(args: argparse.Namespace) -> int:
    """Run ``eulertop check`` (:mod:`grader.check`)."""
    from grader.check import run_check as run

    return run(args)


def whole_number_argument(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def seconds_argument(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds, got {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text}")
    return value


def add_grade_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop grade``."""
    parser.add_argument("hw", type=Path, metavar="HW",
                        help="assignment folder written by 'eulertop generate'")
    parser.add_argument("submissions", type=Path, metavar="SUBMISSIONS",
                        help="folder of submissions: <id>.ipynb or <id>/<one notebook>.ipynb")
    parser.add_argument("--out", type=Path, metavar="DIR",
                        help="where results/, feedback/ and grades.csv go (default: HW/graded)")
    parser.add_argument("--jobs", type=whole_number_argument, metavar="N",
                        help=f"submissions graded at once (default: cores, {os.cpu_count()})")
    parser.add_argument("--timeout", type=seconds_argument, metavar="S",
                        help="time limit for a whole notebook, kernel start included "
                             "(default 120 s; a cell gets at most 30 s)")
    parser.add_argument("--force", action="store_true",
                        help="regrade every submission, even those unchanged since last run")
    parser.add_argument("--reveal", action="store_true",
                        help="show each student their own key values in their feedback page")
    parser.add_argument("--no-sandbox", action="store_true",
                        help="run student code WITHOUT the bubblewrap sandbox (where none can "
                             "be had); it can then read the key and your files. Every run "
                             "warns, and the records and grades.csv say so")
    parser.add_argument("--cold-kernels", action="store_true",
                        help="start every kernel from scratch instead of forking it from a "
                             "pre-imported one (slower; the same isolation)")


def _limits(timeout: float | None):
    """``--timeout S`` sets the whole-notebook limit; a cell then gets at most that too
    (``Limits.effective_cell_timeout``)."""
    from grader.limits import Limits

    return Limits() if timeout is None else Limits(total_timeout=timeout)


def run_grade(args: argparse.Namespace, execute=None) -> int:
    """Run ``eulertop grade``; ``execute`` replaces the execution stage (tests, benchmarks)."""
    from grader.gradebook import summary_table
    from grader.pipeline import UsageError, grade_assignment
    from grader.progress import Progress

    try:
        report = grade_assignment(
            args.hw, args.submissions, args.out, limits=_limits(args.timeout), jobs=args.jobs,
            force=args.force, reveal=args.reveal, execute=execute,
            on_plan=lambda n: Progress(n), cold_kernels=getattr(args, "cold_kernels", False),
            sandbox=not getattr(args, "no_sandbox", False),
        )
    except UsageError as e:
        print(f"eulertop grade: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("eulertop grade: interrupted; every finished result is saved — run the same "
              "command again to grade the rest", file=sys.stderr, flush=True)
        sys.stdout.flush()
        if threading.active_count() > 1:
            os._exit(130)  # abandoned kernels' threads: do not wait for them at exit
        return 130
    print(summary_table(report.results, report.problems), end="")
    out = args.out or args.hw / "graded"
    kept = f"; {len(report.unchanged)} unchanged, kept (--force regrades)" if report.unchanged \
        else ""
    print(f"wrote {out / 'grades.csv'}, {out / 'results'}/, {out / 'feedback'}/, "
          f"{out / 'report.html'}{kept}")
    ignored = [p.message for p in report.problems if p.ignored]
    for line in ignored:
        print(f"eulertop grade: {line}", file=sys.stderr)
    if report.not_graded:
        print(f"eulertop grade: {len(report.not_graded)} submission(s) could not be graded:",
              file=sys.stderr)
        for line in report.not_graded:
            print(f"  {line}", file=sys.stderr)
        return 1
    return 0
