"""The term's calendar in a graded class (issue 32): the policy from the spec, the times from
``--times`` or the LMS download, penalties in every view, and deadlines moved and extensions
granted after grading — recomputed without a kernel, changing only the rows they should.

Graded with a fake execution stage that reads the literals each submission assigns (no
kernel). Every student answers everything right, so their raw points are the maximum and each
penalty is worked out by hand from the policy: 10 % of the points earned per started day past
a 15-minute grace, at most 50 %, nothing after the close.
"""

from __future__ import annotations

import csv
import json
import shutil
from datetime import UTC, datetime, timedelta, timezone
from pathlib import Path

import nbformat
import pytest

from eulertop.cli import main
from grader.assignment import UsageError
from grader.graded_folder import RESULTS
from grader.pipeline import grade_assignment
from grader.results import read_result
from problems.deadlines import LatePolicy
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute

CDT = timezone(timedelta(hours=-5))
DUE = datetime(2026, 3, 14, 23, 59, tzinfo=CDT)
POLICY = LatePolicy(due=DUE, grace=timedelta(minutes=15), percent=10, per="day",
                    max_percent=50, close=DUE + timedelta(days=7))
# id -> how long after the due time it came in (None: no time known), and the penalty (%)
CLASS = {
    "ada": (timedelta(0), 0),                        # exactly at the deadline
    "ben": (timedelta(minutes=10), 0),               # inside the grace
    "cy": (timedelta(minutes=16), 10),               # the first started day
    "dee": (timedelta(days=2, minutes=1), 30),       # three started days
    "eve": (timedelta(days=6), 50),                  # capped
    "fay": (timedelta(days=8), 100),                 # after the close: nothing
    "gus": (None, 0),                                # no time known: not late
}


def _notebook(hw: Path, sid: str) -> str:
    key = json.loads((hw / "key.json").read_text())
    code = "\n".join(f"q{q['question']}_{a['name']} = {a['value']!r}"
                     for q in key["students"][sid]["questions"] for a in q["answers"])
    return nbformat.writes(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)]))


@pytest.fixture(scope="module")
def late_class(tmp_path_factory) -> tuple[Path, Path, Path]:
    root = tmp_path_factory.mktemp("late")
    hw = root / "HW"
    roster = Roster(("id", "Email address"), tuple({"id": s, "Email address": f"{s}@example.edu"}
                                           for s in CLASS))
    generate_assignment(roster, hw, FAMILIES, problems=["sleeping_top", "euler_rotation"],
                        seed=32, late=POLICY)
    subs = root / "subs"
    subs.mkdir()
    for sid in CLASS:
        (subs / f"{sid}.ipynb").write_text(_notebook(hw, sid))
    times = root / "times.csv"
    with open(times, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["id", "submitted_at"])
        for sid, (after, _) in CLASS.items():
            if after is not None:
                writer.writerow([sid, (DUE + after).astimezone(UTC).isoformat()])
    grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=1, times=times)
    return hw, subs, times


@pytest.fixture
def graded(late_class, tmp_path) -> tuple[Path, Path, Path]:
    hw, subs, times = late_class
    return Path(shutil.copytree(hw, tmp_path / "HW")), subs, times


def _rows(hw: Path) -> dict[str, dict]:
    with open(hw / "graded" / "grades.csv", newline="") as f:
        return {r["id"]: r for r in csv.DictReader(f)}


def _record(hw: Path, sid: str):
    return read_result(hw / "graded" / RESULTS / f"{sid}.json")


def test_the_spec_s_policy_is_recorded(late_class):
    hw, _, _ = late_class
    manifest = json.loads((hw / "assignment.json").read_text())
    assert manifest["late"]["due"] == "2026-03-14T23:59:00-05:00"
    assert manifest["late"]["grace_seconds"] == 900.0


def test_penalties_in_every_view(late_class):
    hw, _, _ = late_class
    rows = _rows(hw)
    for sid, (after, percent) in CLASS.items():
        record, row = _record(hw, sid), rows[sid]
        maximum = record.max_points
        expected = maximum * (1 - percent / 100)
        assert record.points == pytest.approx(expected), sid
        assert float(row["raw"]) == pytest.approx(maximum)
        assert float(row["total"]) == pytest.approx(expected, rel=1e-3)
        assert (row["penalty"] != "") == (percent > 0), sid
        late = after is not None and after > timedelta(0)
        assert (row["late_by"] != "") == late, sid
    assert rows["dee"]["late_by"] == "2 d 0 h 01 min"
    page = (hw / "graded" / "feedback" / "dee.html").read_text()
    assert "Deadline: 2026-03-14 23:59 -05:00" in page
    assert "2 d 0 h 01 min late: 3 started days, 30 % of the points earned" in page
    assert "row 5 of times.csv" in page  # where the time came from
    assert "after the assignment closed — no credit" in (
        hw / "graded" / "feedback" / "fay.html").read_text()
    assert "within the grace period: no penalty" in (
        hw / "graded" / "feedback" / "ben.html").read_text()
    assert "on time" in (hw / "graded" / "feedback" / "ada.html").read_text()
    report = (hw / "graded" / "report.html").read_text()
    assert "Late: 5 of 6 submissions with a known time came in after their deadline; " \
           "4 lost points to the penalty" in report


def test_a_moved_deadline_is_recomputed_without_a_kernel(graded, capsys):
    hw, _, _ = graded
    before = _rows(hw)
    later = (DUE + timedelta(days=2)).isoformat()
    assert main(["late", "set", str(hw), "--due", later]) == 0
    said = capsys.readouterr().out
    assert "due: 2026-03-14T23:59:00-05:00 → 2026-03-16T23:59:00-05:00" in said
    after = _rows(hw)
    # dee (2 d 1 min late) is now 1 min late: inside the grace; eve 4 days: 40 %; fay after
    # the close still (the close did not move)
    assert float(after["dee"]["total"]) == pytest.approx(float(after["dee"]["raw"]), rel=1e-3)
    assert float(after["eve"]["penalty"]) == pytest.approx(0.4 * float(after["eve"]["raw"]),
                                                           rel=1e-3)
    for sid in ("ada", "ben", "cy", "fay", "gus"):
        if sid == "cy":
            continue  # cy came 16 min after the old due time: on time now
        assert after[sid]["total"] == before[sid]["total"], sid
    assert after["cy"]["penalty"] == "" and before["cy"]["penalty"] != ""


def test_an_extension_changes_only_its_student(graded, capsys):
    hw, _, _ = graded
    before = {p.name: p.read_bytes() for p in (hw / "graded" / RESULTS).iterdir()}
    extended = (DUE + timedelta(days=3)).isoformat()
    assert main(["late", "extend", str(hw), "dee", "--due", extended,
                 "--reason", "medical"]) == 0
    after = {p.name: p.read_bytes() for p in (hw / "graded" / RESULTS).iterdir()}
    assert {n for n in after if after[n] != before[n]} == {"dee.json"}
    dee = _record(hw, "dee")
    assert dee.points == dee.max_points and dee.late["extension"] == "medical"
    assert "your extension: medical" in (hw / "graded" / "feedback" / "dee.html").read_text()
    assert main(["late", "extend", str(hw), "dee", "--remove"]) == 0
    assert _record(hw, "dee").points == pytest.approx(0.7 * dee.max_points)


@pytest.mark.parametrize(("argv", "message"), [
    (["late", "extend", "{hw}", "dee", "--due", "2026-03-10T00:00:00-05:00", "--reason", "x"],
     "is before the due time"),
    (["late", "set", "{hw}", "--due", "2026-03-20T23:59:00"], "has no time zone offset"),
    (["late", "extend", "{hw}", "nobody", "--due", "2026-03-20T23:59:00-05:00",
      "--reason", "x"], "no student 'nobody'"),
    (["late", "set", "{hw}", "--penalty", "ten percent"], "say 10%/day"),
])
def test_refused_changes_write_nothing(graded, capsys, argv, message):
    hw, _, _ = graded
    before = {p: p.read_bytes() for p in hw.rglob("*") if p.is_file()}
    assert main([a.format(hw=hw) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert {p: p.read_bytes() for p in hw.rglob("*") if p.is_file()} == before


def test_an_override_of_the_total_stands_after_the_penalty(graded):
    hw, _, _ = graded
    most = _record(hw, "eve").max_points
    assert main(["override", str(hw), "eve", "--points", str(most), "--reason", "excused"]) == 0
    eve = _record(hw, "eve")
    assert eve.points == most and eve.late["points"] == pytest.approx(0.5 * most)
    variable = eve.answers[0].variable
    assert main(["override", str(hw), "eve", "--remove"]) == 0
    assert main(["override", str(hw), "cy", variable, "--points", "0", "--reason", "r"]) == 0
    cy = _record(hw, "cy")  # an answer's override comes before the penalty: 10 % of the rest
    rest = cy.max_points - cy.answers[0].verdict.max_points
    assert cy.points == pytest.approx(0.9 * rest)


def test_export_penalised_or_raw(graded):
    hw, _, _ = graded
    for flag, factor in (([], 0.7), (["--no-late"], 1.0)):
        target = hw / f"moodle{len(flag)}.csv"
        assert main(["export", str(hw), "--to", "moodle", "--out", str(target), *flag]) == 0
        with open(target, newline="") as f:
            rows = list(csv.reader(f))
        dee = _record(hw, "dee")
        line = next(r for r in rows if "dee@example.edu" in r)
        assert f"{factor * dee.max_points:.4g}" in line


def test_a_time_that_cannot_be_read_names_its_row_and_nothing_is_written(late_class,
                                                                           tmp_path):
    hw, subs, _ = late_class
    copy = Path(shutil.copytree(hw, tmp_path / "HW"))
    before = {p: p.read_bytes() for p in copy.rglob("*") if p.is_file()}
    bad = tmp_path / "times.csv"
    bad.write_text("id,submitted_at\nada,2026-03-14T23:00:00-05:00\nben,2026-03-15 00:10\n")
    with pytest.raises(UsageError, match=r"times.csv, row 3 \(ben\): .*no time zone offset"):
        grade_assignment(copy, subs, limits="LIMITS", execute=LiteralExecute(), jobs=1,
                         times=bad, force=True)
    assert {p: p.read_bytes() for p in copy.rglob("*") if p.is_file()} == before


def test_times_given_later_reach_kept_records_without_a_kernel(late_class, tmp_path):
    """Graded without times, then again with --times: nothing runs, the penalties land."""
    hw, subs, times = late_class
    fresh = tmp_path / "HW"
    shutil.copytree(hw, fresh, ignore=shutil.ignore_patterns("graded"))
    execute = LiteralExecute()
    grade_assignment(fresh, subs, limits="LIMITS", execute=execute, jobs=1)
    assert _record(fresh, "dee").points == _record(fresh, "dee").max_points  # time unknown
    execute.calls = 0
    grade_assignment(fresh, subs, limits="LIMITS", execute=execute, jobs=1, times=times)
    assert execute.calls == 0
    assert _record(fresh, "dee").points == pytest.approx(0.7 * _record(fresh, "dee").max_points)
    assert _record(fresh, "dee").submitted["source"] == "row 5 of times.csv"
