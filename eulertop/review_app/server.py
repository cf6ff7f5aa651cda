"""The review desk's web server (issue 31): Tornado on 127.0.0.1, every request guarded
(:mod:`eulertop.review_app.guard`), the pages and the JSON API over one
:class:`grader.review.ReviewSession`.

Routes: the pages ``/`` (the written questions and their progress), ``/question/NAME`` (one
question across all students) and ``/flagged`` (the answers the grader flagged, and overrides);
``/static/…`` (the app's own scripts and style, nothing else: Tornado's static handler refuses
any path that leaves the folder); the API ``/api/…`` (:mod:`eulertop.review_app.views`).

The session's calls run in a few worker threads, so the server keeps answering (pages, static
files) while a change waits for the class's lock; the session takes its changes one at a
time. Every response carries a strict Content-Security-Policy (:data:`POLICY`): scripts and
styles only from the app's own files, images only from them or ``data:`` (the answers' kept
attachments), requests only to the desk, nothing framed. What a student wrote reaches the
page only as :func:`grader.statement_html.written_html` made it (no raw HTML, no links, no
images but their own attachments), and under that policy.
"""

from __future__ import annotations

import asyncio
import json
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlencode

import tornado.web
from tornado.httpserver import HTTPServer
from tornado.ioloop import IOLoop
from tornado.netutil import bind_sockets

from eulertop.review_app import views
from eulertop.review_app.guard import Asked, Guard, Refusal
from grader.assignment import UsageError
from grader.graded_folder import RunInProgress
from grader.review import ReviewSession

HERE = Path(__file__).resolve().parent
STATIC, TEMPLATES = HERE / "static", HERE / "templates"
STATIC_FILES = frozenset(p.name for p in STATIC.iterdir() if p.is_file())
"""What ``/static/NAME`` serves: the files of ``static/``, by name."""
MAX_BODY = 1 << 20
"""Bytes a request's body may have (a review's comment is at most 20,000 characters)."""

POLICY = "; ".join((
    "default-src 'none'", "script-src 'self'", "style-src 'self'", "img-src 'self' data:",
    "connect-src 'self'", "form-action 'self'", "base-uri 'none'", "frame-ancestors 'none'"))
"""The Content-Security-Policy of every response (module docstring)."""

HEADERS = {"Content-Security-Policy": POLICY, "X-Content-Type-Options": "nosniff",
           "Referrer-Policy": "no-referrer", "X-Frame-Options": "DENY",
           "Cross-Origin-Opener-Policy": "same-origin",
           "Cross-Origin-Resource-Policy": "same-origin", "Cache-Control": "no-store"}


class Refused(tornado.web.HTTPError):
    """A request answered with ``status`` and a sentence for the person (``message``)."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(status)
        self.message = message


@dataclass
class Desk:
    """What every handler shares: the session, the guard, the worker threads."""

    session: ReviewSession
    guard: Guard
    pool: ThreadPoolExecutor


class Guarded(tornado.web.RequestHandler):
    """Every handler of the desk: the guard first, the security headers, errors as one
    sentence (JSON for the API, text for a page)."""

    page = False  # a page: opened with ?token=…, it sets the cookie and drops the token

    def initialize(self, desk: Desk, **kwargs: Any) -> None:
        self.desk = desk
        super().initialize(**kwargs)

    def set_default_headers(self) -> None:
        for name, value in HEADERS.items():
            self.set_header(name, value)

    def prepare(self) -> None:
        guard, request = self.desk.guard, self.request
        query_token = self.get_query_argument("token", None) \
            if self.page and request.method == "GET" else None
        refusal = guard.refusal(Asked(request.method, request.headers.get("Host", ""),
                                      request.headers.get("Origin"),
                                      request.headers.get("Authorization"),
                                      self.get_cookie(guard.cookie), query_token))
        if refusal is not None:
            raise Refused(refusal.status, refusal.message)
        if query_token is not None:
            self._drop_token()

    def _drop_token(self) -> None:
        """Keep the token in the desk's cookie and send the browser to the same address
        without it (it leaves the address bar and the history)."""
        self.set_cookie(self.desk.guard.cookie, self.desk.guard.token, httponly=True,
                        samesite="Strict", path="/")
        rest = {k: v[-1].decode() for k, v in self.request.query_arguments.items()
                if k != "token"}
        self.redirect(self.request.path + (f"?{urlencode(rest)}" if rest else ""))

    def write_error(self, status_code: int, **kwargs: Any) -> None:
        error = kwargs.get("exc_info", (None, None))[1]
        self.refusal = Refusal(status_code, getattr(error, "message", None) or self._reason)
        if self.request.path.startswith("/api/"):
            self.set_header("Content-Type", "application/json; charset=UTF-8")
            self.finish(json.dumps({"error": self.refusal.message}))
        else:
            self.set_header("Content-Type", "text/plain; charset=UTF-8")
            self.finish(f"{status_code}: {self.refusal.message}\n")

    async def call(self, view: Any, *args: Any) -> Any:
        """``view(session, *args)`` in a worker thread; a refusal of the desk's as 400 (409
        while another command holds the class)."""
        loop = IOLoop.current()
        try:
            return await loop.run_in_executor(self.desk.pool, view, self.desk.session, *args)
        except RunInProgress as e:
            raise Refused(409, str(e)) from None
        except UsageError as e:
            raise Refused(400, str(e)) from None

    def send(self, value: Any) -> None:
        """``value`` as JSON (no NaN; ``</`` escaped)."""
        self.set_header("Content-Type", "application/json; charset=UTF-8")
        text = json.dumps(views.plain(value), ensure_ascii=True, allow_nan=False)
        self.finish(text.replace("</", "<\\/"))

    def body(self) -> Any:
        """The request's JSON body (415 unless it says it is JSON; 400 unless it is)."""
        kind = self.request.headers.get("Content-Type", "").split(";")[0].strip().lower()
        if kind != "application/json":
            raise Refused(415, "send the body as JSON (Content-Type: application/json)")
        try:
            return json.loads(self.request.body or b"null")
        except ValueError as e:
            raise Refused(400, f"the body is not JSON: {e}") from None

    def argument(self, name: str) -> str:
        value = self.get_query_argument(name, None)
        if value is None:
            raise Refused(400, f"the query needs {name}=…")
        return value

    def names(self) -> bool:
        return self.get_query_argument("names", "0") not in ("", "0", "false")

    def render_page(self, template: str, **values: Any) -> None:
        a = self.desk.session.a
        self.render(template, title=a.title, grader=self.desk.session.grader, **values)


class Static(Guarded, tornado.web.StaticFileHandler):
    """The app's own scripts and style, guarded as every request is, and served only by
    name: a file of :data:`STATIC_FILES` or nothing (a path with ``..``, a slash, a NUL or
    an escape of one never reaches the file system)."""

    def prepare(self) -> None:
        super().prepare()
        if self.path_args[0] not in STATIC_FILES:
            raise Refused(404, "no such file of the desk's")


class Index(Guarded):
    page = True

    async def get(self) -> None:
        questions = await self.call(views.questions)
        self.render_page("index.html", questions=questions)


class Question(Guarded):
    page = True

    async def get(self, question: str) -> None:
        if question not in await self.call(lambda session: session.a.written()):
            raise Refused(404, f"no written question {question!r}; see the list at /")
        self.render_page("question.html", question=question)


class Flagged(Guarded):
    page = True

    def get(self) -> None:
        self.render_page("flagged.html")


class Api(Guarded):
    """``GET`` and ``POST`` of one API resource, by name (:data:`READINGS`, :data:`CHANGES`)."""

    async def get(self, resource: str) -> None:
        if resource not in READINGS:
            raise Refused(404, f"no API reading /api/{resource}")
        self.send(await self.call(*READINGS[resource](self)))

    async def post(self, resource: str) -> None:
        if resource not in CHANGES:
            raise Refused(404, f"no API change /api/{resource}")
        self.send(await self.call(CHANGES[resource], self.body()))


READINGS = {
    "questions": lambda h: (views.questions,),
    "progress": lambda h: (lambda s: s.progress(),),
    "written": lambda h: (views.written, h.argument("question"), h.names()),
    "pending": lambda h: (views.pending, h.argument("question")),
    "answer": lambda h: (views.answer, h.argument("id"), h.names()),
    "comments": lambda h: (views.comments, h.argument("question")),
    "flagged": lambda h: (views.flagged,),
}
"""``GET /api/NAME``: the view and its arguments from the request."""

CHANGES = {"review": views.review, "rubric": views.rubric, "comments": views.add_comment,
           "override": views.override}
"""``POST /api/NAME``: the view given the request's JSON body."""


def application(desk: Desk) -> tornado.web.Application:
    """The desk's routes (module docstring)."""
    shared = {"desk": desk}
    return tornado.web.Application([
        (r"/", Index, shared),
        (r"/question/([A-Za-z0-9_]+)", Question, shared),
        (r"/flagged", Flagged, shared),
        (r"/static/(.*)", Static, {**shared, "path": str(STATIC)}),
        (r"/api/([a-z]+)", Api, shared),
    ], template_path=str(TEMPLATES), log_function=_log, compress_response=False)


def _log(handler: tornado.web.RequestHandler) -> None:
    """One line on stderr for each refused request (who knocked, and why); nothing else."""
    refusal = getattr(handler, "refusal", None)
    if refusal is not None and refusal.status in (401, 403):
        print(f"eulertop review: refused {handler.request.method} {handler.request.path}: "
              f"{refusal.message}", file=sys.stderr)


class ReviewServer:
    """The desk bound to 127.0.0.1:``port`` (0: a free port) for ``session``.

    Parameters
    ----------
    session : ReviewSession
        The class under review.
    port : int
        The port; 0 lets the system choose a free one.
    workers : int
        Threads the session's calls run in.

    Raises
    ------
    grader.assignment.UsageError
        The port is taken, or not one to bind.
    """

    def __init__(self, session: ReviewSession, port: int = 0, workers: int = 4) -> None:
        if not 0 <= port <= 65535:  # getaddrinfo would take 70000 for 4464
            raise UsageError(f"--port {port}: a port is a number from 0 to 65535")
        try:
            self._sockets = bind_sockets(port, address="127.0.0.1")
        except (OSError, OverflowError) as e:
            raise UsageError(f"--port {port}: cannot listen on 127.0.0.1:{port} ({e})") from None
        self.guard = Guard(self._sockets[0].getsockname()[1])
        pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="review-desk")
        self.desk = Desk(session, self.guard, pool)
        self._stop: asyncio.Event | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        return self.guard.url

    async def serve(self) -> None:
        """Answer requests until :meth:`stop`."""
        self._loop, self._stop = asyncio.get_running_loop(), asyncio.Event()
        server = HTTPServer(application(self.desk), max_body_size=MAX_BODY)
        server.add_sockets(self._sockets)
        try:
            await self._stop.wait()
        finally:
            server.stop()
            await server.close_all_connections()
            self.desk.pool.shutdown(wait=True)

    def stop(self) -> None:
        """End :meth:`serve` (from any thread, or a signal handler)."""
        if self._loop is not None and self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)

    def start(self) -> ReviewServer:
        """Serve in a thread of its own (tests, benchmarks); :meth:`stop` and :meth:`join`."""
        ready = threading.Event()

        async def run() -> None:
            serving = asyncio.ensure_future(self.serve())
            await asyncio.sleep(0)
            ready.set()
            await serving

        self._thread = threading.Thread(target=asyncio.run, args=(run(),), daemon=True)
        self._thread.start()
        ready.wait(10)
        return self

    def join(self, timeout: float | None = None) -> None:
        if self._thread is not None:
            self._thread.join(timeout)
