"""``eulertop new-family NAME --out DIR``: a working, commented example family to start from.

It writes ``DIR/NAME.py``: a copy of :mod:`eulertop.family_example` (a ball thrown over level
ground — not about rigid bodies, so that it shows the family API rather than the lecture) with
its ``NAME`` changed. The copy passes ``eulertop problems test DIR/NAME.py`` as written. Nothing
is written when ``NAME`` is not a Python identifier, is taken by a built-in family, or when
``DIR/NAME.py`` exists. Exit status: 0 written, 2 refused, 1 the file system failed.
"""

from __future__ import annotations

import argparse
import keyword
import sys
from pathlib import Path

EXAMPLE_NAME = 'NAME = "projectile"'
"""The line of the example that names it."""


def add_new_family_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop new-family``."""
    parser.add_argument("name", metavar="NAME", help="the new family's name (a Python "
                        "identifier, not a built-in family's)")
    parser.add_argument("--out", type=Path, required=True, metavar="DIR",
                        help="the folder to write NAME.py into (made if missing)")


def example_text(name: str) -> str:
    """The example family's source with its ``NAME`` set to ``name``."""
    source = Path(__file__).with_name("family_example.py").read_text(encoding="utf-8")
    if source.count(EXAMPLE_NAME) != 1:  # pragma: no cover - guards the example's edits
        raise RuntimeError("family_example.py must name itself exactly once")
    return source.replace(EXAMPLE_NAME, f'NAME = "{name}"')


def run_new_family(args: argparse.Namespace) -> int:
    """Write ``DIR/NAME.py``; say what to do next."""
    from problems.files import write_text_atomically
    from problems.templates import FAMILIES

    name, out = args.name, args.out
    problem = None
    if not name.isidentifier() or keyword.iskeyword(name):
        problem = f"{name!r} is not a Python identifier (letters, digits, _)"
    elif name in FAMILIES:
        problem = f"{name!r} is a built-in family; choose another name"
    elif (out / f"{name}.py").exists():
        problem = f"{out / f'{name}.py'} exists; nothing was written"
    if problem:
        print(f"eulertop new-family: {problem}", file=sys.stderr)
        return 2
    path = out / f"{name}.py"
    try:
        write_text_atomically(path, example_text(name))
    except OSError as e:
        print(f"eulertop new-family: {e}; nothing was written", file=sys.stderr)
        return 1
    print(f"wrote {path}: a ball thrown over level ground, to edit into your own problem")
    print(f"  check it:      eulertop problems test {path}")
    print(f"  look at it:    eulertop problems preview {path}")
    print(f"  use it:        eulertop generate --families {out} --problems {name},... "
          "--roster roster.csv --out HW")
    return 0


def __getattr__(attribute: str):
    """``eulertop/cli.py`` looks up ``add_new-family_arguments`` and ``run_new-family`` (the
    command's own spelling)."""
    if "-" in attribute:
        return globals()[attribute.replace("-", "_")]
    raise AttributeError(attribute)
