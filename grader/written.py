"""Written answers read from a submitted notebook's file, and shown as safe HTML (issue 31).

A written part (:mod:`problems.written`) is answered in a Markdown cell the generator marked
``metadata["eulertop"]["written"] = "q5_veff_minimum"``. The grader reads it from the
notebook's bytes in its own process — never from the kernel: no code of the student's runs for
it — and parses them as it parses every submission (:func:`grader.notebook_load.notebook_json`,
within its limits).

What is read (:func:`written_answers`)
    The marked cell's text, then the text of each Markdown cell the student added right after
    it (cells without eulertop metadata: a derivation spread over several cells), up to the
    next cell the generator wrote or a code cell, joined by a blank line. A cell still holding
    :data:`problems.written.PLACEHOLDER` counts as empty. Kept per answer:

    * the text, up to :data:`MAX_TEXT_CHARS` characters (the rest cut, and a note says so);
    * the cells' attachments (images pasted into the cell), of the types :data:`KEPT_TYPES`,
      up to :data:`MAX_ATTACHMENT_BYTES` decoded bytes in all and :data:`MAX_ATTACHMENTS` of
      them; any other is *recorded as such* in ``dropped`` (its name, type, size and why), not
      kept.

    The record's ``submitted`` value is ``{"text", "attachments": {name: {"type", "data"}},
    "dropped": [{"name", "type", "bytes", "why"}], "notes": [...]}`` (``data`` base64, as the
    notebook holds it); a written part with no cell, or an empty one, is None (``missing``).

Shown by :func:`grader.statement_html.written_html` (links and images off; kept attachments
as ``data:`` images).

Shipped in the student package too (``student/setup.py``): it imports nothing of the key.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import re
from collections.abc import Mapping, Sequence
from typing import Any

from problems.answers import MAX_WRITTEN_CHARS, PLACEHOLDER

MAX_TEXT_CHARS = MAX_WRITTEN_CHARS
"""Characters of one written answer's text kept (20,000: some ten pages of derivation)."""

MAX_ATTACHMENT_BYTES = 1024 * 1024
"""Decoded bytes of attachments one written answer keeps in all (1 MiB: a few photos of
handwritten work, at a phone's usual JPEG quality and some 1500 pixels across)."""

MAX_ATTACHMENTS = 8
"""Attachments one written answer keeps at most."""

KEPT_TYPES = ("image/png", "image/jpeg", "image/gif")
"""Attachment types kept: raster images, which a browser shows and never runs (an SVG can
hold script, so it is not among them)."""



def written_answers(data: bytes, variables: Sequence[str]) -> dict[str, dict | None]:
    """Each written answer of ``variables`` read from a notebook file's bytes (module
    docstring): ``{variable: value or None}``; all None when the bytes are no notebook.

    Examples
    --------
    >>> import json
    >>> cell = {"cell_type": "markdown", "source": "$x = 1$",
    ...         "metadata": {"eulertop": {"written": "q1_w"}}}
    >>> nb = json.dumps({"nbformat": 4, "cells": [cell]}).encode()
    >>> written_answers(nb, ["q1_w", "q2_v"])["q1_w"]["text"], written_answers(nb, ["q2_v"])
    ('$x = 1$', {'q2_v': None})
    """
    from grader.notebook_load import SubmissionError, notebook_json

    try:
        document = notebook_json(data)
    except SubmissionError:
        return dict.fromkeys(variables)
    cells = document.get("cells") if isinstance(document, dict) else None
    cells = [c for c in cells if isinstance(c, dict)] if isinstance(cells, list) else []
    return {v: _answer(_answer_cells(cells, v)) for v in variables}


def _marker(cell: Mapping) -> Mapping | None:
    metadata = cell.get("metadata")
    eulertop = metadata.get("eulertop") if isinstance(metadata, Mapping) else None
    return eulertop if isinstance(eulertop, Mapping) else None


def _answer_cells(cells: Sequence[Mapping], variable: str) -> list[Mapping]:
    """The cell marked for ``variable`` and the Markdown cells the student added after it."""
    for i, cell in enumerate(cells):
        marker = _marker(cell)
        if marker is None or marker.get("written") != variable:
            continue
        found = [cell]
        for after in cells[i + 1:]:
            if _marker(after) is not None or after.get("cell_type") != "markdown":
                break
            found.append(after)
        return found
    return []


def _source(cell: Mapping) -> str:
    source = cell.get("source", "")
    if isinstance(source, list):
        source = "".join(s for s in source if isinstance(s, str))
    text = source if isinstance(source, str) else ""
    return "" if text.strip() == PLACEHOLDER else text


def _answer(cells: Sequence[Mapping]) -> dict | None:
    """One answer's recorded value from its cells, or None when nothing is written."""
    text = "\n\n".join(t for t in (_source(c) for c in cells) if t.strip())
    notes = []
    if len(text) > MAX_TEXT_CHARS:
        notes.append(f"cut at {MAX_TEXT_CHARS:,} characters (it had {len(text):,})")
        text = text[:MAX_TEXT_CHARS]
    kept, dropped = _attachments(cells)
    if not text.strip() and not kept and not dropped:
        return None
    return {"text": text, "attachments": kept, "dropped": dropped, "notes": notes}


def _attachments(cells: Sequence[Mapping]) -> tuple[dict, list]:
    """The cells' attachments kept (within the limits), and those dropped with why."""
    kept: dict[str, dict] = {}
    dropped: list[dict] = []
    room = MAX_ATTACHMENT_BYTES
    for name, bundle in _bundles(cells):
        kind, data, size = _image(bundle)
        why = _refusal(name, kind, size, kept, room)
        if why:
            dropped.append({"name": name, "type": kind, "bytes": size, "why": why})
            continue
        kept[name] = {"type": kind, "data": data}
        room -= size
    return kept, dropped


def _bundles(cells: Sequence[Mapping]) -> list[tuple[str, Mapping]]:
    found = []
    for cell in cells:
        attachments = cell.get("attachments")
        if isinstance(attachments, Mapping):
            found += [(str(name), bundle) for name, bundle in attachments.items()
                      if isinstance(bundle, Mapping)]
    return found


def _image(bundle: Mapping) -> tuple[str, str, int]:
    """``(type, base64 data, decoded size)`` of an attachment: its first kept type, else its
    first type (size -1: its data is not base64)."""
    types = [t for t in bundle if isinstance(t, str)]
    kind = next((t for t in types if t in KEPT_TYPES), types[0] if types else "")
    data = bundle.get(kind)
    if isinstance(data, list):
        data = "".join(d for d in data if isinstance(d, str))
    if not isinstance(data, str):
        return kind, "", -1
    data = re.sub(r"\s+", "", data)
    try:
        return kind, data, len(base64.b64decode(data, validate=True))
    except (binascii.Error, ValueError):
        return kind, data, -1


def _refusal(name: str, kind: str, size: int, kept: Mapping, room: int) -> str:
    """Why an attachment is not kept, or ``""``."""
    if kind not in KEPT_TYPES:
        return f"not kept: of type {kind or 'unknown'}; only PNG, JPEG and GIF images are"
    if size < 0:
        return "not kept: its data is not base64"
    if name in kept:
        return "not kept: a second attachment of this name"
    if len(kept) >= MAX_ATTACHMENTS:
        return f"not kept: more than {MAX_ATTACHMENTS} attachments"
    if size > room:
        return (f"not kept: over the limit of {MAX_ATTACHMENT_BYTES // 1024} KiB of "
                "attachments per answer")
    return ""


def is_written(value: Any) -> bool:
    """Whether a recorded value is a written answer's (:func:`written_answers`' form)."""
    return isinstance(value, Mapping) and isinstance(value.get("text"), str) \
        and "attachments" in value


def written_text(value: Any) -> str:
    """The text of a recorded written answer (``""`` for none)."""
    if isinstance(value, Mapping):
        value = value.get("text")
    return value if isinstance(value, str) else ""


def text_sha256(value: Any) -> str:
    """SHA-256 (hex) of a recorded written answer's text and kept attachments: what a review
    is of (:mod:`grader.reviews`), so that a review of other text is never applied."""
    digest = hashlib.sha256(written_text(value).encode("utf-8", "surrogatepass"))
    attachments = value.get("attachments") if isinstance(value, Mapping) else None
    for name, a in sorted((attachments or {}).items()):
        digest.update(f"\0{name}\0{a.get('data', '')}".encode("utf-8", "surrogatepass"))
    return digest.hexdigest()
