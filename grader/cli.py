"""``eulertop grade`` and ``eulertop check`` (dispatched from ``eulertop/cli.py``).

Top-level imports stay light (argparse, pathlib) so that ``eulertop --help`` is fast; the
pipeline, nbclient and the comparison are imported inside the run functions.

Exit status of ``grade``: 0 when every submission was graded (whatever the scores), 1 when
some could not be (listed on stderr), 2 on usage errors (no assignment, no key, an unreadable
folder, bad options, another run in progress) — one line, no traceback.

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
from contextlib import nullcontext
from pathlib import Path

# the one --max-size of grade and check (and eulertop-check), in the module both read with
from grader.submission_file import MAX_SIZE_HELP, size_argument


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
                        help="folder of submissions: <id>.ipynb or <id>/<one notebook>.ipynb; "
                             "or the bulk download of Canvas, Moodle, Blackboard or "
                             "Gradescope, as a folder or the .zip itself")
    parser.add_argument("--out", type=Path, metavar="DIR",
                        help="where results/, feedback/ and grades.csv go (default: HW/graded)")
    parser.add_argument("--jobs", type=whole_number_argument, metavar="N",
                        help=f"submissions graded at once (default: cores, {os.cpu_count()})")
    parser.add_argument("--timeout", type=seconds_argument, metavar="S",
                        help="time limit for a whole notebook, kernel start included "
                             "(default 120 s)")
    parser.add_argument("--cell-timeout", type=seconds_argument, metavar="S",
                        help="time limit for one cell (default 30 s; never more than --timeout)")
    parser.add_argument("--max-size", type=size_argument, metavar="SIZE", help=MAX_SIZE_HELP)
    parser.add_argument("--force", action="store_true",
                        help="regrade every submission, even those unchanged since last run")
    parser.add_argument("--times", type=Path, metavar="FILE",
                        help="when each submission came in (CSV id,submitted_at in ISO 8601 "
                             "with its offset), for the late policy, where the LMS download "
                             "does not say")
    parser.add_argument("--wait", type=float, default=600.0, metavar="SECONDS",
                        help="wait this long for another command on the output folder to "
                             "finish (default 600)")
    parser.add_argument("--reveal", action="store_true",
                        help="show each student their own key values in their feedback page")
    parser.add_argument("--yes", action="store_true",
                        help="grade SUBMISSIONS even when it is the assignment's release or "
                             "solutions folder, or a copy of one (refused otherwise: it would "
                             "give everyone 0 or full marks)")
    parser.add_argument("--no-sandbox", action="store_true",
                        help="run student code WITHOUT the bubblewrap sandbox (where none can "
                             "be had); it can then read the key and your files. Every run "
                             "warns, and the records and grades.csv say so")
    parser.add_argument("--roster", type=Path, metavar="CSV",
                        help="an LMS class list whose identifiers match the download's files "
                             "(default: the one the assignment was generated from); its "
                             "student ids must be the assignment's")
    parser.add_argument("--roster-format", metavar="FORMAT",
                        choices=("eulertop", "canvas", "moodle", "blackboard", "gradescope"),
                        help="read --roster as this format instead of recognising it")
    parser.add_argument("--cold-kernels", action="store_true",
                        help="start every kernel from scratch instead of forking it from a "
                             "pre-imported one (slower; the same isolation)")
    parser.add_argument("--cluster", metavar="ADDRESS",
                        help="grade on a Dask cluster: a scheduler's address, e.g. "
                             "tcp://HOST:8786, or local:N to start N local workers; each "
                             "worker runs the sandbox of its machine (needs "
                             "pip install 'eulertop[cluster]'; --jobs is then unused)")


def _limits(args: argparse.Namespace):
    """``--timeout``, ``--cell-timeout``, ``--max-size`` as :class:`grader.limits.Limits`; a
    cell limit above the notebook's is clipped to it, with a note on stderr."""
    from grader.limits import Limits

    given = {"total_timeout": getattr(args, "timeout", None),
             "cell_timeout": getattr(args, "cell_timeout", None),
             "submission_bytes": getattr(args, "max_size", None)}
    limits = Limits(**{k: v for k, v in given.items() if v is not None})
    if limits.cell_timeout > limits.total_timeout and given["cell_timeout"] is not None:
        print(f"eulertop: note: --cell-timeout {limits.cell_timeout:g} s is above --timeout "
              f"{limits.total_timeout:g} s; a cell gets at most {limits.total_timeout:g} s",
              file=sys.stderr)
    return limits


def run_grade(args: argparse.Namespace, execute=None) -> int:
    """Run ``eulertop grade``; ``execute`` replaces the execution stage (tests, benchmarks).

    The run's first zygote is started before anything else is imported or read
    (:func:`grader.kernels.early.early_pool`): it imports while this process does."""
    from grader.kernels.early import early_pool

    warm = execute is None and not getattr(args, "cold_kernels", False) and \
        getattr(args, "cluster", None) is None
    with early_pool(not getattr(args, "no_sandbox", False)) if warm else nullcontext() as early:
        return _grade(args, execute, early)


def _grade(args: argparse.Namespace, execute, early) -> int:
    """``eulertop grade`` with ``early``, the run's first zygote if it has one."""
    from grader.assignment import UsageError
    from grader.gradebook import summary_table
    from grader.graded_folder import graded_folder
    from grader.lms.registry import CLASS_LISTS
    from grader.pipeline import grade_assignment
    from grader.plain_text import printable
    from grader.progress import Progress
    from problems.roster import RosterError, read_roster

    try:
        class_list = () if getattr(args, "roster", None) is None else \
            read_roster(args.roster, args.roster_format, CLASS_LISTS).rows
        report = grade_assignment(
            args.hw, args.submissions, args.out, limits=_limits(args), jobs=args.jobs,
            force=args.force, reveal=args.reveal, execute=execute,
            on_plan=lambda n: Progress(n), cold_kernels=getattr(args, "cold_kernels", False),
            sandbox=not getattr(args, "no_sandbox", False), class_list=class_list,
            cluster=getattr(args, "cluster", None), wait=args.wait,
            yes=getattr(args, "yes", False), times=getattr(args, "times", None),
            early=early,
        )
    except (UsageError, RosterError) as e:
        print(f"eulertop grade: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as stop:
        done = (f" after grading {stop.graded} of {stop.total} submission(s)"
                if hasattr(stop, "graded") else "")
        print(f"\neulertop grade: interrupted{done}; every finished result is saved, those "
              "in flight were stopped and not recorded — run the same command again to grade "
              "the rest", file=sys.stderr, flush=True)
        sys.stdout.flush()
        if threading.active_count() > 1:
            os._exit(130)  # abandoned kernels' threads: do not wait for them at exit
        return 130
    print(printable(summary_table(report.results, report.problems)), end="")
    out = graded_folder(args.hw, args.out)
    kept = f"; {len(report.unchanged)} unchanged, kept (--force regrades)" if report.unchanged \
        else ""
    print(f"wrote {out / 'grades.csv'}, {out / 'results'}/, {out / 'feedback'}/, "
          f"{out / 'report.html'}{kept}")
    ignored = [p.message for p in report.problems if p.ignored]
    for line in report.notes:
        print(f"eulertop grade: {line}", file=sys.stderr)
    for line in ignored:
        print(f"eulertop grade: {printable(line)}", file=sys.stderr)
    if report.not_graded:
        print(f"eulertop grade: {len(report.not_graded)} submission(s) could not be graded:",
              file=sys.stderr)
        for line in report.not_graded:
            print(f"  {printable(line)}", file=sys.stderr)
        return 1
    return 0
