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
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from grader.assignment import Assignment

SHOWN = 50
"""Changes printed at most (the audit trail has them all)."""


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("hw", type=Path, metavar="HW",
                        help="assignment folder written by 'eulertop generate'")
    parser.add_argument("--out", type=Path, metavar="DIR",
                        help="grading output folder (default: HW/graded)")
    parser.add_argument("--dry-run", action="store_true",
                        help="say what would change; write nothing")
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


def _run(command: str, body) -> int:
    from grader.assignment import UsageError

    try:
        return body()
    except UsageError as e:
        print(f"{command}: {e}", file=sys.stderr)
        return 2


def run_rescore(args: argparse.Namespace) -> int:
    """Run ``eulertop rescore``."""
    from grader.rescore import rescore

    def body() -> int:
        _say_rescore("eulertop rescore", rescore(args.hw, args.out, dry_run=args.dry_run,
                                                 reveal=args.reveal))
        return 0

    return _run("eulertop rescore", body)


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


def _with_key(args: argparse.Namespace, command: str, key: dict, lines: list[str],
              event: str, why: str, details: dict, manifest: dict | None = None) -> int:
    """Rescore against ``key`` (written first unless ``--dry-run``; ``manifest``: the
    ``assignment.json`` a dry run reads, where it differs from the file's)."""
    from grader.assignment import load_assignment
    from grader.key_edit import write_key
    from grader.rescore import rescore

    for line in lines[:SHOWN]:
        print(f"  {line}")
    if len(lines) > SHOWN:
        print(f"  … and {len(lines) - SHOWN} more")
    a = load_assignment(args.hw)
    changed = replace(a, key=key, manifest=manifest or a.manifest)
    if args.dry_run:
        _say_rescore(command, rescore(changed, args.out, dry_run=True))
        return 0
    old = write_key(args.hw, key)
    print(f"{command}: wrote {Path(args.hw) / 'key.json'} (the old one kept as {old.name})")
    report = rescore(load_assignment(args.hw), args.out, reveal=args.reveal, why=why,
                     event=event, **details, old_key=old.name)
    _say_rescore(command, report)
    return 0


def _lines(changes) -> list[str]:
    width = max((len(c.student) for c in changes), default=0)
    return [c.line(width) for c in changes]


def run_key(args: argparse.Namespace) -> int:
    """Run ``eulertop key set``."""
    from grader.assignment import load_assignment
    from grader.key_edit import set_answer

    command = "eulertop key set"

    def body() -> int:
        a = load_assignment(args.hw)
        key, changes = set_answer(a, args.answer, rtol=args.rtol, atol=args.atol,
                                  points=args.points, accept=_accepted(args.accept))
        if not changes:
            print(f"{command}: {args.answer} is already so; nothing changed")
            return 0
        fields = sorted({f"{c.field} {c.after!r}" for c in changes})
        print(f"{command}: {args.answer} of {len({c.student for c in changes})} student(s):")
        return _with_key(args, command, key, _lines(changes), "key set",
                         f"key set {args.answer}: {', '.join(fields)}",
                         {"key_changes": [c.as_dict() for c in changes]})

    return _run(command, body)


def run_rekey(args: argparse.Namespace) -> int:
    """Run ``eulertop rekey``."""
    from grader.assignment import load_assignment
    from grader.graded_folder import RESULTS, graded_folder
    from grader.key_edit import rekeyed, write_manifest
    from grader.rescore import rescore
    from problems.templates import FAMILIES

    command = "eulertop rekey"

    def body() -> int:
        a, edited = _edited_families_recorded(command, load_assignment(args.hw), args.dry_run)
        key, changes = rekeyed(a, FAMILIES)
        if edited and not args.dry_run:
            write_manifest(a.folder, a.manifest)
        print(f"{command}: {len(changes)} value(s) of the key differ from what today's "
              "solver gives" + (":" if changes else ""))
        if not changes and not edited:
            print(f"{command}: the key is as the families compute it; nothing changed")
            return 0
        why = "rekey: the key recomputed from the recorded parameters"
        details = {"key_changes": [c.as_dict() for c in changes]}
        if edited:
            details["family_files"] = edited
        if changes:
            return _with_key(args, command, key, _lines(changes), "rekey", why, details,
                             a.manifest)
        if not (graded_folder(a.folder, args.out) / RESULTS).is_dir():
            print(f"{command}: nothing graded yet, so nothing to rescore")
            return 0
        _say_rescore(command, rescore(a, args.out, dry_run=args.dry_run, reveal=args.reveal,
                                      why=why, event="rekey", **details))
        return 0

    return _run(command, body)


def _edited_families_recorded(command: str, a: Assignment,
                              dry_run: bool) -> tuple[Assignment, list[dict]]:
    """``a`` recording the SHA-256 each family file edited since ``generate`` has now (the
    caller writes it), named in the output, and those files for the trail; UsageError for
    one that is gone."""
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


def run_override(args: argparse.Namespace) -> int:
    """Run ``eulertop override``."""
    from grader.assignment import UsageError, load_assignment
    from grader.audit import who
    from grader.grade_one import now
    from grader.graded_folder import graded_folder
    from grader.overrides import Override, read_overrides, write_overrides
    from grader.rescore import rescore

    command = "eulertop override"

    def body() -> int:
        a = load_assignment(args.hw)
        out = graded_folder(a.folder, args.out)
        if args.student not in a.ids:
            raise UsageError(f"no student {args.student!r} in the assignment's roster")
        existing = read_overrides(out)
        kept = [o for o in existing if (o.student, o.answer) != (args.student, args.answer)]
        what = args.answer or "total"
        if args.remove:
            if len(kept) == len(existing):
                raise UsageError(f"no override of {args.student}'s {what} to remove")
            overrides, why, event = kept, f"override of {args.student}'s {what} removed", \
                "override removed"
        else:
            if args.points is None or not args.reason:
                raise UsageError("give --points P and --reason TEXT (or --remove)")
            new = Override(args.student, args.answer, args.points, args.reason, who(), now())
            overrides, why, event = [*kept, new], args.reason, "override"
        _check(a, out, overrides)  # before the file is written: a bad one is refused whole
        if args.dry_run:
            print(f"{command}: {args.student}'s {what}: {why}; nothing written (--dry-run)")
            return 0
        write_overrides(out, overrides)
        _say_rescore(command, rescore(a, out, reveal=args.reveal, why=why, event=event))
        return 0

    return _run(command, body)


def _check(a, out: Path, overrides) -> None:
    """Each override applies to the record it names (raises UsageError otherwise)."""
    from grader.assignment import UsageError
    from grader.graded_folder import RESULTS
    from grader.overrides import apply_overrides
    from grader.results import read_result

    for o in overrides:
        record = read_result(out / RESULTS / f"{o.student}.json")
        if record is None:
            raise UsageError(f"{o.student} has no record in {out / RESULTS} yet: grade first")
        apply_overrides(record, [o])
