"""The late policy at its edges (issue 32): the deadline itself, the grace, each started period,
the cap, the close, extensions, time zones and the days the clocks change.

Expected values are worked out by hand from the rules in :mod:`problems.deadlines`' docstring
(elapsed time from the due instant; each started period past the grace counts).
"""

from __future__ import annotations

from datetime import datetime, timedelta, timezone
from zoneinfo import ZoneInfo

import pytest

from problems.deadlines import (
    Extension,
    LatePolicy,
    PolicyError,
    duration,
    instant,
    penalty_rate,
    policy_from_record,
    read_policy,
)

CDT = timezone(timedelta(hours=-5))
DUE = datetime(2026, 3, 14, 23, 59, tzinfo=CDT)
POLICY = LatePolicy(due=DUE, grace=timedelta(minutes=15), percent=10, per="day",
                    max_percent=50, close=DUE + timedelta(days=7))


@pytest.mark.parametrize(("after", "periods", "percent"), [
    (timedelta(0), 0, 0),                                  # exactly at the deadline
    (-timedelta(hours=3), 0, 0),                           # early
    (timedelta(seconds=1), 0, 0),                          # inside the grace
    (timedelta(minutes=15), 0, 0),                         # the grace's last instant
    (timedelta(minutes=15, seconds=1), 1, 10),             # past it: the first day started
    (timedelta(days=1), 1, 10),                            # a whole day is one day
    (timedelta(days=1, seconds=1), 2, 20),                 # and a second has begun
    (timedelta(days=4, hours=23), 5, 50),                  # at the cap
    (timedelta(days=6, hours=23), 7, 50),                  # capped
])
def test_each_started_day_counts_past_the_grace(after, periods, percent):
    late = POLICY.lateness("ada", DUE + after)
    assert late.periods == periods and late.percent == percent
    assert late.late_by == max(after, timedelta(0))
    assert not late.closed


def test_hours_as_the_period():
    policy = LatePolicy(due=DUE, percent=5, per="hour", max_percent=100)
    assert policy.lateness("ada", DUE + timedelta(minutes=61)).percent == 10
    assert policy.lateness("ada", DUE + timedelta(hours=30)).percent == 100


@pytest.mark.parametrize(("after_close", "practice"), [("zero", False), ("practice", True)])
def test_after_the_close(after_close, practice):
    policy = LatePolicy(due=DUE, percent=10, close=DUE + timedelta(days=2),
                        after_close=after_close)
    at_close = policy.lateness("ada", DUE + timedelta(days=2))
    assert not at_close.closed and at_close.percent == 20
    after = policy.lateness("ada", DUE + timedelta(days=2, seconds=1))
    assert after.closed and after.practice == practice


def test_an_extension_moves_the_deadline_and_the_close_with_it():
    policy = POLICY.with_extension("ada", Extension(DUE + timedelta(days=9), "medical"))
    assert policy.due_for("ada") == (DUE + timedelta(days=9), "medical")
    on_time = policy.lateness("ada", DUE + timedelta(days=8))
    assert on_time.late_by == timedelta(0) and not on_time.closed  # past everyone's close
    late = policy.lateness("ada", DUE + timedelta(days=9, hours=1))
    assert late.periods == 1 and late.extension == "medical"
    assert policy.lateness("bob", DUE + timedelta(days=8)).closed  # bob has none


def test_an_extension_before_the_due_time_is_refused():
    with pytest.raises(PolicyError, match=r"extensions.ada: .* is before the due time"):
        POLICY.with_extension("ada", Extension(DUE - timedelta(days=1), "typo"))


def test_instants_not_clock_readings():
    """The same instant written in two zones is the same time; a second after is late."""
    utc = instant("2026-03-15T04:59:00Z", "t")
    assert POLICY.lateness("ada", utc).late_by == timedelta(0)
    assert POLICY.lateness("ada", utc + timedelta(seconds=1)).late_by == timedelta(seconds=1)


def test_a_day_is_24_hours_on_the_day_the_clocks_change():
    """US daylight saving began 2026-03-08: due Saturday noon CST (-06:00), a submission
    Sunday at 13:00 CDT (-05:00) is 25 h later by the clock on the wall but 24 h later in
    elapsed time: one day. At 13:00:01, two."""
    chicago = ZoneInfo("America/Chicago")
    policy = LatePolicy(due=datetime(2026, 3, 7, 12, 0, tzinfo=chicago), percent=10)
    assert policy.due.utcoffset() == timedelta(hours=-6)
    sunday = datetime(2026, 3, 8, 13, 0, tzinfo=chicago)
    assert sunday.utcoffset() == timedelta(hours=-5)
    assert policy.lateness("ada", sunday).late_by == timedelta(hours=24)
    assert policy.lateness("ada", sunday).periods == 1
    assert policy.lateness("ada", sunday + timedelta(seconds=1)).periods == 2


def test_times_without_an_offset_need_a_zone_and_must_not_be_ambiguous():
    chicago = ZoneInfo("America/Chicago")
    with pytest.raises(PolicyError, match="has no time zone offset"):
        instant("2026-03-14T23:59:00", "due")
    assert instant("2026-03-14T23:59:00", "t", chicago).utcoffset() == timedelta(hours=-5)
    for local in ("2026-11-01T01:30:00", "2026-03-08T02:30:00"):  # twice; never
        with pytest.raises(PolicyError, match="ambiguous in America/Chicago"):
            instant(local, "t", chicago)
    with pytest.raises(PolicyError, match="not a date and time"):
        instant("next Tuesday", "t")


def test_the_spec_table_and_the_record_round_trip():
    table = {"due": DUE, "grace": "15m",
             "penalty": {"percent": 10, "per": "day", "max_percent": 50},
             "close": DUE + timedelta(days=7), "after_close": "practice", "of": "total",
             "zone": "America/Chicago",
             "extensions": {"ada": {"due": DUE + timedelta(days=2), "reason": "medical"}}}
    policy = read_policy(table)
    assert policy.grace == timedelta(minutes=15) and policy.of == "total"
    assert policy.extensions["ada"] == Extension(DUE + timedelta(days=2), "medical")
    assert policy_from_record(policy.record()) == policy


@pytest.mark.parametrize(("table", "message"), [
    ({}, "due: missing"),
    ({"due": datetime(2026, 3, 14, 23, 59)}, "has no time zone offset"),
    ({"due": DUE, "grace": "soon"}, "not a duration"),
    ({"due": DUE, "penalty": {"percent": 120}}, "penalty.percent: 120 is not from 0 to 100"),
    ({"due": DUE, "penalty": {"per": "week"}}, "penalty.per: 'week' is not one of day, hour"),
    ({"due": DUE, "close": DUE - timedelta(days=1)}, "close: .* is before the due time"),
    ({"due": DUE, "after_close": "maybe"}, "after_close"),
    ({"due": DUE, "zone": "Mars/Olympus"}, "not a time zone name"),
    ({"due": DUE, "deadline": DUE}, "unknown key 'deadline'"),
])
def test_a_bad_table_names_the_key(table, message):
    with pytest.raises(PolicyError, match=message):
        read_policy(table)


def test_durations_and_rates():
    assert duration("1h30m") == timedelta(minutes=90)
    assert duration("2d") == timedelta(days=2) and duration("45s") == timedelta(seconds=45)
    assert penalty_rate("10%/day") == (10.0, "day") and penalty_rate("5 % / hour") == (5, "hour")
    with pytest.raises(PolicyError):
        penalty_rate("10 per day")
