"""``eulertop generate``: the generator of :mod:`problems.cli`, with the LMS class lists a roster
may be (their formats are :mod:`grader.lms`'s, a floor above the generator's: composed here,
at the front)."""

from __future__ import annotations

import argparse

from problems.cli import add_generate_arguments

__all__ = ["add_generate_arguments", "run_generate"]


def run_generate(args: argparse.Namespace) -> int:
    """Run ``eulertop generate`` (:func:`problems.cli.run_generate`)."""
    from grader.lms.registry import CLASS_LISTS
    from problems.cli import run_generate as run

    return run(args, CLASS_LISTS)
