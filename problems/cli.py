"""``eulertop problems`` (list, ``test``, ``preview``) and ``eulertop generate`` (dispatched from
``eulertop/cli.py``).

Top-level imports stay light so that ``eulertop --help`` is fast; the generator is imported
inside the run functions. Exit status: 0 done, 2 bad input (nothing written), 1 a template or
the file system failed (nothing written either), or a self-test found a failure.
"""

from __future__ import annotations

import argparse
import html
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

DEFAULT_TEST_SEEDS = 100
DEFAULT_PREVIEW_SEEDS = 3


def _families_option(parser: argparse.ArgumentParser, default: object = None) -> None:
    parser.add_argument("--families", action="append", type=Path, metavar="DIR",
                        default=default,
                        help="a folder of extra problem families (repeatable; "
                             "problems/API.md, 'A family')")


def add_problems_arguments(parser: argparse.ArgumentParser) -> None:
    """``eulertop problems [--families DIR]`` lists; ``test`` and ``preview`` act on one."""
    parser.description = ("List the problem families, one line each: name, where it comes "
                          "from, R-ids, summary. 'test' or 'preview' acts on one of them.")
    _families_option(parser)
    actions = parser.add_subparsers(dest="action", metavar="ACTION")
    test = actions.add_parser(
        "test", help="self-test one family over many seeds (the checks the built-ins pass)",
        description="Self-test one family: the same seed gives the same variant; answers are "
                    "finite and JSON-able; every draw is well posed or rejected; the key is "
                    "recomputed from the recorded parameters; known mistakes lie outside the "
                    "tolerance; no answer value is written in the statement; every tolerance "
                    "is stated in the notebook; time per variant; follow() gives back the "
                    "key; the statement prints each parameter as the parameter cell holds it; "
                    "the solutions notebook, run in the sandbox, gets full marks. Exit 1 on "
                    "any failure.")
    _one_family(test, DEFAULT_TEST_SEEDS)
    test.add_argument("--sandbox-seeds", type=_count, metavar="K",
                      help="run the solutions of the first K seeds in the sandbox "
                           "(default: all of them, in one notebook)")
    _families_option(test, argparse.SUPPRESS)
    preview = actions.add_parser(
        "preview", help="parameters, key and statement of a few variants, as an HTML page",
        description="Write an HTML page with each variant's parameters, key values and "
                    "statement, rendered as the feedback pages render it.")
    _one_family(preview, DEFAULT_PREVIEW_SEEDS)
    preview.add_argument("--out", type=Path, metavar="FILE",
                         help="the page to write (default: preview-NAME.html here)")
    _families_option(preview, argparse.SUPPRESS)


def _one_family(parser: argparse.ArgumentParser, seeds: int) -> None:
    """The family and seeds ``test`` and ``preview`` act on."""
    parser.add_argument("family", metavar="NAME|PATH",
                        help="a family's name, or its file (a .py file or a package folder)")
    parser.add_argument("--seeds", type=_count, default=seeds, metavar="N",
                        help=f"seeds 0 … N−1 (default {seeds})")
    parser.add_argument("--seed", type=_seed, metavar="S", help="seed S only")


def _count(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _seed(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be ≥ 0, got {value}")
    return value


def run_problems(args: argparse.Namespace, grade_solutions: Callable | None = None,
                 render: Callable[[str], str] | None = None) -> int:
    """List the families (name, where it comes from, R-ids, summary), or test or preview one.
    ``grade_solutions`` runs a solutions notebook for the self-test, ``render`` turns a
    statement into HTML for the preview: the grader's, handed in by the front end
    (:mod:`eulertop.problems_cli`)."""
    from problems.family import FamilyError

    action = getattr(args, "action", None)
    command = "eulertop problems" + (f" {action}" if action else "")
    try:
        if action == "test":
            return _test(args, grade_solutions)
        if action == "preview":
            return _preview(args, render)
        return _list(args)
    except FamilyError as e:
        print(f"{command}: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        raise  # the reader left: eulertop.cli.main says nothing and exits 141
    except OSError as e:
        print(f"{command}: {e}; nothing was written", file=sys.stderr)
        return 1


def _list(args: argparse.Namespace) -> int:
    from problems.family_files import catalogue

    families = catalogue(args.families or ())
    if not families:
        print("eulertop problems: no problem families are registered yet", file=sys.stderr)
        return 0
    origins = {name: f.origin for name, f in families.items()}
    rids = {name: ",".join(f.results) or "-" for name, f in families.items()}
    widths = [max(len(x) for x in column) for column in (families, origins.values(),
                                                          rids.values())]
    for name, family in families.items():
        print(f"{name:<{widths[0]}}  {origins[name]:<{widths[1]}}  {rids[name]:<{widths[2]}}"
              f"  {family.summary}")
    return 0


def _family(args: argparse.Namespace):
    """The family named (or whose file is given) by ``args.family``."""
    from problems.family import FamilyError
    from problems.family_files import catalogue, load_family_file

    families = catalogue(args.families or ())
    given = Path(args.family)
    if args.family in families:
        return families[args.family]
    if given.suffix == ".py" or given.is_dir() or given.exists():
        family = load_family_file(given)
        taken = families.get(family.name)
        if taken is not None:
            raise FamilyError(f"{family.where}: NAME {family.name!r} is "
                              f"{'a built-in family' if taken.origin == 'built-in' else 'taken'}"
                              f" ({taken.where}); give this family another NAME")
        return family
    raise FamilyError(f"unknown family {args.family!r} (not a file either); known: "
                      f"{', '.join(families)}")


def _seeds(args: argparse.Namespace) -> range:
    return range(args.seed, args.seed + 1) if args.seed is not None else range(args.seeds)


def _test(args: argparse.Namespace, grade_solutions: Callable | None) -> int:
    from problems.selftest import report_lines, self_test

    family = _family(args)
    report = self_test(family, _seeds(args), sandbox_seeds=args.sandbox_seeds,
                       grade_solutions=grade_solutions)
    print(f"eulertop problems test {family.name} ({family.origin}): "
          f"{len(report.seeds)} seed(s)")
    for line in report_lines(report):
        print(line)
    return 0 if report.passed else 1


def _preview(args: argparse.Namespace, render: Callable[[str], str] | None) -> int:
    from problems.files import write_text_atomically
    from problems.preview import preview_page, preview_text

    family = _family(args)
    seeds = _seeds(args)
    out = args.out if args.out is not None else Path(f"preview-{family.name}.html")
    page, variants = preview_page(family, seeds, render or html.escape)
    for line in preview_text(family, seeds, variants):
        print(line)
    write_text_atomically(out, page)
    print(f"wrote {out}")
    return 0


def add_generate_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop generate``."""
    parser.add_argument("--spec", type=Path, metavar="TOML",
                        help="an assignment spec: title, seed, roster, families, and per "
                             "question the family or pool, points, tolerances, parameters "
                             "(README, 'Your own problems'); the options below override it")
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
                             "see 'eulertop problems'); the short form of --spec")
    _families_option(parser)
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
    from problems.family import FamilyError
    from problems.generate import GenerateError, TemplateError, reroll_students
    from problems.roster import RosterError
    from problems.spec import SpecError

    try:
        if args.reroll:
            given = [f"--{o}" for o in ("roster", "seed", "problems", "title", "spec")
                     if getattr(args, o) is not None] + (["--force"] if args.force else [])
            if given:
                raise GenerateError(f"--reroll uses the assignment's own roster, seed, problems "
                                    f"and title: drop {', '.join(given)}")
            from problems.family_files import catalogue

            summary = reroll_students(args.out, args.reroll, catalogue(args.families or ()),
                                      progress=_progress)
        else:
            summary = _generate(args, class_lists)
    except (GenerateError, RosterError, SpecError, FamilyError) as e:
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


def _generate(args: argparse.Namespace, class_lists: Mapping[str, Any] | None = None):
    """A new assignment from the options, or from ``--spec`` (which they override)."""
    from problems.family_files import catalogue
    from problems.generate import GenerateError, Question, generate_assignment
    from problems.roster import read_roster
    from problems.spec import check_spec, read_spec

    spec = None if args.spec is None else read_spec(args.spec)
    if spec is not None and args.problems is not None:
        raise GenerateError("give the questions either in --spec or by --problems, not both")
    folders = [*(spec.families if spec else ()), *(args.families or ())]
    families = catalogue(folders)
    roster_path = args.roster if args.roster is not None else (spec.roster if spec else None)
    if roster_path is None:
        raise GenerateError("--roster CSV is required (or roster = \"...\" in --spec, or "
                            "--reroll ID on an existing HW)")
    questions = None
    if spec is not None:
        check_spec(spec, families)
        questions = tuple(Question(q.label, q.pool, q.settings, q.written, q.title)
                          for q in spec.questions)
    problems = None if args.problems is None else args.problems.split(",")
    roster = read_roster(roster_path, getattr(args, "roster_format", None), class_lists)
    for note in roster.notes:
        print(f"eulertop generate: {note}", file=sys.stderr)
    seed = args.seed if args.seed is not None else (spec.seed if spec else None)
    title = args.title if args.title is not None else (spec.title if spec else None)
    return generate_assignment(
        roster, args.out, families, problems=problems, questions=questions,
        spec_file=None if spec is None else spec.path, seed=seed, title=title,
        follow_through=None if spec is None else spec.follow_through,
        late=None if spec is None else spec.late,
        install=None if spec is None else spec.install,
        force=args.force, progress=_progress,
    )


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
