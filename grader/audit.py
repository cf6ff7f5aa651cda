"""The audit trail of a class's grades: ``HW/graded/audit.jsonl`` (issue 26).

Append-only, one JSON line per event — a grading run, a rescore, a key change, an override
added or removed: when (UTC), who (the operating system's user), what (``event``; the changes:
student, answer, points before → after) and why. Lines are only ever appended (``O_APPEND``,
one ``write`` each), never rewritten, so an interrupted run leaves the earlier ones whole.

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


def record_event(out: Path, event: str, changes: Iterable[Mapping[str, Any]] = (),
                 why: str = "", **details: Any) -> dict:
    """Append one line to ``out``'s trail; the line's data."""
    line = {"when": datetime.now(UTC).isoformat(timespec="seconds"), "who": who(),
            "event": event, "why": why, **details, "changes": [dict(c) for c in changes]}
    data = (storable(json.dumps(line, ensure_ascii=False, allow_nan=False)) + "\n")
    fd = os.open(Path(out) / AUDIT, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        os.write(fd, data.encode("utf-8"))
    finally:
        os.close(fd)
    return line


def read_trail(out: Path) -> list[dict]:
    """Every line of ``out``'s trail (none when there is no file)."""
    path = Path(out) / AUDIT
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line]
