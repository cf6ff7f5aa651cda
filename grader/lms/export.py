"""``eulertop export HW --to canvas|moodle|blackboard|gradescope``: the gradebook an LMS imports.

Written from the result records (``HW/graded/results/<id>.json``) — like ``grades.csv``, a view
of them — one row per roster student, in roster order, in the layout of the LMS's own import
(each LMS module's ``write_import``; ``docs/lms.md``). The students' LMS identifiers come from
the class list the assignment was generated with, or from ``--roster`` (an LMS class list whose
student ids are the assignment's). A student with no submission is left blank — the LMS then
keeps whatever it has — unless ``--missing-as-zero``; a submission that could not be graded
has its record's 0. Written answers not reviewed yet (``pending``, :mod:`grader.reviews`) count
0 in a total: the export says how many there are and refuses unless ``--allow-pending``, with
which it exports the totals as they are and warns.

``answers.csv`` (one row per student and answer: :func:`grader.gradebook.answers_rows`) is
written beside the results every time, too.

Exit status: 0 written, 2 a usage error (no graded results, a roster without the LMS's
identifiers …), one line, no traceback.

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

LMS_NAMES = ("canvas", "moodle", "blackboard", "gradescope")


def add_export_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop export``."""
    parser.add_argument("hw", type=Path, metavar="HW",
                        help="assignment folder written by 'eulertop generate', graded")
    parser.add_argument("--to", required=True, choices=LMS_NAMES, metavar="LMS",
                        help="the LMS whose import to write: " + ", ".join(LMS_NAMES))
    parser.add_argument("--out", type=Path, metavar="FILE",
                        help="file to write (default: GRADED/<lms>-import.csv)")
    parser.add_argument("--graded", type=Path, metavar="DIR",
                        help="the grading run's folder (default: HW/graded)")
    parser.add_argument("--roster", type=Path, metavar="CSV",
                        help="the LMS's class list, if the assignment was generated from "
                             "another one (its student ids must be the assignment's)")
    parser.add_argument("--roster-format", metavar="FORMAT",
                        choices=("eulertop", *LMS_NAMES),
                        help="read --roster as this format instead of recognising it")
    parser.add_argument("--assignment-id", metavar="N",
                        help="the LMS's id of the gradebook column (Canvas: the assignment "
                             "id; Blackboard: the Grade Center column id)")
    parser.add_argument("--missing-as-zero", action="store_true",
                        help="give 0 to students with no submission (default: leave blank)")
    parser.add_argument("--no-late", action="store_true",
                        help="the points before the late penalty, for an LMS that applies its "
                             "own late policy (an override of a total still stands)")
    parser.add_argument("--allow-pending", action="store_true",
                        help="export even though some written answers are not reviewed yet "
                             "(they count 0 in the totals)")


class ExportError(ValueError):
    """The export cannot be written; nothing was."""


def pending_line(results) -> str:
    """How many written answers of how many students wait for a review (``""``: none)."""
    from grader.gradebook import pending_count

    waiting = {sid: pending_count(r) for sid, r in results.items() if r is not None}
    waiting = {sid: n for sid, n in waiting.items() if n}
    if not waiting:
        return ""
    return (f"{sum(waiting.values())} written answer(s) of {len(waiting)} student(s) are not "
            "reviewed yet and count 0 in their totals")


def _rows(assignment, roster_path: Path | None, roster_format: str | None) -> tuple[dict, ...]:
    """The roster rows of the assignment's students, from ``--roster`` when given."""
    if roster_path is None:
        return assignment.rows
    from grader.lms.registry import CLASS_LISTS
    from problems.roster import read_roster

    roster = read_roster(roster_path, roster_format, CLASS_LISTS)
    by_id = {r["id"]: r for r in roster.rows}
    absent = [sid for sid in assignment.ids if sid not in by_id]
    if absent:
        raise ExportError(f"{roster_path}: the assignment's students "
                          f"{', '.join(absent[:5])}{' …' if len(absent) > 5 else ''} are not "
                          "in this class list (its student ids must be the assignment's)")
    return tuple(by_id[sid] for sid in assignment.ids)


def _feedback(result) -> str:
    """One line for the student: points, per question, and the record's first message line."""
    from grader.gradebook import number

    if result is None or result.status == "missing":
        return "no submission"
    per = result.question_points()
    maxima: dict[int, float] = {}
    for a in result.answers:
        maxima[a.question] = maxima.get(a.question, 0.0) + a.verdict.max_points
    parts = [f"{number(result.points)} of {number(result.max_points)} points",
             ", ".join(f"Q{q} {number(per[q])}/{number(m)}" for q, m in sorted(maxima.items()))]
    if result.status == "failed" and result.message:
        parts.append(result.message.splitlines()[0])
    return "; ".join(p for p in parts if p)


def _before_penalty(result) -> float:
    """A record's total without the late penalty; an override of the total stands."""
    if "total" in result.overridden:
        return result.points
    return result.points + result.late.get("points", 0.0)


def build_grades(hw: Path, graded: Path, roster: Path | None = None,
                 roster_format: str | None = None, column_id: str | None = None,
                 missing_as_zero: bool = False, no_late: bool = False):
    """The :class:`~grader.lms.classlist.Grades` of a graded assignment, and its records."""
    from grader.assignment import load_assignment
    from grader.gradebook import number
    from grader.graded_folder import RESULTS
    from grader.lms.classlist import Grades
    from grader.results import read_result

    a = load_assignment(hw)
    if not (graded / RESULTS).is_dir():
        raise ExportError(f"{graded}: no results/ here — run 'eulertop grade' first")
    results = {sid: read_result(graded / RESULTS / f"{sid}.json") for sid in a.ids}
    scores = {}
    for sid, r in results.items():
        blank = r is None or r.status == "missing"
        scores[sid] = ("0" if missing_as_zero else "") if blank else \
            number(_before_penalty(r) if no_late else r.points)
    maxima = [r.max_points for r in results.values() if r is not None]
    max_points = max(maxima) if maxima else 0.0
    rows = _rows(a, roster, roster_format)
    feedback = {sid: _feedback(r) for sid, r in results.items()}
    return Grades(rows, scores, feedback, a.title, max_points, column_id), a, results


def write_export(hw: Path, lms: str, out: Path | None = None, graded: Path | None = None,
                 **options) -> tuple[Path, Path]:
    """Write the import file of ``lms`` and ``answers.csv``; their paths.

    ``options``: ``roster``, ``roster_format``, ``column_id``, ``missing_as_zero``, ``no_late`` of
    :func:`build_grades`, and ``allow_pending`` (written answers not reviewed yet: refused
    without it, :class:`ExportError`; warned of on stderr with it). Raises
    :class:`ExportError`, ``grader.assignment.UsageError``, ``problems.roster.RosterError`` or
    ``grader.lms.classlist.ImportError_`` on bad input.
    """
    from grader.assignment import require_assignment_folder
    from grader.graded_folder import graded_folder
    from grader.transaction import class_lock

    graded = graded_folder(require_assignment_folder(hw), graded)
    if not graded.is_dir():
        raise ExportError(f"{graded}: no results/ here — run 'eulertop grade' first")
    with class_lock(graded, Path(hw), command="eulertop export"):  # no change read half-way
        return _export(hw, lms, out, graded, options)


def _export(hw: Path, lms: str, out: Path | None, graded: Path,
            options: dict) -> tuple[Path, Path]:
    from grader.gradebook import answers_rows, gradebook_csv
    from grader.graded_folder import ANSWERS
    from grader.lms.registry import LMS
    from grader.results import atomic_write_text

    allow_pending = options.pop("allow_pending", False)
    grades, a, results = build_grades(Path(hw), graded, **options)
    pending = pending_line(results)
    if pending and not allow_pending:
        raise ExportError(f"{pending}: review them first, or pass --allow-pending to export "
                          "the totals as they are")
    if pending:
        print(f"eulertop export: warning: {pending}", file=sys.stderr)
    table = LMS[lms].write_import(grades)
    out = Path(out) if out is not None else graded / f"{lms}-import.csv"
    # Blackboard wants every field of a .csv quoted
    atomic_write_text(out, gradebook_csv(table, quote_all=lms == "blackboard"))
    present = {sid: r for sid, r in results.items() if r is not None}
    answers = graded / ANSWERS
    atomic_write_text(answers, gradebook_csv(answers_rows(a.rows, present)))
    return out, answers


def run_export(args: argparse.Namespace) -> int:
    """Run ``eulertop export``."""
    from grader.assignment import UsageError
    from grader.lms.classlist import ImportError_
    from problems.roster import RosterError

    try:
        out, answers = write_export(
            args.hw, args.to, args.out, args.graded, roster=args.roster,
            roster_format=args.roster_format, column_id=args.assignment_id,
            missing_as_zero=args.missing_as_zero, no_late=args.no_late,
            allow_pending=args.allow_pending)
    except (ExportError, UsageError, RosterError, ImportError_) as e:
        print(f"eulertop export: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"eulertop export: cannot write: {e}", file=sys.stderr)
        return 2
    print(f"wrote {out} (import it into {args.to.title()}) and {answers}")
    return 0
