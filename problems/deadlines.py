"""An assignment's deadline and late policy (issue 32): the spec's ``[late]`` table, as
``assignment.json`` records it, and what it makes of the time one submission came in.

::

    [late]
    due = 2026-03-14T23:59:00-05:00          # an offset is required
    grace = "15m"
    penalty = { percent = 10, per = "day", max_percent = 50 }   # each started day counts
    close = 2026-03-21T23:59:00-05:00        # after it: no credit
    after_close = "zero"                     # or "practice": graded and shown, no credit
    of = "earned"                            # the penalty's base: points earned, or "total"
    zone = "America/Chicago"                 # reads times an LMS writes without an offset
    [late.extensions]
    ada = { due = 2026-03-16T23:59:00-05:00, reason = "medical" }

Rules (:meth:`LatePolicy.lateness`): a submission is late by how long after its student's due
time it came (an extension replaces the due time; a student's close is never before their own
due time). At or before the due time, or within the grace after it, there is no penalty; past
the grace, each started period (a day is 24 hours of elapsed time, on a day the clocks change
as on any other; an hour 60 minutes) counted from the due time costs ``percent`` of the base,
up to ``max_percent``. After the close the submission earns nothing (``zero``), or is graded
and shown to the student as practice, earning nothing. Times are compared as instants: their
time zones only say how they were written.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime, timedelta, tzinfo
from typing import Any

PERIODS = {"day": timedelta(days=1), "hour": timedelta(hours=1)}
AFTER_CLOSE = ("zero", "practice")
BASES = ("earned", "total")
_KEYS = ("due", "grace", "penalty", "close", "after_close", "of", "zone", "extensions")
_PENALTY_KEYS = ("percent", "per", "max_percent")
_DURATION = re.compile(r"(?:(\d+(?:\.\d+)?)\s*([dhms]))", re.I)
_UNITS = {"d": 86400.0, "h": 3600.0, "m": 60.0, "s": 1.0}


class PolicyError(ValueError):
    """A late policy, a time or a duration that cannot be read; the message names it."""


def duration(text: Any, what: str = "grace") -> timedelta:
    """``"15m"``, ``"1h30m"``, ``"2d"``, ``"45s"`` (or a number of seconds) as a timedelta.

    Examples
    --------
    >>> duration("1h30m"), duration("15m"), duration(0)
    (datetime.timedelta(seconds=5400), datetime.timedelta(seconds=900), datetime.timedelta(0))
    """
    if isinstance(text, int | float) and not isinstance(text, bool):
        if text < 0:
            raise PolicyError(f"{what}: {text!r} is negative")
        return timedelta(seconds=float(text))
    text = str(text).strip()
    parts = _DURATION.findall(text)
    if not parts or _DURATION.sub("", text).strip():
        raise PolicyError(f"{what}: {text!r} is not a duration (say 15m, 2h, 1d, 1h30m)")
    return timedelta(seconds=sum(float(n) * _UNITS[u.lower()] for n, u in parts))


def instant(value: Any, what: str, zone: tzinfo | None = None) -> datetime:
    """``value`` (a TOML or ISO 8601 date-time) as an aware datetime; one without an offset is
    read in ``zone`` where given, else refused (naming ``what``)."""
    if isinstance(value, datetime):
        moment = value
    else:
        try:
            moment = datetime.fromisoformat(str(value).strip().replace("Z", "+00:00"))
        except ValueError:
            raise PolicyError(f"{what}: {value!r} is not a date and time (ISO 8601, e.g. "
                              "2026-03-14T23:59:00-05:00)") from None
    if moment.tzinfo is None or moment.utcoffset() is None:
        if zone is None:
            raise PolicyError(f"{what}: {value!s} has no time zone offset (write it as "
                              "2026-03-14T23:59:00-05:00, or set the policy's zone)")
        moment = moment.replace(tzinfo=zone)
        if moment.replace(fold=0).utcoffset() != moment.replace(fold=1).utcoffset():
            raise PolicyError(f"{what}: {value!s} is ambiguous in {zone} (the clocks changed "
                              "then: that local time came twice, or not at all); give it with "
                              "its offset")
    return moment


def zone_named(name: str | None) -> tzinfo | None:
    """The IANA time zone ``name`` (None stays None); PolicyError for an unknown one."""
    if name is None:
        return None
    from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

    try:
        return ZoneInfo(str(name))
    except (ZoneInfoNotFoundError, ValueError):
        raise PolicyError(f"zone: {name!r} is not a time zone name (say America/Chicago)") \
            from None


def _utc(moment: datetime) -> datetime:
    return moment.astimezone(UTC)


@dataclass(frozen=True)
class Extension:
    """A student's own due time, and why."""

    due: datetime
    reason: str


@dataclass(frozen=True)
class Lateness:
    """What the policy makes of one submission's time."""

    due: datetime  # the due time that applied to the student
    extension: str  # its reason, where it was an extension ("" otherwise)
    submitted: datetime
    late_by: timedelta  # zero when on time
    periods: int  # started periods counted (0 on time or within the grace)
    percent: float  # of the base, capped
    closed: bool  # came after the student's close
    practice: bool  # closed, and the policy shows such work as practice

    @property
    def late(self) -> bool:
        return self.late_by > timedelta(0)


@dataclass(frozen=True)
class LatePolicy:
    """An assignment's late policy (module docstring)."""

    due: datetime
    grace: timedelta = timedelta(0)
    percent: float = 0.0
    per: str = "day"
    max_percent: float = 100.0
    close: datetime | None = None
    after_close: str = "zero"
    of: str = "earned"
    zone: str | None = None
    extensions: Mapping[str, Extension] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.per not in PERIODS:
            raise PolicyError(f"penalty.per: {self.per!r} is not one of {', '.join(PERIODS)}")
        if not (0 <= self.percent <= 100 and 0 <= self.max_percent <= 100):
            raise PolicyError("penalty: percent and max_percent must be from 0 to 100")
        if self.after_close not in AFTER_CLOSE:
            raise PolicyError(f"after_close: {self.after_close!r} is not one of "
                              f"{', '.join(AFTER_CLOSE)}")
        if self.of not in BASES:
            raise PolicyError(f"of: {self.of!r} is not one of {', '.join(BASES)}")
        if self.close is not None and _utc(self.close) < _utc(self.due):
            raise PolicyError(f"close: {self.close.isoformat()} is before the due time "
                              f"{self.due.isoformat()}")
        for sid, ext in self.extensions.items():
            if _utc(ext.due) < _utc(self.due):
                raise PolicyError(f"extensions.{sid}: {ext.due.isoformat()} is before the due "
                                  f"time {self.due.isoformat()}; an extension moves the "
                                  "deadline later")

    def due_for(self, student: str) -> tuple[datetime, str]:
        """The due time of ``student``, and the extension's reason (``""``: none)."""
        ext = self.extensions.get(student)
        return (self.due, "") if ext is None else (ext.due, ext.reason)

    def lateness(self, student: str, submitted: datetime) -> Lateness:
        """What the policy makes of ``student``'s submission at ``submitted`` (module
        docstring)."""
        due, reason = self.due_for(student)
        # as instants: Python subtracts and compares two times of one tzinfo by their clock
        # readings, which is an hour off across a change of the clocks
        late_by = max(_utc(submitted) - _utc(due), timedelta(0))
        periods = 0
        if late_by > self.grace:
            periods = math.ceil(late_by / PERIODS[self.per])
        percent = min(self.max_percent, self.percent * periods)
        close = None if self.close is None else max(_utc(self.close), _utc(due))
        closed = close is not None and _utc(submitted) > close
        return Lateness(due, reason, submitted, late_by, periods, percent, closed,
                        closed and self.after_close == "practice")

    def with_extension(self, student: str, extension: Extension | None) -> LatePolicy:
        """This policy with ``student``'s extension set (None: taken back)."""
        extensions = dict(self.extensions)
        if extension is None:
            extensions.pop(student, None)
        else:
            extensions[student] = extension
        return replace(self, extensions=extensions)

    def record(self) -> dict:
        """As ``assignment.json`` records it (:func:`policy_from_record` reads it back)."""
        out = {"due": self.due.isoformat(), "grace_seconds": self.grace.total_seconds(),
               "percent": self.percent, "per": self.per, "max_percent": self.max_percent,
               "after_close": self.after_close, "of": self.of}
        if self.close is not None:
            out["close"] = self.close.isoformat()
        if self.zone is not None:
            out["zone"] = self.zone
        if self.extensions:
            out["extensions"] = {sid: {"due": e.due.isoformat(), "reason": e.reason}
                                 for sid, e in sorted(self.extensions.items())}
        return out


def policy_from_record(record: Mapping[str, Any]) -> LatePolicy:
    """A policy as :meth:`LatePolicy.record` wrote it."""
    return LatePolicy(
        due=instant(record["due"], "due"),
        grace=timedelta(seconds=float(record.get("grace_seconds", 0))),
        percent=float(record.get("percent", 0)), per=record.get("per", "day"),
        max_percent=float(record.get("max_percent", 100)),
        close=None if record.get("close") is None else instant(record["close"], "close"),
        after_close=record.get("after_close", "zero"), of=record.get("of", "earned"),
        zone=record.get("zone"),
        extensions={sid: Extension(instant(e["due"], f"extensions.{sid}.due"),
                                   str(e.get("reason", "")))
                    for sid, e in record.get("extensions", {}).items()})


def read_policy(table: Any) -> LatePolicy:
    """The spec's ``[late]`` table (module docstring) as a policy; PolicyError naming the key
    at fault (``penalty.per: …``)."""
    if not isinstance(table, Mapping):
        raise PolicyError("must be a table ([late])")
    unknown = sorted(set(table) - set(_KEYS))
    if unknown:
        raise PolicyError(f"unknown key {unknown[0]!r} (known: {', '.join(_KEYS)})")
    if "due" not in table:
        raise PolicyError("due: missing (the due date and time, with its offset)")
    zone = table.get("zone")
    zone_named(zone)
    penalty = table.get("penalty", {})
    if not isinstance(penalty, Mapping) or set(penalty) - set(_PENALTY_KEYS):
        raise PolicyError(f"penalty: a table of {', '.join(_PENALTY_KEYS)}")
    return LatePolicy(
        due=instant(table["due"], "due"), grace=duration(table.get("grace", 0)),
        percent=_percent(penalty.get("percent", 0), "penalty.percent"),
        per=str(penalty.get("per", "day")),
        max_percent=_percent(penalty.get("max_percent", 100), "penalty.max_percent"),
        close=None if "close" not in table else instant(table["close"], "close"),
        after_close=str(table.get("after_close", "zero")), of=str(table.get("of", "earned")),
        zone=zone, extensions=_extensions(table.get("extensions", {})))


def _percent(value: Any, what: str) -> float:
    if isinstance(value, str):
        value = value.strip().removesuffix("%")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise PolicyError(f"{what}: {value!r} is not a percentage") from None
    if not 0 <= number <= 100:
        raise PolicyError(f"{what}: {number:g} is not from 0 to 100")
    return number


def _extensions(table: Any) -> dict[str, Extension]:
    if not isinstance(table, Mapping):
        raise PolicyError("extensions: a table of student = { due = …, reason = … }")
    found = {}
    for sid, entry in table.items():
        if not isinstance(entry, Mapping) or "due" not in entry or set(entry) - {"due", "reason"}:
            raise PolicyError(f"extensions.{sid}: give {{ due = …, reason = \"…\" }}")
        found[str(sid)] = Extension(instant(entry["due"], f"extensions.{sid}.due"),
                                    str(entry.get("reason", "")))
    return found


def penalty_rate(text: str) -> tuple[float, str]:
    """``"10%/day"`` → ``(10.0, "day")`` (``eulertop late set --penalty``)."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*%?\s*/\s*(day|hour)\s*", str(text))
    if not m:
        raise PolicyError(f"--penalty {text!r}: say 10%/day or 5%/hour")
    return _percent(m[1], "--penalty"), m[2]


def spoken(span: timedelta) -> str:
    """A duration for people: ``2 d 3 h 05 min``, ``45 s``.

    Examples
    --------
    >>> spoken(timedelta(days=1, hours=2, minutes=5)), spoken(timedelta(seconds=45))
    ('1 d 2 h 05 min', '45 s')
    """
    seconds = int(span.total_seconds())
    days, rest = divmod(seconds, 86400)
    hours, rest = divmod(rest, 3600)
    minutes, seconds = divmod(rest, 60)
    if not (days or hours or minutes):
        return f"{seconds} s"
    parts = [f"{days} d"] if days else []
    if days or hours:
        parts.append(f"{hours} h")
    parts.append(f"{minutes:02d} min" if parts else f"{minutes} min")
    return " ".join(parts)
