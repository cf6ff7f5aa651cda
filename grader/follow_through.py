"""Follow-through credit (error carried forward): a later answer wrong against the key but right
against what the student's own earlier answers give, where those are a genuine attempt (issues
26, 30; the rule as instructors read it: docs/instructors/rescore.md, "Follow-through credit").

An answer the statement asks to compute from earlier answers of the same question declares them
(``Answer.depends_on``, in the key file too), and its family says how it follows from the
parameters and those values (the family's ``follow``: a solver call, for the built-ins). When
such an answer is ``wrong`` against the key and every answer it depends on was given in a
readable form:

1. if every earlier value is the key's own (:func:`problems.genuine.same_as_key`), the answer
   is judged against the key alone; otherwise it is judged against the student's own values,
   right or not — so a key change that turns an earlier answer right (a widened tolerance)
   never takes this credit away;
2. the answer is recomputed from the student's earlier values and compared again, with its own
   rule and tolerance; if it agrees it earns ``fraction`` of its points (the assignment's
   ``follow_through`` setting, default 1.0; 0 turns this off), verdict ``follows``, with a
   message saying what it follows from (``follows from your q2_omega3_c = 140.2``);
3. unless those earlier values are degenerate — the family's own ``degenerate`` says so, or a
   default case of :mod:`problems.genuine` (a zero, the identity, a value far from any
   physical one, a number copied from the statement, a later answer that is then a copy): the
   answer then stays ``wrong`` with 0 points, and its message says why in one line
   (``no follow-through: your q1_I_offdiag is zero, which makes q1_moments a copy of your
   diagonal``).

A recomputation that raises, gives no value of the answer's form, or takes longer than
:data:`FOLLOW_SECONDS` (the worker's start and a family's loading apart: :data:`START_SECONDS`)
earns nothing. A family that cannot be loaded, or whose file changed since ``eulertop
generate`` (its recorded SHA-256), stops the run with :class:`~grader.assignment.UsageError`
naming the file: credit is never computed with another family than the key's.

Grading and rescoring reach all this through one entry, :meth:`FollowThrough.apply`.
Recomputations run in a process of their own (the student's values are data, but the family's
code is still run on them): one worker per run (``python -m grader.follow_through``, JSON lines
in and out), started when the first one is needed, killed and replaced after one that ran out
of time or ended it.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import subprocess
import sys
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from grader.assignment import Assignment, UsageError
from grader.compare import KeyAnswer
from grader.plain_text import value_text
from grader.results import AnswerResult, StudentResult
from problems.answers import Answer, Verdict, check_form, grade, numbers_of
from problems.genuine import Given, default_reason, named, same_as_key

FOLLOW_SECONDS = 5.0
"""Longest one recomputation may take, seconds."""
START_SECONDS = 120.0
"""Longest the worker may take to start and load a family (numpy, scipy, the solver: seconds on
a busy machine), apart from the recomputations' own limit."""

FRACTION_KEY = "follow_through"
"""The setting in ``assignment.json`` (from the spec): the fraction of points it earns."""


class FamilyUnavailable(UsageError):
    """A family follow-through credit needs cannot be loaded (the message names its file):
    ``family``, and the ``cause`` its loading gave."""

    def __init__(self, message: str, family: str = "", cause: str = "") -> None:
        super().__init__(message)
        self.family, self.cause = family, cause


_loaded: dict[tuple[str, str | None], Any] = {}


def _load(family: str, path: str | None) -> Any:
    """In the worker: ``family`` (built-in or installed, or the file ``path``), loaded once."""
    key = (family, path)
    if key not in _loaded:
        if path is None:
            from problems.family_files import entry_point_families
            from problems.templates import FAMILIES

            _loaded[key] = FAMILIES[family] if family in FAMILIES else \
                {f.name: f for f in entry_point_families()}[family]
        else:
            from problems.family_files import load_family_file

            source = Path(path)  # a package is recorded by its __init__.py
            _loaded[key] = load_family_file(source.parent if source.name == "__init__.py"
                                            else source)
    return _loaded[key]


def _recomputed(family: Any, request: Mapping[str, Any]) -> dict[str, Any]:
    """In the worker: the answer recomputed (:meth:`problems.family.Family.follow`) and the
    family's own reason why the earlier values are degenerate
    (:meth:`~problems.family.Family.degenerate`)."""
    args = (request["name"], request["params"], request["earlier"])
    value = family.follow(*args)
    return {"value": value.tolist() if hasattr(value, "tolist") else value,
            "degenerate": family.degenerate(*args)}


def serve() -> None:
    """The worker (``python -m grader.follow_through``): one JSON request per line on stdin —
    a family to load, or an answer to recompute — one JSON reply per line on stdout
    (``{"value": ..., "degenerate": ...}``, or ``{"error": "..."}``). Whatever the family's
    code prints goes to stderr, never into a reply."""
    replies = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    if "--warm" in sys.argv[1:]:  # started ahead (FollowWorker(warm=True)): the slow part first
        with contextlib.suppress(Exception):  # its request then says what is wrong
            import problems.templates  # noqa: F401  (numpy, scipy, sympy, the solver)
    for line in sys.stdin:
        try:
            request = json.loads(line)
            family = _load(request["family"], request.get("path"))
            reply = json.dumps(_recomputed(family, request) if "name" in request
                               else {"value": None})
        except Exception as e:  # reported, never fatal: the next request is another's
            reply = json.dumps({"error": f"{type(e).__name__}: {e}"})
        replies.write(reply + "\n")
        replies.flush()


class FollowWorker:
    """One :func:`serve` process, and a thread reading its replies (a queue: a reply awaited
    with a time limit, on any system)."""

    def __init__(self, warm: bool = False) -> None:
        """``warm``: the built-in families imported before the first request (a worker started
        ahead of its first recomputation, :func:`warm_worker`)."""
        self.process = subprocess.Popen(
            [sys.executable, "-m", "grader.follow_through", *(["--warm"] if warm else [])],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, start_new_session=True)
        self.replies: queue.Queue[bytes] = queue.Queue()
        threading.Thread(target=self._read, name="eulertop-follow-replies", daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self.replies.put(line)
        self.replies.put(b"")  # the worker ended

    def ask(self, request: Mapping[str, Any], seconds: float) -> dict:
        """The reply; TimeoutError, BrokenPipeError (the worker ended), or RuntimeError
        for a reply that is an error."""
        self.process.stdin.write((json.dumps(request) + "\n").encode("utf-8"))
        self.process.stdin.flush()
        try:
            line = self.replies.get(timeout=seconds)
        except queue.Empty:
            raise TimeoutError(f"no reply within {seconds:g} s") from None
        if not line:
            raise BrokenPipeError("the follow-through worker ended")
        reply = json.loads(line)
        if "error" in reply:
            raise RuntimeError(reply["error"])
        return reply

    def kill(self) -> None:
        self.process.kill()
        self.process.wait()
        for pipe in (self.process.stdin, self.process.stdout):
            with contextlib.suppress(OSError):
                pipe.close()


@dataclass
class FollowThrough:
    """An assignment's follow-through credit: its students' recorded parameters and the
    families of their questions, and the fraction of points it earns (module docstring)."""

    students: Mapping[str, Any]  # assignment.json "students"
    sources: Mapping[str, str | None]  # family name -> its file (None: built-in)
    fraction: float = 1.0
    seconds: float = FOLLOW_SECONDS

    def __post_init__(self) -> None:
        self._lock = threading.Lock()
        self._worker: FollowWorker | None = None
        self._ready: set[str] = set()  # families the worker has loaded

    @classmethod
    def of(cls, a: Assignment, worker: FollowWorker | None = None) -> FollowThrough | None:
        """``a``'s follow-through, or None when its setting turns it off (0).
        :class:`~grader.assignment.UsageError` when a family file its chains need changed since
        ``eulertop generate`` (:func:`unchanged_families`). ``worker``: one started ahead
        (:func:`warm_worker`), which it then owns — or kills, when it gives none."""
        follow = None
        try:
            manifest = a.manifest
            fraction = float(manifest.get(FRACTION_KEY, 1.0))
            if fraction > 0:
                unchanged_families(a)
                sources = {name: (None if where.get("file") is None
                                  else str(Path(a.folder) / where["file"]))
                           for name, where in manifest.get("families", {}).items()}
                follow = cls(a.students, sources, min(fraction, 1.0), FOLLOW_SECONDS)
                follow._worker = worker
        finally:
            if follow is None and worker is not None:
                worker.kill()
        return follow

    # -- the worker

    def _value(self, family: str, name: str, params: dict, earlier: dict) -> dict:
        """``{"value": answer name recomputed, "degenerate": the family's reason or None}``."""
        with self._lock:
            self._load(family)
            request = {"family": family, "path": self.sources.get(family), "name": name,
                       "params": params, "earlier": earlier}
            return self._ask(request, self.seconds)

    def _load(self, family: str) -> None:
        """The worker started and ``family`` loaded in it (its start is not a recomputation's
        time); :class:`FamilyUnavailable` naming the family's file if it cannot be loaded."""
        if self._worker is None:
            self._worker, self._ready = FollowWorker(), set()
        if family in self._ready:
            return
        path = self.sources.get(family)
        try:
            self._ask({"family": family, "path": path}, START_SECONDS)
        except (RuntimeError, TimeoutError, OSError) as e:  # its file, or not installed here
            where = path or "installed families"
            raise FamilyUnavailable(f"{where}: family {family!r} cannot be loaded for "
                                    f"follow-through credit: {e}", family, str(e)) from None
        self._ready.add(family)

    def load_families(self) -> None:
        """Load every family of a file or an installed package in the worker, as grading
        would (a package checks its copies with this); :class:`FamilyUnavailable` for the first
        that cannot be."""
        with self._lock:
            for family in self.sources:
                self._load(family)

    def _ask(self, request: Mapping[str, Any], seconds: float) -> Any:
        try:
            return self._worker.ask(request, seconds)
        except (TimeoutError, OSError, ValueError):  # stuck or gone: a fresh worker next
            self._kill()
            raise

    def _kill(self) -> None:
        worker, self._worker = self._worker, None
        if worker is not None:
            worker.kill()

    def close(self) -> None:
        """Stop the worker (if one was started)."""
        with self._lock:
            self._kill()

    # -- credit: the one entry

    def apply(self, result: StudentResult, expected: Sequence[KeyAnswer]) -> StudentResult:
        """``result`` (a record compared with ``expected``) with follow-through credit where it
        is due and its points summed again: what grading and rescoring call (module
        docstring). A record that is not ``graded`` is returned as it is."""
        if result.status != "graded":
            return result
        answers = self._credit(result.student_id, expected, result.answers)
        if answers == result.answers:
            return result
        return replace(result, answers=answers,
                       points=sum(x.verdict.points for x in answers))

    def _credit(self, student_id: str, expected: Sequence[KeyAnswer],
                answers: Sequence[AnswerResult]) -> tuple[AnswerResult, ...]:
        by_variable = {a.variable: a for a in answers}
        keys = {k.variable: k for k in expected}
        out = []
        for a in answers:
            k = keys.get(a.variable)
            if k is not None and k.answer.depends_on and a.verdict.status == "wrong":
                a = self._credited(student_id, k, a, by_variable, keys) or a
            out.append(a)
        return tuple(out)

    def _credited(self, student_id: str, k: KeyAnswer, a: AnswerResult,
                  by_variable: Mapping[str, AnswerResult],
                  keys: Mapping[str, KeyAnswer]) -> AnswerResult | None:
        """``a`` credited (``follows``), or explained (degenerate), or None: unchanged."""
        earlier = _earlier(k, by_variable, keys)
        if earlier is None or all(same_as_key(g) for g in earlier.values()):
            return None  # nothing to follow from, or the key's own values: judged by the key
        question = self.students[student_id]["questions"][k.question - 1]
        params = dict(question["parameters"])
        try:
            reply = self._value(question["family"], k.answer.name, params,
                                {name: g.value for name, g in earlier.items()})
            if not _agrees(k.answer, reply["value"], a.submitted):
                return None  # follows from nothing of theirs either
        except FamilyUnavailable:
            raise
        except Exception:  # a recomputation that fails, or leaves the physics: no credit
            return None
        mine = [key for key in keys.values() if key.question == k.question]
        others = [Given(key.answer, by_variable[key.variable].submitted) for key in mine
                  if key.variable in by_variable]
        reason = reply["degenerate"] or default_reason(
            k.answer, list(earlier.values()), reply["value"], params, others,
            question.get("param_units", {}))
        if reason is None:
            return _follows(a, k, earlier, self.fraction)
        names = [*(key.answer.name for key in mine), *question.get("params", {})]
        return _refused(a, named(reason, k.question, names))


def _follows(a: AnswerResult, k: KeyAnswer, earlier: Mapping[str, Given],
             fraction: float) -> AnswerResult:
    """``a`` with the verdict ``follows``: ``fraction`` of its points, and what from."""
    source = ", ".join(f"q{k.question}_{name} = {value_text(g.value)}"
                       for name, g in earlier.items())
    return replace(a, verdict=Verdict("follows", round(fraction * k.answer.points, 12),
                                      k.answer.points, f"follows from your {source} (right "
                                      "for that value; the key's differs)"))


def _refused(a: AnswerResult, reason: str) -> AnswerResult:
    """``a`` as it was, its message saying why it has no follow-through credit (braces left
    around a name that is no notebook variable dropped)."""
    why = reason.replace("{", "").replace("}", "")
    said = a.verdict.message.rstrip(".")
    return replace(a, verdict=replace(a.verdict, message=f"{said}; no follow-through: {why}"))


def _earlier(k: KeyAnswer, by_variable: Mapping[str, AnswerResult],
             keys: Mapping[str, KeyAnswer]) -> dict[str, Given] | None:
    """The earlier answers ``k`` depends on, each with the student's value; None when one is
    missing or malformed (nothing to follow from)."""
    earlier = {}
    for name in k.answer.depends_on:
        variable = f"q{k.question}_{name}"
        given, key = by_variable.get(variable), keys.get(variable)
        if given is None or key is None or \
                check_form(key.answer, given.submitted).status != "correct":
            return None
        earlier[name] = Given(key.answer, given.submitted)
    return earlier


def _agrees(answer: Answer, value: Any, submitted: Any) -> bool:
    """Whether ``submitted`` is ``value`` (``answer`` recomputed) under ``answer``'s rule and
    tolerance."""
    try:
        trial = replace(answer, value=value, mistakes=(), accepted=(), depends_on=())
    except ValueError:  # a recomputed zero, which a relative tolerance matches exactly only
        mine, zero = numbers_of(answer, submitted), numbers_of(answer, value)
        return mine is not None and zero is not None and not np.any(zero) and not np.any(mine)
    return grade(trial, submitted).status == "correct"


def unchanged_families(a: Assignment) -> None:
    """:class:`~grader.assignment.UsageError` naming each family file whose answers have
    follow-through credit and that changed (or is gone) since ``eulertop generate``: credit
    would come from another family than the key's. ``eulertop rekey`` recomputes with it."""
    from problems.family_files import edited_families

    chained = _chained_families(a)
    edited = [e for e in edited_families(a.manifest, a.folder) if e.name in chained]
    if edited:
        raise UsageError(edited_message(a.folder, edited) + f"; run 'eulertop rekey {a.folder}'"
                         " to recompute the key and the credit with it and record it (or put "
                         "the file back as it was)")


def edited_message(folder: Path, edited: Sequence[Any]) -> str:
    """One line naming each edited family file (:func:`problems.family_files.edited_families`):
    its path, what was recorded and what it is now."""
    parts = []
    for e in edited:
        now = "is gone" if e.now is None else f"changed (sha256 {e.now[:12]}…)"
        parts.append(f"{os.path.normpath(Path(folder) / e.path)}, family {e.name!r}, {now} "
                     f"since 'eulertop generate' recorded sha256 {e.recorded[:12]}…")
    return "; ".join(parts)


def warm_worker(a: Assignment) -> FollowWorker | None:
    """A worker started now, importing the built-in families while the caller reads and
    compares the class (their import is most of a worker's start: about a second), for
    :meth:`FollowThrough.of`; None when ``a`` has no follow-through chain or turns the credit
    off. Only started, never asked anything: the family it will load is still checked
    (:meth:`FollowThrough.of`) before it is."""
    if float(a.manifest.get(FRACTION_KEY, 1.0)) <= 0 or not _chained_families(a):
        return None
    return FollowWorker(warm=True)


def _chained_families(a: Assignment) -> set[str]:
    """The families of the questions whose key has an answer with ``depends_on``."""
    chained = set()
    for sid, entry in a.key.get("students", {}).items():
        questions = a.students.get(sid, {}).get("questions", [])
        for q, record in zip(questions, entry.get("questions", []), strict=False):
            if any(x.get("depends_on") for x in record.get("answers", [])):
                chained.add(q.get("family"))
    return chained


if __name__ == "__main__":
    serve()
