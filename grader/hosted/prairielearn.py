"""PrairieLearn's external grader: the entrypoint (``/grade/tests/run``) of an eulertop
question made by ``eulertop package --for prairielearn``.

Layout (PrairieLearn's "External Grading", ``docs/hosted.md``)
    ``ROOT/student/`` the workspace's graded file (``homework.ipynb``); ``ROOT/data/data.json``
    the question's ``data`` (``params["eulertop_variant"]``, set by the question's
    ``server.py`` from PrairieLearn's variant seed; ``variant_seed`` is used if it is absent);
    ``ROOT/tests/`` the question's ``tests/`` folder (``assignment/`` with every variant's key,
    :data:`grader.hosted.grading.CONFIG`); ``ROOT/results/results.json`` written here (the
    folder is made). ``ROOT`` is ``/grade``, or ``$EULERTOP_PRAIRIELEARN_ROOT``.

Results
    ``gradable`` (false, so that no attempt is used, when no notebook was submitted or it is not
    a notebook), ``score`` (points / max points, in [0, 1]), ``message`` (what happened, the
    isolation used, the points), and ``tests``: one per answer with ``name``, ``points``,
    ``max_points``, ``message`` (the feedback).

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import json
import sys
import zlib
from collections.abc import Mapping, Sequence
from pathlib import Path

from grader.assignment import Assignment, UsageError
from grader.grade_one import claimed_student
from grader.gradebook import number
from grader.hosted.grading import (
    HostedError,
    choose_isolation,
    env_root,
    find_notebook,
    grade_notebook,
    open_package,
)
from grader.results import StudentResult, atomic_write_text

ROOT_VARIABLE = "EULERTOP_PRAIRIELEARN_ROOT"
DEFAULT_ROOT = "/grade"
ASSIGNMENT = "assignment"
NOT_A_NOTEBOOK = "invalid_notebook"


def variant_of(data: Mapping, a: Assignment) -> str:
    """The variant ``data`` names: ``params["eulertop_variant"]``, else the one the question's
    ``server.py`` derives from ``variant_seed`` (the same rule); :class:`HostedError` if none."""
    params = data.get("params") if isinstance(data.get("params"), Mapping) else {}
    variant = params.get("eulertop_variant")
    if variant is None and "variant_seed" in data:
        text = str(data["variant_seed"])
        n = int(text) if text.isdigit() else zlib.crc32(text.encode())
        variant = a.ids[n % len(a.ids)]
    if variant not in a.ids:
        raise HostedError(f"data.json names no variant of this question ({variant!r}); was the "
                          "question's server.py changed?")
    return variant


def not_gradable(why: str) -> dict:
    """PrairieLearn's ``results.json`` of a submission not graded (no attempt used)."""
    return {"gradable": False, "message": why, "format_errors": [why]}


def results_json(result: StudentResult, lines: Sequence[str]) -> dict:
    """PrairieLearn's ``results.json`` for ``result``."""
    out = list(lines)
    if result.message:
        out.insert(0, result.message)
    out.append(f"Points: {number(result.points)} / {number(result.max_points)}")
    tests = [{"name": f"Question {ans.question}: {ans.name} ({ans.variable})",
              "points": ans.verdict.points, "max_points": ans.verdict.max_points,
              "message": ans.verdict.message} for ans in result.answers]
    score = result.points / result.max_points if result.max_points > 0 else 0.0
    return {"gradable": True, "score": min(1.0, max(0.0, score)), "message": "\n".join(out),
            "tests": tests}


def _not_a_notebook(result: StudentResult) -> bool:
    return result.execution.get("status") == NOT_A_NOTEBOOK or (
        result.status == "failed" and result.message.startswith(("invalid submission",
                                                                 "not a valid notebook")))


def grade(root: Path) -> tuple[dict, int]:
    """Grade ``ROOT/student``: ``(results.json content, exit status)`` (1: the question's own
    fault, reported as not gradable)."""
    tests = root / "tests"
    try:
        config, a, limits = open_package(tests, ASSIGNMENT, root, [root / "data"])
        data = json.loads((root / "data" / "data.json").read_text(encoding="utf-8"))
        variant = variant_of(data if isinstance(data, Mapping) else {}, a)
    except (HostedError, UsageError, OSError, ValueError) as e:
        return not_gradable(f"The grader could not grade this submission: {e}"), 1
    path, why = find_notebook(root / "student", config.get("notebook"))
    if path is None:
        return not_gradable(f"Not graded: {why}."), 0
    try:
        isolation = choose_isolation(config.get("sandbox", "auto"), config.get("kernel_user"))
    except HostedError as e:
        return not_gradable(f"The grader could not grade this submission: {e}"), 1
    result = grade_notebook(a, variant, path, limits, isolation)
    if result.execution.get("retry"):  # no kernel could be started: not the student's doing
        return not_gradable(f"The grader could not run the notebook: {result.message}"), 1
    if _not_a_notebook(result):
        return not_gradable(f"Not graded: {result.message}"), 0
    lines = [f"Graded as variant {variant}. Isolation: {isolation.note}"]
    claim = claimed_student(path)
    if claim is not None and claim != variant:
        lines.insert(0, f"FLAGGED: this notebook was made for variant {claim}, not {variant}; "
                        f"it was graded against {variant}.")
    return results_json(result, lines), 0


def write_results(root: Path, results: Mapping) -> Path:
    folder = root / "results"
    folder.mkdir(parents=True, exist_ok=True)  # "not automatically created"
    path = folder / "results.json"
    atomic_write_text(path, json.dumps(results, indent=1, ensure_ascii=False) + "\n")
    return path


def main(argv: Sequence[str] | None = None) -> int:
    """The entrypoint: grade, write ``results.json``; the exit status of :func:`grade`."""
    root = env_root(ROOT_VARIABLE, DEFAULT_ROOT)
    try:
        results, status = grade(root)
    except Exception as e:  # the grader's own fault: still a results.json that says so
        results = not_gradable(f"The grader failed ({type(e).__name__}: {e})")
        status = 1
    path = write_results(root, results)
    print(f"eulertop: wrote {path}")
    print(results["message"])
    return status


if __name__ == "__main__":
    sys.exit(main())
