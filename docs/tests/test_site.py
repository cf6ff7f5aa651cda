"""The built documentation site, page by page, in headless Chromium.

Run after the build, as ``.ci/run`` does::

    python -m sphinx -W -b html docs docs/_build/html
    python -m pytest docs/tests

It builds nothing itself (``EULERTOP_SITE`` names another built site). Every page of the site —
one per Markdown page and notebook in ``docs/`` (``docs/conf.py``'s exclusions applied), and the
index, search and module pages Sphinx adds — is opened from disk (``file://``, as a reader who
downloaded it would) in one headless Chromium driven over the DevTools protocol on a pipe
(``--remote-debugging-pipe``). For each page: no script error and nothing logged at error level
on the console; no request to anything but a local file or inline data (the site works offline,
MathJax included); every image loaded; and, once MathJax has finished, every formula typeset,
none of them a TeX error or of zero width, and no MathJax font failed to load. Chromium is
Debian's ``chromium``, which ``.ci/run`` installs; a missing browser or site fails, never skips.
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import runpy
import select
import shutil
import subprocess
import time
from pathlib import Path

import pytest
from sphinx.util.matching import Matcher

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
SITE = Path(os.environ.get("EULERTOP_SITE", DOCS / "_build" / "html"))
BUILD = "python -m sphinx -W -b html docs docs/_build/html"
SPECIAL_PAGES = ("genindex", "search", "py-modindex")
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--remote-debugging-pipe")
LOAD_TIMEOUT = 60  # s for one page to load and MathJax to finish

# What a page reports once it has loaded and MathJax (where the page loads it) is done.
INSPECT = r"""(async () => {
  if (window.MathJax && MathJax.startup && MathJax.startup.promise) {
    await MathJax.startup.promise;
  }
  await document.fonts.ready;
  const sources = [...document.querySelectorAll('.math')];
  return {
    formulas: sources.length,
    display: document.querySelectorAll('div.math').length,
    typeset: sources.filter(e => e.querySelector('mjx-container')).length,
    tex_errors: document.querySelectorAll('mjx-merror').length,
    empty: [...document.querySelectorAll('mjx-container')]
      .filter(c => c.getBoundingClientRect().width === 0).length,
    fonts_failed: [...document.fonts].filter(f => f.status === 'error').map(f => f.family),
    images_broken: [...document.images].filter(i => !(i.complete && i.naturalWidth > 0))
      .map(i => i.src),
    images: document.images.length,
    cell_outputs: document.querySelectorAll('.cell_output').length,
  };
})()"""


def docnames() -> list[str]:
    """Every page the build makes from ``docs/``: its sources, found as Sphinx finds them (links
    followed, an excluded folder left whole), less ``conf.py``'s exclusions."""
    excluded = Matcher(runpy.run_path(str(DOCS / "conf.py"))["exclude_patterns"])
    names = []
    for folder, subfolders, files in os.walk(DOCS, followlinks=True):
        here = Path(folder).relative_to(DOCS)
        subfolders[:] = [d for d in subfolders if not excluded((here / d).as_posix())]
        for file in files:
            relative = (here / file).as_posix()
            if file.endswith((".md", ".ipynb")) and not excluded(relative):
                names.append(relative.rsplit(".", 1)[0])
    return sorted(names)


PAGES = [*docnames(), *SPECIAL_PAGES]


class Chromium:
    """One headless Chromium, driven over the DevTools protocol on fds 3 and 4."""

    def __init__(self, executable: str, profile: Path) -> None:
        to_browser, self._out = os.pipe()
        self._in, from_browser = os.pipe()
        # the browser's ends above fds 3 and 4, so that the redirections cannot overwrite them
        # (bash, not dash: dash takes no fd number above 9)
        ends = [fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (to_browser, from_browser)]
        for fd in (to_browser, from_browser):
            os.close(fd)
        redirect = f'exec "$0" "$@" 3<&{ends[0]} 4>&{ends[1]} {ends[0]}<&- {ends[1]}>&-'
        self.process = subprocess.Popen(
            ["bash", "-c", redirect, executable, *CHROMIUM_FLAGS,
             f"--user-data-dir={profile}", "about:blank"],
            pass_fds=ends, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for fd in ends:
            os.close(fd)
        self._buffer, self._count, self.events = b"", 0, []
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = self.call("Target.attachToTarget",
                                 {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Runtime", "Log", "Network", "Page"):
            self.call(f"{domain}.enable", session=self.session)

    def _message(self, deadline: float) -> dict:
        while b"\0" not in self._buffer:
            ready, _, _ = select.select([self._in], [], [], max(0.0, deadline - time.monotonic()))
            if not ready:
                raise TimeoutError("Chromium did not answer in time")
            chunk = os.read(self._in, 1 << 16)
            if not chunk:
                raise EOFError("Chromium closed its pipe")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def call(self, method: str, params: dict | None = None, session: str | None = None,
             timeout: float = LOAD_TIMEOUT) -> dict:
        """Send one command; its result (events that arrive meanwhile go to ``events``)."""
        self._count += 1
        command = {"id": self._count, "method": method, "params": params or {}}
        if session:
            command["sessionId"] = session
        os.write(self._out, json.dumps(command).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            message = self._message(deadline)
            if message.get("id") == self._count:
                assert "error" not in message, (method, message["error"])
                return message["result"]
            self.events.append(message)

    def wait_for(self, method: str, timeout: float = LOAD_TIMEOUT) -> dict:
        deadline = time.monotonic() + timeout
        while not any(e.get("method") == method for e in self.events):
            self.events.append(self._message(deadline))
        return next(e for e in self.events if e.get("method") == method)

    def visit(self, url: str) -> tuple[dict, list[dict]]:
        """Load ``url``; what :data:`INSPECT` finds there, and every event of the load."""
        self.events = []
        self.call("Page.navigate", {"url": url}, session=self.session)
        self.wait_for("Page.loadEventFired")
        found = self.call("Runtime.evaluate", {"expression": INSPECT, "awaitPromise": True,
                                               "returnByValue": True}, session=self.session)
        assert "exceptionDetails" not in found, found
        return found["result"]["value"], self.events

    def close(self) -> None:
        try:
            self.call("Browser.close", timeout=10)
        except (EOFError, TimeoutError, OSError):
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self._in)
        os.close(self._out)


@pytest.fixture(scope="module")
def site() -> Path:
    if not (SITE / "index.html").is_file():
        pytest.fail(f"no built site in {SITE}: run `{BUILD}` first (.ci/run does)",
                    pytrace=False)
    return SITE


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    executable = shutil.which("chromium") or shutil.which("chromium-browser")
    if executable is None:
        pytest.fail("chromium is not installed: `apt-get install chromium` (.ci/run does); "
                    "the site must be checked in a browser, never skipped", pytrace=False)
    chromium = Chromium(executable, tmp_path_factory.mktemp("chromium-profile"))
    yield chromium
    chromium.close()


@pytest.fixture(scope="module")
def visits(site, browser):
    """Each page loaded once: ``{docname: (what INSPECT found, the load's events)}``."""
    cache: dict[str, tuple[dict, list[dict]]] = {}

    def visit(name: str) -> tuple[dict, list[dict]]:
        if name not in cache:
            page = site / f"{name}.html"
            assert page.is_file(), f"the build made no {page.relative_to(site)}"
            cache[name] = browser.visit(page.as_uri())
        return cache[name]

    return visit


def console_errors(events: list[dict]) -> list[str]:
    """Script errors, error-level console and log entries, and loads that failed."""
    found = []
    for event in events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.exceptionThrown":
            found.append(f"exception: {params['exceptionDetails'].get('text')}")
        elif method == "Runtime.consoleAPICalled" and params["type"] in ("error", "assert"):
            found.append(f"console.{params['type']}: {params['args']}")
        elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
            found.append(f"log: {params['entry']['text']} {params['entry'].get('url', '')}")
        elif method == "Network.loadingFailed":
            found.append(f"failed load: {params.get('errorText')}")
    return found


def remote_requests(events: list[dict]) -> list[str]:
    """Every request the page made for anything but a local file or inline data."""
    urls = [e["params"]["request"]["url"] for e in events
            if e.get("method") == "Network.requestWillBeSent"]
    return [url for url in urls if not url.startswith(("file:", "data:", "about:"))]


@pytest.mark.parametrize("name", PAGES)
def test_page_loads_offline_without_a_console_error(visits, name):
    found, events = visits(name)
    assert console_errors(events) == []
    assert remote_requests(events) == []
    assert found["images_broken"] == []


@pytest.mark.parametrize("name", PAGES)
def test_every_formula_of_the_page_is_typeset(visits, name):
    found, _ = visits(name)
    assert found["typeset"] == found["formulas"]
    assert found["tex_errors"] == 0 and found["empty"] == 0
    assert found["fonts_failed"] == []


def test_the_physics_page_shows_every_display_formula_of_its_source(visits):
    """R1–R21's display formulas (``$$ … $$`` in docs/physics/index.md) are all on the page,
    typeset — the page is not formula-free by accident."""
    source = (DOCS / "physics" / "index.md").read_text(encoding="utf-8")
    display = len(re.findall(r"\$\$.+?\$\$", source, re.S))
    found, _ = visits("physics/index")
    assert display >= 21 and found["display"] == display
    assert found["typeset"] == found["formulas"] > display  # inline formulas too


def test_the_lecture_notebook_shows_every_display_formula_of_its_markdown(visits):
    """lecture24's formulas are LaTeX, as the physics page's are (issue 33): each ``$$ … $$`` of
    its markdown cells is on its page, typeset, with its inline formulas."""
    cells = json.loads((ROOT / "notebooks" / "lecture24.ipynb").read_text())["cells"]
    source = "".join("".join(c["source"]) for c in cells if c["cell_type"] == "markdown")
    display = len(re.findall(r"\$\$.+?\$\$", source, re.S))
    found, _ = visits("notebooks/lecture24")
    assert display >= 10 and found["display"] == display
    assert found["typeset"] == found["formulas"] > display


@pytest.mark.parametrize("notebook", sorted((ROOT / "notebooks").glob("*.ipynb")),
                         ids=lambda p: p.name)
def test_each_notebook_is_a_page_with_its_outputs_and_figures(visits, notebook):
    """The notebooks are committed without outputs: what the page shows, the build executed.
    A notebook that draws (``plt.``) has its figures on its page."""
    code = [c["source"] for c in json.loads(notebook.read_text())["cells"]
            if c["cell_type"] == "code"]
    found, _ = visits(f"notebooks/{notebook.stem}")
    assert found["cell_outputs"] > 0
    if any("plt." in "".join(source) for source in code):
        assert found["images"] > 0
