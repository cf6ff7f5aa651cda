"""A student's notebook: the release version (answers ``None``) and the solutions version.

Layout (cell ids are fixed names, so the same inputs give byte-identical files):

==================  ========  ==========================================================
id                  type      content
==================  ========  ==========================================================
``title``           markdown  the assignment title, and how to install and run the check
``rules``           markdown  the student's id, the rules, the conventions shared by every
                              question (:mod:`problems.conventions`)
``parameters``      code      the student's parameters, ``q{k}_{name} = value  # unit``
``q{k}-statement``  markdown  question k: title, statement, how each answer is compared
``q{k}-answer``     code      one line per answer, ``q{k}_{name} = None  # unit — what``
                              (its form where not a plain number, its points where not 1);
                              absent where the question has only written parts
``q{k}-w{j}-prompt``  markdown  written part j of question k (:mod:`problems.written`): its
                              variable, points and prompt
``q{k}-w{j}-written`` markdown  the student's answer to it (the release holds
                              :data:`problems.written.PLACEHOLDER`, the solutions the rubric),
                              marked ``metadata["eulertop"]["written"] = "q{k}_{name}"``
==================  ========  ==========================================================

All cells but the answer cells are marked ``"editable": false`` (and every generated cell
``"deletable": false``); the grader does not rely on it. ``metadata["eulertop"]`` holds the
public answer spec (:func:`problems.variant.answer_spec`: names, kinds, units, vector lengths,
options, symbols — never values, never mistakes) so ``eulertop check`` works without the key.

Parameters are prefixed by their question (``q2_M``) because two questions may both have an
``M``; one cell holding all of them keeps a student who reruns cells out of order from using
another question's values.

In the solutions notebook every answer is a Python literal of the key's plain-JSON value:
floats by ``repr`` (which round-trips exactly), vectors as lists, booleans, choice strings, and
expressions as *strings* — exactly what the grader extracts from a student's sympy expression,
so executing the solutions notebook and extracting its answers reproduces ``key.json``.
"""

from __future__ import annotations

import html
import json
import math
from collections.abc import Callable, Mapping, Sequence
from functools import lru_cache
from typing import Any

import nbformat
from nbformat import v4

from problems.answers import WRITTEN, Answer, comparison_rule, kind_hint
from problems.conventions import conventions_text
from problems.variant import Variant, answer_spec, variable_name
from problems.written import PLACEHOLDER

FORMAT_VERSION = 1
KERNELSPEC = {"name": "python3", "display_name": "Python 3 (ipykernel)", "language": "python"}

DEFAULT_INSTALL = "eulertop-check"
"""What ``%pip install`` is given for the checker (the student package, ``student/``), unless
the spec names another address (``[student] install``: a wheel's URL, an index's name)."""

TITLE_CELL = """\
# {title}

**Before you submit**, check your answers from inside this notebook: run `%pip install \
{install}` once, then, in a cell, `import eulertop_check; eulertop_check.check()`. It says \
which answers are missing or malformed, never whether they are right; \
`eulertop_check.check(run=True)` also runs your saved notebook as the grader will (save it \
first). In a terminal: `eulertop-check {file}`.\
"""

RULES = """\
**Student:** {who}

Your numbers are yours alone: use them as given (the key is computed from exactly these \
values). Write each answer into its variable in the answer cell (leave `None` to skip it); only \
these variables are graded, after the whole notebook runs in a fresh kernel.

{conventions}
"""


def python_literal(value: Any) -> str:
    """A Python literal for a plain-JSON answer value (None, bool, number, str, list).

    Floats use ``repr``, the shortest string that reads back as the same float.

    Examples
    --------
    >>> python_literal([0.1, 2.5e-07, True, "loops"])
    "[0.1, 2.5e-07, True, 'loops']"
    """
    if type(value) is float and math.isfinite(value):  # the common case, first
        return float.__repr__(value)
    if value is None or isinstance(value, bool | str):
        return repr(value)
    if isinstance(value, int):
        return repr(int(value))
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write a non-finite answer {value!r}")
        return repr(float(value))
    if isinstance(value, list | tuple):
        return "[" + ", ".join(python_literal(v) for v in value) + "]"
    raise TypeError(f"answer value {value!r} is not plain JSON (number, bool, str or list)")


def _one_line(text: str) -> str:
    return " ".join(text.split())


def answer_line(spec: Mapping[str, Any], value: Any = None) -> str:
    """``q3_beta1 = None  # rad — β₁, the upper turning point`` (value None in the release).

    The comment gives the unit, and the form where it is not a plain number (``kg m^2, a list
    of 3 numbers``); the points when they are not 1 (the notebook's conventions say so).
    """
    head, tail = _answer_line_parts(spec)
    return head + python_literal(value) + tail


def _answer_line_parts(spec: Mapping[str, Any]) -> tuple[str, str]:
    """:func:`answer_line` before and after its value (made once for a student's two
    notebooks)."""
    form = spec["unit"] or kind_hint(spec)
    if spec["unit"] and spec["kind"] not in ("scalar", "angle"):
        form = f"{spec['unit']}, {kind_hint(spec)}"
    points = spec.get("points", 1.0)
    worth = f" ({points:g} point{'' if points == 1 else 's'})" if points != 1 else ""
    notes = [form, _one_line(spec["description"]) + worth]
    comment = " — ".join(n for n in notes if n.strip())
    return f"{spec['variable']} = ", f"  # {comment}"


def _parameter_cell(variants: Sequence[Variant]) -> str:
    lines = ["# Your parameters: use them as given. SI units, angles in radians."]
    for k, variant in enumerate(variants, start=1):
        lines.append(f"\n# Question {k}: {_one_line(variant.title)}")
        for name, value in variant.params.items():
            unit = variant.param_units.get(name, "")
            comment = f"  # {unit}" if unit else ""
            lines.append(f"{variable_name(k, name)} = {python_literal(value)}{comment}")
    return "\n".join(lines)


def comparison_line(variants_answers: Sequence[Any], question: int) -> str:
    """The line under a question saying how each of its answers is compared, e.g.
    ``*Compared:* `q1_T`, `q1_L`: within 0.1 %.``; answers compared alike share
    one entry. Derived from each answer's own kind and tolerances
    (:func:`problems.answers.comparison_rule`), never typed into a template."""
    groups: dict[str, list[str]] = {}
    for answer in variants_answers:
        rule = comparison_rule(answer)
        groups.setdefault(rule, []).append(f"`{variable_name(question, answer.name)}`")
    parts = [f"{', '.join(names)}: {rule}" for rule, names in groups.items()]
    return "*Compared:* " + "; ".join(parts) + "."


def notebook_conventions(variants: Sequence[Variant],
                         families: Mapping[str, Any] | None = None) -> str:
    """The conventions paragraph of a notebook: the general rules and the topics its questions'
    families list in their ``CONVENTIONS`` (:mod:`problems.conventions`). ``families``: the
    :class:`~problems.family.Family` objects by name (default: the built-in ones)."""
    if families is None:
        from problems.templates import FAMILIES as families
    topics = [t for v in variants if v.family in families
              for t in families[v.family].conventions]
    return conventions_text(topics)


def _rules_cell(student: Mapping[str, str], conventions: str = "") -> str:
    sid = student["id"]
    name = student.get("name", "").strip()
    who = f"`{sid}`" + (f" ({html.escape(name, quote=False)})" if name else "")
    return RULES.format(who=who, conventions=conventions).rstrip("\n")


def build_notebook(
    title: str,
    student: Mapping[str, str],
    variants: Sequence[Variant],
    *,
    solutions: bool = False,
    families: Mapping[str, Any] | None = None,
    install: str = DEFAULT_INSTALL,
) -> dict:
    """The release notebook of one student, or (``solutions=True``) its solutions version.

    Returned as a plain nbformat-v4-shaped dict (``nbformat.from_dict`` makes it a
    ``NotebookNode``); :func:`notebook_text` validates and serialises it.

    Parameters
    ----------
    title : str
        The assignment's title.
    student : mapping
        The student's roster row; ``"id"`` is required, ``"name"`` is shown when present.
    variants : sequence of Variant
        The student's questions, in order (question ``k`` is ``variants[k - 1]``).
    solutions : bool
        Fill the answer variables with the key's values instead of ``None``.
    families : mapping, optional
        The families by name, for their convention topics (default: the built-in ones).
    install : str
        What the first cell tells the student to ``%pip install`` for the checker.
    """
    (notebook,) = _notebooks(title, student, variants, (solutions,), families, install)
    return notebook


def build_notebooks(
    title: str, student: Mapping[str, str], variants: Sequence[Variant],
    families: Mapping[str, Any] | None = None, install: str = DEFAULT_INSTALL,
) -> tuple[dict, dict]:
    """The release and the solutions notebook of one student (:func:`build_notebook`), built
    together: every cell and metadata entry the two have in common is one shared object, so
    :func:`notebook_text` with one ``memo`` for both encodes it once."""
    release, solutions = _notebooks(title, student, variants, (False, True), families, install)
    return release, solutions


def notebook_texts(
    title: str, student: Mapping[str, str], variants: Sequence[Variant],
    families: Mapping[str, Any] | None = None, install: str = DEFAULT_INSTALL,
    *, validate: bool = True,
) -> tuple[str, str]:
    """The text of the release and the solutions notebook of one student: the same as
    :func:`notebook_text` of each of :func:`build_notebooks`, cheaper for a class.

    Every cell is encoded by :func:`_cell_text` (around its source, the rest made once per
    process), and every question's record in the metadata by :func:`_encoded_question`, which
    keeps it, and its answer lines' parts, by its content: often the same for many students.
    ``validate`` checks the texts against the nbformat schema (:func:`notebook_text`).
    """
    memo: dict = {}  # the metadata both notebooks share, encoded once
    texts = tuple(_indented(nb, "\n", memo) + "\n" for nb in _notebooks(
        title, student, variants, (False, True), families, install, _cell_text,
        _encoded_question))
    if validate:
        for text in texts:
            _validate(json.loads(text))
    return texts


def _notebooks(
    title: str, student: Mapping[str, str], variants: Sequence[Variant],
    kinds: Sequence[bool], families: Mapping[str, Any] | None = None,
    install: str = DEFAULT_INSTALL, cell: Callable[..., Any] | None = None,
    question: Callable[[dict], tuple[Any, Sequence[tuple[str, str]]]] | None = None,
) -> list[dict]:
    """One notebook per entry of ``kinds`` (True: solutions), sharing what they have in common;
    each cell made by ``cell`` (the arguments of :func:`_cell`; default: :func:`_cell`), each
    question's record in the metadata and its answer lines' parts by ``question`` (of the
    record; default: :func:`_question_parts`)."""
    cell, question = cell or _cell, question or _question_parts
    questions = [
        {"question": k, "family": v.family, "title": v.title,
         "answers": [answer_spec(a, k) for a in v.answers]}
        for k, v in enumerate(variants, start=1)
    ]
    heading = TITLE_CELL.format(title=_one_line(title), file=f"{student['id']}.ipynb",
                                install=_one_line(install))
    rules = _rules_cell(student, notebook_conventions(variants, families))
    shared = [
        cell("markdown", "title", heading),
        cell("markdown", "rules", rules),
        cell("code", "parameters", _parameter_cell(variants)),
    ]
    statements = [cell("markdown", f"q{k}-statement", _statement(k, v), question=k)
                  for k, v in enumerate(variants, start=1)]
    made = [question(q) for q in questions]  # (record, its answer lines' parts)
    records = [record for record, _ in made]
    answered = [list(zip([a.value for a in variant.answers if a.kind != WRITTEN], parts,
                         strict=True)) for variant, (_, parts) in zip(variants, made, strict=True)]
    notebooks = []
    for solutions in kinds:
        cells = list(shared)
        for k, (variant, parts, statement) in enumerate(
                zip(variants, answered, statements, strict=True), start=1):
            lines = [head + python_literal(value if solutions else None) + tail
                     for value, (head, tail) in parts]
            cells.append(statement)
            if lines:
                cells.append(cell("code", f"q{k}-answer", "\n".join(lines), editable=True,
                                  question=k))
            cells += _written_cells(k, variant, solutions, cell)
        metadata = {
            "kernelspec": dict(KERNELSPEC),
            "language_info": {"name": "python"},
            "eulertop": {
                "format_version": FORMAT_VERSION,
                "notebook": "solutions" if solutions else "release",
                "student": student["id"],
                "assignment": title,
                "questions": records,
            },
        }
        notebooks.append({"nbformat": v4.nbformat, "nbformat_minor": v4.nbformat_minor,
                          "metadata": metadata, "cells": cells})
    return notebooks


def _statement(k: int, variant: Variant) -> str:
    """Question ``k``'s statement cell: its title, statement, and how its answers are compared
    (written parts have their own cells)."""
    compared = [a for a in variant.answers if a.kind != WRITTEN]
    statement = f"## Question {k}: {_one_line(variant.title)}\n\n{variant.statement.strip()}"
    if compared:
        statement += f"\n\n{comparison_line(compared, k)}"
    return statement


def _written_cells(k: int, variant: Variant, solutions: bool,
                   cell: Callable[..., Any]) -> list[Any]:
    """The prompt and answer cells of question ``k``'s written parts (module docstring), each
    made by ``cell`` (:func:`_notebooks`)."""
    cells = []
    parts = [a for a in variant.answers if a.kind == WRITTEN]
    for j, answer in enumerate(parts, start=1):
        variable = variable_name(k, answer.name)
        points = f"{answer.points:g} point{'' if answer.points == 1 else 's'}"
        prompt = (f"**Written answer `{variable}`** ({points}, scored by a person against a "
                  f"rubric; write it in the cell below)\n\n{answer.value.strip()}")
        cells.append(cell("markdown", f"q{k}-w{j}-prompt", prompt, question=k))
        text = rubric_text(answer) if solutions else PLACEHOLDER
        cells.append(cell("markdown", f"q{k}-w{j}-written", text, editable=True, question=k,
                          written=variable))
    return cells


def rubric_text(answer: Answer) -> str:
    """A written answer's rubric as Markdown (the solutions notebook's answer cell)."""
    items = "\n".join(f"- {r.item} ({r.points:g})" for r in answer.rubric)
    return f"*Rubric ({answer.points:g} points):*\n\n{items}"


def _cell(kind: str, cell_id: str, source: str, editable: bool = False,
          question: int | None = None, written: str | None = None) -> dict:
    """A cell as a plain dict: generated cells are never deletable, only answer cells editable;
    ``written``: the variable of the written answer the cell holds."""
    # Built as plain dicts: nbformat.v4.new_*_cell validates every cell against the schema, which
    # made it most of the generator's run time; notebook_text validates the whole notebook once.
    role = cell_id.split("-")[-1]
    metadata: dict = {"deletable": False} if editable else {"editable": False, "deletable": False}
    metadata["eulertop"] = {"role": role}
    if question is not None:
        metadata["eulertop"]["question"] = question
    if written is not None:
        metadata["eulertop"]["written"] = written
    # Sources as lists of lines, the way nbformat writes them (line-based diffs).
    cell = {"cell_type": kind, "id": cell_id, "metadata": metadata,
            "source": source.splitlines(keepends=True)}
    if kind == "code":
        cell.update(execution_count=None, outputs=[])
    return cell


def notebook_text(nb: Mapping, *, validate: bool = True, memo: dict | None = None) -> str:
    """The notebook as JSON in nbformat's own layout; ValueError if it is not valid nbformat v4.

    Same text as ``json.dumps(nb, indent=1, sort_keys=True, ensure_ascii=False)`` — the layout
    of ``nbformat.writes`` — without its defensive deep copy, which doubled the time per
    notebook, and without the json module's pure-Python encoder (which ``indent`` selects):
    :func:`indented_json` writes the same bytes in a third of the time.

    ``validate=False`` skips the schema check (a few hundred microseconds a notebook): the
    generator validates one student's notebooks per run, since every notebook is built by the
    same code, and the tests validate all of them.

    ``memo`` (a dict, empty at first) lets notebooks that share parts (:func:`build_notebooks`)
    encode each shared part once: pass the same one for both, while both exist unchanged.
    """
    if validate:
        _validate(nb)
    return indented_json(nb, memo) + "\n"


def _validate(nb: Mapping) -> None:
    try:
        nbformat.validate(nb)
    except nbformat.ValidationError as e:
        raise ValueError(f"generated an invalid notebook: {e}") from None


_COMPACT = json.JSONEncoder(sort_keys=True, ensure_ascii=False, allow_nan=False)
"""One line of JSON, by the json module's C encoder: several times faster than indenting."""


class _Encoded(str):
    """JSON text that :func:`_indented` writes as it is: a cell or a question's record already
    encoded for its place in a notebook (:func:`notebook_texts`)."""


_CELL_NEWLINE = "\n  "
"""Where a cell's nested lines start in a notebook (in the list ``cells``, itself in the
notebook: two levels deep)."""


def _cell_text(kind: str, cell_id: str, source: str, editable: bool = False,
               question: int | None = None, written: str | None = None) -> _Encoded:
    """:func:`_cell` of these arguments, encoded as it stands in a notebook's cells: its
    source's lines encoded into the rest, which is encoded once per process
    (:func:`_cell_frame`)."""
    lines = source.splitlines(keepends=True)
    if not lines:  # no line to put between the frame's parts (no generated cell is empty)
        return _Encoded(_indented(_cell(kind, cell_id, source, editable, question, written),
                                  _CELL_NEWLINE, {}))
    head, between, tail = _cell_frame(kind, cell_id, editable, question, written)
    return _Encoded(head + between.join(map(_encode_string, lines)) + tail)


_LINES = ("\x01\n", "\x02")
"""A source of two lines, to find where a cell's lines go in its text (:func:`_cell_frame`);
any two would do, these are short."""


@lru_cache(maxsize=1024, typed=True)
def _cell_frame(kind: str, cell_id: str, editable: bool, question: int | None,
                written: str | None) -> tuple[str, str, str]:
    """The text of a cell (:func:`_cell`, as :func:`_cell_text` places it) before its
    source's first line, between two lines, and after the last: that of the cell with the
    source :data:`_LINES`, cut around them. ``source`` is the cell's last key in sorted order,
    so they are the last two strings of that text."""
    cell = _cell(kind, cell_id, "".join(_LINES), editable, question, written)
    if max(cell) != "source":  # the premise above; never seen unless _cell changes
        raise AssertionError(f"a cell's last key is {max(cell)!r}, not 'source'")
    first, second = map(_encode_string, _LINES)
    text, tail = _indented(cell, _CELL_NEWLINE, {}).rsplit(second, 1)
    head, between = text.rsplit(first, 1)
    return head, between, tail


_QUESTION_NEWLINE = "\n    "
"""Where a question's record's nested lines start in a notebook (``metadata``, ``eulertop``,
``questions``: four levels deep)."""


def _question_parts(record: dict) -> tuple[dict, tuple[tuple[str, str], ...]]:
    """A question's record (:func:`_notebooks`) as it is, and the parts of its answer lines
    (:func:`_answer_line_parts`; a written part has none)."""
    return record, tuple(_answer_line_parts(spec) for spec in record["answers"]
                         if spec["kind"] != WRITTEN)


def _encoded_question(record: dict) -> tuple[_Encoded, tuple[tuple[str, str], ...]]:
    """:func:`_question_parts`, the record encoded as it stands in a notebook's metadata; both
    kept by the record's content, its one line of JSON (:func:`_indented_of`)."""
    compact = _COMPACT.encode(record)
    return _indented_of(compact, _QUESTION_NEWLINE), _line_parts_of(compact)


@lru_cache(maxsize=1024)
def _line_parts_of(compact: str) -> tuple[tuple[str, str], ...]:
    """The answer lines' parts of the question record written as ``compact``
    (:func:`_encoded_question`), kept by it as :func:`_indented_of` is."""
    return _question_parts(json.loads(compact))[1]


@lru_cache(maxsize=1024)
def _indented_of(compact: str, newline: str) -> _Encoded:
    """The value written as ``compact`` (one line of JSON, :data:`_COMPACT`), indented.

    A function of the one line alone (a value of plain JSON with string keys, as a question's
    record is, reads back the same to the last bit), so its result is kept by it: cheap to
    make, the line is the content's key."""
    return _Encoded(_indented(json.loads(compact), newline, {}))


_encode_string = json.encoder.encode_basestring  # the C encoder's, as ensure_ascii=False uses


def indented_json(value: Any, memo: dict | None = None) -> str:
    """``json.dumps(value, indent=1, sort_keys=True, ensure_ascii=False, allow_nan=False)``.

    For plain JSON (dicts with string keys, lists, strings, numbers, booleans, None) it writes
    the same bytes faster than the json module, whose ``indent`` layout is pure Python; any other
    value (a tuple, a non-string key) is handed to ``json.dumps`` itself.

    ``memo`` keeps the text of each list and dict by identity and depth: values encoded with one
    memo must all stay alive and unchanged while it is in use (it serves the parts two notebooks
    share).

    Examples
    --------
    >>> print(indented_json({"b": [1, "x"], "a": {}}))
    {
     "a": {},
     "b": [
      1,
      "x"
     ]
    }
    """
    try:
        return _indented(value, "\n", {} if memo is None else memo)
    except _NotPlain:
        return json.dumps(value, indent=1, sort_keys=True, ensure_ascii=False, allow_nan=False)


class _NotPlain(Exception):
    """A value :func:`_indented` leaves to ``json.dumps``."""


def _indented(value: Any, newline: str, memo: dict) -> str:
    """``value`` as indented JSON, its nested lines starting with ``newline`` plus one space."""
    kind = type(value)
    if kind is str:
        return _encode_string(value)
    if kind is _Encoded:
        return value
    if kind is dict or kind is list:
        known = (id(value), len(newline))
        text = memo.get(known)
        if text is None:
            text = memo[known] = _container(value, newline, memo)
        return text
    if value is None:
        return "null"
    if value is True:
        return "true"
    if value is False:
        return "false"
    if kind is int:
        return int.__repr__(value)
    if kind is float and math.isfinite(value):
        return float.__repr__(value)
    raise _NotPlain


def _container(value: dict | list, newline: str, memo: dict) -> str:
    inner = newline + " "
    if type(value) is dict:
        if not value:
            return "{}"
        parts = []
        for key in sorted(value):
            if type(key) is not str:
                raise _NotPlain
            item = value[key]
            text = _encode_string(item) if type(item) is str else _indented(item, inner, memo)
            parts.append(f"{_encode_string(key)}: {text}")
        return "{" + inner + ("," + inner).join(parts) + newline + "}"
    if not value:
        return "[]"
    items = [_encode_string(v) if type(v) is str else _indented(v, inner, memo) for v in value]
    return "[" + inner + ("," + inner).join(items) + newline + "]"
