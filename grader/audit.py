"""The audit trail of a class's grades: ``HW/graded/audit.jsonl`` (issue 26).

Append-only, one JSON line per event — a student graded, a grading run, a rescore, a key
change, an override added or removed: when (UTC), who (the operating system's user), what
(``event``; the changes: student, answer, points before → after) and why. Lines are only ever
appended (``O_APPEND``, one ``write`` for all the lines of one change), never rewritten, so an
interrupted run leaves the earlier ones whole; each change writes its lines as part of its
transaction (:mod:`grader.transaction`). The file is its owner's alone (0600).

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import json
import os
import pwd
from collections.abc import Iterable, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from grader.plain_text import storable

AUDIT = "audit.jsonl"


def who() -> str:
    """The operating system's name of the user running this (``uid N`` where it has none)."""
    uid = os.geteuid()
    try:
        return pwd.getpwuid(uid).pw_name
    except KeyError:
        return f"uid {uid}"


def trail_line(event: str, changes: Iterable[Mapping[str, Any]] = (), why: str = "",
               **details: Any) -> dict:
    """One line of the trail: when (UTC, now), who, ``event``, ``why``, ``details`` and the
    ``changes`` (student, answer, before, after, why)."""
    return {"when": datetime.now(UTC).isoformat(timespec="seconds"), "who": who(),
            "event": event, "why": why, **details, "changes": [dict(c) for c in changes]}


def append_lines(out: Path, lines: Iterable[Mapping[str, Any]]) -> None:
    """Append ``lines`` to ``out``'s trail in one ``write`` (a kill leaves all of them or none);
    the file readable by its owner only, as the gradebook is."""
    data = "".join(storable(json.dumps(line, ensure_ascii=False, allow_nan=False)) + "\n"
                   for line in lines)
    fd = os.open(Path(out) / AUDIT, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
    try:
        os.fchmod(fd, 0o600)  # a trail written before this rule was 0644
        os.write(fd, data.encode("utf-8"))
    finally:
        os.close(fd)


def record_event(out: Path, event: str, changes: Iterable[Mapping[str, Any]] = (),
                 why: str = "", **details: Any) -> dict:
    """Append one line to ``out``'s trail at once (outside a transaction); the line's data."""
    line = trail_line(event, changes, why, **details)
    append_lines(out, [line])
    return line


def trail_has(out: Path, transaction: str, tail_bytes: int = 1 << 20) -> bool:
    """Whether a line of transaction ``transaction`` is among the last ``tail_bytes`` of
    ``out``'s trail (where a transaction being finished put its lines, if they got there)."""
    path = Path(out) / AUDIT
    try:
        with open(path, "rb") as f:
            f.seek(max(0, f.seek(0, os.SEEK_END) - tail_bytes))
            tail = f.read()
    except FileNotFoundError:
        return False
    return f'"transaction": "{transaction}"'.encode() in tail


def read_trail(out: Path) -> list[dict]:
    """Every line of ``out``'s trail (none when there is no file)."""
    path = Path(out) / AUDIT
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line]
