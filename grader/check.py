"""``eulertop check NOTEBOOK.ipynb``: run a notebook as the grader would; are its answers well
formed?

For a student, before submitting. The notebook runs exactly as in ``eulertop grade``
(:func:`grader.run_file.run_one`: the same safe read, private copy, kernel start and retries;
default :class:`~grader.limits.Limits`, and the same ``--max-size``), then each
answer listed in the notebook's own ``metadata["eulertop"]`` (the public answer spec written
by the generator: names, kinds, units, vector lengths, options, symbols — never values) is
reported as *well formed*, *missing* or *malformed and why*
(:func:`problems.answers.check_spec`). It never says whether an answer is right: the key is not
here.

Advisory only: the metadata is in the student's hands and may have been edited; the grader
never reads it (it takes the answer list from the instructor's key).

Sandbox: the notebook runs in the grader's sandbox (:mod:`grader.sandbox`) where one can be
had, and otherwise without one, with a note saying so: a student checking their own notebook
on their own machine runs their own code, with nothing of the key there to protect (``eulertop
grade``, in contrast, refuses to run without a sandbox unless told ``--no-sandbox``).

Exit status: 0 when every answer is present and well formed; 1 otherwise (or when the notebook
could not be run to the end); 2 on usage errors — no such file, not a notebook, no eulertop
metadata, not a regular file (a named pipe, a device, a link: refused at once, never opened) or
over the size limit (as ``eulertop grade`` would refuse it) — with one line saying what to do,
never a traceback.

The same module is the student package's command, ``eulertop-check NOTEBOOK``
(:mod:`eulertop_check.cli`, issue 33): one implementation, one set of verdicts.

Module-level imports stay light: ``eulertop --help`` imports this module.

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

WHERE_METADATA = ("check works on the notebook you were given (release/<your id>.ipynb); if "
                  "you moved your work to a new notebook, copy it back into that one")


class CheckUsageError(ValueError):
    """The notebook cannot be checked at all (exit status 2); the message says what to do."""


@dataclass(frozen=True)
class AnswerCheck:
    """The form of one answer: ``verdict.status`` is correct (= well formed), missing, invalid."""

    variable: str
    spec: dict
    verdict: Any  # problems.answers.Verdict


@dataclass(frozen=True)
class CheckReport:
    """What ``eulertop check`` found: the run, and one entry per answer of the spec."""

    execution: Any  # grader.execute.Execution
    answers: tuple[AnswerCheck, ...]

    @property
    def all_well_formed(self) -> bool:
        """Every answer present and well formed, and the notebook ran to the end."""
        return self.execution.status == "ok" and all(
            a.verdict.status == "correct" for a in self.answers)


def add_check_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``eulertop check`` (and ``eulertop-check``)."""
    from grader.submission_file import MAX_SIZE_HELP, size_argument

    parser.add_argument("notebook", type=Path, metavar="NOTEBOOK.ipynb",
                        help="your notebook, as you will submit it")
    parser.add_argument("--max-size", type=size_argument, metavar="SIZE", help=MAX_SIZE_HELP)


def run_check(args: argparse.Namespace, prog: str = "eulertop check") -> int:
    """Run ``eulertop check`` (``prog`` names the command in its messages); the exit status
    (module docstring)."""
    from grader.limits import Limits

    max_size = getattr(args, "max_size", None)
    limits = Limits() if max_size is None else Limits(submission_bytes=max_size)
    try:
        report = check_notebook(args.notebook, limits)
    except CheckUsageError as err:
        print(f"{prog}: {err}", file=sys.stderr)
        return 2
    print(format_report(report, args.notebook, prog))
    return 0 if report.all_well_formed else 1


def answer_specs(path: Path, max_bytes: int | None = None) -> tuple[dict, ...]:
    """The public answer specs in the notebook's ``metadata["eulertop"]``, in question order.

    The file is read as the grader reads a submission (:func:`grader.notebook_load.read_notebook`:
    a regular file of at most ``max_bytes``, default ``--max-size``'s, parsed within the
    grader's limits).

    Raises
    ------
    CheckUsageError
        No such file, not a regular file, too large, not a notebook, no (or damaged) eulertop
        metadata.
    """
    from grader.notebook_load import SubmissionError, read_notebook
    from grader.notebook_metadata import NoAnswerList, answer_list
    from grader.submission_file import DEFAULT_MAX_BYTES

    path = Path(path)
    if not os.path.lexists(path):
        raise CheckUsageError(f"{path}: no such file")
    try:
        metadata = read_notebook(path, max_bytes or DEFAULT_MAX_BYTES).notebook.get("metadata")
    except SubmissionError as err:
        raise CheckUsageError(f"{path}: {err}") from None
    try:
        return answer_list(metadata)
    except NoAnswerList as err:
        raise CheckUsageError(f"{path} {err}: {WHERE_METADATA}") from None


def check_notebook(path: Path, limits: Any) -> CheckReport:
    """Run the notebook under ``limits`` and check the form of each answer of its spec.

    Raises
    ------
    CheckUsageError
        See :func:`answer_specs`.
    """
    from grader.run_file import run_one

    specs = answer_specs(path, getattr(limits, "submission_bytes", None))
    written = [s["variable"] for s in specs if s.get("kind") == "written"]
    run = run_one(Path(path), [s["variable"] for s in specs if s["variable"] not in written],
                  limits, written=written)
    if run.execution is None:  # too large, not a regular file, or no kernel could run it
        raise CheckUsageError(f"{path}: {run.problem}")
    execution = run.execution
    read = {**execution.answers, **(run.written or {})}  # written ones from the file itself
    answers = tuple(
        AnswerCheck(s["variable"], s, check_value(s, read.get(s["variable"]))) for s in specs
    )
    return CheckReport(execution, answers)


def check_value(spec: Mapping[str, Any], value: Any) -> Any:
    """The form :class:`~problems.answers.Verdict` of one extracted value (markers included)."""
    from grader.extract import invalid_reason
    from problems.answers import Verdict, check_spec, kind_hint

    try:
        reason = invalid_reason(value)
        if reason is not None:
            return Verdict("invalid", 0.0, float(spec.get("points", 1.0)),
                           f"{reason}; {kind_hint(spec)} is expected")
        return check_spec(spec, value)
    except Exception:  # a spec edited into nonsense: say so, never a traceback
        return Verdict("invalid", 0.0, 0.0, "could not be checked: the notebook's metadata "
                       "for this answer is damaged")


_WORDS = {"correct": "ok", "missing": "MISSING", "invalid": "MALFORMED"}


def format_report(report: CheckReport, path: Path, prog: str = "eulertop check") -> str:
    """The report printed by ``eulertop check`` (``prog``: the command to run again)."""
    execution = report.execution
    lines = [f"Ran {Path(path).name} as the grader will, in a fresh kernel."]
    lines += [f"Note: {note}." for note in getattr(execution, "notes", ())]
    if execution.status != "ok":
        lines += [execution.message + ".", "No answer could be read, so none could be checked. "
                  f"Fix the problem above and run {prog} again."]
        return "\n".join(lines)
    if execution.cell_errors:
        lines.append(f"{len(execution.cell_errors)} cell(s) did not finish normally (answers "
                     "they did not set count as missing):")
        lines += [f"  - {error}" for error in execution.cell_errors]
    if execution.output_truncated:
        lines.append("(Much output: only the beginning was kept. Output is never graded.)")
    if not getattr(execution, "sandboxed", True):
        lines.append("(Ran without the grader's sandbox — bubblewrap is not available here; "
                     "the grader runs it in one.)")
    width = max(len(a.variable) for a in report.answers)
    for a in report.answers:
        word = _WORDS[a.verdict.status]
        lines.append(f"  {word:<9} {a.variable:<{width}}  {a.verdict.message}")
    lines.append(_tally([a.verdict.status for a in report.answers]))
    lines.append("This checks the form of your answers only, never whether they are right.")
    return "\n".join(lines)


def _tally(statuses: Sequence[str]) -> str:
    n, good = len(statuses), statuses.count("correct")
    missing, bad = statuses.count("missing"), statuses.count("invalid")
    text = f"{good} of {n} answers present and well formed"
    if missing or bad:
        text += f"; {missing} missing, {bad} malformed"
    return text + "."
