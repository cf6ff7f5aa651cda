"""The `eulertop` console script: one subcommand per part, each implemented beside its part.

Subcommand modules are imported lazily so that `eulertop --help` stays fast.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# subcommand -> (module, one-line help). The module defines `add_<name>_arguments(parser)` and
# `run_<name>(args) -> int` (exit status), so one module may serve several subcommands.
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "solve": ("solver.cli", "answer one rigid-body scene, or a JSON-lines batch of them"),
    "problems": ("problems.cli", "list the problem families, one line each"),
    "generate": ("problems.cli", "generate an assignment: one notebook per student, and the key"),
    "check": ("grader.cli", "run a notebook as the grader would: are its answers well formed?"),
    "grade": ("grader.cli", "grade every submission against the key: gradebook, feedback, summary"),
    "report": ("grader.report.cli", "the class report: item statistics, common wrong answers, "
               "copied answers"),
    "bench": ("solver.work_precision", "work-precision charts and the stability battery"),
    "demo": ("eulertop.demo", "the whole pipeline on a built-in sample class, end to end"),
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (the others just list their help)."""
    parser = argparse.ArgumentParser(
        prog="eulertop",
        description="Autograder and problem generator for rigid-body rotation.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_text) in SUBCOMMANDS.items():
        sp = sub.add_parser(name, help=help_text, description=help_text)
        if name == command:
            getattr(importlib.import_module(module), f"add_{name}_arguments")(sp)
        sp.set_defaults(_module=module)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(next((a for a in argv if a in SUBCOMMANDS), None))
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(getattr(importlib.import_module(args._module), f"run_{args.command}")(args))
    except KeyboardInterrupt:
        print("eulertop: interrupted", file=sys.stderr)
        return 130
