"""``eulertop review``: the review desk, a local web app for scoring written answers by rubric
and looking through the answers the grader flagged (issue 31).

A room of its own above ``grader/`` (tests/test_layout.py): it reads and changes a graded
class only through :class:`grader.review.ReviewSession` — the same records, overrides, reviews,
lock, transactions and audit trail as every command — and nothing in ``grader/`` imports it.
Its templates (``templates/``) and static files (``static/``) sit beside it, installed with it
as package data.

Modules: :mod:`~eulertop.review_app.guard` (the token, ``Host`` and ``Origin`` checks),
:mod:`~eulertop.review_app.views` (what each API call answers),
:mod:`~eulertop.review_app.server` (Tornado: routes, headers, the server),
:mod:`~eulertop.review_app.cli` (the subcommand). docs/instructors/review.md is the user's
page; grader/API.md says why Tornado.
"""
