"""The desk over HTTP (issue 31): the token, ``Host`` and ``Origin`` refusals, the headers
every response carries, no file outside the app's own static files, and the JSON API — its
answers checked against the class as it was handed in and the rubric as the spec declares it,
its changes against the records, ``grades.csv``, the trail and ``eulertop override`` itself."""

from __future__ import annotations

import csv
import html.parser
import io
import json
import re
import shutil

import pytest

from eulertop.cli import main
from eulertop.review_app.server import POLICY
from grader.audit import read_trail
from grader.graded_folder import RESULTS
from grader.results import read_result
from grader.reviews import REVIEWS
from tests.review_app.client import ask, token_of
from tests.review_app.desk_class import (
    AXIS,
    BEACON,
    FAMILY_WRITTEN,
    OWN,
    RUBRIC,
    STUDENTS,
    TEXT,
    DeskClass,
)

PAGES = ("/", f"/question/{OWN}", "/flagged", "/static/desk.css", "/static/question.js",
         "/static/common.js", "/static/flagged.js")
READINGS = ("/api/questions", "/api/progress", f"/api/written?question={OWN}",
            "/api/flagged", f"/api/comments?question={OWN}")


@pytest.fixture
def desk(desk_class, serve):
    return serve(desk_class)


def _ids(desk, question: str = OWN) -> dict[str, str]:
    """Student → answer id, as the API gives them with names."""
    rows = ask(desk.url, "GET", f"/api/written?question={question}&names=1").json()
    return {r["student"]: r["id"] for r in rows}


def _state(made: DeskClass) -> dict:
    """What a refused change must leave as it was."""
    return {p.name: p.read_bytes() for p in (made.out / "grades.csv", made.out / "audit.jsonl",
                                             made.out / RESULTS / "dee.json")} | {
        REVIEWS: (made.out / REVIEWS).read_bytes() if (made.out / REVIEWS).exists() else None}


# -- the token


def test_the_printed_address_sets_the_cookie_and_leaves_the_address_bar(desk):
    reply = ask(desk.url, "GET", f"/question/{OWN}?token={token_of(desk.url)}&names=1",
                token=None)
    assert reply.status == 302
    assert reply.headers["Location"] == f"/question/{OWN}?names=1"
    cookie = reply.headers["Set-Cookie"]
    name, value = cookie.split(";")[0].split("=", 1)
    assert value == token_of(desk.url)
    assert {"HttpOnly", "SameSite=Strict", "Path=/"} <= {p.strip() for p in cookie.split(";")}
    page = ask(desk.url, "GET", f"/question/{OWN}", token=None,
               headers={"Cookie": f"{name}={value}"})
    assert page.status == 200 and "review desk" in page.text


@pytest.mark.parametrize("path", PAGES + READINGS)
def test_every_page_file_and_reading_needs_the_token(desk, path):
    assert ask(desk.url, "GET", path, token=None).status == 401
    assert ask(desk.url, "GET", path, token="not-the-token").status == 401
    assert ask(desk.url, "GET", path).status == 200  # control: with it, served


@pytest.mark.parametrize("resource", ["review", "rubric", "comments", "override"])
def test_every_change_needs_the_token_and_writes_nothing_without(desk, desk_class, resource):
    before = _state(desk_class)
    reply = ask(desk.url, "POST", f"/api/{resource}", {"id": _ids(desk)["dee"]}, token=None)
    assert reply.status == 401 and "token" in reply.json()["error"]
    assert _state(desk_class) == before


def test_the_token_in_the_query_opens_pages_only(desk):
    assert ask(desk.url, "GET", f"/api/questions?token={token_of(desk.url)}",
               token=None).status == 401


# -- Host and Origin


@pytest.mark.parametrize("host", ["evil.example:{port}", "127.0.0.1:{other}", "127.0.0.1",
                                  "localhost", "[::1]:{port}", "127.0.0.1.nip.io:{port}"])
@pytest.mark.parametrize("path", ["/", "/api/questions", "/static/desk.css"])
def test_a_request_for_another_host_is_refused_token_or_not(desk, host, path):
    port = int(desk.url.split(":")[2].split("/")[0])
    reply = ask(desk.url, "GET", path, headers={"Host": host.format(port=port, other=port + 1)})
    assert reply.status == 403 and "not this desk's address" in reply.text


def test_localhost_is_the_desk_too(desk):
    port = int(desk.url.split(":")[2].split("/")[0])
    assert ask(desk.url, "GET", "/api/questions",
               headers={"Host": f"localhost:{port}"}).status == 200


@pytest.mark.parametrize("origin", ["http://evil.example", "null", "http://127.0.0.1:1",
                                    "https://127.0.0.1:{port}", "http://localhost.evil:{port}"])
def test_a_foreign_origin_is_refused_and_changes_nothing(desk, desk_class, origin):
    port = int(desk.url.split(":")[2].split("/")[0])
    headers = {"Origin": origin.format(port=port)}
    before = _state(desk_class)
    assert ask(desk.url, "GET", "/api/questions", headers=headers).status == 403
    reply = ask(desk.url, "POST", "/api/review", {"id": _ids(desk)["dee"], "rubric": [0]},
                headers=headers)
    assert reply.status == 403 and "Origin" in reply.json()["error"]
    assert _state(desk_class) == before


def test_a_change_with_the_cookie_must_carry_the_desks_origin(desk, desk_class):
    cookie = ask(desk.url, "GET", f"/?token={token_of(desk.url)}", token=None) \
        .headers["Set-Cookie"].split(";")[0]
    port = int(desk.url.split(":")[2].split("/")[0])
    body = {"id": _ids(desk)["dee"], "rubric": [0]}
    before = _state(desk_class)
    assert ask(desk.url, "POST", "/api/review", body, token=None,
               headers={"Cookie": cookie}).status == 403
    assert _state(desk_class) == before
    reply = ask(desk.url, "POST", "/api/review", body, token=None,
                headers={"Cookie": cookie, "Origin": f"http://127.0.0.1:{port}"})
    assert reply.status == 200 and reply.json()["status"] == "reviewed"


def test_a_body_a_cross_site_form_could_send_is_refused(desk, desk_class):
    """A form of another site can post ``text/plain`` without asking first; the desk takes
    JSON only."""
    before = _state(desk_class)
    reply = ask(desk.url, "POST", "/api/review", raw=json.dumps(
        {"id": _ids(desk)["dee"], "rubric": [0]}).encode(),
        headers={"Content-Type": "text/plain"})
    assert reply.status == 415
    assert _state(desk_class) == before


# -- what every response carries


@pytest.mark.parametrize("path, token", [(p, "") for p in PAGES + READINGS] + [
    ("/", None), ("/api/questions", None), ("/static/nothing.js", ""), ("/question/nope", "")])
def test_every_response_carries_the_policy_and_headers(desk, path, token):
    reply = ask(desk.url, "GET", path, token=token)
    policy = reply.headers["Content-Security-Policy"]
    assert policy == POLICY
    directives = dict(d.strip().split(" ", 1) for d in policy.split(";"))
    assert directives["default-src"] == "'none'" and directives["script-src"] == "'self'"
    assert directives["frame-ancestors"] == "'none'" and "unsafe" not in policy
    assert reply.headers["X-Content-Type-Options"] == "nosniff"
    assert reply.headers["Referrer-Policy"] == "no-referrer"


class _Tags(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))


def _tags(text: str) -> list[tuple[str, dict]]:
    parser = _Tags()
    parser.feed(text)
    return parser.tags


@pytest.mark.parametrize("path", ["/", f"/question/{OWN}", "/flagged"])
def test_pages_run_only_the_apps_own_script_files(desk, path):
    tags = _tags(ask(desk.url, "GET", path).text)
    scripts = [a for t, a in tags if t == "script"]
    assert scripts and all(re.fullmatch(r"/static/[a-z]+\.js", a.get("src", "")) for a in scripts)
    assert not [(t, k) for t, a in tags for k in a if k.startswith("on") or k == "style"]


# -- files


@pytest.mark.parametrize("path", [
    "/static/../server.py", "/static/..%2fserver.py", "/static/%2e%2e/server.py",
    "/static/%2e%2e%2f%2e%2e%2f%2e%2e%2fpyproject.toml", "/static/../../../../../etc/passwd",
    "/static//etc/passwd", "/static/%2fetc%2fpasswd", "/static/..%5cserver.py",
    "/static/../templates/base.html", "/static/", "/static/.", "/../server.py",
    "/%2e%2e/server.py", "/question/..%2f..%2fserver.py", "/static/desk.css%00.py",
    "/templates/base.html", "/server.py", "/static/%252e%252e/server.py",
])
def test_no_path_outside_the_apps_static_files_is_read(desk, path):
    from eulertop.review_app import server

    reply = ask(desk.url, "GET", path)
    assert reply.status in (400, 403, 404, 405), (path, reply.status)
    for secret in ("root:x:0:0", "class ReviewServer", "{% block", "[project]"):
        assert secret not in reply.text
    assert "class ReviewServer" in open(server.__file__).read()  # the probe can find it


def test_the_apps_static_files_are_served(desk):
    """Control of the test above."""
    reply = ask(desk.url, "GET", "/static/desk.css")
    assert reply.status == 200 and "WCAG" in reply.text


# -- the API


def test_written_lists_each_answer_anonymous_unless_names_are_asked(desk):
    rows = ask(desk.url, "GET", f"/api/written?question={FAMILY_WRITTEN}").json()
    assert all({"id", "text", "review"} <= set(r) and "student" not in r and "name" not in r
               for r in rows)
    assert sorted(r["text"] for r in rows if r["status"] == "pending") == [AXIS] * 5
    named = ask(desk.url, "GET", f"/api/written?question={FAMILY_WRITTEN}&names=1").json()
    assert {r["student"]: r["name"] for r in named} == STUDENTS
    assert [r["id"] for r in named] == [r["id"] for r in rows]
    missing = next(r for r in named if r["student"] == "cyd")  # left as released
    assert missing["status"] == "missing" and missing["text"] == ""


def test_an_answer_comes_with_its_text_as_the_feedback_page_renders_it(desk):
    found = ask(desk.url, "GET", f"/api/answer?id={_ids(desk)['dee']}").json()
    assert found["text"] == TEXT and "student" not in found
    assert "<strong>one minimum</strong>" in found["html"] and "<mfrac>" in found["html"]


def _allowed(tags: list[tuple[str, dict]]) -> list:
    """The elements and attributes of a student's rendered text that could run, load or
    link anything: none may be there."""
    from grader.statement_html import MATHML_ELEMENTS

    harmless = MATHML_ELEMENTS | {"p", "strong", "em", "code", "pre", "ul", "ol", "li",
                                  "blockquote", "h1", "h2", "h3", "h4", "h5", "h6", "hr", "br",
                                  "table", "thead", "tbody", "tr", "th", "td"}
    bad = [t for t, _ in tags if t not in harmless and t != "img"]
    for tag, attrs in tags:
        for name, value in attrs.items():
            if name.startswith("on") or name in ("href", "style", "action", "formaction",
                                                 "xlink:href", "srcset", "data"):
                bad.append((tag, name, value))
            if name == "src" and not (value or "").startswith("data:image/"):
                bad.append((tag, name, value))
    return bad


def test_hostile_markdown_comes_back_as_text_only(desk):
    found = ask(desk.url, "GET", f"/api/answer?id={_ids(desk)['ada']}").json()
    assert BEACON in found["text"]  # what she wrote is all there, for the TA to read
    tags = _tags(found["html"])
    assert _allowed(tags) == []
    assert "&lt;script&gt;" in found["html"] and "&lt;svg" in found["html"]
    assert _allowed([("script", {}), ("a", {"href": "x"}), ("mi", {"onclick": "x"})]) != []


def _grades(made: DeskClass) -> dict[str, dict]:
    text = (made.out / "grades.csv").read_text(encoding="utf-8")
    return {row["id"]: row for row in csv.DictReader(io.StringIO(text))}


def test_a_review_lands_in_the_record_the_gradebook_the_page_and_the_trail(desk, desk_class):
    before = float(_grades(desk_class)["dee"]["total"])
    body = {"id": _ids(desk)["dee"], "rubric": [0, 2], "adjust": -0.5,
            "comment": "Say why the stationary point is a *minimum*."}
    found = ask(desk.url, "POST", "/api/review", body).json()
    want = RUBRIC[0] + RUBRIC[2] - 0.5
    assert (found["status"], found["points"], found["review"]["by"]) == ("reviewed", want,
                                                                          "ta-one")
    assert found["progress"][OWN]["reviewed"] == 1
    answer = next(a for a in read_result(desk_class.out / RESULTS / "dee.json").answers
                  if a.variable == OWN)
    assert (answer.verdict.status, answer.verdict.points) == ("reviewed", want)
    assert float(_grades(desk_class)["dee"]["total"]) == pytest.approx(before + want)
    page = (desk_class.out / "feedback" / "dee.html").read_text(encoding="utf-8")
    assert "<em>minimum</em>" in page and "Comment from ta-one" in page
    (line,) = [x for x in read_trail(desk_class.out) if x["event"] == "review"]
    assert (line["student"], line["answer"], line["review"]["by"]) == ("dee", OWN, "ta-one")


@pytest.mark.parametrize("body, field", [
    ({"rubric": [0]}, "'id'"),
    ({"id": "0000000000000000", "rubric": [0]}, "0000000000000000"),
    ({"id": "ID", "rubric": "0"}, "'rubric'"),
    ({"id": "ID", "rubric": [7]}, "7"),
    ({"id": "ID", "rubric": [0, 0]}, "twice"),
    ({"id": "ID", "adjust": "1"}, "'adjust'"),
    ({"id": "ID", "adjust": True}, "'adjust'"),
    ({"id": "ID", "comment": "x" * 20_001}, "20001 characters"),
    ({"id": "ID", "rubrics": [0]}, "'rubrics'"),
    (["ID"], "JSON object"),
])
def test_a_refused_review_names_its_field_and_writes_nothing(desk, desk_class, body, field):
    if isinstance(body, dict) and body.get("id") == "ID":
        body["id"] = _ids(desk)["dee"]
    before = _state(desk_class)
    reply = ask(desk.url, "POST", "/api/review", body)
    assert reply.status == 400 and field in reply.json()["error"]
    assert "Traceback" not in reply.text
    assert _state(desk_class) == before


def test_nothing_written_is_nothing_to_review(desk, desk_class):
    reply = ask(desk.url, "POST", "/api/review",
                {"id": _ids(desk, FAMILY_WRITTEN)["cyd"], "rubric": [0]})
    assert reply.status == 400 and "nothing to review" in reply.json()["error"]


def test_a_rubric_items_points_rescore_everyone_who_has_it(desk, desk_class):
    ids = _ids(desk)
    for sid, items in (("dee", [2]), ("eve", [0, 1])):
        ask(desk.url, "POST", "/api/review", {"id": ids[sid], "rubric": items})
    question = ask(desk.url, "POST", "/api/rubric",
                   {"question": OWN, "item": 2, "points": 3}).json()
    assert [r["points"] for r in question["rubric"]] == [RUBRIC[0], RUBRIC[1], 3.0]
    assert question["points"] == RUBRIC[0] + RUBRIC[1] + 3.0
    points = {sid: next(a.verdict.points for a in read_result(
        desk_class.out / RESULTS / f"{sid}.json").answers if a.variable == OWN)
        for sid in ("dee", "eve")}
    assert points == {"dee": 3.0, "eve": RUBRIC[0] + RUBRIC[1]}
    assert ask(desk.url, "POST", "/api/rubric", {"question": OWN, "item": 5,
                                                 "points": 1}).status == 400


def test_reusable_comments_are_kept_and_taken_back(desk):
    path = f"/api/comments?question={OWN}"
    assert ask(desk.url, "GET", path).json() == {}
    kept = ask(desk.url, "POST", "/api/comments",
               {"question": OWN, "name": "ends", "text": "Argue both ends."}).json()
    assert kept == {"ends": "Argue both ends."} == ask(desk.url, "GET", path).json()
    assert ask(desk.url, "POST", "/api/comments",
               {"question": OWN, "name": "ends", "text": None}).json() == {}
    assert ask(desk.url, "GET", "/api/comments?question=q9_nothing").status == 400


def test_flagged_answers_carry_the_students_value_and_the_keys(desk, desk_class):
    key = json.loads((desk_class.hw / "key.json").read_text())
    rate = {sid: next(a["value"] for q in key["students"][sid]["questions"]
                      for a in q["answers"] if a["name"] == "rate") for sid in ("eve", "fay")}
    rows = {(f["student"], f["variable"]): f for f in ask(desk.url, "GET", "/api/flagged").json()}
    assert rows[("fay", "q1_rate")]["why"] == "invalid"
    assert rows[("fay", "q1_rate")]["submitted"] == "fast"
    assert rows[("eve", "q1_rate")]["why"] == "within twice the tolerance"
    assert rows[("eve", "q1_rate")]["submitted"] == pytest.approx(rate["eve"] * 1.0015)
    assert rows[("eve", "q1_rate")]["key"] == pytest.approx(rate["eve"])
    assert rows[("fay", "q1_stable2")]["why"] == "known mistake: wrong_stability"
    assert {s for s, _ in rows} == {"eve", "fay"}


def test_an_override_from_the_desk_is_eulertop_override(desk, desk_class, tmp_path):
    twin = tmp_path / "twin"
    shutil.copytree(desk_class.hw.parent, twin, symlinks=True)
    ask(desk.url, "POST", "/api/override", {"student": "eve", "answer": "q1_rate",
                                            "points": 0.75, "reason": "rounding"})
    assert main(["override", str(twin / "HW"), "eve", "q1_rate", "--points", "0.75",
                 "--reason", "rounding"]) == 0
    mine = read_result(desk_class.out / RESULTS / "eve.json")
    theirs = read_result(twin / "HW" / "graded" / RESULTS / "eve.json")
    assert mine.points == theirs.points
    assert mine.overridden["q1_rate"]["by"] == "ta-one"
    assert {k: v for k, v in mine.overridden["q1_rate"].items() if k not in ("at", "by")} == \
        {k: v for k, v in theirs.overridden["q1_rate"].items() if k not in ("at", "by")}
    assert [x["event"] for x in read_trail(desk_class.out)][-1] == \
        [x["event"] for x in read_trail(twin / "HW" / "graded")][-1] == "override"
    removed = ask(desk.url, "POST", "/api/override",
                  {"student": "eve", "answer": "q1_rate", "remove": True}).json()
    assert removed["overridden"] == {}


def test_unknown_routes_and_questions_are_404_in_one_sentence(desk):
    assert ask(desk.url, "GET", "/api/nothing").json()["error"] == "no API reading /api/nothing"
    assert ask(desk.url, "POST", "/api/questions", {}).status == 404
    page = ask(desk.url, "GET", "/question/q9_nothing")
    assert page.status == 404 and "no written question 'q9_nothing'" in page.text
    assert ask(desk.url, "GET", "/api/written").json()["error"] == "the query needs question=…"


def test_a_change_while_another_command_holds_the_class_is_409_and_readings_go_on(
        desk_class):
    """A grading run (here: the lock held by the test) holds the class longer than the
    desk's ``--wait``: the review is refused, naming the holder, and nothing is written; the
    desk still answers readings meanwhile, and the same review lands once the class is free."""
    from eulertop.review_app.server import ReviewServer
    from grader.review import ReviewSession
    from grader.transaction import class_lock

    with ReviewSession(desk_class.hw, grader="ta-one", wait=0.3) as session:
        server = ReviewServer(session).start()
        try:
            body = {"id": _ids(Served(server))["dee"], "rubric": [0]}
            before = _state(desk_class)
            with class_lock(desk_class.out, desk_class.hw, command="eulertop grade"):
                refused = ask(server.url, "POST", "/api/review", body)
                assert ask(server.url, "GET", "/api/questions").status == 200
            assert refused.status == 409 and "eulertop grade" in refused.json()["error"]
            assert _state(desk_class) == before
            assert ask(server.url, "POST", "/api/review", body).status == 200
        finally:
            server.stop()
            server.join(10)


class Served:
    """What :func:`_ids` needs of a desk: its address."""

    def __init__(self, server) -> None:
        self.url = server.url


def test_every_template_and_static_file_is_package_data():
    """An installed wheel has the desk's pages: pyproject.toml's package data names every
    file beside the app (a built wheel held all 8 when this was written)."""
    import fnmatch
    import tomllib
    from pathlib import Path

    from eulertop.review_app import server

    root = Path(server.__file__).parent
    pyproject = tomllib.loads((root.parents[1] / "pyproject.toml").read_text())
    patterns = pyproject["tool"]["setuptools"]["package-data"]["eulertop.review_app"]
    files = [p.relative_to(root).as_posix() for folder in ("templates", "static")
             for p in (root / folder).iterdir()]
    assert len(files) >= 8
    assert [f for f in files if not any(fnmatch.fnmatch(f, pat) for pat in patterns)] == []
