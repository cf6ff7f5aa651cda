"""Gradescope's autograder: ``run_autograder`` grades ``/autograder/submission/*.ipynb``.

Layout (Gradescope's "Autograder Specifications", ``docs/hosted.md``)
    ``ROOT/source/`` the extracted zip (``assignment/`` with ``assignment.json`` and
    ``key.json``, :data:`grader.hosted.grading.CONFIG`, the wheel); ``ROOT/submission/`` the
    student's files; ``ROOT/submission_metadata.json`` (``users[]``: ``email``, ``name``, and
    ``sid`` where the course has one); ``ROOT/results/results.json`` written here. ``ROOT`` is
    ``/autograder``, or ``$EULERTOP_GRADESCOPE_ROOT``.

The student
    The submitter is matched to the roster by SID, then email (:data:`MATCH`, as for
    Gradescope's bulk export in :mod:`grader.lms.gradescope`). A submitter not on the roster
    gets score 0 and a message saying so. In a group submission, the member whose variant the
    notebook's own metadata names is graded if they are a member, else the first matched. A
    notebook whose metadata names another student is graded against the submitter's variant
    and the output says so.

Results
    ``score`` (points), ``execution_time`` (s), ``output`` (what happened, the isolation used,
    the score), and one test per answer: ``name``, ``score``, ``max_score``, ``output`` (the
    feedback message), ``visibility`` (the package's ``--visibility``).

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from grader.assignment import Assignment, UsageError
from grader.grade_one import claimed_student
from grader.gradebook import number
from grader.hosted.grading import (
    HostedError,
    Isolation,
    choose_isolation,
    env_root,
    find_notebook,
    grade_notebook,
    open_package,
)
from grader.lms.download import Students
from grader.results import StudentResult, atomic_write_text

ROOT_VARIABLE = "EULERTOP_GRADESCOPE_ROOT"
DEFAULT_ROOT = "/autograder"
ASSIGNMENT = "assignment"
VISIBILITIES = ("hidden", "after_due_date", "after_published", "visible")


def match_columns(sid: str, email: str) -> list[tuple[str, str]]:
    """The ``(roster column, value)`` pairs a submitter is looked up by, in order."""
    return [("SID", sid), ("id", sid), ("Email", email), ("id", email), ("Email address", email)]


def submitters(metadata: Mapping, a: Assignment) -> tuple[list[str], list[str]]:
    """``(matched roster ids, a line per user not matched)`` of ``metadata["users"]``."""
    students = Students(a.rows)
    ids, unmatched = [], []
    users = metadata.get("users") if isinstance(metadata, Mapping) else None
    for user in users if isinstance(users, list) else []:
        user = user if isinstance(user, Mapping) else {}
        sid, email = (str(user.get(k) or "").strip() for k in ("sid", "email"))
        found, _ = students.by_any(match_columns(sid, email))
        who = f"{user.get('name') or '?'} ({email or 'no email'}, SID {sid or '-'})"
        if len(found) == 1:
            ids.append(found[0])
        else:
            why = "matches several roster students" if found else "is not on the roster"
            unmatched.append(f"{who} {why}")
    return ids, unmatched


def choose_student(ids: Sequence[str], claim: str | None) -> str:
    """Of a submission's matched members, the one graded (module docstring)."""
    return claim if claim in ids else ids[0]


def results_json(result: StudentResult | None, lines: Sequence[str], visibility: str,
                 seconds: float) -> dict:
    """Gradescope's ``results.json`` for ``result`` (None: nothing graded, score 0)."""
    tests = []
    for ans in result.answers if result is not None else ():
        tests.append({"name": f"Question {ans.question}: {ans.name} ({ans.variable})",
                      "score": ans.verdict.points, "max_score": ans.verdict.max_points,
                      "output": ans.verdict.message, "visibility": visibility})
    score = result.points if result is not None else 0.0
    out = list(lines)
    if result is not None:
        if result.message:
            out.insert(0, result.message)
        out.append(f"Score: {number(result.points)} / {number(result.max_points)}")
    return {"score": score, "execution_time": round(seconds), "output": "\n".join(out),
            "tests": tests}


def write_results(root: Path, results: Mapping[str, Any]) -> Path:
    """Write ``ROOT/results/results.json``; its path."""
    folder = root / "results"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "results.json"
    atomic_write_text(path, json.dumps(results, indent=1, ensure_ascii=False) + "\n")
    return path


def _read_metadata(root: Path) -> dict:
    path = root / "submission_metadata.json"
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise HostedError(f"cannot read Gradescope's {path.name}: {e}") from None


def grade(root: Path) -> tuple[dict, int]:
    """Grade the submission under ``root``: ``(results.json content, exit status)``.

    Exit status 0 when the submission was graded or refused for the student's own reason
    (not on the roster, no notebook), 1 when the package itself is at fault."""
    start = time.monotonic()
    source = root / "source"
    lines: list[str] = []
    try:
        config, a, limits = open_package(source, ASSIGNMENT, root,
                                         [root / "submission_metadata.json"])
        visibility = config.get("visibility", "visible")
        ids, unmatched = submitters(_read_metadata(root), a)
    except (HostedError, UsageError) as e:
        lines.append(f"The autograder could not grade this submission: {e}")
        return results_json(None, lines, "visible", time.monotonic() - start), 1
    lines += [f"note: submitter {u}" for u in unmatched]
    if not ids:
        lines.insert(0, "Not graded: the submitter is not on the class roster this assignment "
                        "was generated for, so there is no variant to grade against; ask your "
                        "instructor to add you.")
        return results_json(None, lines, visibility, time.monotonic() - start), 0
    path, why = find_notebook(root / "submission")
    if path is None:
        lines.insert(0, f"Not graded: {why}.")
        return results_json(None, lines, visibility, time.monotonic() - start), 0
    try:
        isolation: Isolation = choose_isolation(config.get("sandbox", "auto"),
                                                config.get("kernel_user"))
    except HostedError as e:
        lines.append(f"The autograder could not grade this submission: {e}")
        return results_json(None, lines, "visible", time.monotonic() - start), 1
    claim = claimed_student(path)
    sid = choose_student(ids, claim)
    result = grade_notebook(a, sid, path, limits, isolation)
    if result.execution.get("retry"):  # no kernel could be started: not the student's doing
        lines.append(f"The autograder could not run the notebook ({result.message}); this is "
                     "not your fault: ask your instructor to rerun the autograder.")
        return results_json(None, lines, "visible", time.monotonic() - start), 1
    if claim is not None and claim != sid:
        lines.append(f"FLAGGED: this notebook was made for {claim}, not for {sid} who submitted "
                     f"it; it was graded against {sid}'s own variant.")
    lines.append(f"Graded as {sid}'s variant. Isolation: {isolation.note}")
    return results_json(result, lines, visibility, time.monotonic() - start), 0


def main(argv: Sequence[str] | None = None) -> int:
    """``run_autograder``: grade and write ``results.json``; the exit status of :func:`grade`."""
    root = env_root(ROOT_VARIABLE, DEFAULT_ROOT)
    try:
        results, status = grade(root)
    except Exception as e:  # a fault of the grader's own: still a results.json that says so
        why = f"The autograder failed ({type(e).__name__}: {e}); this is not your fault."
        results, status = results_json(None, [why], "visible", 0.0), 1
    path = write_results(root, results)
    print(f"eulertop: wrote {path} (score {number(results['score'])})")
    print(results["output"])
    return status


if __name__ == "__main__":
    sys.exit(main())
