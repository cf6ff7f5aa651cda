"""Load and sanitize a submission: file → notebook → the code cells the grader will run.

Stage *load/sanitize* of the pipeline (``grader/API.md``). Everything here treats the file as
untrusted and fails with a :class:`SubmissionError` whose message is for the student.

Decisions
    * nbformat v4 is read as is. **nbformat v3 is converted** to v4 with nbformat's own
      converter (it is mature and lossless for code cells) and the run's message says so;
      v1, v2 and anything newer than v4 are refused.
    * Only the *sources of the code cells* survive sanitizing: outputs (never trusted: a
      notebook whose saved outputs show right answers gets nothing for them), kernelspec and
      language metadata (the grader always runs its own Python kernel), cell tags (nbclient
      would honour ``skip-execution``), attachments and widget state are dropped.
    * A notebook with no non-blank code cell is refused as empty (nothing could ever be
      graded; most likely the wrong file was submitted).
    * Other departures from the nbformat schema (extra metadata written by some editors) are
      tolerated, since nothing but the code cells' sources is kept.
    * Files over :data:`MAX_NOTEBOOK_BYTES` are refused before being read.

Cells are numbered for people: ``cell 7`` is the seventh cell of the notebook counting
Markdown cells too, as a student scrolling through it would count.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import nbformat

MAX_NOTEBOOK_BYTES = 50 * 1024**2
"""Largest submission read (bytes); generated notebooks are a few tens of kB."""

RESAVE = "open it in Jupyter and save it again"


class SubmissionError(ValueError):
    """The submission is not a notebook the grader can run; the message says why, for a person."""


@dataclass(frozen=True)
class CodeCell:
    """One non-blank code cell of a submission.

    Attributes
    ----------
    position : int
        1-based position among *all* the notebook's cells (Markdown included).
    source : str
        The cell's code.
    """

    position: int
    source: str

    @property
    def label(self) -> str:
        """``cell 7 (`q1_T = 1/0`)``: the position and the first non-blank line, shortened."""
        first = next(line.strip() for line in self.source.splitlines() if line.strip())
        if len(first) > 40:
            first = first[:39] + "…"
        return f"cell {self.position} (`{first}`)"


@dataclass(frozen=True)
class LoadedNotebook:
    """A submission read from disk.

    Attributes
    ----------
    notebook : nbformat.NotebookNode
        The notebook as nbformat v4 (converted from v3 if need be).
    cells : tuple of CodeCell
        Its non-blank code cells, in order (never empty).
    notes : tuple of str
        Remarks for the run's message, e.g. that the notebook was converted from nbformat v3.
    """

    notebook: nbformat.NotebookNode
    cells: tuple[CodeCell, ...]
    notes: tuple[str, ...] = ()


def read_notebook(path: Path) -> LoadedNotebook:
    """Read a submission: its v4 notebook, its code cells, and notes about the reading.

    Raises
    ------
    SubmissionError
        Missing or unreadable file, too large, not UTF-8, not JSON, not a notebook, an
        unsupported nbformat version, malformed cells, or no code at all.
    """
    path = Path(path)
    document = _parse_json(_read_text(path))
    version = document.get("nbformat") if isinstance(document, dict) else None
    if isinstance(version, bool) or not isinstance(version, int):
        raise SubmissionError("this is JSON, but not a Jupyter notebook (it has no 'nbformat' "
                              f"version); {RESAVE}")
    notes: tuple[str, ...] = ()
    if version == 3:
        nb, notes = _from_v3(document), ("converted from the old notebook format v3 to v4",)
    elif version == 4:
        nb = nbformat.from_dict(document)
    else:
        raise SubmissionError(f"notebook format v{version} is not supported (v4 is, and v3 is "
                              f"converted); {RESAVE} with a current Jupyter")
    cells = code_cells(nb)
    if not cells:
        raise SubmissionError("the notebook has no code: no code cell holds anything (an empty "
                              "notebook, or the wrong file?)")
    return LoadedNotebook(nb, cells, notes)


def load_submission(path: Path) -> nbformat.NotebookNode:
    """The submission at ``path`` as an nbformat v4 notebook (``grader/API.md``).

    nbformat v3 is converted (see the module docstring); for the note saying so, and for the
    code cells the grader runs, use :func:`read_notebook`.

    Raises
    ------
    SubmissionError
        With a message for the student (see :func:`read_notebook`).
    """
    return read_notebook(path).notebook


def code_cells(nb: nbformat.NotebookNode) -> tuple[CodeCell, ...]:
    """The non-blank code cells of a v4 notebook, numbered by position among all cells.

    Raises
    ------
    SubmissionError
        ``cells`` is not a list of cells, or a code cell's source is not text.
    """
    cells = nb.get("cells")
    if not isinstance(cells, list):
        raise SubmissionError(f"the notebook has no list of cells; {RESAVE}")
    found = []
    for position, cell in enumerate(cells, start=1):
        if not isinstance(cell, dict) or not isinstance(cell.get("cell_type"), str):
            raise SubmissionError(f"cell {position} is malformed (no cell type); {RESAVE}")
        if cell["cell_type"] != "code":
            continue
        source = _source_text(cell.get("source", ""), position)
        if source.strip():
            found.append(CodeCell(position, source))
    return tuple(found)


def executable_notebook(cells: Sequence[CodeCell]) -> nbformat.NotebookNode:
    """The notebook the grader actually runs: a fresh v4 notebook of these sources only.

    Nothing else of the submission survives (module docstring): no outputs, metadata or tags.
    """
    return nbformat.from_dict({
        "nbformat": 4,
        "nbformat_minor": 5,
        "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3",
                                    "language": "python"},
                     "language_info": {"name": "python"}},
        "cells": [{"cell_type": "code", "id": f"cell-{c.position}", "metadata": {},
                   "source": c.source, "outputs": [], "execution_count": None} for c in cells],
    })


def _read_text(path: Path) -> str:
    try:
        size = path.stat().st_size
        if size > MAX_NOTEBOOK_BYTES:
            raise SubmissionError(f"the file is {size / 1024**2:.0f} MB, more than the "
                                  f"{MAX_NOTEBOOK_BYTES // 1024**2} MB a notebook may be "
                                  "(clear large outputs and save it again)")
        data = path.read_bytes()
    except FileNotFoundError:
        raise SubmissionError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise SubmissionError(f"{path} is a folder, not a notebook file") from None
    except OSError as e:
        raise SubmissionError(f"{path}: cannot read it ({e.strerror or e})") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise SubmissionError(f"not a notebook: the file is not UTF-8 text (byte {e.start}); "
                              f"{RESAVE}") from None
    if not text.strip():
        raise SubmissionError("the file is empty, not a notebook")
    return text


def _parse_json(text: str) -> object:
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise SubmissionError(f"not a notebook: not valid JSON (line {e.lineno}, column "
                              f"{e.colno}: {e.msg}); {RESAVE}") from None
    except (RecursionError, ValueError) as e:
        raise SubmissionError(f"not a notebook: unreadable JSON ({type(e).__name__}); "
                              f"{RESAVE}") from None


def _from_v3(document: dict) -> nbformat.NotebookNode:
    try:
        nb = nbformat.reads(json.dumps(document), as_version=4)
    except Exception as e:  # nbformat raises many kinds on malformed v3; all mean "can't read"
        raise SubmissionError(f"an nbformat v3 notebook that could not be converted to v4 "
                              f"({type(e).__name__}); {RESAVE}") from None
    if nb.get("nbformat") != 4:
        raise SubmissionError(f"an nbformat v3 notebook that could not be converted; {RESAVE}")
    return nb


def _source_text(source: object, position: int) -> str:
    if isinstance(source, str):
        return source
    if isinstance(source, list) and all(isinstance(line, str) for line in source):
        return "".join(source)
    raise SubmissionError(f"cell {position}: its source is not text; {RESAVE}")
