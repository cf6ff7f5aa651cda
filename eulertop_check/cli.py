"""``eulertop-check NOTEBOOK``: the student package's command — ``eulertop check`` itself
(:mod:`grader.check`: the same arguments, run, verdicts and exit status), under its own name.

Floor 8 of the grader's front ends (grader/API.md).
"""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    """Run ``eulertop-check``; the exit status (0 all well formed, 1 not, 2 usage error)."""
    from eulertop_check import HIDDEN

    if HIDDEN is not None:
        print(f"eulertop-check: {HIDDEN}", file=sys.stderr)
        return 2
    from grader.check import add_check_arguments, run_check

    parser = argparse.ArgumentParser(
        prog="eulertop-check",
        description="Run a notebook as the grader would: are its answers all there and well "
                    "formed? (Never whether they are right.)")
    add_check_arguments(parser)
    try:
        return run_check(parser.parse_args(argv), prog="eulertop-check")
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
