"""Benchmark the review desk's web app (issue 31, ``eulertop review``) on a class of
``--students`` (600), in Debian's Chromium driven by Playwright, as a TA uses it.

The class is :mod:`benchmarks.bench_review`'s: three written parts a student, a paragraph of
Markdown and LaTeX in each, graded without a kernel. The desk (a ``ReviewSession`` and its
server) runs in this process, in a thread; the browser in its own processes. Measured:

* the question page: from ``goto`` until its first answer is shown (the page, its script and
  style, the question, the 600 answers' list, the first answer's HTML), ``--loads`` times;
* "next" (key ``j``): from the key press until the next answer is shown, ``--moves`` times;
* a review (keys ``1``, ``3``, ``s``): from ``s`` until the desk has answered that it landed
  (the record, its page, ``grades.csv``, ``answers.csv``, ``reviews.json`` and the trail
  committed), and until the next pending answer is shown, ``--reviews`` times;
  each also timed in the page itself: from the key's ``keydown`` event to the moment the
  page changed what it shows (a ``MutationObserver`` on the desk's ``data-shown`` and
  ``data-saved``, installed by :data:`CLOCK`), which leaves out Playwright's own round trips;
* the same API calls over HTTP without the browser (``http.client``): the answers' list, one
  answer with its HTML, the pending ids, a review.

Medians (and the slowest) of one run. Run from the repository root::

    PYTHONPATH=. python benchmarks/bench_review_app.py [--students 600]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


CLOCK = """
window.__clock = {keys: [], shown: [], saved: []};
document.addEventListener('keydown', e => window.__clock.keys.push([e.key, e.timeStamp]), true);
document.addEventListener('DOMContentLoaded', () => {
  const desk = document.getElementById('desk');
  if (desk) new MutationObserver(changes => { for (const c of changes)
      window.__clock[c.attributeName.slice(5)].push(performance.now()); })
    .observe(desk, {attributes: true, attributeFilter: ['data-shown', 'data-saved']});
});
"""
"""The in-page clock (module docstring): key presses and the desk's changes, timestamped."""


def in_page(page, key: str, change: str) -> list[float]:
    """Seconds from each press of ``key`` to the first ``change`` (shown, saved) after it."""
    clock = page.evaluate("window.__clock")
    changes = sorted(clock[change])
    found = []
    for k, at in clock["keys"]:
        after = [t for t in changes if t > at]
        if k == key and after:
            found.append((after[0] - at) / 1000)
    return found


def _ms(samples: list[float]) -> str:
    return (f"median {1000 * statistics.median(samples):.1f} ms, slowest "
            f"{1000 * max(samples):.1f} ms over {len(samples)}")


def _timed(call) -> float:
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def page_loads(page, base: str, question: str, loads: int) -> list[float]:
    def load() -> None:
        page.goto(f"{base}/question/{question}")
        page.wait_for_selector("#desk[data-ready]")

    return [_timed(load) for _ in range(loads)]


def moves(page, count: int) -> list[float]:
    def move() -> None:
        before = page.get_attribute("#desk", "data-shown")
        page.keyboard.press("j")
        page.wait_for_function("b => document.querySelector('#desk').dataset.shown !== b",
                               arg=before)

    return [_timed(move) for _ in range(count)]


def reviews(page, count: int) -> tuple[list[float], list[float]]:
    landed, next_shown = [], []
    for _ in range(count):
        shown = page.get_attribute("#desk", "data-shown")
        page.keyboard.press("1")
        page.keyboard.press("3")
        start = time.perf_counter()
        page.keyboard.press("s")
        page.wait_for_function("a => document.querySelector('#desk').dataset.saved === a",
                               arg=shown)
        landed.append(time.perf_counter() - start)
        page.wait_for_function("a => document.querySelector('#desk').dataset.shown !== a",
                               arg=shown)
        next_shown.append(time.perf_counter() - start)
    return landed, next_shown


def api_calls(url: str, session, question: str, count: int) -> dict[str, list[float]]:
    from tests.review_app.client import ask

    answers = session.written(question)
    ids = [a["id"] for a in answers if a["status"] == "pending"][-count:]
    return {
        f"GET /api/written ({len(answers)} answers)": [
            _timed(lambda: ask(url, "GET", f"/api/written?question={question}"))
            for _ in range(count)],
        "GET /api/answer (with its HTML)": [
            _timed(lambda i=i: ask(url, "GET", f"/api/answer?id={i}")) for i in ids],
        "GET /api/pending": [
            _timed(lambda: ask(url, "GET", f"/api/pending?question={question}"))
            for _ in range(count)],
        "POST /api/review": [
            _timed(lambda i=i: ask(url, "POST", "/api/review", {"id": i, "rubric": [0]}))
            for i in ids],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, default=600)
    parser.add_argument("--loads", type=int, default=10)
    parser.add_argument("--moves", type=int, default=50)
    parser.add_argument("--reviews", type=int, default=50)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from benchmarks.bench_grade import machine
    from benchmarks.bench_review import build
    from tests.review_app.browser import launch

    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        hw = build(Path(tmp), args.students)  # before the browser: its loop blocks asyncio.run
        with launch() as browser:
            measure(browser, hw, args)


def measure(browser, hw: Path, args: argparse.Namespace) -> None:
    """Every measurement of the module docstring, printed, on a desk serving ``hw``."""
    from eulertop.review_app.server import ReviewServer
    from grader.review import ReviewSession
    from tests.review_app.browser import open_desk

    with ReviewSession(hw, grader="bench") as session:
        server = ReviewServer(session).start()
        base = server.url.split("/?")[0]
        question = session.questions()[0]["question"]
        context = browser.new_context(viewport={"width": 1280, "height": 900})
        context.add_init_script(CLOCK)
        page = open_desk(context, server.url)
        print(f"question page, goto until the first answer is shown: "
              f"{_ms(page_loads(page, base, question, args.loads))}")
        print(f"next (j) until the next answer is shown: {_ms(moves(page, args.moves))}; "
              f"in the page: {_ms(in_page(page, 'j', 'shown'))}")
        landed, next_shown = reviews(page, args.reviews)
        print(f"review (s) until the desk answered it landed: {_ms(landed)}; in the page: "
              f"{_ms(in_page(page, 's', 'saved'))}")
        print(f"review (s) until the next pending answer is shown: {_ms(next_shown)}; in the "
              f"page: {_ms(in_page(page, 's', 'shown'))}")
        for name, samples in api_calls(server.url, session, question, args.reviews).items():
            print(f"{name}, over HTTP: {_ms(samples)}")
        server.stop()
        server.join(30)


if __name__ == "__main__":
    main()
