"""Follow-through credit (error carried forward): a later answer wrong against the key but right
against what the student's own earlier answers give (issue 26).

An answer the statement asks to compute from earlier answers of the same question declares them
(``Answer.depends_on``, in the key file too), and its family says how it follows from the
parameters and those values (the family's ``follow``: a solver call, for the built-ins). When
such an answer is ``wrong`` against the key, every answer it depends on was given in a
readable form, and not all of them are right, the answer is recomputed from the student's own
earlier values and compared again, with its own rule and tolerance: if it agrees, it earns
``fraction`` of its points (the assignment's ``follow_through`` setting, default 1.0; 0 turns
this off) with the verdict ``follows`` and a message saying what it follows from
(``follows from your q2_omega3_c = 140.2``). A recomputation that raises, gives no value of
the answer's form, or takes longer than :data:`FOLLOW_SECONDS` (the worker's start and a
family's loading apart: :data:`START_SECONDS`) earns nothing.

Recomputations run in a process of their own (the student's values are data, but the solver
is still run on them): one worker per run (``python -m grader.follow_through``, JSON lines in
and out), started when the first one is needed, killed and replaced after one that ran out of
time or ended it.

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

from grader.assignment import Assignment
from grader.compare import KeyAnswer
from grader.plain_text import value_text
from grader.results import AnswerResult, StudentResult
from problems.answers import Verdict, check_form, grade

FOLLOW_SECONDS = 5.0
"""Longest one recomputation may take, seconds."""
START_SECONDS = 120.0
"""Longest the worker may take to start and load a family (numpy, scipy, the solver: seconds on
a busy machine), apart from the recomputations' own limit."""

FRACTION_KEY = "follow_through"
"""The setting in ``assignment.json`` (from the spec): the fraction of points it earns."""


_loaded: dict[tuple[str, str | None], Any] = {}


def _load(family: str, path: str | None) -> Any:
    """In the worker: ``family`` (a built-in, or the file ``path``), loaded once."""
    key = (family, path)
    if key not in _loaded:
        if path is None:
            from problems.templates import FAMILIES

            _loaded[key] = FAMILIES[family]
        else:
            from problems.family_files import load_family_file

            _loaded[key] = load_family_file(Path(path))
    return _loaded[key]


def serve() -> None:
    """The worker (``python -m grader.follow_through``): one JSON request per line on stdin —
    a family to load, or an answer to recompute (:meth:`problems.family.Family.follow`) — one
    JSON reply per line on stdout (``{"value": ...}`` or ``{"error": "..."}``). Whatever the
    family's code prints goes to stderr, never into a reply."""
    replies = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    for line in sys.stdin:
        try:
            request = json.loads(line)
            family = _load(request["family"], request.get("path"))
            value = None
            if "name" in request:
                value = family.follow(request["name"], request["params"], request["earlier"])
                value = value.tolist() if hasattr(value, "tolist") else value
            reply = json.dumps({"value": value})
        except Exception as e:  # reported, never fatal: the next request is another's
            reply = json.dumps({"error": f"{type(e).__name__}: {e}"})
        replies.write(reply + "\n")
        replies.flush()


class _Worker:
    """One :func:`serve` process, and a thread reading its replies (a queue: a reply awaited
    with a time limit, on any system)."""

    def __init__(self) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "grader.follow_through"], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, start_new_session=True)
        self.replies: queue.Queue[bytes] = queue.Queue()
        threading.Thread(target=self._read, name="eulertop-follow-replies", daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self.replies.put(line)
        self.replies.put(b"")  # the worker ended

    def ask(self, request: Mapping[str, Any], seconds: float) -> Any:
        """The reply's value; TimeoutError, BrokenPipeError (the worker ended), or RuntimeError
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
        return reply["value"]

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
        self._worker: _Worker | None = None
        self._ready: set[str] = set()  # families the worker has loaded

    @classmethod
    def of(cls, a: Assignment) -> FollowThrough | None:
        """``a``'s follow-through, or None when its setting turns it off (0)."""
        manifest = a.manifest
        fraction = float(manifest.get(FRACTION_KEY, 1.0))
        if fraction <= 0:
            return None
        sources = {name: (None if where.get("file") is None
                          else str(Path(a.folder) / where["file"]))
                   for name, where in manifest.get("families", {}).items()}
        return cls(a.students, sources, min(fraction, 1.0), FOLLOW_SECONDS)

    # -- the worker

    def _value(self, family: str, name: str, params: dict, earlier: dict) -> Any:
        with self._lock:
            if self._worker is None:
                self._worker, self._ready = _Worker(), set()
            request = {"family": family, "path": self.sources.get(family)}
            if family not in self._ready:  # its start is not the recomputation's time
                self._ask(request, START_SECONDS)
                self._ready.add(family)
            return self._ask({**request, "name": name, "params": params, "earlier": earlier},
                             self.seconds)

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

    # -- credit

    def credit(self, student_id: str, expected: Sequence[KeyAnswer],
               answers: Sequence[AnswerResult]) -> tuple[AnswerResult, ...]:
        """``answers`` (one student's, compared with ``expected``) with follow-through credit
        where it is due (module docstring)."""
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
        earlier, shown = {}, []
        for name in k.answer.depends_on:
            variable = f"q{k.question}_{name}"
            given, key = by_variable.get(variable), keys.get(variable)
            if given is None or key is None or \
                    check_form(key.answer, given.submitted).status != "correct":
                return None  # missing or malformed: nothing to follow from
            earlier[name] = given.submitted
            shown.append((variable, given))
        if all(given.verdict.status == "correct" for _, given in shown):
            return None  # followed from the key itself: judged against it already
        question = self.students[student_id]["questions"][k.question - 1]
        try:
            value = self._value(question["family"], k.answer.name,
                                dict(question["parameters"]), earlier)
            trial = replace(k.answer, value=value, mistakes=(), accepted=(), depends_on=())
            verdict = grade(trial, a.submitted)
        except Exception:  # a recomputation that fails, or leaves the physics: no credit
            return None
        if verdict.status != "correct":
            return None
        points = round(self.fraction * k.answer.points, 12)
        source = ", ".join(f"{v} = {value_text(g.submitted)}" for v, g in shown)
        return replace(a, verdict=Verdict("follows", points, k.answer.points,
                                          f"follows from your {source} (right for that "
                                          "value; the key's differs)"))

    def apply(self, result: StudentResult, expected: Sequence[KeyAnswer]) -> StudentResult:
        """``result`` with :meth:`credit` applied to its answers (a graded record only)."""
        if result.status != "graded":
            return result
        answers = self.credit(result.student_id, expected, result.answers)
        if answers == result.answers:
            return result
        return replace(result, answers=answers,
                       points=sum(x.verdict.points for x in answers))


if __name__ == "__main__":
    serve()
