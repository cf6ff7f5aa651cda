"""``eulertop rescore``, ``eulertop key set``, ``eulertop rekey`` and ``eulertop override``:
amending a graded class without running a notebook again (issue 26).

Each prints what changed — student, answer, points before → after, and why — and a summary;
``--dry-run`` prints the same and writes nothing. A key change or an override is followed by a
rescore (:func:`grader.rescore.rescore`), which rebuilds the records, ``grades.csv``,
``answers.csv``, the feedback pages and the report, and writes one line to the audit trail
(``HW/graded/audit.jsonl``: when, who, what, why). Exit status 0, or 2 on usage errors (one
line, no traceback).

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from grader.assignment import Assignment

from grader.transaction import LOCK_WAIT

SHOWN = 50
"""Changes printed at most (the audit trail has them all)."""


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("hw", type=Path, metavar="HW",
                        help="assignment folder written by 'eulertop generate'")
    parser.add_argument("--out", type=Path, metavar="DIR",
                        help="grading output folder (default: HW/graded)")
    parser.add_argument("--dry-run", action="store_true",
                        help="say what would change; write nothing")
    parser.add_argument("--wait", type=float, default=LOCK_WAIT, metavar="SECONDS",
                        help="wait this long for another command on the class to finish "
                             f"(default {LOCK_WAIT:g})")
    parser.add_argument("--reveal", action="store_true",
                        help="show each student their own key values in their feedback page "
                             "(as 'eulertop grade --reveal')")


def add_rescore_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop rescore``."""
    _common(parser)


def add_key_arguments(parser: argparse.ArgumentParser) -> None:
    """``eulertop key set HW ANSWER [--rtol R] [--atol A] [--points P] [--accept VALUE]``."""
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    change = actions.add_parser("set", help="change one answer of the key, then rescore",
                                description="Change one answer's tolerances, points or accepted "
                                            "values, for every student or one; then rescore.")
    _common(change)
    change.add_argument("answer", metavar="ANSWER",
                        help="an answer variable (q3_T_nut) for every student, or "
                             "STUDENT:q3_T_nut for one")
    change.add_argument("--rtol", type=float, metavar="R", help="relative tolerance")
    change.add_argument("--atol", type=float, metavar="A", help="absolute tolerance")
    change.add_argument("--points", type=float, metavar="P", help="points of the answer")
    change.add_argument("--accept", action="append", default=[], metavar="VALUE",
                        help="also accept VALUE (JSON: 2.5, [1, 0, 0], true, \"loops\"; "
                             "repeatable), e.g. another sign convention")


def add_rekey_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop rekey``."""
    _common(parser)


def add_override_arguments(parser: argparse.ArgumentParser) -> None:
    """``eulertop override HW STUDENT [ANSWER] --points P --reason "..." | --remove``."""
    _common(parser)
    parser.add_argument("student", metavar="STUDENT", help="the student's id")
    parser.add_argument("answer", nargs="?", metavar="ANSWER",
                        help="an answer variable (q3_T_nut); without it, the student's total")
    parser.add_argument("--points", type=float, metavar="P", help="the points to give")
    parser.add_argument("--reason", metavar="TEXT", help="why (shown to the student)")
    parser.add_argument("--remove", action="store_true",
                        help="take back the override of that answer (or total)")


def _say_rescore(command: str, report) -> None:
    from grader.rescore import change_lines

    verb = "would change" if report.dry_run else "changed"
    if report.changes:
        print(f"{command}: {verb}:")
        for line in change_lines(report.changes, SHOWN):
            print(line)
    students = {c.student for c in report.changes}
    print(f"{command}: {len(report.rescored)} student(s) rescored, {len(students)} {verb}, "
          f"{report.unchanged} unchanged" + ("; nothing written (--dry-run)"
                                             if report.dry_run else ""))
    if report.unread:
        answers = sorted({v for vs in report.unread.values() for v in vs})
        print(f"{command}: {len(report.unread)} student(s) answered before the key had "
              f"{', '.join(answers)}: those answers are unread until their notebooks run "
              f"again; 'eulertop grade HW SUBMISSIONS' runs exactly these: "
              f"{', '.join(sorted(report.unread))}")


def _run(command: str, body) -> int:
    from grader.assignment import UsageError

    try:
        return body()
    except UsageError as e:
        print(f"{command}: {e}", file=sys.stderr)
        return 2


def _rescore(args: argparse.Namespace, command: str, change=None) -> int:
    """Rescore (after ``change``, worked out under the class's lock), and say what happened."""
    from grader.rescore import rescore

    def body() -> int:
        report = rescore(args.hw, args.out, change=change, dry_run=args.dry_run,
                         reveal=args.reveal, wait=args.wait, command=command)
        amendment = report.amendment
        for line in amendment.lines[:SHOWN]:
            print(f"  {line}")
        if len(amendment.lines) > SHOWN:
            print(f"  … and {len(amendment.lines) - SHOWN} more")
        if amendment.unchanged:
            print(f"{command}: {amendment.unchanged}; nothing changed")
            return 0
        if amendment.key is not None and not args.dry_run:
            print(f"{command}: wrote {Path(args.hw) / 'key.json'} (the old one kept beside it)")
        _say_rescore(command, report)
        return 0

    return _run(command, body)


def run_rescore(args: argparse.Namespace) -> int:
    """Run ``eulertop rescore``."""
    return _rescore(args, "eulertop rescore")


def _accepted(texts: list[str]) -> list:
    from grader.assignment import UsageError

    values = []
    for text in texts:
        try:
            values.append(json.loads(text))
        except json.JSONDecodeError:
            values.append(text)  # a bare word: a choice or an expression
        if isinstance(values[-1], float) and values[-1] != values[-1]:
            raise UsageError(f"--accept {text}: not a value to accept")
    return values


def _lines(changes) -> tuple[str, ...]:
    width = max((len(c.student) for c in changes), default=0)
    return tuple(c.line(width) for c in changes)


def key_change(args: argparse.Namespace):
    """``eulertop key set``'s change: the key with one answer changed (UsageError: refused)."""
    from grader.key_edit import set_answer
    from grader.rescore import Amendment

    def change(a, overrides) -> Amendment:
        key, changes = set_answer(a, args.answer, rtol=args.rtol, atol=args.atol,
                                  points=args.points, accept=_accepted(args.accept))
        if not changes:
            return Amendment(unchanged=f"{args.answer} is already so")
        fields = sorted({f"{c.field} {c.after!r}" for c in changes})
        students = len({c.student for c in changes})
        return Amendment("key set", f"key set {args.answer}: {', '.join(fields)}", key=key,
                         details={"key_changes": [c.as_dict() for c in changes]},
                         students=frozenset(),  # those whose key entry changed
                         lines=(f"{args.answer} of {students} student(s):",
                                *_lines(changes)))

    return change


def run_key(args: argparse.Namespace) -> int:
    """Run ``eulertop key set``."""
    return _rescore(args, "eulertop key set", key_change(args))


def rekey_change(args: argparse.Namespace):
    """``eulertop rekey``'s change: the key recomputed from the recorded parameters, with each
    family file edited since ``generate`` named and its new SHA-256 recorded."""
    from grader.key_edit import rekeyed
    from grader.rescore import Amendment
    from problems.templates import FAMILIES

    def change(a, overrides) -> Amendment:
        a, edited = _edited_families_recorded("eulertop rekey", a, args.dry_run)
        key, changes = rekeyed(a, FAMILIES)
        head = (f"{len(changes)} value(s) of the key differ from what today's solver gives",)
        if not changes and not edited:
            return Amendment(unchanged="the key is as the families compute it", lines=head)
        details = {"key_changes": [c.as_dict() for c in changes]}
        if edited:
            details["family_files"] = edited
        return Amendment("rekey", "rekey: the key recomputed from the recorded parameters",
                         key=key, details=details, manifest=a.manifest if edited else None,
                         # an edited family may credit anyone who has it: everyone, then
                         students=None if edited else frozenset(),
                         lines=head + _lines(changes))

    return change


def run_rekey(args: argparse.Namespace) -> int:
    """Run ``eulertop rekey``."""
    return _rescore(args, "eulertop rekey", rekey_change(args))


def _edited_families_recorded(command: str, a: Assignment,
                              dry_run: bool) -> tuple[Assignment, list[dict]]:
    """``a`` recording the SHA-256 each family file edited since ``generate`` has now (the
    caller writes it), named in the output, and those files for the trail; UsageError for
    one that is gone."""
    from dataclasses import replace

    from grader.assignment import UsageError
    from grader.follow_through import edited_message
    from problems.family_files import edited_families, with_family_hashes

    edited = edited_families(a.manifest, a.folder)
    if not edited:
        return a, []
    if any(e.now is None for e in edited):
        raise UsageError(f"{edited_message(a.folder, edited)}: put it back to recompute the key "
                         "with it")
    done = "would be recorded (--dry-run)" if dry_run else "recorded"
    print(f"{command}: {edited_message(a.folder, edited)}: the key and follow-through credit "
          f"are recomputed with it; its new sha256 {done} in {a.folder / 'assignment.json'}")
    return replace(a, manifest=with_family_hashes(a.manifest, edited)), \
        [{"family": e.name, "file": str(e.path), "was": e.recorded, "now": e.now}
         for e in edited]


def override_change(args: argparse.Namespace):
    """``eulertop override``'s change: the overrides with one added, replaced or removed, from
    the overrides as they are under the lock (so that none is lost)."""
    from grader.assignment import UsageError
    from grader.audit import who
    from grader.grade_one import now
    from grader.overrides import Override
    from grader.rescore import Amendment

    def change(a, existing) -> Amendment:
        if args.student not in a.ids:
            raise UsageError(f"no student {args.student!r} in the assignment's roster")
        kept = tuple(o for o in existing if (o.student, o.answer) != (args.student, args.answer))
        what = args.answer or "total"
        if args.remove:
            if len(kept) == len(existing):
                raise UsageError(f"no override of {args.student}'s {what} to remove")
            return Amendment("override removed", f"override of {args.student}'s {what} removed",
                             overrides=kept, students=frozenset({args.student}))
        if args.points is None or not args.reason:
            raise UsageError("give --points P and --reason TEXT (or --remove)")
        new = Override(args.student, args.answer, args.points, args.reason, who(), now())
        return Amendment("override", args.reason, overrides=(*kept, new),
                         students=frozenset({args.student}))

    return change


def run_override(args: argparse.Namespace) -> int:
    """Run ``eulertop override``."""
    return _rescore(args, "eulertop override", override_change(args))
