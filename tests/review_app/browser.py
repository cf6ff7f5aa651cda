"""Debian's Chromium driven by Playwright for Python, and axe-core run in it, for the review
desk's browser tests and the docs' screenshots (issue 31).

Chromium is ``/usr/bin/chromium`` (``.ci/run`` installs it; Playwright downloads no browser of
its own). axe-core is the copy ``axe-playwright-python`` ships (its ``axe.min.js``), injected
into the page by Playwright, which the page's Content-Security-Policy does not govern; it runs
the rules tagged WCAG 2.0 and 2.1, levels A and AA (:data:`WCAG_21_AA`).
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

CHROMIUM = "/usr/bin/chromium"
FLAGS = ("--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync",
         "--host-resolver-rules=MAP rebind.test 127.0.0.1")  # a name rebound to the desk
WCAG_21_AA = ("wcag2a", "wcag2aa", "wcag21a", "wcag21aa")


def missing() -> str | None:
    """Why the browser tests cannot run here, or None."""
    if shutil.which(CHROMIUM) is None:
        return f"{CHROMIUM} is not installed (apt-get install chromium; .ci/run does it)"
    return None


@contextmanager
def launch() -> Iterator[Any]:
    """One headless Chromium (Playwright's sync API)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=list(FLAGS))
        try:
            yield browser
        finally:
            browser.close()


def violations(page: Any) -> list[str]:
    """axe-core's WCAG 2.1 A and AA violations on ``page``: one line each (rule, impact, the
    elements), empty when there is none."""
    from axe_playwright_python.sync_playwright import Axe

    found = Axe().run(page, options={"runOnly": {"type": "tag", "values": list(WCAG_21_AA)}})
    return [f"{v['id']} ({v['impact']}): {', '.join(str(n['target']) for n in v['nodes'])}"
            for v in found.response["violations"]]


def open_desk(context: Any, url: str, path: str = "/") -> Any:
    """A page of ``context`` that opened the desk's address with its token, then ``path``."""
    page = context.new_page()
    page.goto(url)
    if path != "/":
        page.goto(url.split("/?")[0] + path)
    return page


def question_page(context: Any, url: str, question: str) -> Any:
    """The page of ``question``, loaded (its first answer shown)."""
    page = open_desk(context, url, f"/question/{question}")
    page.wait_for_selector("#desk[data-ready]")
    return page


def screenshots(browser: Any, made: Any, out: Path) -> list[Path]:
    """The docs' screenshots of the desk on class ``made``: the question page with a review
    being made, and the flagged view."""
    from eulertop.review_app.server import ReviewServer
    from grader.review import ReviewSession
    from tests.review_app.desk_class import OWN

    out.mkdir(parents=True, exist_ok=True)
    with ReviewSession(made.hw, grader="ta-one") as session:
        server = ReviewServer(session).start()
        try:
            context = browser.new_context(viewport={"width": 1280, "height": 900})
            page = question_page(context, server.url, OWN)
            first = page.get_attribute("#desk", "data-shown")
            for key in "123s":  # a review of the first, and on to the next
                page.keyboard.press(key)
            page.wait_for_function("a => document.querySelector('#desk').dataset.shown !== a",
                                   arg=first)
            for key in "13":
                page.keyboard.press(key)
            page.fill("#comment", "Say why $V_\\text{eff} \\to +\\infty$ at both ends, and why "
                      "the stationary point is a *minimum* ($V_\\text{eff}'' > 0$).")
            shots = [out / "review.png", out / "review_flagged.png"]
            page.screenshot(path=str(shots[0]))
            flagged = open_desk(context, server.url, "/flagged")
            flagged.wait_for_selector("#flagged tbody tr")
            flagged.screenshot(path=str(shots[1]))
            context.close()
        finally:
            server.stop()
            server.join(10)
    return shots
