"""The check from inside the notebook (issue 33): the answers *live* in this kernel, read as the
grader reads them (:func:`grader.extract.live_answers`) and checked against the notebook's
public answer list (:func:`grader.check.check_value`, the verdicts of ``eulertop check``); with
``run=True`` the saved notebook is run as the grader runs it (:func:`grader.check.check_notebook`)
and every answer it gives otherwise than this kernel is named.

Floor 8 of the grader's front ends (grader/API.md).
"""

from __future__ import annotations

import json
import math
import sys
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from eulertop_check.where import Found, NotebookNotFound, find_notebook

WORDS = {"correct": "ok", "missing": "missing", "invalid": "malformed"}
"""A form verdict's status, as the table says it."""

SAVE_AND_RERUN = "save it, then Restart and Run All"


@dataclass(frozen=True)
class Row:
    """One answer: its variable, its form here (``ok``, ``missing``, ``malformed``) and why, and
    what the saved notebook gives where that differs (``""`` where it agrees or did not run)."""

    variable: str
    word: str
    message: str
    saved: str = ""


@dataclass(frozen=True)
class LiveCheck:
    """What :func:`eulertop_check.check` found; shown as a table (:mod:`eulertop_check.show`)."""

    notebook: str  # its name, and where it was found
    rows: tuple[Row, ...]
    notes: tuple[str, ...] = ()  # about the saved run, when there was one

    @property
    def all_well_formed(self) -> bool:
        """Every answer present and well formed here, and the saved run (if any) agrees."""
        return all(r.word == "ok" and not r.saved for r in self.rows) and not self.notes

    def __str__(self) -> str:
        from eulertop_check.show import text

        return text(self)

    def _repr_pretty_(self, printer: Any, cycle: bool) -> None:
        printer.text(str(self))

    def _repr_html_(self) -> str:
        from eulertop_check.show import html_table

        return html_table(self)


class CheckError(RuntimeError):
    """The notebook cannot be checked (not found, not a notebook, no answer list): shown as its
    one line, never a traceback (:meth:`_render_traceback_`)."""

    def _render_traceback_(self) -> list[str]:  # IPython shows this instead of a traceback
        return [f"eulertop_check: {self}"]


def live_check(notebook: str | Path | None = None, *, run: bool = False,
               max_size: int | None = None, namespace: Mapping[str, Any] | None = None,
               ) -> LiveCheck:
    """:func:`eulertop_check.check` (its docstring); ``namespace``: where the answers live
    (default: the IPython kernel's, else the caller's caller's globals).

    Raises
    ------
    CheckError
        The notebook cannot be found or read, or has no eulertop answer list.
    """
    namespace = _namespace() if namespace is None else namespace
    found = _found(notebook, namespace)
    specs = _specs(found, max_size)
    from grader.check import check_value
    from grader.extract import live_answers

    written = [s["variable"] for s in specs if s.get("kind") == "written"]
    live = live_answers(namespace, [s["variable"] for s in specs
                                    if s["variable"] not in written])
    live.update(_saved_written(found, written, max_size))
    rows = [Row(s["variable"], *_form(check_value(s, live.get(s["variable"])))) for s in specs]
    notes: tuple[str, ...] = ()
    if run:
        rows, notes = _with_saved_run(found, specs, live, rows, max_size)
    return LiveCheck(_label(found), tuple(rows), notes)


def _namespace() -> Mapping[str, Any]:
    try:
        from IPython import get_ipython

        shell = get_ipython()
    except ImportError:
        shell = None
    if shell is not None:
        return shell.user_ns
    return sys._getframe(3).f_globals  # check() → live_check() → here: the caller of check()


def _found(notebook: str | Path | None, namespace: Mapping[str, Any]) -> Found:
    if notebook is not None:
        return Found("as named", Path(notebook))
    try:
        return find_notebook(namespace)
    except NotebookNotFound as err:
        raise CheckError(str(err)) from None


def _label(found: Found) -> str:
    name = found.path.name if found.path is not None else _document_name(found.document)
    return f"{name} (found by {found.how})" if found.how != "as named" else name


def _document_name(document: Mapping[str, Any] | None) -> str:
    try:
        return f"{document['metadata']['eulertop']['student']}.ipynb"
    except (KeyError, TypeError):
        return "notebook.ipynb"


def _specs(found: Found, max_size: int | None) -> tuple[dict, ...]:
    """The notebook's public answer list, read as ``eulertop check`` reads it."""
    from grader.check import CheckUsageError, answer_specs
    from grader.notebook_metadata import NoAnswerList, answer_list

    try:
        if found.path is not None:
            return answer_specs(found.path, max_size)
        return answer_list(found.document.get("metadata"))
    except CheckUsageError as err:
        raise CheckError(str(err)) from None
    except NoAnswerList as err:
        raise CheckError(f"this notebook {err}") from None


def _form(verdict: Any) -> tuple[str, str]:
    return WORDS[verdict.status], verdict.message


def _with_saved_run(found: Found, specs: Sequence[dict], live: Mapping[str, Any],
                    rows: list[Row], max_size: int | None) -> tuple[list[Row], tuple[str, ...]]:
    """The rows, each saying where the saved notebook, run as the grader runs it, gives
    another answer than this kernel; and notes on that run."""
    from grader.check import CheckUsageError, check_notebook
    from grader.limits import Limits

    limits = Limits() if max_size is None else Limits(submission_bytes=max_size)
    with tempfile.TemporaryDirectory(prefix="eulertop-check-") as folder:
        path = found.path or _written(found.document, Path(folder))
        try:
            report = _in_a_thread(check_notebook, path, limits)
        except CheckUsageError as err:
            raise CheckError(str(err)) from None
    execution = report.execution
    notes = tuple(f"{note}." for note in execution.notes)
    if execution.status != "ok":
        return rows, (*notes, f"Your saved notebook, run as the grader runs it: "
                              f"{execution.message}; {SAVE_AND_RERUN}.")
    notes += tuple(f"Your saved notebook: {e}." for e in execution.cell_errors)
    answers = execution.answers
    return [_compared(row, live.get(row.variable), answers.get(row.variable))
            if row.variable in answers else row for row in rows], notes


def _saved_written(found: Found, variables: Sequence[str],
                   max_size: int | None) -> dict[str, Any]:
    """The written answers (Markdown cells, issue 31) as the notebook was last saved: no kernel
    holds them (:func:`grader.written.written_answers`)."""
    if not variables:
        return {}
    from grader.submission_file import DEFAULT_MAX_BYTES, InvalidSubmission, read_submission
    from grader.written import written_answers

    if found.path is None:
        data = json.dumps(found.document).encode("utf-8")
    else:
        try:
            data = read_submission(found.path, max_size or DEFAULT_MAX_BYTES)
        except (OSError, InvalidSubmission) as err:
            raise CheckError(f"{found.path}: {err}") from None
    return written_answers(data, variables)


def _in_a_thread(function: Any, *args: Any) -> Any:
    """``function(*args)`` in a thread of its own: the run drives its kernel with
    ``asyncio.run``, which cannot start inside the live kernel's own running event loop."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(1) as pool:
        return pool.submit(function, *args).result()


def _written(document: Mapping[str, Any], folder: Path) -> Path:
    path = folder / _document_name(document)
    path.write_text(json.dumps(document), encoding="utf-8")
    return path


def _compared(row: Row, here: Any, saved: Any) -> Row:
    if _same(here, saved):
        return row
    said = (f"your saved notebook gives {row.variable} = {_shown(saved)}, this kernel "
            f"{_shown(here)}: {SAVE_AND_RERUN}")
    return Row(row.variable, row.word, row.message, said)


def _same(a: Any, b: Any) -> bool:
    """Equal plain values (NaN equal to NaN, as the grader would read both alike)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return type(a) is type(b) and a == b


def _shown(value: Any, limit: int = 40) -> str:
    from grader.extract import invalid_reason

    reason = invalid_reason(value)
    text = f"<{reason}>" if reason is not None else json.dumps(value, allow_nan=True)
    text = text.replace("null", "None").replace("true", "True").replace("false", "False")
    return text if len(text) <= limit else text[: limit - 1] + "…"
