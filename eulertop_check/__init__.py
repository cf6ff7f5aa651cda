"""Check an eulertop notebook from inside it (issue 33): ``import eulertop_check;
eulertop_check.check()`` in any cell.

:func:`check` reads the answers *live* in this kernel against the notebook's public answer list
(what ``eulertop generate`` recorded in its metadata: names, kinds, lengths, units, symbols,
options — never a key value) and says of each: ok, missing, or malformed and why — never right
or wrong. ``check(run=True)`` also runs the *saved* notebook as the grader does and says where
it differs from this kernel. The terminal command is ``eulertop-check NOTEBOOK``
(:mod:`eulertop_check.cli`), the same check as the full package's ``eulertop check``.

This module imports nothing heavy: :mod:`eulertop_check.live` is imported when ``check`` runs.

Floor 8 of the grader's front ends (grader/API.md), in a room of its own: the student package.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["check"]


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
    from eulertop_check.live import live_check

    return live_check(notebook, run=run, max_size=max_size)
