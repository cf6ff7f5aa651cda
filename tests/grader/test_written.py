"""Written answers end to end (issue 31): generate → a notebook with Markdown answers → grade
(pending) → reviews by two TAs at once → grades.csv, the feedback page, the report, export.

The class is graded with a fake execution stage that reads the code cells' literals (no kernel
starts; one test at the end runs the real one): what is under test is what happens to the
written answers, which every run reads from the notebook's file itself. The expected points are
worked out here from the rubric this file's spec declares, never read back from the code under
test.
"""

from __future__ import annotations

import base64
import csv
import html.parser
import io
import json
import re
import shutil
import threading
from dataclasses import dataclass
from pathlib import Path

import pytest

from eulertop.cli import main
from grader.assignment import UsageError, load_assignment
from grader.audit import read_trail
from grader.gradebook import summary_table
from grader.graded_folder import RESULTS
from grader.hosted.grading import Isolation, grade_notebook
from grader.limits import Limits
from grader.pipeline import grade_assignment
from grader.results import read_result
from grader.review import ReviewError, ReviewSession
from grader.reviews import REVIEWS, STALE
from grader.written import MAX_ATTACHMENT_BYTES
from problems.generate import Question, generate_assignment
from problems.roster import read_roster
from problems.spec import check_spec, read_spec
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute

RUBRIC = (1.0, 1.0, 2.0)  # the standalone question's items, as SPEC declares them
SPEC = """
title = "Written work"
seed = 5
roster = "roster.csv"

[[questions]]
family = "near_axis_stability"
written = true

[[questions]]
written = "Show that $V_\\\\text{eff}(\\\\beta)$ has exactly one minimum."
name = "veff_minimum"
title = "One minimum"
rubric = [
  { item = "$V_\\\\text{eff}$ in terms of $p_\\\\alpha$, $p_\\\\gamma$", points = 1 },
  { item = "both ends argued", points = 1 },
  { item = "one stationary point shown", points = 2 },
]
"""
STUDENTS = ("ada", "bob", "cyd", "dee")
FAMILY_WRITTEN, OWN = "q1_intermediate_axis", "q2_veff_minimum"
PAYLOAD = ('<script>alert("pwned")</script> [click](javascript:alert(1)) '
           '<img src=x onerror=alert(2)> ![t](http://evil.example/t.png) <http://evil.example> '
           '$\\href{javascript:alert(3)}{x}$')
TEXT = "With $u = \\cos\\beta$ the potential $V_\\text{eff}(u)$ grows at both ends. "
PNG = base64.b64encode(b"\x89PNG\r\n\x1a\n" + b"\0" * 64).decode()
BIG = base64.b64encode(b"\0" * (MAX_ATTACHMENT_BYTES + 1)).decode()


class RecordingExecute(LiteralExecute):
    """The literal reader, remembering which variables the kernel was asked for."""

    def __init__(self) -> None:
        super().__init__()
        self.asked: set[str] = set()

    def __call__(self, path, variables, limits):
        with self.lock:
            self.asked |= set(variables)
        return super().__call__(path, variables, limits)


@dataclass
class Graded:
    hw: Path
    subs: Path
    out: Path
    execute: RecordingExecute

    def record(self, sid: str):
        return read_result(self.out / RESULTS / f"{sid}.json")

    def answer(self, sid: str, variable: str):
        return next(a for a in self.record(sid).answers if a.variable == variable)

    def grades(self) -> dict[str, dict]:
        text = (self.out / "grades.csv").read_text(encoding="utf-8")
        return {row["id"]: row for row in csv.DictReader(io.StringIO(text))}

    def page(self, sid: str) -> str:
        return (self.out / "feedback" / f"{sid}.html").read_text(encoding="utf-8")


def _generate(folder: Path) -> Path:
    (folder / "roster.csv").write_text("id,name,email\n" + "".join(
        f"{s},{s.title()},{s}@example.edu\n" for s in STUDENTS))
    (folder / "spec.toml").write_text(SPEC)
    spec = read_spec(folder / "spec.toml")
    check_spec(spec, FAMILIES)
    hw = folder / "HW"
    generate_assignment(read_roster(folder / "roster.csv"), hw, FAMILIES, seed=5,
                        questions=[Question(q.label, q.pool, q.settings, q.written, q.title)
                                   for q in spec.questions])
    return hw


def _written_cells(nb: dict) -> dict[str, dict]:
    return {c["metadata"]["eulertop"]["written"]: c for c in nb["cells"]
            if c["metadata"].get("eulertop", {}).get("written")}


def _submit(hw: Path, subs: Path, sid: str, texts: dict, extra: dict | None = None) -> None:
    """``sid``'s solutions notebook with its written cells holding ``texts`` (absent: the
    release's placeholder), ``extra`` Markdown cells added after one."""
    nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
    release = _written_cells(json.loads((hw / "release" / f"{sid}.ipynb").read_text()))
    for variable, cell in _written_cells(nb).items():
        cell["source"] = texts.get(variable, release[variable]["source"])
        if isinstance(texts.get(variable), dict):
            cell["source"], cell["attachments"] = texts[variable]["text"], \
                texts[variable]["attachments"]
    for variable, text in (extra or {}).items():
        at = nb["cells"].index(_written_cells(nb)[variable])
        nb["cells"].insert(at + 1, {"cell_type": "markdown", "id": f"mine-{at}",
                                    "metadata": {}, "source": text})
    subs.mkdir(exist_ok=True)
    (subs / f"{sid}.ipynb").write_text(json.dumps(nb))


def _class(folder: Path) -> Graded:
    hw = _generate(folder)
    subs = folder / "subs"
    _submit(hw, subs, "ada", {FAMILY_WRITTEN: TEXT, OWN: TEXT + PAYLOAD})
    _submit(hw, subs, "bob", {FAMILY_WRITTEN: TEXT, OWN: {"text": TEXT, "attachments": {
        "photo.png": {"image/png": PNG}, "sketch.svg": {"image/svg+xml": PNG},
        "huge.png": {"image/png": BIG}}}})
    _submit(hw, subs, "cyd", {OWN: TEXT})  # the family's written cell left as released
    _submit(hw, subs, "dee", {FAMILY_WRITTEN: "First part.", OWN: "Part one, $a = b$."},
            extra={OWN: "Part two, continued in a cell of my own."})
    execute = RecordingExecute()
    grade_assignment(hw, subs, execute=execute)
    return Graded(hw, subs, hw / "graded", execute)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Graded:
    return _class(tmp_path_factory.mktemp("written"))


@pytest.fixture
def graded(pristine, tmp_path) -> Graded:
    """A copy of the graded class of its own for each test."""
    shutil.copytree(pristine.hw.parent, tmp_path / "c", symlinks=True)
    root = tmp_path / "c"
    return Graded(root / "HW", root / "subs", root / "HW" / "graded", pristine.execute)


def _expected_points(items: list[int], adjust: float) -> float:
    return min(max(sum(RUBRIC[i] for i in items) + adjust, 0.0), sum(RUBRIC))


def _numbers(g: Graded, sid: str) -> float:
    """The points of ``sid``'s answers that are not written (the solutions': all right)."""
    return sum(a.verdict.points for a in g.record(sid).answers
               if a.variable not in (FAMILY_WRITTEN, OWN))


# -- generate


def test_generate_records_the_written_parts_in_key_manifest_and_notebooks(pristine):
    hw = pristine.hw
    key = json.loads((hw / "key.json").read_text())["students"]["ada"]["questions"]
    own = key[1]["answers"][0]
    assert (own["kind"], own["points"]) == ("written", sum(RUBRIC))
    assert [r["points"] for r in own["rubric"]] == list(RUBRIC)
    family = next(a for a in key[0]["answers"] if a["kind"] == "written")
    assert family["name"] == "intermediate_axis" and len(family["rubric"]) == 3
    spec = json.loads((hw / "assignment.json").read_text())["students"]["ada"]["questions"][1]
    (public,) = spec["answers"]
    assert public["prompt"].startswith("Show that") and "rubric" not in public
    release = json.loads((hw / "release" / "ada.ipynb").read_text())
    ids = [c["id"] for c in release["cells"]]
    assert ids[-3:] == ["q2-statement", "q2-w1-prompt", "q2-w1-written"]  # no code cell
    cells = _written_cells(release)
    assert set(cells) == {FAMILY_WRITTEN, OWN}
    assert all(c["cell_type"] == "markdown" for c in cells.values())
    prompt = release["cells"][ids.index("q2-w1-prompt")]
    assert "exactly one minimum" in "".join(prompt["source"])
    assert prompt["metadata"]["editable"] is False
    solution = _written_cells(json.loads((hw / "solutions" / "ada.ipynb").read_text()))
    assert "one stationary point shown (2)" in "".join(solution[OWN]["source"])


# -- grading


def test_written_answers_come_from_the_file_never_from_the_kernel(pristine):
    assert pristine.execute.asked and not pristine.execute.asked & {FAMILY_WRITTEN, OWN}
    ada = pristine.answer("ada", OWN)
    assert ada.submitted["text"] == TEXT + PAYLOAD
    assert (ada.verdict.status, ada.verdict.points, ada.verdict.max_points) == \
        ("pending", 0.0, sum(RUBRIC))
    assert pristine.answer("cyd", FAMILY_WRITTEN).verdict.status == "missing"
    dee = pristine.answer("dee", OWN).submitted["text"]
    assert dee == "Part one, $a = b$.\n\nPart two, continued in a cell of my own."


def test_attachments_are_kept_within_the_limit_and_the_others_recorded_as_such(pristine):
    bob = pristine.answer("bob", OWN).submitted
    assert bob["attachments"] == {"photo.png": {"type": "image/png", "data": PNG}}
    dropped = {d["name"]: d for d in bob["dropped"]}
    assert set(dropped) == {"sketch.svg", "huge.png"}
    assert "only PNG, JPEG and GIF" in dropped["sketch.svg"]["why"]
    assert dropped["huge.png"]["bytes"] == MAX_ATTACHMENT_BYTES + 1
    assert "over the limit" in dropped["huge.png"]["why"]
    assert pristine.answer("bob", OWN).verdict.status == "pending"


def test_grades_csv_and_the_summary_say_what_is_pending(pristine):
    rows = pristine.grades()
    pending = {"ada": 2, "bob": 2, "cyd": 1, "dee": 2}  # cyd left one cell as released
    assert {sid: int(row["pending"]) for sid, row in rows.items()} == pending
    for sid in STUDENTS:
        assert float(rows[sid]["total"]) == pytest.approx(_numbers(pristine, sid))
    records = [pristine.record(s) for s in STUDENTS]
    summary = summary_table(records)
    assert f"written answers pending review: {sum(pending.values())}, of 4 student(s)" \
        in summary
    head = next(line for line in summary.splitlines() if line.startswith("answer"))
    assert "pending" in head and "reviewed" not in head


def test_export_refuses_pending_answers_unless_allowed(graded, capsys):
    base = ["export", str(graded.hw), "--to", "gradescope"]
    assert main(base) == 2
    assert "7 written answer(s) of 4 student(s) are not reviewed yet" in capsys.readouterr().err
    assert not (graded.out / "gradescope-import.csv").exists()
    assert main([*base, "--allow-pending"]) == 0
    assert "warning: 7 written answer(s)" in capsys.readouterr().err
    assert (graded.out / "gradescope-import.csv").is_file()


# -- reviews


def _ids(desk: ReviewSession, variable: str) -> dict[str, str]:
    return {a["student"]: a["id"] for a in desk.written(variable)}


def test_two_sessions_submitting_at_once_both_land_attributed(graded):
    plans = {"ta-a": {"ada": ([0, 2], 0.0), "cyd": ([1], 0.5)},
             "ta-b": {"bob": ([0, 1, 2], -1.0), "dee": ([], 3.0)}}
    desks = {who: ReviewSession(graded.hw, grader=who) for who in plans}
    ids = _ids(desks["ta-a"], OWN)
    start, errors = threading.Barrier(len(desks)), []

    def review(who: str) -> None:
        try:
            start.wait()
            for sid, (items, adjust) in plans[who].items():
                desks[who].submit(ids[sid], items, adjust, f"from {who} to {sid}")
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=review, args=(who,)) for who in desks]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert errors == []
    rows = graded.grades()
    stored = json.loads((graded.out / REVIEWS).read_text())["reviews"]
    assert {(r["student"], r["by"]) for r in stored} == {
        (sid, who) for who, plan in plans.items() for sid in plan}
    lines = [x for x in read_trail(graded.out) if x["event"] == "review"]
    assert sorted((x["student"], x["review"]["by"]) for x in lines) == sorted(
        (sid, who) for who, plan in plans.items() for sid in plan)
    for plan in plans.values():
        for sid, (items, adjust) in plan.items():
            want = _expected_points(items, adjust)
            answer = graded.answer(sid, OWN)
            assert (answer.verdict.status, answer.verdict.points) == ("reviewed", want)
            assert float(rows[sid]["total"]) == pytest.approx(_numbers(graded, sid) + want)
            assert int(rows[sid]["pending"]) == (0 if sid == "cyd" else 1)
    for desk in desks.values():
        desk.close()


def test_two_sessions_reviewing_one_answer_both_land_the_last_stands(graded):
    one, two = (ReviewSession(graded.hw, grader=w) for w in ("ta-a", "ta-b"))
    target = _ids(one, OWN)["ada"]
    start = threading.Barrier(2)

    def review(desk, items):
        start.wait()
        desk.submit(target, items, 0.0, "")

    threads = [threading.Thread(target=review, args=(d, i)) for d, i in ((one, [0]),
                                                                          (two, [2]))]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    lines = [x for x in read_trail(graded.out) if x["event"] == "review"]
    assert sorted(x["review"]["by"] for x in lines) == ["ta-a", "ta-b"]
    last = lines[-1]["review"]
    (stored,) = json.loads((graded.out / REVIEWS).read_text())["reviews"]
    assert (stored["by"], stored["rubric"]) == (last["by"], last["rubric"])
    assert graded.answer("ada", OWN).verdict.points == _expected_points(last["rubric"], 0.0)
    # each session reads what the other wrote before its next change
    for desk in (one, two):
        assert desk.answer(target)["review"]["by"] == last["by"]
        desk.close()


def test_the_feedback_page_shows_the_review_and_renders_the_text(graded):
    with ReviewSession(graded.hw, grader="ta-lin") as desk:
        desk.submit(_ids(desk, OWN)["dee"], [0, 2], -0.5, "Good; see **R16** for $\\beta\\to\\pi$.")
    page = graded.page("dee")
    assert "one stationary point shown" in page and "✓ given" in page and "✗ not given" in page
    assert "Adjustment: -0.5 points." in page
    assert "Comment from ta-lin" in page and "<strong>R16</strong>" in page
    assert "<math" in page and "Part two, continued" in page
    assert f"{2.5:g} / {sum(RUBRIC):g} points" in page


def test_the_report_shows_the_written_questions_score_distributions(graded):
    with ReviewSession(graded.hw, grader="ta") as desk:
        ids = _ids(desk, OWN)
        desk.submit(ids["ada"], [0, 1, 2], 0.0, "")
        desk.submit(ids["bob"], [0], 0.0, "")
        before = (graded.out / "report.html").read_text()
    report = (graded.out / "report.html").read_text()
    assert report != before  # rebuilt by close(), once
    section = report[report.index('id="written"'):report.index('id="mistakes"')]
    assert "2 reviewed, mean 2.5 of 4; 2 pending review; 0 unanswered" in section
    assert "distribution of the reviewed scores of q2_veff_minimum" in section
    rows = dict(_table_rows(section))
    assert rows["1. $V_\\text{eff}$ in terms of $p_\\alpha$, $p_\\gamma$"] == ["2", "2"]
    assert rows["2. both ends argued"] == ["1", "2"]


def _table_rows(section: str):
    """(first cell, other cells) of each body row of the HTML tables in ``section``."""
    parser = _Cells()
    parser.feed(section)
    return [(r[0], r[1:]) for r in parser.rows if r]


class _Cells(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.rows: list[list[str]] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
        elif tag == "td":
            self._cell = []

    def handle_endtag(self, tag):
        if tag == "td" and self._cell is not None:
            self.rows[-1].append("".join(self._cell))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


class _Markup(html.parser.HTMLParser):
    """Every element and attribute of a page, as a browser's parser would see them."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, {k: v or "" for k, v in attrs}))


def _markup(page: str) -> list[tuple[str, dict]]:
    parser = _Markup()
    parser.feed(page)
    return parser.tags


def test_nothing_a_student_writes_reaches_a_page_as_markup(graded):
    with ReviewSession(graded.hw, grader="ta") as desk:
        ada = _ids(desk, OWN)["ada"]
        desk.submit(ada, [0], 0.0, "")
        shown = desk.html(ada)
    pages = {"feedback": graded.page("ada"), "desk": shown,
             "report": (graded.out / "report.html").read_text()}
    assert "alert(&quot;pwned&quot;)" in pages["feedback"] or "alert(\"pwned\")" in \
        pages["feedback"]  # the text is there, as text
    for name, page in pages.items():
        for tag, attrs in _markup(page):
            assert tag not in ("iframe", "object", "embed", "form"), name
            assert not any(k.startswith("on") for k in attrs), (name, tag, attrs)
            for value in attrs.values():
                assert not value.strip().lower().startswith("javascript:"), (name, tag)
            if tag == "img":
                assert attrs["src"].startswith("data:image/"), (name, attrs)
            if tag == "a":
                assert attrs.get("href", "").startswith(("#", "data:text/csv")), (name, attrs)
            if tag == "script":
                assert name == "report", name  # the report's own sorting script only
        assert "<script>alert" not in page and "evil.example/t.png\"" not in page, name


def test_a_rubric_items_points_rescore_everyone_who_has_it(graded):
    with ReviewSession(graded.hw, grader="ta") as desk:
        ids = _ids(desk, OWN)
        desk.submit(ids["ada"], [1], 0.0, "")
        desk.submit(ids["bob"], [0, 2], 0.0, "")
        before = {sid: graded.record(sid) for sid in STUDENTS}
        question = desk.set_rubric(OWN, 1, 3.0)
    assert [r["points"] for r in question["rubric"]] == [1.0, 3.0, 2.0]
    assert len(list(graded.hw.glob("key.json.*"))) == 1  # the old key kept beside it
    for sid in STUDENTS:
        after = graded.record(sid)
        assert after.max_points == before[sid].max_points + 2.0
    assert graded.answer("ada", OWN).verdict.points == 3.0  # item 2 given: now worth 3
    assert graded.answer("bob", OWN).verdict.points == 3.0  # items 1 and 3: unchanged
    assert graded.answer("cyd", OWN).verdict.status == "pending"
    line = [x for x in read_trail(graded.out) if x["event"] == "key set"][-1]
    assert {c["student"] for c in line["key_changes"]} == set(STUDENTS)


def test_key_set_rubric_on_the_command_line(graded, capsys):
    assert main(["key", "set", str(graded.hw), OWN, "--rubric", "3=1"]) == 0
    key = load_assignment(graded.hw).expected("dee")
    own = next(k for k in key if k.variable == OWN)
    assert [r.points for r in own.answer.rubric] == [1.0, 1.0, 1.0] and own.answer.points == 3
    assert main(["key", "set", str(graded.hw), "q1_rate", "--rubric", "1=1"]) == 2
    assert "no written answer" in capsys.readouterr().err


def test_a_review_of_other_text_is_not_applied(graded):
    with ReviewSession(graded.hw, grader="ta") as desk:
        desk.submit(_ids(desk, OWN)["ada"], [0, 1, 2], 0.0, "")
    _submit(graded.hw, graded.subs, "ada", {FAMILY_WRITTEN: TEXT, OWN: "Something else."})
    grade_assignment(graded.hw, graded.subs, execute=LiteralExecute())
    answer = graded.answer("ada", OWN)
    assert (answer.verdict.status, answer.verdict.points, answer.verdict.message) == \
        ("pending", 0.0, STALE)
    with ReviewSession(graded.hw, grader="ta") as desk:
        assert desk.answer(_ids(desk, OWN)["ada"])["review"]["stale"] is True
        assert desk.progress()[OWN]["stale"] == 1


def test_refused_reviews_write_nothing(graded):
    trail = (graded.out / "audit.jsonl").read_bytes()
    with ReviewSession(graded.hw, grader="ta") as desk:
        with pytest.raises(ReviewError, match="no written answer with id"):
            desk.submit("0123456789abcdef", [0], 0.0, "")
        with pytest.raises(ReviewError, match="nothing to review"):
            desk.submit(_ids(desk, FAMILY_WRITTEN)["cyd"], [0], 0.0, "")
        with pytest.raises(UsageError, match="not distinct items"):
            desk.submit(_ids(desk, OWN)["ada"], [3], 0.0, "")
        with pytest.raises(ReviewError, match="finite number"):
            desk.submit(_ids(desk, OWN)["ada"], [0], float("nan"), "")
        with pytest.raises(ReviewError, match="no written question"):
            desk.written("q1_rate")
    assert (graded.out / "audit.jsonl").read_bytes() == trail
    assert not (graded.out / REVIEWS).exists()


def test_ids_are_opaque_and_the_same_in_every_session(graded):
    one, two = ReviewSession(graded.hw), ReviewSession(graded.hw)
    assert one.written(OWN) == two.written(OWN)
    assert all(a["id"] != a["student"] and a["student"] not in a["id"]
               for a in one.written(OWN))
    one.close()
    two.close()


def test_reusable_comments_are_kept_per_question(graded):
    with ReviewSession(graded.hw, grader="ta") as desk:
        desk.add_comment(OWN, "ends", "Argue both ends.")
        desk.add_comment(OWN, "sign", "Mind the sign.")
        assert desk.add_comment(OWN, "sign", None) == {"ends": "Argue both ends."}
    with ReviewSession(graded.hw) as other:
        assert other.comments(OWN) == {"ends": "Argue both ends."}
        assert other.comments(FAMILY_WRITTEN) == {}


def test_progress_counts_each_question(graded):
    with ReviewSession(graded.hw, grader="ta") as desk:
        desk.submit(_ids(desk, OWN)["bob"], [0], 0.0, "")
        progress = desk.progress()
    assert progress[OWN] == {"answers": 4, "written": 4, "reviewed": 1, "pending": 3,
                             "stale": 0}
    assert progress[FAMILY_WRITTEN]["written"] == 3  # cyd left it as released


def test_an_override_from_the_desk_is_eulertop_overrides(graded):
    with ReviewSession(graded.hw, grader="ta-lin") as desk:
        done = desk.override("bob", "q1_rate", 0.0, "worked with ada")
    assert done["overridden"]["q1_rate"]["by"] == "ta-lin"
    toml = (graded.out / "overrides.toml").read_text()
    assert 'student = "bob"' in toml and 'reason = "worked with ada"' in toml
    line = [x for x in read_trail(graded.out) if x["event"] == "override"][-1]
    assert (line["student"], line["answer"]) == ("bob", "q1_rate")
    assert "q1_rate" in graded.grades()["bob"]["overridden"]


def test_flagged_answers_carry_the_students_value_and_the_keys(graded):
    nb = json.loads((graded.subs / "dee.ipynb").read_text())
    key = {k.variable: k.answer for k in load_assignment(graded.hw).expected("dee")}
    rate = key["q1_rate"]
    off = rate.value * (1 + 1.5 * rate.rtol)  # wrong, within twice the tolerance
    for cell in nb["cells"]:
        if cell["cell_type"] == "code" and "q1_rate = " in "".join(cell["source"]):
            source = "".join(cell["source"]).replace(f"q1_rate = {rate.value!r}",
                                                     f"q1_rate = {off!r}")
            cell["source"] = source + "\nq1_stable1 = 'maybe'\n"
    (graded.subs / "dee.ipynb").write_text(json.dumps(nb))
    grade_assignment(graded.hw, graded.subs, execute=LiteralExecute())
    with ReviewSession(graded.hw) as desk:
        flagged = {(f["student"], f["variable"]): f for f in desk.flagged()}
    assert flagged[("dee", "q1_rate")]["why"] == "within twice the tolerance"
    assert flagged[("dee", "q1_rate")]["submitted"] == off
    assert flagged[("dee", "q1_rate")]["key"] == rate.value
    assert flagged[("dee", "q1_stable1")]["why"] == "invalid"
    assert all(sid == "dee" for sid, _ in flagged)  # the others' solutions are all right


def test_hosted_packages_grade_the_numbers_only(graded):
    a = load_assignment(graded.hw)
    isolation = Isolation("bwrap", "test", True, LiteralExecute())
    result = grade_notebook(a, "ada", graded.subs / "ada.ipynb", Limits(), isolation)
    variables = {x.variable for x in result.answers}
    assert variables and not variables & {FAMILY_WRITTEN, OWN}
    numbers = sum(k.answer.points for k in a.expected("ada")
                  if k.variable not in (FAMILY_WRITTEN, OWN))
    assert result.max_points == numbers == result.points


def test_a_real_grading_run_reads_written_answers_beside_the_kernels(tmp_path):
    hw = _generate(tmp_path)
    subs = tmp_path / "subs"
    _submit(hw, subs, "ada", {OWN: TEXT})
    report = grade_assignment(hw, subs, limits=Limits(total_timeout=60))
    ada = next(r for r in report.results if r.student_id == "ada")
    assert ada.status == "graded"
    statuses = {a.variable: a.verdict.status for a in ada.answers}
    assert statuses[OWN] == "pending" and statuses[FAMILY_WRITTEN] == "missing"
    assert statuses["q1_rate"] == "correct"


def test_the_text_is_cut_at_the_limit_and_the_record_says_so():
    from grader.written import MAX_TEXT_CHARS, written_answers

    cell = {"cell_type": "markdown", "metadata": {"eulertop": {"written": "q1_w"}},
            "source": ["x" * MAX_TEXT_CHARS, "tail"]}
    (value,) = written_answers(json.dumps({"nbformat": 4, "cells": [cell]}).encode(),
                               ["q1_w"]).values()
    assert len(value["text"]) == MAX_TEXT_CHARS
    assert value["notes"] == [f"cut at {MAX_TEXT_CHARS:,} characters (it had "
                              f"{MAX_TEXT_CHARS + 4:,})"]


@pytest.mark.parametrize("data", [b"", b"not json", b"[" * 200 + b"]" * 200,
                                  b'{"nbformat": 4, "cells": "none"}'])
def test_bytes_that_are_no_notebook_give_no_written_answer(data):
    from grader.written import written_answers

    assert written_answers(data, ["q1_w"]) == {"q1_w": None}


def test_a_hosted_package_says_which_parts_the_platform_grades_by_hand(pristine):
    from grader.hosted.package import _written_note

    note = _written_note(pristine.hw)
    assert f"the written parts ({FAMILY_WRITTEN}, {OWN}) are not autograded" in note


def test_eulertop_check_lists_written_parts_from_the_saved_file(pristine):
    from grader.check import check_notebook, format_report

    report = check_notebook(pristine.subs / "cyd.ipynb", Limits(total_timeout=60))
    words = {a.variable: a.verdict.status for a in report.answers}
    assert words[OWN] == "correct" and words[FAMILY_WRITTEN] == "missing"
    text = format_report(report, pristine.subs / "cyd.ipynb")
    assert re.search(rf"MISSING +{FAMILY_WRITTEN} +no answer: the answer cell is empty", text)
    assert re.search(rf"ok +{OWN} +well formed: {len(TEXT.strip())} characters", text)
