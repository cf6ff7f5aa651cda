"""``eulertop report HW [--graded DIR] [--out FILE] [--submissions DIR]``.

Writes the class report of a graded assignment (``report.html``, with ``report.csv`` and
``report_items.csv`` beside it). ``eulertop grade`` writes the same report at the end of every
run; this command rewrites it, for instance with the submissions folder for the code comparison.
Exit status 0, or 2 on a usage error (one line naming what is wrong, no traceback).

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_report_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop report``."""
    parser.add_argument("hw", type=Path, metavar="HW",
                        help="assignment folder written by 'eulertop generate'")
    parser.add_argument("--graded", type=Path, metavar="DIR",
                        help="the folder 'eulertop grade' wrote (default: HW/graded)")
    parser.add_argument("--out", type=Path, metavar="FILE",
                        help="the page to write (default: GRADED/report.html); the CSV files "
                             "go beside it")
    parser.add_argument("--submissions", type=Path, metavar="DIR",
                        help="the submissions folder, to compare the notebooks' code as well")


def submitted_notebooks(folder: Path, ids) -> dict[str, Path]:
    """Roster id → notebook, found as ``eulertop grade`` finds them (:mod:`grader.discover`)."""
    from grader.discover import discover

    return {s.student_id: s.path for s in discover(folder, ids).submissions}


def _locked_report(a, graded, submissions, page):
    """:func:`grader.report.write.report_for`, holding the class's lock (its records read
    whole, never half-way through a change) where the graded folder exists."""
    from grader.graded_folder import graded_folder
    from grader.report.write import report_for
    from grader.transaction import class_lock

    folder = graded_folder(a.folder, graded)
    if not folder.is_dir():
        return report_for(a, graded, submissions, page)  # its own message: nothing graded
    with class_lock(folder, a.folder, command="eulertop report"):
        return report_for(a, graded, submissions, page)


def run_report(args: argparse.Namespace) -> int:
    """Run ``eulertop report``; the exit status."""
    from grader.assignment import UsageError, load_assignment

    try:
        if args.out is not None and args.out.is_dir():
            raise UsageError(f"--out {args.out}: is a folder; give the page's file name, "
                             "e.g. report.html")
        a = load_assignment(args.hw)  # read once
        submissions = None
        if args.submissions is not None:
            if not args.submissions.is_dir():
                raise UsageError(f"--submissions {args.submissions}: not a folder")
            submissions = submitted_notebooks(args.submissions, a.ids)
        report, page = _locked_report(a, args.graded, submissions, args.out)
    except UsageError as err:
        print(f"eulertop report: {err}", file=sys.stderr)
        return 2
    except OSError as err:
        print(f"eulertop report: cannot write {err.filename}: {err.strerror}", file=sys.stderr)
        return 2
    flagged = len(report.flagged_pairs)
    print(f"wrote {page} (and its CSV files): {len(report.data.graded)} graded students, "
          f"{len(report.slips)} common wrong answer(s), {flagged} flagged pair(s), "
          f"{len(report.code)} pair(s) with near-identical code")
    return 0
