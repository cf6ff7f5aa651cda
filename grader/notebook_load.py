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
    * Files over the size limit (``--max-size``: ``Limits.submission_bytes``, which
      :func:`grader.execute.execute_submission` passes; :data:`MAX_NOTEBOOK_BYTES` for other
      readers) are refused before being read, and JSON with more values, objects and arrays or
      nesting than a notebook needs (:data:`MAX_JSON_VALUES`, :data:`MAX_JSON_CONTAINERS`,
      :data:`MAX_JSON_DEPTH`) before it is parsed (:func:`notebook_json`): parsing builds a
      Python object per value, and a 19 MiB file of ``{}`` once made the grader 3.2 GB larger
      (issue 23). Every reader of a submitted notebook in the grader's process goes through
      :func:`notebook_json`. The text itself has no limit of its own beyond the file's size
      (issue 33): a file of N bytes is at most 4N bytes as Python characters (one emoji makes
      every character of the text 4 bytes wide), and a limit on that once refused an 11 MiB
      notebook with one emoji in an output, whatever ``--max-size`` said.
    * A notebook whose code cells hold more than :data:`MAX_CODE_CHARS` characters is refused:
      the grader holds and sends the code several times over while it runs (a 16 MiB cell of
      comments cost it 146 MiB), and no answer needs that much.

Cells are numbered for people: ``cell 7`` is the seventh cell of the notebook counting
Markdown cells too, as a student scrolling through it would count.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import nbformat

from grader.submission_file import InvalidSubmission, read_submission

MAX_NOTEBOOK_BYTES = 50 * 1024**2
"""Largest submission read (bytes); generated notebooks are a few tens of kB."""

MAX_JSON_VALUES = 500_000
"""Most values a notebook's JSON may hold, counted as its commas and opening brackets outside
strings (about one Python object each; a notebook of a hundred cells holds a few thousand)."""

MAX_JSON_CONTAINERS = 50_000
"""Most objects and arrays (each a dict or list, and another one in nbformat's copy)."""

MAX_JSON_DEPTH = 100
"""Deepest nesting of objects and arrays (a notebook's own is under 10)."""

MAX_CODE_CHARS = 1_000_000
"""Most characters of code (all code cells together) a notebook may have run; a generated
solution has a few thousand."""

RESAVE = "open it in Jupyter and save it again"
CLEAR = "clear all outputs, then open it in Jupyter and save it again"


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


def read_notebook(path: Path, max_bytes: int | None = None) -> LoadedNotebook:
    """Read a submission: its v4 notebook, its code cells, and notes about the reading.

    ``max_bytes``: the largest file read (``--max-size``; default :data:`MAX_NOTEBOOK_BYTES`).

    Raises
    ------
    SubmissionError
        Missing or unreadable file, too large, not UTF-8, not JSON, not a notebook, an
        unsupported nbformat version, malformed cells, no code at all or too much of it.
    """
    path = Path(path)
    limit = MAX_NOTEBOOK_BYTES if max_bytes is None else max_bytes
    document = notebook_json(_read_bytes(path, limit))
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
    size = sum(len(c.source) for c in cells)
    if size > MAX_CODE_CHARS:
        raise SubmissionError(f"the notebook's code cells hold {size:,} characters, more than "
                              f"the {MAX_CODE_CHARS:,} the grader runs (remove data pasted into "
                              f"code cells); {RESAVE}")
    return LoadedNotebook(nb, cells, notes + language_note(nb))


def notebook_language(nb: dict) -> str:
    """The language a notebook's metadata says its code is in (``kernelspec.language``, else
    ``language_info.name``), lower case; ``"python"`` when it says none."""
    metadata = nb.get("metadata")
    for entry, key in (("kernelspec", "language"), ("language_info", "name")):
        found = metadata.get(entry) if isinstance(metadata, dict) else None
        value = found.get(key) if isinstance(found, dict) else None
        if isinstance(value, str) and value.strip():
            return value.strip().lower()
    return "python"


def language_note(nb: dict) -> tuple[str, ...]:
    """A note for the run's message when the notebook says its code is not Python: the grader
    runs every notebook in Python 3, whatever its kernel (module docstring)."""
    language = notebook_language(nb)
    if language.startswith("python") or language == "ipython":
        return ()
    return (f"this notebook's kernel runs {language[:40]!r}, but the grader runs every notebook "
            "as Python 3: open the notebook you were given (Python 3 kernel) and write your "
            "code there, in Python",)


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


def notebook_json(data: bytes) -> object:
    """The JSON document of a notebook file's bytes, parsed only if its size is bounded.

    What parsing would build is counted on the bytes first (:func:`json_shape`): more values,
    objects and arrays or nesting than the limits (module docstring) is refused before any
    object is made, so reading any file of at most ``N`` bytes costs ``O(N)`` memory.

    Raises
    ------
    SubmissionError
        Over a limit, not UTF-8, empty, or not JSON; the message is for the student.
    """
    problem = json_shape(data)
    if problem is not None:
        raise SubmissionError(f"not a notebook the grader reads: its JSON holds {problem}, far "
                              f"more than a notebook needs; {CLEAR}")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise SubmissionError(f"not a notebook: the file is not UTF-8 text (byte {e.start}); "
                              f"{RESAVE}") from None
    del data  # passed as a temporary, the bytes go now: the text is up to four times larger
    if not text.strip():
        raise SubmissionError("the file is empty, not a notebook")
    return _parse_json(text)


_NOT_BRACKET = bytes(b for b in range(256) if b not in b"[]{}")
_CHUNK = 1 << 18  # bytes looked at at once: the pieces of one chunk are all that is held


def json_shape(data: bytes) -> str | None:
    """What in the JSON text ``data`` is over a limit (``"1,400,002 values (at most …)"``), or
    None when it is within them all.

    The escapes ``\\\\`` and ``\\"`` are removed first (left to right, as a parser reads
    them; UTF-8 puts no ``"`` or ``\\`` inside a character), so that every ``"`` left opens or
    closes a string. Then, a chunk at a time, what lies outside strings is counted: ``{`` and
    ``[`` are the objects and arrays, each comma one more value, and the brackets' running
    balance is the nesting. Malformed JSON is left for the parser to describe.

    Examples
    --------
    >>> json_shape(b'{"cells": [{"source": "[[[,,,"}]}') is None
    True
    >>> json_shape(b"[" * 101 + b"]" * 101)
    'objects and arrays nested 101 deep (at most 100)'
    """
    text = data.replace(b"\\\\", b"").replace(b'\\"', b"")
    containers = commas = depth = deepest = 0
    inside = False  # a string runs on from the chunk before
    for start in range(0, len(text), _CHUNK):
        parts = text[start:start + _CHUNK].split(b'"')
        outside = b"".join(parts[1::2] if inside else parts[::2])
        inside ^= len(parts) % 2 == 0
        containers += outside.count(b"{") + outside.count(b"[")
        commas += outside.count(b",")
        if containers > MAX_JSON_CONTAINERS:
            return f"more than {MAX_JSON_CONTAINERS:,} objects and arrays"
        if containers + commas > MAX_JSON_VALUES:
            return f"more than {MAX_JSON_VALUES:,} values"
        for b in outside.translate(None, _NOT_BRACKET):  # as many as objects and arrays
            depth += 1 if b in b"[{" else -1
            if depth < 0:
                return None  # a bracket closed that was never opened: the parser says so
            deepest = max(deepest, depth)
    if deepest > MAX_JSON_DEPTH:
        return f"objects and arrays nested {deepest} deep (at most {MAX_JSON_DEPTH})"
    return None


def _read_bytes(path: Path, max_bytes: int) -> bytes:
    """The file's bytes, read as a submission is (:func:`grader.submission_file.read_submission`:
    a regular file only — never a FIFO, a device or a link, which could block or never end —
    of at most ``max_bytes``)."""
    try:
        return read_submission(path, max_bytes)
    except InvalidSubmission as e:
        raise SubmissionError(f"{e}; clear large outputs and save it again" if "limit" in str(e)
                              else str(e)) from None
    except FileNotFoundError:
        raise SubmissionError(f"{path}: no such file") from None
    except OSError as e:
        raise SubmissionError(f"{path}: cannot read it ({e.strerror or e})") from None


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
