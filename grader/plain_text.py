"""Student-controlled text made safe to show: no control characters (issue 11).

A cell's source, an exception message or a file name can hold terminal escape sequences
(``ESC [ 2 J`` clears an instructor's screen; ``ESC ] 8`` makes links), carriage returns that
overwrite a line, or bidirectional overrides that reorder what is read. Before any such text
reaches a terminal, a CSV cell or an HTML page, every control character — C0 and C1 (but tab
and newline), DEL, and the Unicode bidirectional embeddings, overrides and isolates — is shown
as its escape (``\\x1b``, ``\\u202e``) instead of acting.

A Python string can also hold what no file can: a *lone surrogate* (``\\ud800``), from an
answer's JSON escape or a file name's undecodable byte (``b"\\xff"`` becomes ``"\\udcff"``).
UTF-8 cannot encode one, so writing it stops the writer; :func:`printable` shows surrogates as
their escapes too, and :func:`storable` shows only them (issue 23).

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import json
import re
from typing import Any

_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069"
                      "\ud800-\udfff]")
SURROGATE = re.compile("[\ud800-\udfff]")
"""A lone surrogate: what no UTF-8 file can hold."""


def _escape(match: re.Match) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def printable(text: object, newlines: bool = True) -> str:
    """``str(text)`` with every control character written as its escape (module docstring);
    with ``newlines=False`` newlines (and tabs) too.

    Examples
    --------
    >>> printable("ok\\x1b[2J done\\r")
    'ok\\\\x1b[2J done\\\\x0d'
    >>> printable("a\\nb", newlines=False)
    'a\\\\x0ab'
    """
    text = str(text)
    if newlines:
        return _CONTROL.sub(_escape, text)
    return _CONTROL.sub(_escape, text.replace("\t", "\\x09").replace("\n", "\\x0a"))


def storable(text: str) -> str:
    """``text`` with each lone surrogate written as its escape, so that UTF-8 can hold it;
    every other character kept as it is.

    Examples
    --------
    >>> storable("x\\ud800 \\n é")
    'x\\\\ud800 \\n é'
    """
    return SURROGATE.sub(_escape, text)


def value_text(value: Any) -> str:
    """A plain JSON value in a line of text: numbers to 6 significant figures, lists of them in
    brackets, strings quoted as JSON.

    Examples
    --------
    >>> value_text([221.123456, True, "loops", None])
    '[221.123, True, "loops", None]'
    """
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(value_text(v) for v in value) + "]"
    return json.dumps(value, ensure_ascii=False) if isinstance(value, str) else str(value)
