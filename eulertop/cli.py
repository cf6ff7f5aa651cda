"""The `eulertop` console script: one subcommand per part, each implemented beside its part.

Subcommand modules are imported lazily so that `eulertop --help` stays fast.
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import importlib
import os
import sys

# subcommand -> (module, one-line help). The module defines `add_<name>_arguments(parser)` and
# `run_<name>(args) -> int` (exit status), so one module may serve several subcommands.
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "solve": ("solver.cli", "answer one rigid-body scene, or a JSON-lines batch of them"),
    "problems": ("eulertop.problems_cli",
                 "list the problem families; 'test' or 'preview' one of them"),
    "new-family": ("eulertop.new_family", "write a working, commented example family to edit"),
    "generate": ("eulertop.generate",
                 "generate an assignment: one notebook per student, and the key"),
    "check": ("grader.cli", "run a notebook as the grader would: are its answers well formed?"),
    "grade": ("grader.cli", "grade every submission against the key: gradebook, feedback, summary"),
    "rescore": ("grader.amend", "every verdict again from the stored answers and the key as it "
                "is now: no notebook runs"),
    "key": ("grader.amend", "change the key after grading ('key set'), then rescore"),
    "rekey": ("grader.amend", "recompute the key from the recorded parameters with today's "
              "solver, then rescore"),
    "override": ("grader.amend", "give one student's answer (or total) points, with a reason; "
                 "kept through every regrade"),
    "review": ("eulertop.review_app.cli", "the review desk: score written answers by rubric "
               "and look through flagged ones, in the browser"),
    "late": ("grader.amend", "the deadline, late penalty and extensions ('late set', 'late "
             "extend'), then rescore"),
    "export": ("grader.lms.export", "write the gradebook Canvas, Moodle, Blackboard or Gradescope "
               "imports, and answers.csv"),
    "report": ("grader.report.cli", "the class report: item statistics, common wrong answers, "
               "copied answers"),
    "package": ("grader.hosted.package", "build the autograder for Gradescope (a zip) or a "
                "PrairieLearn question (a folder)"),
    "bench": ("solver.bench.cli", "work-precision charts and the stability battery"),
    "demo": ("eulertop.demo", "the whole pipeline on a built-in sample class, end to end"),
    "doctor": ("grader.doctor", "what this machine allows the grader: Python, bubblewrap, user "
               "namespaces, the isolation tier grade would use (starts one kernel)"),
}

ONE_BLAS_THREAD = ("check", "grade")
"""Subcommands whose own numerical work is tiny (comparing answers) while the machine's cores
run students' kernels: BLAS gets one thread (set before numpy is imported; a user's own
setting wins). OpenBLAS's idle threads otherwise spin after each call: in a profile of one
grading of 50 notebooks (``perf record -a``), 114 ms of the grader's CPU was in OpenBLAS with
its default threads, under 2 ms with one."""

BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


QUICK_EXIT = ("grade",)
"""Subcommands whose process ends without tearing its interpreter down (:func:`script`):
every file they write is written whole and closed by then (atomically, by the one writer of
records), and what the interpreter's teardown would do — free each module of numpy, scipy and
matplotlib one by one — took 0.15 s of every ``eulertop grade`` (issue 34)."""


def version() -> str:
    """The installed eulertop version (``0+unknown`` when run from a source tree not installed)."""
    from importlib import metadata

    try:
        return metadata.version("eulertop")
    except metadata.PackageNotFoundError:
        return "0+unknown"


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (the others just list their help)."""
    parser = argparse.ArgumentParser(
        prog="eulertop",
        description="Autograder and problem generator for rigid-body rotation.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_text) in SUBCOMMANDS.items():
        sp = sub.add_parser(name, help=help_text, description=help_text)
        if name == command:
            getattr(importlib.import_module(module), f"add_{name}_arguments")(sp)
        sp.set_defaults(_module=module)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one subcommand; its exit status (130 on Ctrl-C, 141 when stdout's reader left)."""
    try:
        status = _dispatch(sys.argv[1:] if argv is None else list(argv))
        sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's exit flush
        return status
    except BrokenPipeError:
        # `eulertop problems | head -1`: the reader closed the pipe. Say nothing (there is no
        # one to say it to), and point stdout at /dev/null so the interpreter's final flush at
        # exit does not raise again; 141 = 128 + SIGPIPE, what a shell reports for such a cut.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return 141


def script() -> int:
    """The console script and ``python -m eulertop``: :func:`main`; for a subcommand of
    :data:`QUICK_EXIT`, once every thread is joined and every other exit handler has run
    (this one, registered first, runs last), the streams are flushed and the process ends
    with its status at once, without the interpreter's teardown."""
    status: list[int] = []
    command = next((a for a in sys.argv[1:] if a in SUBCOMMANDS), None)
    if command in QUICK_EXIT:
        atexit.register(_leave, status)
    status.append(main())
    return status[0]


def _leave(status: list[int]) -> None:
    """At exit, after every other handler: flush the streams and end with ``status``."""
    if not status:
        return  # main() raised: the interpreter reports it and ends as usual
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):
            stream.flush()
    os._exit(status[0])


def _innermost(parser: argparse.ArgumentParser,
               args: argparse.Namespace) -> argparse.ArgumentParser:
    """The parser of the innermost subcommand ``args`` name (``eulertop key set``'s for
    ``key set``), ``parser`` itself if none."""
    while True:
        chosen = [action.choices[getattr(args, action.dest)] for action in parser._actions
                  if isinstance(action, argparse._SubParsersAction)
                  and getattr(args, action.dest, None) in action.choices]
        if not chosen:
            return parser
        parser = chosen[0]


def _dispatch(argv: list[str]) -> int:
    parser = build_parser(next((a for a in argv if a in SUBCOMMANDS), None))
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # said by the (sub)command given them, with its usage, not eulertop's
        _innermost(parser, args).error(f"unrecognized arguments: {' '.join(unknown)}")
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    if args.command in ONE_BLAS_THREAD and "numpy" not in sys.modules:
        for variable in BLAS_THREAD_VARIABLES:
            os.environ.setdefault(variable, "1")
    try:
        return int(getattr(importlib.import_module(args._module), f"run_{args.command}")(args))
    except KeyboardInterrupt:
        print("eulertop: interrupted", file=sys.stderr)
        return 130
