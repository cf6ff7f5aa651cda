"""``eulertop problems`` (list, ``test``, ``preview``): :mod:`problems.cli`, with the grader's
pieces it needs — the self-test's run of a solutions notebook in the sandbox
(:func:`grader.selftest_run.grade_solutions`) and the feedback pages' renderer
(:func:`grader.statement_html.statement_html`) — composed here, at the front (``problems/``
sits below ``grader/``)."""

from __future__ import annotations

import argparse

from problems.cli import add_problems_arguments

__all__ = ["add_problems_arguments", "run_problems"]


def run_problems(args: argparse.Namespace) -> int:
    """Run ``eulertop problems`` (:func:`problems.cli.run_problems`)."""
    from grader.selftest_run import grade_solutions
    from grader.statement_html import statement_html
    from problems.cli import run_problems as run

    return run(args, grade_solutions, statement_html)
