"""``eulertop review HW [--port P] [--grader NAME] [--no-browser] [--out DIR]``: the review
desk for one graded class, until Ctrl-C (issue 31; docs/instructors/review.md).

It loads the class (:class:`grader.review.ReviewSession`), listens on 127.0.0.1, prints the
address with its token, as Jupyter does, and opens it in the browser — through a private file
that redirects to it, so that the token is not on a command line another user can read.
Ctrl-C (or SIGTERM) stops it: the class report is rebuilt once, if anything changed. Exit
status 0, or 2 on usage errors (one line, no traceback).
"""

from __future__ import annotations

import argparse
import asyncio
import html
import os
import signal
import sys
import tempfile
import webbrowser
from pathlib import Path
from typing import TYPE_CHECKING

from grader.review import WAIT

if TYPE_CHECKING:
    from eulertop.review_app.server import ReviewServer
    from grader.review import ReviewSession


def add_review_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop review``."""
    parser.add_argument("hw", type=Path, metavar="HW",
                        help="assignment folder written by 'eulertop generate', graded")
    parser.add_argument("--out", type=Path, metavar="DIR",
                        help="grading output folder (default: HW/graded)")
    parser.add_argument("--port", type=int, default=0, metavar="P",
                        help="port on 127.0.0.1 (default: a free one)")
    parser.add_argument("--grader", metavar="NAME",
                        help="who reviews: each review and override is signed with it "
                             "(default: your user name)")
    parser.add_argument("--no-browser", action="store_true",
                        help="print the address; do not open a browser")
    parser.add_argument("--reveal", action="store_true",
                        help="feedback pages rewritten with each student's key values "
                             "(as 'eulertop grade --reveal')")
    parser.add_argument("--wait", type=float, default=WAIT, metavar="SECONDS",
                        help="how long a change waits for another command holding the class "
                             f"(default {WAIT:g})")


def run_review(args: argparse.Namespace) -> int:
    """Run ``eulertop review``: serve until stopped, then close the session."""
    from grader.assignment import UsageError

    try:
        session, server = _desk(args)
    except UsageError as e:
        print(f"eulertop review: {e}", file=sys.stderr)
        return 2
    _announce(session, server.url)
    opener = None if args.no_browser else _open(server.url)
    try:
        asyncio.run(_until_stopped(server))
    finally:
        if opener is not None:
            opener.unlink(missing_ok=True)
        print("eulertop review: stopping; the class report is rebuilt if anything changed",
              flush=True)
        session.close()
    return 0


def _desk(args: argparse.Namespace) -> tuple[ReviewSession, ReviewServer]:
    """The class loaded and the server bound (UsageError: either cannot be)."""
    from eulertop.review_app.server import ReviewServer
    from grader.assignment import UsageError
    from grader.review import ReviewSession

    session = ReviewSession(args.hw, args.out, grader=args.grader, reveal=args.reveal,
                            wait=args.wait)
    try:
        return session, ReviewServer(session, args.port)
    except UsageError:
        session.close()
        raise


def _announce(session: ReviewSession, url: str) -> None:
    questions = session.questions()
    print(f"eulertop review: {session.a.title}: {len(questions)} written question(s), "
          f"{len(session.a.ids)} student(s), reviewing as {session.grader}")
    print(f"    {url}")
    print("Open that address (its token is the key to the desk); Ctrl-C stops it.", flush=True)


async def _until_stopped(server: ReviewServer) -> None:
    """Serve until SIGINT or SIGTERM (then :meth:`ReviewServer.stop`)."""
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, server.stop)
    await server.serve()


def _open(url: str) -> Path | None:
    """Open ``url`` in the browser through a private file that redirects to it (mode 0600);
    the file, or None where no browser could be started."""
    fd, name = tempfile.mkstemp(prefix="eulertop-review-", suffix=".html")
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><meta '
                f'http-equiv="refresh" content="0;url={html.escape(url)}"><title>Review '
                f'desk</title></head><body><a href="{html.escape(url)}">Open the review '
                "desk</a></body></html>\n")
    path = Path(name)
    if not webbrowser.open(path.as_uri(), new=2):
        print("eulertop review: no browser could be opened; open the address above",
              file=sys.stderr)
        path.unlink(missing_ok=True)
        return None
    return path
