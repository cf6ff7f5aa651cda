"""The page: self-contained, escaped, its one script pinned by the CSP — and rendered by a real
browser (Debian's headless ``chromium``, installed by ``.ci/run``) with its figures."""

from __future__ import annotations

import base64
import hashlib
import re
import subprocess
from dataclasses import replace

import numpy as np
import pytest
from matplotlib.image import imread

from grader.report import build_report, write_report
from grader.report.figures import COLOURS
from grader.report.page import SORT_SCRIPT, STYLE
from tests.grader.report.synthetic_class import CHROMIUM_FLAGS, PLANTED, chromium, screenshot


def _page(planted_class) -> str:
    return (planted_class.made.graded / "report.html").read_text(encoding="utf-8")


def _csp_hash(text: str) -> str:
    return "sha256-" + base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode()


def test_the_page_loads_nothing_from_anywhere(planted_class):
    page = _page(planted_class)
    sources = re.findall(r'\b(?:src|href)="([^"]*)"', page)
    assert sources and all(s.startswith(("data:", "#")) for s in sources)
    assert "http://" not in page and "https://" not in page
    policy = re.search(r'http-equiv="Content-Security-Policy" content="([^"]*)"', page).group(1)
    assert "default-src 'none'" in policy and "img-src data:" in policy


def test_the_policy_allows_exactly_the_pages_own_script_and_style(planted_class):
    page = _page(planted_class)
    policy = re.search(r'content="(default-src[^"]*)"', page).group(1)
    scripts = re.findall(r"<script>(.*?)</script>", page, flags=re.S)
    styles = re.findall(r"<style>(.*?)</style>", page, flags=re.S)
    assert scripts == [SORT_SCRIPT] and styles == [STYLE]
    assert f"script-src '{_csp_hash(scripts[0])}'" in policy
    assert f"style-src '{_csp_hash(styles[0])}'" in policy
    assert " style=" not in page and "onclick" not in page  # nothing the policy would block


def test_instructor_and_roster_text_is_escaped(planted_class, tmp_path):
    data = planted_class.report.data
    rows = tuple({**r, "name": "<img src=x onerror=alert(1)>"} for r in data.assignment.rows)
    hostile = replace(data, assignment=replace(data.assignment, title="<script>alert(1)</script>",
                                               rows=rows))
    page = write_report(build_report(hostile), tmp_path / "r.html").read_text(encoding="utf-8")
    assert "<script>alert(1)" not in page and "<img src=x" not in page
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page


def test_notebooks_not_the_students_own_are_listed_first_and_escaped(planted_class, tmp_path):
    """A record whose notebook is another variant's (or another student's) is named at the top
    and in the copying section; the why holds the student's own text, escaped."""
    data = planted_class.report.data
    first, second = data.graded[:2]
    why = "another variant's notebook: its parameters are not this student's (q1_M = " \
          "'<img src=x onerror=alert(1)>' where theirs is 1.5)"
    results = dict(data.results)
    results[second] = replace(results[second],
                              execution={**results[second].execution, "foreign": why})
    page = write_report(build_report(replace(data, results=results)),
                        tmp_path / "r.html").read_text(encoding="utf-8")
    escaped = why.replace("'", "&#x27;").replace("<", "&lt;").replace(">", "&gt;")
    assert f"the notebook graded as <b>{second}</b>'s: {escaped}" in page
    section = page.split('<h2 id="copying">')[1].split("<h3>Nearly identical code")[0]
    assert f"<td>{second}</td><td>{escaped}</td>" in section
    assert f"<td>{first}</td>" not in section and "<img src=x" not in page



def test_a_classmates_notebook_handed_in_is_listed_and_an_honest_class_lists_none(
        planted_class, honest_class):
    copier, source = PLANTED["notebook"]  # handed in the source's notebook as it is
    section = _page(planted_class).split("Notebooks that are not the student's own")[1]
    assert (f"<td>{copier}</td><td>another student&#x27;s notebook: its metadata names student "
            f"&#x27;{source}&#x27;</td>") in section.split("<h3>")[0]
    honest = (honest_class.made.graded / "report.html").read_text(encoding="utf-8")
    assert "None: no notebook graded is another student's or another variant's" \
        in honest and "the notebook graded as" not in honest


def test_the_same_records_give_the_same_page(planted_class, tmp_path):
    report = planted_class.report
    one = write_report(report, tmp_path / "one" / "report.html").read_bytes()
    two = write_report(report, tmp_path / "two" / "report.html").read_bytes()
    assert one == two


def test_the_csv_link_holds_the_student_table(planted_class):
    page = _page(planted_class)
    uri = re.search(r'href="data:text/csv;charset=utf-8;base64,([^"]*)"', page).group(1)
    written = (planted_class.made.graded / "report.csv").read_bytes().decode("utf-8")
    assert base64.b64decode(uri).decode("utf-8") == written


@pytest.fixture(scope="module")
def browser():
    """The path of chromium; missing is a failure, never a skip, here as in CI (README:
    ``.ci/run`` installs it)."""
    path = chromium()
    if path is None:
        pytest.fail("chromium is not installed (apt-get install chromium; .ci/run does it): "
                    "the page must be checked in a browser, never skipped", pytrace=False)
    return path


def test_chromium_runs_the_sort_script_under_the_policy_and_blocks_nothing(
        planted_class, browser, tmp_path):
    page = planted_class.made.graded / "report.html"
    run = subprocess.run([browser, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}",
                          "--enable-logging=stderr", "--v=0", "--dump-dom", page.as_uri()],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    dom = run.stdout
    tables = dom.count('class="sortable"')
    assert tables >= 3 and dom.count('data-sortable="on"') == tables  # the script ran
    assert dom.count('src="data:image/svg+xml;base64,') >= 4
    assert "Content Security Policy" not in run.stderr  # nothing refused


def test_chromium_renders_the_figures(planted_class, browser, tmp_path):
    png = tmp_path / "shot.png"
    screenshot(planted_class.made.graded / "report.html", png, tmp_path / "profile",
               size="1200,2600")
    pixels = imread(png)[..., :3]
    assert pixels.shape[:2] == (2600, 1200) and pixels.std() > 0.1

    def share(colour: str) -> float:
        rgb = np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)]) / 255
        return float(np.mean(np.all(np.abs(pixels - rgb) < 0.03, axis=-1)))

    # the histogram (blue) and the outcome bars (green, red) are drawn: the page's text and
    # tables use none of these colours
    for name in ("scores", "correct", "wrong"):
        assert share(COLOURS[name]) > 0.002, name
