"""The desk in a real browser (issue 31): Debian's Chromium driven by Playwright — a review
made with the keyboard alone, two browsers and two desks at once, the refusals a browser
meets, a hostile answer inert, the flagged view's override, and axe-core's WCAG 2.1 AA rules
on every page of the desk, every feedback page and the class report.

What lands is read from the class's files (records, ``reviews.json``, the trail), and the
points expected are worked out from the rubric the spec declares
(:data:`tests.review_app.desk_class.RUBRIC`)."""

from __future__ import annotations

import json

import pytest

from grader.audit import read_trail
from grader.graded_folder import RESULTS
from grader.results import read_result
from grader.reviews import REVIEWS
from tests.review_app.browser import open_desk, question_page, violations
from tests.review_app.desk_class import BEACON, FAMILY_WRITTEN, OWN, RUBRIC, STUDENTS


@pytest.fixture
def context(browser):
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    yield context
    context.close()


def _points(made, sid: str, variable: str = OWN) -> tuple[str, float]:
    answer = next(a for a in read_result(made.out / RESULTS / f"{sid}.json").answers
                  if a.variable == variable)
    return answer.verdict.status, answer.verdict.points


def _student(served, answer_id: str) -> str:
    return next(a["student"] for q in (OWN, FAMILY_WRITTEN)
                for a in served.session.written(q) if a["id"] == answer_id)


def _shown(page) -> str:
    return page.get_attribute("#desk", "data-shown")


def _next_shown(page, before: str) -> str:
    page.wait_for_function("b => document.querySelector('#desk').dataset.shown !== b",
                           arg=before)
    return _shown(page)


# -- keyboard


def test_a_review_made_with_the_keyboard_alone(desk_class, serve, context):
    served = serve(desk_class)
    page = question_page(context, served.url, OWN)
    first = _shown(page)
    page.keyboard.press("1")
    page.keyboard.press("3")
    assert page.text_content("#score") == (
        f"Score with this review: {RUBRIC[0] + RUBRIC[2]:g} of {sum(RUBRIC):g} points.")
    page.keyboard.press("s")
    second = _next_shown(page, first)  # submitted, and on to the next pending answer
    assert page.text_content("#status").startswith("Saved answer")
    page.keyboard.press("2")
    page.keyboard.press("a")
    page.keyboard.press("Control+a")
    page.keyboard.type("0.5")
    page.keyboard.press("Escape")
    page.keyboard.press("c")
    page.keyboard.type("Argue the *minimum*.")
    page.keyboard.press("Control+Enter")  # submits from inside the comment
    third = _next_shown(page, second)
    assert _points(desk_class, _student(served, first)) == ("reviewed", RUBRIC[0] + RUBRIC[2])
    assert _points(desk_class, _student(served, second)) == ("reviewed", RUBRIC[1] + 0.5)
    page.keyboard.press("k")  # back: the review as it was submitted
    assert _next_shown(page, third) == second
    assert page.is_checked("#item-1") and not page.is_checked("#item-0")
    assert page.input_value("#adjust") == "0.5"
    assert page.input_value("#comment") == "Argue the *minimum*."
    page.keyboard.press("j")
    assert _next_shown(page, second) == third
    assert page.text_content("#progress-text").startswith("2 of 6 written answers reviewed")


def test_leaving_an_unsubmitted_review_asks_first(desk_class, serve, context):
    served = serve(desk_class)
    page = question_page(context, served.url, OWN)
    first = _shown(page)
    page.keyboard.press("2")
    page.keyboard.press("j")
    assert _shown(page) == first and "not submitted" in page.text_content("#status")
    page.keyboard.press("j")
    assert _next_shown(page, first) != first
    assert not (desk_class.out / REVIEWS).exists()


def test_a_rubric_key_pressed_while_the_next_answer_loads_counts_for_it(desk_class, serve,
                                                                       context):
    served = serve(desk_class)
    page = question_page(context, served.url, OWN)
    first = _shown(page)
    page.keyboard.press("j")
    page.keyboard.press("3")
    assert _next_shown(page, first) != first
    page.wait_for_function("() => document.querySelector('#item-2').checked")
    assert not page.is_checked("#item-0")


def test_the_page_keeps_reusable_comments_and_changes_a_rubric_items_points(desk_class,
                                                                             serve, context):
    served = serve(desk_class)
    reviewed = next(a for a in served.session.written(OWN) if a["student"] == "dee")
    served.session.submit(reviewed["id"], [2], 0.0, "")
    page = question_page(context, served.url, OWN)
    page.fill("#comment", "Argue both ends.")
    page.fill("#save-name", "ends")
    page.click("#save-comment")
    page.wait_for_function("() => document.querySelector('#saved').options.length === 1")
    page.fill("#comment", "")
    page.click("#insert")
    assert page.input_value("#comment") == "Argue both ends."
    assert served.session.comments(OWN) == {"ends": "Argue both ends."}
    page.click("#rubric-points summary")
    page.fill("#points-2", "3")
    page.get_by_role("button", name="Set item 3's points").click()
    page.wait_for_function("() => document.querySelector('#status').textContent"
                           ".startsWith('Item 3 is now worth 3 points')")
    assert _points(desk_class, "dee") == ("reviewed", 3.0)
    assert "(3 points)" in page.text_content("#items")


def test_a_pasted_image_is_shown_from_the_page_itself(desk_class, serve, context):
    served = serve(desk_class)
    bob = next(a["id"] for a in served.session.written(OWN) if a["student"] == "bob")
    page = open_desk(context, served.url)
    page.goto(f"{served.base}/question/{OWN}#{bob}")
    page.wait_for_selector("#desk[data-ready]")
    image = page.locator("#text img")
    assert image.get_attribute("alt") == "sketch.png"
    assert image.evaluate("i => i.complete && i.naturalWidth") == 1


def test_shortcuts_can_be_turned_off(desk_class, serve, context):
    """WCAG 2.1.4: single-key shortcuts can be turned off."""
    served = serve(desk_class)
    page = question_page(context, served.url, OWN)
    page.uncheck("#shortcuts")
    page.focus("#names")
    page.keyboard.press("1")
    assert not page.is_checked("#item-0")
    page.check("#shortcuts")
    page.keyboard.press("1")
    assert page.is_checked("#item-0")


@pytest.mark.parametrize("path", ["/", f"/question/{OWN}", "/flagged"])
def test_every_control_is_reached_with_tab(desk_class, serve, context, path):
    served = serve(desk_class)
    page = open_desk(context, served.url, path)
    page.wait_for_load_state("networkidle")
    page.evaluate("document.querySelectorAll('details').forEach(d => d.open = true)")
    controls = set(page.evaluate("""[...document.querySelectorAll(
        'a[href], button, input, select, textarea, summary')].filter(e => !e.disabled &&
        e.offsetParent !== null).map(e => e.id || e.textContent.trim())"""))
    reached: list[str] = []
    for _ in range(2 * len(controls) + 10):  # Tab until the focus comes round again
        page.keyboard.press("Tab")
        reached.append(page.evaluate("document.activeElement.id || "
                                     "document.activeElement.textContent.trim()"))
        if len(reached) > 1 and reached[-1] == reached[0]:
            break
    assert controls and controls <= set(reached)


def test_names_are_hidden_until_asked_for(desk_class, serve, context):
    served = serve(desk_class)
    page = question_page(context, served.url, OWN)
    assert page.text_content("#who").startswith("Anonymous")
    assert not any(name in page.content() for name in STUDENTS.values())
    shown = _shown(page)
    page.check("#names")
    page.wait_for_function(
        "() => !document.querySelector('#who').textContent.startsWith('Anon')")
    sid = _student(served, shown)
    assert page.text_content("#who").startswith(f"{sid} ({STUDENTS[sid]})")


# -- many graders


def _review_by_keys(page, keys: str) -> str:
    shown = _shown(page)
    for key in keys:
        page.keyboard.press(key)
    page.keyboard.press("s")
    page.wait_for_function("a => document.querySelector('#desk').dataset.saved === a",
                           arg=shown)
    return shown


def test_two_desks_and_two_browsers_review_at_once(desk_class, serve, browser):
    """Two TAs, each on their own desk (``--grader``), and a second browser on the first
    desk: their reviews interleave, every one lands, attributed, and each desk shows what
    the other did."""
    one, two = serve(desk_class, "ta-one"), serve(desk_class, "ta-two")
    contexts = [browser.new_context() for _ in range(3)]
    pages = [question_page(contexts[0], one.url, OWN), question_page(contexts[1], two.url, OWN),
             question_page(contexts[2], one.url, FAMILY_WRITTEN)]
    made = []  # (answer id, reviewer, items)
    plan = [(0, "13"), (1, "2"), (2, "12"), (0, "3"), (1, "123"), (2, "3")]
    for which, keys in plan:
        page = pages[which]
        if made:  # the next answer pending now (the other desk's reviews counted)
            before = _shown(page)
            page.keyboard.press("n")
            _next_shown(page, before)
        made.append((_review_by_keys(page, keys), ("ta-one", "ta-two", "ta-one")[which], keys))
    ids = {a for a, _, _ in made}
    assert len(ids) == len(made)  # no answer reviewed twice: each desk saw the others' work
    stored = json.loads((desk_class.out / REVIEWS).read_text())["reviews"]
    lines = [x for x in read_trail(desk_class.out) if x["event"] == "review"]
    want = sorted((_student(one, a), by) for a, by, _ in made)
    assert sorted((r["student"], r["by"]) for r in stored) == want
    assert sorted((x["student"], x["review"]["by"]) for x in lines) == want
    for answer, _, keys in made:
        sid = _student(one, answer)
        variable = next(v for v in (OWN, FAMILY_WRITTEN)
                        if any(a["id"] == answer for a in one.session.written(v)))
        if variable == OWN:
            assert _points(desk_class, sid) == ("reviewed", sum(RUBRIC[int(k) - 1]
                                                                for k in keys))
    theirs = made[1][0]
    pages[0].goto(f"{one.base}/question/{OWN}#{theirs}")
    # the page is already on this question: only its fragment changes, and the desk shows that
    # answer once it has fetched it (reading before then raced the fetch)
    pages[0].wait_for_function("id => document.querySelector('#desk').dataset.shown === id",
                               arg=theirs)
    assert pages[0].text_content("#reviewed-by").startswith("Reviewed by ta-two")
    for context in contexts:
        context.close()


# -- refusals


def test_a_browser_without_the_token_or_at_another_name_is_refused(desk_class, serve, context):
    served = serve(desk_class)
    page = context.new_page()
    response = page.goto(served.base + "/")
    assert response.status == 401 and "needs its token" in page.text_content("body")
    port = served.base.rsplit(":", 1)[1]
    response = page.goto(f"http://rebind.test:{port}/?token={served.url.rsplit('=', 1)[1]}")
    assert response.status == 403 and "not this desk's address" in page.text_content("body")
    assert page.context.cookies() == []  # the rebound name got no cookie


def test_another_site_cannot_make_a_change_with_the_tas_cookie(desk_class, serve, context):
    """The TA has the desk open; a page of another site (served here by Playwright's
    router) posts a review by script and by a form: refused, nothing written."""
    served = serve(desk_class)
    open_desk(context, served.url)
    target = next(a["id"] for a in served.session.written(OWN) if a["status"] == "pending")
    attack = f"""<!DOCTYPE html><html><body>
      <form id="f" method="POST" action="{served.base}/api/review" enctype="text/plain">
        <input name='{{"id": "{target}", "rubric": [0], "x": "' value='"}}'></form>
      <script>
        fetch("{served.base}/api/review", {{method: "POST", credentials: "include",
          mode: "no-cors", headers: {{"Content-Type": "text/plain"}},
          body: JSON.stringify({{id: "{target}", rubric: [0, 1, 2]}})}})
          .finally(() => document.getElementById("f").submit());
      </script></body></html>"""
    context.route("http://evil.test/", lambda route: route.fulfill(
        status=200, content_type="text/html", body=attack))
    posted = []
    context.on("request", lambda r: posted.append(r.url) if r.method == "POST" else None)
    page = context.new_page()
    page.goto("http://evil.test/")
    page.wait_for_timeout(300)
    page.wait_for_load_state()
    assert len(posted) == 2  # both tries were made
    assert not (desk_class.out / REVIEWS).exists()
    assert [x for x in read_trail(desk_class.out) if x["event"] == "review"] == []


# -- a hostile answer


SPY = """
window.__seen = {dialogs: 0, violations: []};
document.addEventListener('securitypolicyviolation',
  e => window.__seen.violations.push(e.violatedDirective + ' ' + e.blockedURI));
"""


def test_a_hostile_answer_runs_nothing_and_loads_nothing(desk_class, serve, context):
    served = serve(desk_class)
    ada = next(a["id"] for a in served.session.written(OWN) if a["student"] == "ada")
    foreign, dialogs = [], []
    context.add_init_script(SPY)
    context.on("request", lambda r: foreign.append(r.url)
               if not r.url.startswith((served.base, "data:")) else None)
    page = open_desk(context, served.url)
    page.on("dialog", lambda d: (dialogs.append(d.message), d.dismiss()))
    page.goto(f"{served.base}/question/{OWN}#{ada}")
    page.wait_for_selector("#desk[data-ready]")
    assert _shown(page) == ada and BEACON in page.text_content("#text")
    page.hover("#text")
    page.click("#text")
    for _ in range(5):
        page.keyboard.press("Tab")
    page.wait_for_timeout(300)
    assert dialogs == [] and foreign == []
    assert page.evaluate("window.pwned") is None
    assert page.evaluate("window.__seen.violations") == []  # nothing even tried
    found = page.evaluate("""[...document.querySelectorAll('#text *')].flatMap(e =>
        [e.localName].concat([...e.attributes].map(a => e.localName + '@' + a.name)))""")
    assert not [f for f in found if f.split("@")[0] in ("script", "svg", "a", "iframe", "form",
                                                        "object", "style", "link", "meta")]
    assert not [f for f in found if "@on" in f or f.endswith(("@href", "@style", "@src"))]
    assert page.evaluate("getComputedStyle(document.body).display") == "block"


def test_the_feedback_page_of_a_hostile_answer_is_inert_too(desk_class, context):
    foreign, dialogs = [], []
    context.on("request", lambda r: foreign.append(r.url)
               if not r.url.startswith(("file:", "data:")) else None)
    page = context.new_page()
    page.on("dialog", lambda d: (dialogs.append(d.message), d.dismiss()))
    page.goto((desk_class.out / "feedback" / "ada.html").as_uri())
    page.hover("body")
    page.wait_for_timeout(200)
    assert dialogs == [] and foreign == [] and BEACON in page.text_content("body")


# -- flagged


def test_an_override_from_the_flagged_view_with_the_keyboard(desk_class, serve, context):
    served = serve(desk_class)
    page = open_desk(context, served.url, "/flagged")
    page.wait_for_selector("#flagged tbody tr")
    assert page.text_content("#count") == "3 answers flagged."
    row = page.locator("#flagged tbody tr", has_text="within twice the tolerance")
    assert "eve" in row.text_content()
    row.get_by_role("button").focus()
    page.keyboard.press("Enter")
    assert page.evaluate("document.activeElement.id") == "override-points"
    page.keyboard.press("Control+a")
    page.keyboard.type("0.75")
    page.keyboard.press("Tab")
    page.keyboard.type("within rounding of the key")
    page.keyboard.press("Enter")
    page.wait_for_function("() => document.querySelector('#status').textContent"
                           ".startsWith('Overrode')")
    record = read_result(desk_class.out / RESULTS / "eve.json")
    override = record.overridden["q1_rate"]
    assert (override["points"], override["reason"], override["by"]) == (
        0.75, "within rounding of the key", "ta-one")
    assert [x for x in read_trail(desk_class.out) if x["event"] == "override"][-1][
        "student"] == "eve"
    page.wait_for_function("() => document.querySelector('#flagged tbody').textContent"
                           ".includes('within rounding of the key')")


# -- accessibility


def test_every_page_of_the_desk_passes_axe(desk_class, serve, context):
    served = serve(desk_class)
    found = {}
    page = open_desk(context, served.url)
    found["index"] = violations(page)
    page = question_page(context, served.url, OWN)
    found["question"] = violations(page)
    page.check("#names")
    page.evaluate("document.querySelectorAll('details').forEach(d => d.open = true)")
    page.keyboard.press("2")
    page.keyboard.press("j")  # the warning shown
    found["question, all open"] = violations(page)
    page.goto(f"{served.base}/question/{FAMILY_WRITTEN}")
    page.wait_for_selector("#desk[data-ready]")
    found["the other question"] = violations(page)
    page = open_desk(context, served.url, "/flagged")
    page.wait_for_selector("#flagged tbody tr")
    page.locator("#flagged tbody button").first.click()
    found["flagged, override open"] = violations(page)
    assert {name: v for name, v in found.items() if v} == {}


def test_every_feedback_page_and_the_report_pass_axe(desk_class, serve, context):
    served = serve(desk_class)
    for answer in served.session.written(OWN)[:3]:
        served.session.submit(answer["id"], [0, 2], -0.5, "A comment with $\\omega$.")
    served.session.override("eve", "q1_rate", 0.5, "close enough")
    served.session.close()  # the report rebuilt, with its written answers
    pages = [*sorted((desk_class.out / "feedback").glob("*.html")),
             desk_class.out / "report.html"]
    page = context.new_page()
    found = {}
    for path in pages:
        page.goto(path.as_uri())
        found[path.name] = violations(page)
    assert len(found) == len(STUDENTS) + 1
    assert {name: v for name, v in found.items() if v} == {}
