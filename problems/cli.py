"""``eulertop problems`` and ``eulertop generate`` (dispatched from ``eulertop/cli.py``).

Top-level imports stay light so that ``eulertop --help`` is fast; the generator is imported
inside the run functions. Exit status: 0 done, 2 bad input (nothing written), 1 a template or
the file system failed (nothing written either).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any


def add_problems_arguments(parser: argparse.ArgumentParser) -> None:
    """``eulertop problems`` takes no arguments."""


def run_problems(args: argparse.Namespace) -> int:
    """Print one line per registered family: name, R-ids, summary."""
    from problems.templates import FAMILIES

    if not FAMILIES:
        print("eulertop problems: no problem families are registered yet", file=sys.stderr)
        return 0
    width = max(len(name) for name in FAMILIES)
    rids = {name: ",".join(m.RESULTS) for name, m in FAMILIES.items()}
    rwidth = max(len(r) for r in rids.values())
    for name, module in FAMILIES.items():
        print(f"{name:<{width}}  {rids[name]:<{rwidth}}  {module.SUMMARY}")
    return 0


def add_generate_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop generate``."""
    parser.add_argument("--roster", type=Path, metavar="CSV",
                        help="class list: UTF-8 CSV with a header and a column 'id', or the "
                             "class list Canvas, Moodle, Blackboard or Gradescope exports "
                             "(recognised from its header)")
    parser.add_argument("--roster-format", metavar="FORMAT",
                        choices=("eulertop", "canvas", "moodle", "blackboard", "gradescope"),
                        help="read --roster as this format instead of recognising it: "
                             "eulertop, canvas, moodle, blackboard, gradescope")
    parser.add_argument("--out", type=Path, required=True, metavar="HW",
                        help="assignment folder to write (must not exist, unless --force)")
    parser.add_argument("--seed", type=int, metavar="N",
                        help="assignment seed (default: a fresh one, reported and stored)")
    parser.add_argument("--problems", metavar="a,b,...",
                        help="comma-separated families, in question order (default: all; "
                             "see 'eulertop problems')")
    parser.add_argument("--title", metavar="T", help="assignment title (default: the folder name)")
    parser.add_argument("--reroll", action="append", metavar="ID",
                        help="give student ID a fresh variant in the existing HW, keeping "
                             "everything else byte for byte (repeatable; takes only --out)")
    parser.add_argument("--force", action="store_true",
                        help="replace an existing HW written by 'eulertop generate' (keeps its "
                             "seed when --seed is not given, and its reroll counts)")


def _progress(done: int, total: int) -> None:
    # A counter line for interactive runs only: logs and tests get the summary alone.
    if sys.stderr.isatty():
        end = "\n" if done == total else ""
        print(f"\r  {done}/{total} students", end=end, file=sys.stderr, flush=True)


def run_generate(args: argparse.Namespace, class_lists: Mapping[str, Any] | None = None) -> int:
    """Run ``eulertop generate``; see ``problems.generate`` for what it writes. ``class_lists``:
    the LMS class-list formats a roster may be (:func:`problems.roster.read_roster`)."""
    from problems.generate import (
        GenerateError,
        TemplateError,
        generate_assignment,
        reroll_students,
    )
    from problems.roster import RosterError, read_roster
    from problems.templates import FAMILIES

    try:
        if args.reroll:
            given = [f"--{o}" for o in ("roster", "seed", "problems", "title")
                     if getattr(args, o) is not None] + (["--force"] if args.force else [])
            if given:
                raise GenerateError(f"--reroll uses the assignment's own roster, seed, problems "
                                    f"and title: drop {', '.join(given)}")
            summary = reroll_students(args.out, args.reroll, FAMILIES, progress=_progress)
        else:
            if args.roster is None:
                raise GenerateError("--roster CSV is required (or --reroll ID on an existing HW)")
            problems = None if args.problems is None else args.problems.split(",")
            roster = read_roster(args.roster, getattr(args, "roster_format", None), class_lists)
            for note in roster.notes:
                print(f"eulertop generate: {note}", file=sys.stderr)
            summary = generate_assignment(
                roster, args.out, FAMILIES, problems=problems, seed=args.seed,
                title=args.title, force=args.force, progress=_progress,
            )
    except (GenerateError, RosterError) as e:
        print(f"eulertop generate: {e}", file=sys.stderr)
        return 2
    except (TemplateError, OSError) as e:
        print(f"eulertop generate: {e}; nothing was written", file=sys.stderr)
        return 1
    for note in summary.notes:
        print(f"eulertop generate: {note}", file=sys.stderr)
    verb = "rerolled" if args.reroll else "generated"
    print(f"{verb} {len(summary.students)} student(s) × {len(summary.problems)} question(s) "
          f"in {summary.out} (seed {summary.seed})")
    print(where_things_are(summary.out))
    return 0


def where_things_are(out: Path) -> str:
    """The lines ``eulertop generate`` ends with: what is in ``out``, and what to hand out."""
    from problems.generate import KEY, RELEASE, SOLUTIONS

    return "\n".join([
        f"  student notebooks: {out / RELEASE}/  <- hand out this folder: each student gets "
        "their own <id>.ipynb",
        f"  solutions:         {out / SOLUTIONS}/  (instructor only: answers filled in)",
        f"  answer key:        {out / KEY}  (instructor only: keep it for "
        f"'eulertop grade {out} SUBMISSIONS')",
    ])
