"""Check an eulertop notebook from inside it (issue 33): ``import eulertop_check;
eulertop_check.check()`` in any cell.

:func:`check` reads the answers *live* in this kernel against the notebook's public answer list
(what ``eulertop generate`` recorded in its metadata: names, kinds, lengths, units, symbols,
options — never a key value) and says of each: ok, missing, or malformed and why — never right
or wrong. ``check(run=True)`` also runs the *saved* notebook as the grader does and says where
it differs from this kernel. The terminal command is ``eulertop-check NOTEBOOK``
(:mod:`eulertop_check.cli`), the same check as the full package's ``eulertop check``.

This module imports nothing heavy: :mod:`eulertop_check.live` is imported when ``check`` runs.

The student package installs no other top-level package: the modules it shares with the full
``eulertop`` (of ``grader``, ``problems``, ``eulertop_base``) are in ``_shared/`` beside this file
(``student/setup.py``), put on ``sys.path`` here — at its end, and only where one of those names
is not found — so that an installed ``eulertop`` (or an editable one) keeps its own, and the
student's kernels see none of them. :data:`HIDDEN` says when another module of one of those
names hides what the check needs.

Floor 8 of the grader's front ends (grader/API.md), in a room of its own: the student package.
"""

from __future__ import annotations

import sys
from importlib.util import find_spec
from pathlib import Path
from typing import Any

__all__ = ["check"]

SHARED_FOLDER = Path(__file__).with_name("_shared")
"""The shared modules' folder in the student package (absent where the full package runs)."""

SHARED = ("eulertop_base", "grader", "problems")
"""The top-level names of the shared modules."""

NEEDED = ("eulertop_base", "grader.check", "problems.answers")
"""What the check imports of them, first."""


def _found(name: str) -> Any:
    try:
        return find_spec(name)
    except ImportError:  # a parent that is a module, not a package
        return None


def _share() -> str | None:
    """Put the shared modules on ``sys.path`` (appended: whatever is found first keeps its
    name) where one of their names is not found; what hides one the check needs, or None."""
    if SHARED_FOLDER.is_dir() and any(_found(name) is None for name in SHARED):
        sys.path.append(str(SHARED_FOLDER))
    missing = [name for name in NEEDED if _found(name) is None]
    return _why_missing(missing[0].partition(".")[0]) if missing else None


def _why_missing(top: str) -> str:
    """Why the shared package ``top`` cannot be imported, for the student."""
    spec = _found(top)
    if spec is None:  # its folder is gone
        return f"eulertop's own {top!r} is missing: install eulertop-check again"
    where = spec.origin or next(iter(spec.submodule_search_locations or ()), "?")
    return (f"another module named {top!r} ({where}) hides eulertop's own: rename it, "
            "or install eulertop-check in a virtual environment of its own")


HIDDEN = _share()
"""Why the check cannot run here (another module of a shared name found first), or None."""


def check(notebook: str | Path | None = None, *, run: bool = False,
          max_size: int | None = None) -> Any:
    """Check this notebook's answers: a table (HTML in a notebook, text elsewhere).

    Parameters
    ----------
    notebook : str or Path, optional
        The notebook's file. By default it is found where the front end says: JupyterLab and
        Notebook 7 (``JPY_SESSION_NAME``, or the Jupyter server's sessions), VS Code
        (``__vsc_ipynb_file__``), Colab (the notebook Colab holds).
    run : bool
        Also run the saved notebook as the grader does (a fresh kernel, the grader's limits)
        and say where it gives other answers than this kernel. The notebook is never saved
        for you: save it first.
    max_size : int, optional
        Largest notebook read, bytes (``--max-size``; default 20 MiB).

    Returns
    -------
    eulertop_check.live.LiveCheck
        Shown as a table; ``.all_well_formed`` and ``.rows`` for code.
    """
    from eulertop_check.live import CheckError, live_check

    if HIDDEN is not None:
        raise CheckError(HIDDEN)
    return live_check(notebook, run=run, max_size=max_size)
