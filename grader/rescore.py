"""``eulertop rescore`` — and ``key set``, ``rekey`` and ``override``, which are a change followed
by one: every verdict again from the answers stored in the records and the key as it is now,
without starting a kernel (issue 26), as one transaction (issue 30).

What a student submitted is in their record (``results/<id>.json``: each answer's value as the
grader extracted it), so a changed key — a tolerance that was too tight, points moved, an
accepted alternative, a solver fix — needs no notebook to run again. Under the class's lock
(:func:`grader.transaction.class_lock`) the command reads the key, the overrides and the records
as they are, works out its change (:class:`Amendment`: a new key, new overrides), compares each
record again (:func:`rescored`), gives follow-through credit and applies the overrides
(:func:`grader.publish.settled`) — any of which may refuse the change, before a file is written
— then commits the key, the overrides, the records that changed, the views and one line of the
audit trail together (:class:`grader.transaction.Transaction`). A record whose verdicts did not
change keeps its bytes.

A record that is not ``graded`` (missing, or a notebook that could not be run) has no answers
to compare: its answers are all missing against the new key, its points and its message as
they were. An answer the key holds but the record does not (a key that gained an answer) was
never read from the notebook: it is recorded *unread* (missing, and the record's
``execution["unread"]`` names it), so the next ``eulertop grade`` runs exactly those students'
notebooks again; the command says who they are.

Non-finite numbers: a record keeps NaN and infinities as the strings ``"NaN"``,
``"Infinity"``, ``"-Infinity"`` (strict JSON); they are read back as numbers where the answer
is numeric (scalar, angle, vector), as they were extracted. (A student who typed one of those
strings for a numeric answer is read as having given the number: invalid either way.)

Floor 7 of grader/ (the class run; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from grader.assignment import (
    Assignment,
    UsageError,
    load_assignment,
    require_assignment_folder,
)
from grader.follow_through import FollowThrough, FollowWorker, warm_worker
from grader.grade_one import VARIANT, parameters_hash, scored
from grader.graded_folder import RESULTS, graded_folder
from grader.overrides import (
    OVERRIDES,
    TOTAL,
    Override,
    check_overrides,
    overrides_toml,
    read_overrides,
    without_overrides,
)
from grader.publish import (
    NO_REVIEWS,
    RowCache,
    pages_reveal,
    records,
    report_notebooks,
    settled,
    stage_record,
    stage_report,
    stage_scoped_views,
    stage_stale_report,
    stage_views,
)
from grader.results import StudentResult, non_finite_read
from grader.reviews import REVIEWS, Reviews, check_reviews, read_reviews, reviews_json
from grader.transaction import LOCK_WAIT, Transaction, class_lock
from problems.answers import Verdict
from problems.generate import json_text
from problems.variant import variable_name

NUMERIC = ("scalar", "angle", "vector")
UNREAD = "unread"
"""``execution`` key of a record: the answers the key gained after its notebook ran."""
UNREAD_MESSAGE = ("not read yet: the key gained this answer after your notebook was graded; it "
                  "is read when the notebook runs again")


@dataclass(frozen=True)
class Change:
    """One student's points that a rescore changes: an answer's (``answer`` its variable) or
    the total (``answer`` is ``"total"``), before and after, and why."""

    student: str
    answer: str
    before: float
    after: float
    why: str

    def as_dict(self) -> dict:
        return {"student": self.student, "answer": self.answer, "before": self.before,
                "after": self.after, "why": self.why}


@dataclass(frozen=True)
class Amendment:
    """A change to a graded class, worked out from its state under the lock: the new key or
    overrides (None: unchanged), and what the trail and the person are told. ``unchanged``
    set: there is nothing to change (why), and nothing is written."""

    event: str = "rescore"
    why: str = "rescore"
    key: dict | None = None
    overrides: tuple[Override, ...] | None = None
    details: dict = field(default_factory=dict)
    lines: tuple[str, ...] = ()  # the change itself, for the person (key changes)
    unchanged: str = ""
    manifest: dict | None = None  # a new assignment.json (rekey: edited families' hashes)
    students: frozenset[str] | None = None  # whom it reaches beyond a changed key (None: all)
    report: bool = True  # rebuild the class report now (False: left for a later command)
    reviews: Reviews | None = None  # the reviews of written answers, changed (grader.reviews)


Amend = Callable[[Assignment, tuple[Override, ...]], Amendment]
"""``change(assignment, overrides) -> Amendment``, run under the class's lock; raises
:class:`UsageError` to refuse."""


@dataclass(frozen=True)
class Rescore:
    """What a rescore did (or, with ``dry_run``, would do)."""

    changes: tuple[Change, ...]
    rescored: tuple[str, ...]  # the students rescored: those the change reaches, with a record
    unchanged: int  # of them, how many kept every point
    dry_run: bool
    amendment: Amendment = Amendment()
    unread: Mapping[str, tuple[str, ...]] = field(default_factory=dict)  # id → answers unread
    other_variant: tuple[str, ...] = ()  # graded as a variant of theirs that has changed since
    every_page: bool = False  # a change of some students wrote every feedback page (_commit)
    pages_showed: bool | None = None  # the key values on every page before (None: not known)


def _unread(a: Assignment, old: StudentResult) -> tuple[str, ...]:
    """The answers of ``a``'s key that ``old``'s notebook run never read (module docstring)."""
    had = {x.variable for x in old.answers}
    before = set(old.execution.get(UNREAD, ()))
    return tuple(k.variable for k in a.expected(old.student_id)
                 if k.variable not in had or k.variable in before)


VARIANT_CHANGED = ("this student's variant changed after the notebook was graded (its "
                   "parameters are no longer theirs: a reroll?)")
"""A record's ``foreign`` note when the parameters it was graded as (:data:`VARIANT`) are not
the student's any more: its answers are compared with their new key all the same."""


def variant_changed(a: Assignment, old: StudentResult) -> bool:
    """Whether ``old`` was graded as parameters of its student's that ``a`` no longer holds
    (a record without their hash, made before records kept it, is taken as it is)."""
    was, own = old.execution.get(VARIANT), a.parameters(old.student_id)
    return bool(was and own) and was != parameters_hash(own)


def rescored(a: Assignment, old: StudentResult) -> StudentResult:
    """``old`` compared again with ``a``'s key (the module docstring's rules), before
    follow-through credit and overrides; a record graded as a variant of its student's that
    has changed since says so (:data:`VARIANT_CHANGED`)."""
    sid = old.student_id
    expected, execution, extracted = a.expected(sid), dict(old.execution), None
    execution.pop(UNREAD, None)
    message = old.message
    if not execution.get("foreign") and variant_changed(a, old):
        execution["foreign"] = VARIANT_CHANGED
        message = "\n".join(filter(None, (message, f"{VARIANT_CHANGED}; its answers are "
                                                    "compared with their new key all the same")))
    unread = _unread(a, old) if old.status == "graded" else ()
    if old.status == "graded":
        kinds = {k.variable: k.answer.kind for k in expected}
        extracted = {x.variable: non_finite_read(x.submitted) if kinds.get(x.variable) in NUMERIC
                     else x.submitted for x in old.answers if x.variable not in unread}
        extracted.update({k.variable: None for k in expected if k.variable not in extracted})
        if unread:
            execution[UNREAD] = list(unread)
    new = replace(scored(sid, expected, a.key_hash(sid), status=old.status, message=message,
                         extracted=extracted, execution=execution, sandboxed=old.sandboxed,
                         submission_sha256=old.submission_sha256), submitted=old.submitted)
    if not unread:
        return new
    answers = tuple(replace(x, verdict=Verdict("missing", 0.0, x.verdict.max_points,
                                               UNREAD_MESSAGE)) if x.variable in unread else x
                    for x in new.answers)
    return replace(new, answers=answers, points=sum(x.verdict.points for x in answers))


def restored(old: StudentResult) -> StudentResult:
    """``old`` as its comparison with the key left it — its answers' verdicts and
    follow-through credit as recorded, its overrides and late penalty taken back (the reviews
    are, by :func:`grader.publish.settled`) — built as :func:`rescored` builds it, reading no
    key answer: what a change that leaves its key entry and the families as they were
    (:func:`keeps_comparisons`, :func:`compared_as_stored`) settles again."""
    base = without_overrides(old)
    return replace(scored(old.student_id, (), old.key_sha256, status=old.status,
                          message=old.message, extracted=None, execution=dict(old.execution),
                          sandboxed=old.sandboxed, submission_sha256=old.submission_sha256,
                          compared=base.answers), submitted=old.submitted)


def keeps_comparisons(a: Assignment, amendment: Amendment) -> bool:
    """Whether ``amendment`` changes only what settles a record — overrides, reviews, the late
    policy — not the key, the families or follow-through (a plain rescore compares again)."""
    if amendment.key is not None:
        return False
    if amendment.manifest is not None and \
            _but_late(amendment.manifest) != _but_late(a.manifest):
        return False
    return amendment.overrides is not None or amendment.reviews is not None or \
        amendment.manifest is not None


def _but_late(manifest: Mapping) -> dict:
    return {k: v for k, v in manifest.items() if k != "late"}


def compared_as_stored(a: Assignment, old: StudentResult) -> bool:
    """Whether ``old`` was compared with ``a``'s key entry as it is: the hash the record names
    is the entry's, recomputed from its questions (:meth:`Assignment.verified`), every answer
    of the entry was read (none *unread*), and the record holds them all, in order."""
    sid = old.student_id
    if old.execution.get(UNREAD) or not a.verified(sid) or old.key_sha256 != a.key_hash(sid):
        return False
    variables = [variable_name(q["question"], x["name"])
                 for q in a.key["students"][sid]["questions"] for x in q["answers"]]
    return [x.variable for x in old.answers] == variables


def _proven(a: Assignment, old: Mapping[str, StudentResult | None], amendment: Amendment,
            scope: frozenset[str] | None) -> frozenset[str]:
    """The students of ``scope`` whose records a change settles again from their stored
    comparisons (:func:`restored`): none unless it :func:`keeps_comparisons`."""
    if not keeps_comparisons(a, amendment):
        return frozenset()
    return frozenset(sid for sid, r in old.items()
                     if r is not None and (scope is None or sid in scope)
                     and compared_as_stored(a, r))


def changes_between(old: StudentResult, new: StudentResult, why: str) -> list[Change]:
    """Every answer whose points differ between the two records, then the total's."""
    before = {x.variable: x.verdict.points for x in old.answers}
    found = []
    for x in new.answers:
        was = before.get(x.variable, 0.0)
        if x.verdict.points != was:
            note = new.overridden.get(x.variable, {}).get("reason")
            found.append(Change(old.student_id, x.variable, was, x.verdict.points,
                                f"overridden: {note}" if note else why))
    if new.points != old.points:
        note = new.overridden.get(TOTAL, {}).get("reason")
        found.append(Change(old.student_id, TOTAL, old.points, new.points,
                            f"overridden: {note}" if note else why))
    return found


def same_record(old: StudentResult, new: StudentResult) -> bool:
    """Whether two records say the same, their ``graded_at`` apart."""
    return replace(new, graded_at=old.graded_at) == old


def rescore(hw: Path, out: Path | None = None, *, change: Amend | None = None,
            dry_run: bool = False, reveal: bool = False, wait: float = LOCK_WAIT,
            command: str = "eulertop rescore") -> Rescore:
    """Rescore the graded class of assignment folder ``hw`` (output folder ``out``, default
    ``HW/graded``), after ``change`` if given (module docstring); ``dry_run``: work it all out,
    write nothing. ``wait``: seconds to wait for another command holding the class.

    Raises
    ------
    grader.assignment.UsageError
        No assignment or no records; a change refused (it names why); an unreadable overrides
        file; another command holding the class longer than ``wait``
        (:class:`grader.graded_folder.RunInProgress`). Nothing is written then.
    """
    hw = require_assignment_folder(hw)
    out = graded_folder(hw, out)
    if not (out / RESULTS).is_dir():
        raise UsageError(f"{out / RESULTS}: no result records here; run 'eulertop grade' "
                         "first (or pass --out DIR)")
    with class_lock(out, hw, command=command, wait=wait):
        a, overrides = load_assignment(hw), read_overrides(out)
        amendment = change(a, overrides) if change is not None else Amendment()
        if amendment.unchanged:
            return Rescore((), (), 0, dry_run, amendment)
        state = Loaded(hw, out, a, overrides, read_reviews(out), None)
        report, _ = amended_class(state, amendment, dry_run=dry_run, reveal=reveal,
                                  command=command)
    return report


@dataclass
class Loaded:
    """A graded class as a command read it under the lock: the assignment folder and output
    folder, the assignment, the overrides, the reviews and the records (None: read them when
    needed) — what :func:`amended_class` works a change out from."""

    hw: Path
    out: Path
    a: Assignment
    overrides: tuple[Override, ...]
    reviews: Reviews
    records: dict[str, StudentResult | None] | None


def amended_class(state: Loaded, amendment: Amendment, *, dry_run: bool = False,
                  reveal: bool = False, command: str = "eulertop rescore",
                  follow: FollowThrough | None = None, rows: RowCache | None = None,
                  ) -> tuple[Rescore, dict[str, StudentResult | None]]:
    """``amendment`` of the class ``state`` holds (under its lock), worked out and — unless
    ``dry_run`` — committed as one transaction (:func:`rescore`'s, from state already loaded:
    what a review desk that keeps the class in memory calls, :mod:`grader.review`). The report
    and every record as it now is. ``follow``: the class's follow-through, kept open by the
    caller (default: one for this change, closed after it); ``rows``: the gradebook's rows of
    the records met before (:class:`grader.publish.RowCache`). A class not loaded
    (``state.records`` None) has only the records of the students the change reaches read,
    and those alone returned (:func:`grader.publish.stage_scoped_views`)."""
    # a worker of our own for follow-through credit starts importing the families now, while
    # the records are read and the keys checked (a second of imports it would otherwise wait)
    warm = warm_worker(state.a) if follow is None else None
    try:
        scope = _reached(state.a, amendment)
        old = records(state.a, state.out, scope) if state.records is None else state.records
        proven = _proven(state.a, old, amendment, scope)
        a, overrides, reviews = _amended(state.a, state.overrides, state.reviews, amendment,
                                         scope, proven)
    except BaseException:
        if warm is not None:
            warm.kill()
        raise
    report, new = _rescored_class(a, old, overrides, amendment, scope, reviews, follow, proven,
                                  warm)
    report = replace(report, dry_run=dry_run)
    if not dry_run:
        every_page, showed = _commit(a, state.hw, state.out, old, new, report, reveal, command,
                                     scope, rows, whole=state.records is not None or scope is None)
        report = replace(report, every_page=every_page, pages_showed=showed)
    return report, new


def _reached(a: Assignment, amendment: Amendment) -> frozenset[str] | None:
    """The students ``amendment`` reaches (None: the whole class): those it names, and those
    whose key entry it changes; the others' records are kept as they are, unread."""
    if amendment.students is None:
        return None
    reached = set(amendment.students)
    if amendment.key is not None:
        old, new = a.key["students"], amendment.key["students"]
        reached |= {sid for sid in a.ids if old[sid] != new[sid]}  # not the hash: hand edits
    return frozenset(reached)


def _amended(a: Assignment, overrides: tuple[Override, ...], reviews: Reviews,
             amendment: Amendment, scope: frozenset[str] | None,
             proven: frozenset[str] = frozenset(),
             ) -> tuple[Assignment, tuple[Override, ...], Reviews]:
    """The assignment, overrides and reviews as ``amendment`` makes them, checked together
    (the key of every student in ``scope``: None, all — but those ``proven`` read by their
    records, :func:`compared_as_stored`)."""
    if amendment.key is not None:
        a = replace(a, key=amendment.key)
    if amendment.manifest is not None:
        a = replace(a, manifest=amendment.manifest)
    if amendment.overrides is not None:
        overrides = tuple(amendment.overrides)
    if amendment.reviews is not None:
        reviews = amendment.reviews
    for sid in a.ids if scope is None else sorted(scope):
        if sid not in proven:
            a.expected(sid)  # UsageError naming a student whose key entry cannot be read
    check_overrides(a, overrides, None if amendment.overrides is not None else OVERRIDES)
    check_reviews(a, _to_check(reviews, amendment, scope),
                  "the reviews" if amendment.reviews is not None else REVIEWS)
    return a, overrides, reviews


def _to_check(reviews: Reviews, amendment: Amendment,
              scope: frozenset[str] | None) -> Reviews:
    """The reviews to check against the key: all of them, but where only the reviews of the
    students ``scope`` names change (the key and the manifest as they were), theirs."""
    if amendment.reviews is None or amendment.key is not None or \
            amendment.manifest is not None or scope is None:
        return reviews
    return replace(reviews, reviews=tuple(r for r in reviews.reviews if r.student in scope))


def _rescored_class(a: Assignment, old: Mapping[str, StudentResult | None],
                    overrides: Sequence[Override], amendment: Amendment,
                    scope: frozenset[str] | None = None, reviews: Reviews = NO_REVIEWS,
                    follow: FollowThrough | None = None,
                    proven: frozenset[str] = frozenset(), warm: FollowWorker | None = None,
                    ) -> tuple[Rescore, dict[str, StudentResult | None]]:
    """Every record of ``scope`` (None: all) rescored and settled (nothing written): the
    report, and the new records (an unchanged one is the old one, its bytes kept).
    ``follow``: the caller's (kept open), else one made and closed here. The records of
    ``proven`` are settled again from their stored comparisons (:func:`restored`: their
    follow-through credit with them), the others compared again. ``warm``: a worker started
    ahead for our own follow-through (:func:`grader.follow_through.warm_worker`), which it
    takes."""
    own = follow is None
    follow = FollowThrough.of(a, warm) if own else follow
    new: dict[str, StudentResult | None] = dict(old)
    changes: list[Change] = []
    other: list[str] = []  # graded as a variant of theirs that has changed since
    try:
        for sid, record in old.items():
            if record is None or (scope is not None and sid not in scope):
                continue
            again = sid in proven
            result = settled(a, restored(record) if again else rescored(a, record),
                             None if again else follow, overrides, reviews)
            new[sid] = record if same_record(record, result) else result
            moved = variant_changed(a, result)
            if moved:
                other.append(sid)
            changes += changes_between(record, result, amendment.why + (
                "; their variant changed after grading" if moved else ""))
    finally:
        if own and follow is not None:
            follow.close()  # its worker, if one was started
    done = tuple(sid for sid, r in old.items()
                 if r is not None and (scope is None or sid in scope))
    unread = {sid: tuple(r.execution[UNREAD]) for sid, r in new.items()
              if r is not None and r.execution.get(UNREAD)}
    touched = {c.student for c in changes}
    return Rescore(tuple(changes), done, len(done) - len(touched), False, amendment,
                   unread, tuple(other)), new


def _commit(a: Assignment, hw: Path, out: Path, old: Mapping[str, StudentResult | None],
            new: Mapping[str, StudentResult | None], report: Rescore, reveal: bool,
            command: str, scope: frozenset[str] | None = None,
            rows: RowCache | None = None, whole: bool = True) -> tuple[bool, bool | None]:
    """The change, its records and their views, and its line of the trail, as one
    transaction. ``whole``: ``old`` holds every record of the class (else those of
    ``scope``). Whether a change of some students wrote every feedback page again (they
    showed the key values where ``reveal`` says not to, or the other way round, or that was
    not known), and what they showed before (:func:`grader.publish.pages_reveal`)."""
    amendment, details = report.amendment, dict(report.amendment.details)
    tx = Transaction(out)
    if amendment.key is not None:
        from grader.key_edit import stage_key

        details["old_key"] = stage_key(tx, hw, amendment.key).name
    if amendment.overrides is not None:
        tx.write(out / OVERRIDES, overrides_toml(amendment.overrides))
    if amendment.reviews is not None:
        tx.write(out / REVIEWS, reviews_json(amendment.reviews))
    if amendment.manifest is not None:
        tx.write(hw / "assignment.json", json_text(amendment.manifest))  # as generate writes it
    changed = {sid for sid, r in new.items() if r is not None and r is not old[sid]}
    for sid in changed:
        stage_record(tx, a, out, new[sid], reveal)
    showed = pages_reveal(out) if scope is not None else None  # every page is written else
    every_page = scope is not None and showed is not reveal
    if every_page:  # the other pages show the key values otherwise (or that is not known): all
        # of them again as this command is told, never a class of pages of both kinds
        every = new if whole else {**records(a, out, frozenset(a.ids) - frozenset(new)), **new}
        stage_views(tx, a, out, every, reveal, published=changed, cache=rows)
    elif whole:
        stage_views(tx, a, out, new, reveal, published=changed,
                    pages=None if scope is None else frozenset(), cache=rows)
    else:
        stage_scoped_views(tx, a, out, old, new, reveal, published=changed)
    if amendment.report:
        stage_report(tx, a, out, new, report_notebooks(out), command)
    elif report.changes:
        stage_stale_report(tx, out)
    tx.trail(amendment.event, (c.as_dict() for c in report.changes), why=amendment.why,
             students=len(report.rescored), unchanged=report.unchanged,
             **({"unread": dict(report.unread)} if report.unread else {}),
             **({"other_variant": list(report.other_variant)} if report.other_variant else {}),
             **details)
    tx.commit()
    return every_page, showed


def override_amendment(a: Assignment, existing: Sequence[Override], student: str,
                       answer: str | None, points: float | None, reason: str, by: str,
                       at: str, remove: bool = False) -> Amendment:
    """The overrides with ``student``'s ``answer`` (None: total) given ``points`` for
    ``reason``, replacing one of the same target — or that one taken back (``remove``) — from
    the overrides as they are under the lock, so that none is lost: what ``eulertop override``
    and the review desk's override (:mod:`grader.review`) both commit. UsageError: refused."""
    if student not in a.ids:
        raise UsageError(f"no student {student!r} in the assignment's roster")
    kept = tuple(o for o in existing if (o.student, o.answer) != (student, answer))
    what = answer or TOTAL
    details = {"student": student, "answer": what}
    if remove:
        if len(kept) == len(existing):
            raise UsageError(f"no override of {student}'s {what} to remove")
        return Amendment("override removed", f"override of {student}'s {what} removed",
                         overrides=kept, students=frozenset({student}), details=details,
                         report=False)
    if points is None or not reason:
        raise UsageError("give --points P and --reason TEXT (or --remove)")
    new = Override(student, answer, points, reason, by, at)
    return Amendment("override", reason, overrides=(*kept, new),
                     students=frozenset({student}), details=details, report=False)


def change_lines(changes: Sequence[Change], limit: int | None = None) -> list[str]:
    """The changes as lines for a person: ``ada  q3_T_nut  0 → 2  (why)``."""
    from grader.gradebook import number

    shown = list(changes)[:limit] if limit else list(changes)
    width = max((len(c.student) for c in shown), default=0)
    answer = max((len(c.answer) for c in shown), default=0)
    lines = [f"  {c.student:<{width}}  {c.answer:<{answer}}  {number(c.before)} → "
             f"{number(c.after)}  ({c.why})" for c in shown]
    if limit and len(changes) > limit:
        lines.append(f"  … and {len(changes) - limit} more")
    return lines


def students_changed(changes: Sequence[Change]) -> Mapping[str, float]:
    """Each student whose total changed: the change in points."""
    return {c.student: c.after - c.before for c in changes if c.answer == TOTAL}
