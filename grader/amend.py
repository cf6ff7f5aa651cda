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
import math
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
    change.add_argument("--rubric", action="append", default=[], metavar="N=POINTS",
                        help="a written answer's rubric item N (from 1) worth POINTS "
                             "(repeatable); the answer's points become the items' sum")


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


def add_late_arguments(parser: argparse.ArgumentParser) -> None:
    """``eulertop late set HW [--due T] [--grace D] [--penalty 10%/day] [--max 50%] [--close T]
    …`` and ``eulertop late extend HW STUDENT --due T --reason TEXT | --remove``."""
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    change = actions.add_parser("set", help="set or change the deadline and the late penalty, "
                                "then rescore", description="Set or change the assignment's "
                                "deadline and late policy; then rescore (no notebook runs).")
    _common(change)
    change.add_argument("--due", metavar="TIME", help="the due time, ISO 8601 with its offset "
                        "(2026-03-14T23:59:00-05:00)")
    change.add_argument("--grace", metavar="DURATION", help="no penalty this long after the "
                        "due time (15m, 2h)")
    change.add_argument("--penalty", metavar="RATE", help="per started period: 10%%/day, "
                        "5%%/hour")
    change.add_argument("--max", metavar="PERCENT", help="the most the penalty takes (50%%)")
    change.add_argument("--close", metavar="TIME", help="after it no credit ('none': no close)")
    change.add_argument("--after-close", choices=("zero", "practice"),
                        help="after the close: no credit (zero), or graded as practice")
    change.add_argument("--of", choices=("earned", "total"),
                        help="the penalty's base: the points earned (default) or the total")
    change.add_argument("--zone", metavar="NAME", help="time zone (America/Chicago) for times "
                        "an LMS writes without an offset")
    extend = actions.add_parser("extend", help="give one student their own due time, then "
                                "rescore them", description="Give one student an extension "
                                "(or take it back with --remove); then rescore them.")
    _common(extend)
    extend.add_argument("student", metavar="STUDENT", help="the student's id")
    extend.add_argument("--due", metavar="TIME", help="their due time, ISO 8601 with its offset")
    extend.add_argument("--reason", metavar="TEXT", help="why (shown to the student)")
    extend.add_argument("--remove", action="store_true", help="take the extension back")


def _say_rescore(command: str, report, reveal: bool = False) -> None:
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
    if report.every_page:  # a change of some students, and the pages showed otherwise
        before = {None: "what they showed was not recorded", True: "they showed them",
                  False: "they did not show them"}[report.pages_showed]
        print(f"{command}: every student's feedback page written again "
              f"{'with' if reveal else 'without'} their key values, as this command was"
              f"{'' if reveal else ' not'} given --reveal ({before})")
    if report.unread:
        answers = sorted({v for vs in report.unread.values() for v in vs})
        print(f"{command}: {len(report.unread)} student(s) answered before the key had "
              f"{', '.join(answers)}: those answers are unread until their notebooks run "
              f"again; 'eulertop grade HW SUBMISSIONS' runs exactly these: "
              f"{', '.join(sorted(report.unread))}")
    if report.other_variant:
        who = sorted(report.other_variant)
        print(f"{command}: {len(who)} student(s) graded as a variant of theirs that has "
              f"changed since (a reroll?): {', '.join(who[:SHOWN])}"
              f"{f' and {len(who) - SHOWN} more' if len(who) > SHOWN else ''}; their stored "
              "answers are compared with their new keys all the same, and their records "
              f"{'would say' if report.dry_run else 'say'} so; 'eulertop grade HW SUBMISSIONS' "
              "grades the notebooks they submit for their new variants")


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
        _say_rescore(command, report, args.reveal)
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


def _rubric_points(texts: list[str]) -> dict[int, float]:
    """``--rubric N=POINTS`` options as ``{N: points}``; UsageError naming one that is not."""
    from grader.assignment import UsageError

    found = {}
    for text in texts:
        n, _, points = text.partition("=")
        try:
            found[int(n)] = float(points)
        except ValueError:
            raise UsageError(f"--rubric {text}: expected N=POINTS, such as 2=1.5") from None
        if not math.isfinite(found[int(n)]) or found[int(n)] < 0:
            raise UsageError(f"--rubric {text}: points must be a number ≥ 0")
    return found


def _lines(changes) -> tuple[str, ...]:
    width = max((len(c.student) for c in changes), default=0)
    return tuple(c.line(width) for c in changes)


def key_change(args: argparse.Namespace):
    """``eulertop key set``'s change: the key with one answer changed (UsageError: refused)."""
    from grader.key_edit import set_answer
    from grader.rescore import Amendment

    def change(a, overrides) -> Amendment:
        key, changes = set_answer(a, args.answer, rtol=args.rtol, atol=args.atol,
                                  points=args.points, accept=_accepted(args.accept),
                                  rubric=_rubric_points(getattr(args, "rubric", [])))
        if not changes:
            return Amendment(unchanged=f"{args.answer} is already so")
        fields = sorted({f"{c.field} {c.after!r}" for c in changes})
        students = len({c.student for c in changes})
        return Amendment("key set", f"key set {args.answer}: {', '.join(fields)}", key=key,
                         details={"key_changes": [c.as_dict() for c in changes]},
                         students=frozenset(),  # those whose key entry changed
                         report=":" not in args.answer,  # one student's: a later command's
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
    the overrides as they are under the lock (so that none is lost):
    :func:`grader.rescore.override_amendment`."""
    from grader.audit import who
    from grader.grade_one import now
    from grader.rescore import override_amendment

    def change(a, existing):
        return override_amendment(a, existing, args.student, args.answer, args.points,
                                  args.reason, who(), now(), remove=args.remove)

    return change


def run_override(args: argparse.Namespace) -> int:
    """Run ``eulertop override``."""
    return _rescore(args, "eulertop override", override_change(args))


def late_change(args: argparse.Namespace):
    """``eulertop late set`` / ``late extend``'s change: the policy ``assignment.json`` records,
    changed (:mod:`problems.deadlines`); refused (UsageError) when it cannot be read."""
    from grader.assignment import UsageError
    from grader.late import policy_of
    from grader.rescore import Amendment
    from problems.deadlines import PolicyError

    def change(a, overrides) -> Amendment:
        before = policy_of(a.manifest)
        try:
            after = _policy_set(before, args) if args.action == "set" else \
                _extension_set(before, args, a)
        except PolicyError as e:
            raise UsageError(str(e)) from None
        if after == before:
            return Amendment(unchanged="the late policy is already so")
        lines = tuple(_policy_lines(before, after))
        who = None if args.action == "set" else frozenset({args.student})
        return Amendment(f"late {args.action}", "; ".join(lines),
                         manifest={**a.manifest, "late": after.record()}, students=who,
                         report=who is None,  # an extension: one student's, a later command's
                         details={"late": {"before": None if before is None else before.record(),
                                           "after": after.record()}}, lines=lines)

    return change


def _policy_set(policy, args: argparse.Namespace):
    """``policy`` (None: none yet) with ``late set``'s options applied."""
    from dataclasses import replace

    from problems.deadlines import (
        LatePolicy,
        PolicyError,
        duration,
        instant,
        penalty_rate,
        zone_named,
    )

    zone = zone_named(args.zone if args.zone is not None else getattr(policy, "zone", None))
    if policy is None:
        if args.due is None:
            raise PolicyError("the assignment has no late policy yet: give --due")
        policy = LatePolicy(due=instant(args.due, "--due", zone))
    changes: dict = {}
    if args.due is not None:
        changes["due"] = instant(args.due, "--due", zone)
    if args.grace is not None:
        changes["grace"] = duration(args.grace, "--grace")
    if args.penalty is not None:
        changes["percent"], changes["per"] = penalty_rate(args.penalty)
    if args.max is not None:
        changes["max_percent"] = penalty_rate(f"{args.max}/day")[0]
    if args.close is not None:
        changes["close"] = None if args.close == "none" else instant(args.close, "--close", zone)
    for name in ("after_close", "of", "zone"):
        if getattr(args, name) is not None:
            changes[name] = getattr(args, name)
    return replace(policy, **changes)


def _extension_set(policy, args: argparse.Namespace, a):
    """``policy`` with ``late extend``'s extension given or taken back."""
    from grader.assignment import UsageError
    from problems.deadlines import Extension, PolicyError, instant, zone_named

    if policy is None:
        raise PolicyError("the assignment has no late policy: set one first ('eulertop late "
                          "set HW --due …')")
    if args.student not in a.ids:
        raise UsageError(f"no student {args.student!r} in the assignment's roster")
    if args.remove:
        if args.student not in policy.extensions:
            raise UsageError(f"{args.student} has no extension to take back")
        return policy.with_extension(args.student, None)
    if args.due is None or not args.reason:
        raise UsageError("give --due TIME and --reason TEXT (or --remove)")
    due = instant(args.due, "--due", zone_named(policy.zone))
    return policy.with_extension(args.student, Extension(due, args.reason))


def _policy_lines(before, after) -> list[str]:
    """What changed between two policies, a line each: ``due: … → …``."""
    old = {} if before is None else before.record()
    new = after.record()
    lines = []
    for name in dict.fromkeys([*old, *new]):
        if name == "extensions":
            continue
        if old.get(name) != new.get(name):
            lines.append(f"{name}: {old.get(name, '—')} → {new.get(name, '—')}")
    was, now = old.get("extensions", {}), new.get("extensions", {})
    for sid in sorted(set(was) | set(now)):
        if was.get(sid) != now.get(sid):
            lines.append(f"extension of {sid}: " + (
                "taken back" if sid not in now else
                f"due {now[sid]['due']} ({now[sid]['reason']})"))
    return lines


def run_late(args: argparse.Namespace) -> int:
    """Run ``eulertop late set`` / ``eulertop late extend``."""
    return _rescore(args, f"eulertop late {args.action}", late_change(args))
