"""An assignment's late policy applied to its records (issue 32; the policy itself:
:mod:`problems.deadlines`).

When each submission came in is recorded in its record (``StudentResult.submitted``): from the
LMS download where it says so (Gradescope's ``:created_at:``, Blackboard's attempt time), else
from ``eulertop grade --times FILE`` (CSV ``id,submitted_at``, ISO 8601), else unknown (not
late). The policy is applied after follow-through credit and the overrides of answers, before
an override of the total (:func:`grader.overrides.apply_overrides`): the penalty takes a
percentage of the points earned (or of the total, ``of = "total"``), never more than was
earned; after the close, everything earned. An override of the total stands after the
penalty.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import csv
from collections.abc import Mapping
from datetime import datetime
from pathlib import Path
from typing import Any

from grader.assignment import UsageError
from problems.deadlines import LatePolicy, PolicyError, instant, policy_from_record, zone_named

TIMES_COLUMNS = ("id", "submitted_at")


def policy_of(manifest: Mapping[str, Any]) -> LatePolicy | None:
    """The policy ``assignment.json`` records (None: the assignment has none)."""
    record = manifest.get("late")
    if record is None:
        return None
    try:
        return policy_from_record(record)
    except (PolicyError, KeyError, TypeError, ValueError) as e:
        raise UsageError(f"assignment.json: its late policy cannot be read: {e}") from None


def late_entry(policy: LatePolicy, student: str, submitted: datetime, earned: float,
               maximum: float) -> tuple[dict, float]:
    """What ``policy`` makes of ``student``'s submission at ``submitted`` that earned
    ``earned`` of ``maximum`` points: the record's ``late`` entry, and the points it takes."""
    lateness = policy.lateness(student, submitted)
    if lateness.closed:
        taken = earned
    else:
        base = earned if policy.of == "earned" else maximum
        taken = min(earned, base * lateness.percent / 100.0)
    entry = {"due": lateness.due.isoformat(), "late_by_seconds": lateness.late_by.total_seconds(),
             "periods": lateness.periods, "per": policy.per, "percent": lateness.percent,
             "of": policy.of, "points": taken}
    if lateness.extension:
        entry["extension"] = lateness.extension
    if lateness.closed:
        entry["closed"] = "practice" if lateness.practice else "zero"
    return entry, taken


def submitted_time(entry: Mapping[str, Any]) -> datetime | None:
    """A record's ``submitted`` entry's time (None: unknown)."""
    at = entry.get("at")
    return None if not at else instant(at, "submitted")


def read_times(path: Path, ids: set[str], zone: str | None) -> dict[str, dict]:
    """``--times FILE``: ``{id: {"at", "source"}}`` for the roster ``ids``; :class:`UsageError`
    naming the row of a time that cannot be read (without an offset and no policy ``zone``:
    ambiguous) or of an id twice."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = list(csv.DictReader(f))
            header = set(rows[0]) if rows else set()
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise UsageError(f"--times {path}: cannot read it: {e}") from None
    if rows and not set(TIMES_COLUMNS) <= header:
        raise UsageError(f"--times {path}: expected the columns {', '.join(TIMES_COLUMNS)}")
    found: dict[str, dict] = {}
    for n, row in enumerate(rows, start=2):
        sid = (row.get("id") or "").strip()
        where = f"--times {path}, row {n} ({sid or 'no id'})"
        if sid not in ids:
            raise UsageError(f"{where}: no such student in the roster")
        if sid in found:
            raise UsageError(f"{where}: a second time for {sid}")
        found[sid] = {"at": _read(row.get("submitted_at"), where, zone),
                      "source": f"row {n} of {Path(path).name}"}
    return found


def _read(text: Any, where: str, zone: str | None) -> str:
    """``text`` as an ISO 8601 time with its offset; UsageError naming ``where``."""
    try:
        return instant(text, "submitted_at", zone_named(zone)).isoformat()
    except PolicyError as e:
        raise UsageError(f"{where}: {e}") from None


def download_time(text: str, source: str, where: str, zone: str | None) -> dict:
    """A time an LMS download gives (as it wrote it), for the record; UsageError naming
    ``where`` when it cannot be read or carries no offset and there is no policy ``zone``."""
    return {"at": _read(text, where, zone), "source": source}
