"""Fixtures of the review desk's tests.

``pristine``
    The small graded class of :mod:`tests.review_app.desk_class`, made once.
``desk_class``
    A copy of it of the test's own.
``serve``
    ``serve(desk_class, grader)``: a desk on that class, serving in a thread; stopped (and its
    session closed) after the test.
``browser``
    One headless Chromium for the module (missing is a failure, never a skip). Playwright's
    sync API leaves its event loop marked running in the thread while it lives, so that
    ``asyncio.run`` (nbclient's kernels among its callers) fails there: the browser lives no
    longer than the module that uses it, and the class is made before it starts.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass

import pytest

from eulertop.review_app.server import ReviewServer
from grader.review import ReviewSession
from tests.review_app import browser as chromium
from tests.review_app.desk_class import DeskClass, build


@pytest.fixture(scope="session")
def pristine(tmp_path_factory) -> DeskClass:
    return build(tmp_path_factory.mktemp("desk"))


@pytest.fixture
def desk_class(pristine, tmp_path) -> DeskClass:
    root = tmp_path / "class"
    shutil.copytree(pristine.hw.parent, root, symlinks=True)
    return DeskClass(root / "HW", root / "HW" / "graded", root / "subs")


@dataclass
class Served:
    session: ReviewSession
    server: ReviewServer

    @property
    def url(self) -> str:
        return self.server.url

    @property
    def base(self) -> str:
        return self.server.url.split("/?")[0]


@pytest.fixture
def serve():
    started: list[Served] = []

    def start(made: DeskClass, grader: str = "ta-one") -> Served:
        session = ReviewSession(made.hw, grader=grader)
        served = Served(session, ReviewServer(session).start())
        started.append(served)
        return served

    yield start
    for served in started:
        served.server.stop()
        served.server.join(10)
        served.session.close()


@pytest.fixture(scope="module")
def browser(pristine):
    why = chromium.missing()
    if why is not None:
        pytest.fail(why)
    with chromium.launch() as b:
        yield b
