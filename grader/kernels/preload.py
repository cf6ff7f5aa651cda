"""What a class's zygotes preload (floor 2): the packages its notebooks' code imports, read
from the submissions, out of a fixed list.

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import re
from collections.abc import Iterable

PRELOADABLE: dict[str, tuple[str, ...]] = {
    "numpy": ("numpy",),
    "scipy": ("scipy", "scipy.linalg", "scipy.special", "scipy.integrate", "scipy.optimize"),
    "sympy": ("sympy",),
    "matplotlib": ("matplotlib", "matplotlib.pyplot"),
}
"""What a zygote may import for the class, by the package a notebook imports (numpy, scipy
and sympy are the zygote's default, :data:`grader.kernels.zygote.PRELOAD`). Nothing else is ever
preloaded: the list is fixed here, whatever a notebook names."""


_IMPORT_LINE = re.compile(r"^\s*(?:from|import)\s+(.+)$", re.MULTILINE)


_PACKAGE = re.compile(r"\b(" + "|".join(PRELOADABLE) + r")\b")


def packages_imported(notebook: bytes) -> set[str]:
    """Which of :data:`PRELOADABLE`'s packages a notebook's code cells import (``import`` and
    ``from`` lines; the assignment's own Markdown names numpy and sympy, so only code counts).
    A notebook that cannot be read gives none (the run itself will say what is wrong)."""
    from grader.notebook_load import notebook_json

    try:  # parsed within the limits every reader of a submission keeps
        cells = notebook_json(notebook).get("cells", [])
        code = "\n".join(
            "".join(c["source"]) if isinstance(c["source"], list) else c["source"]
            for c in cells if isinstance(c, dict) and c.get("cell_type") == "code")
        lines = _IMPORT_LINE.findall(code)
    except Exception:
        return set()
    return {name for line in lines for name in _PACKAGE.findall(line)}


def preload_for(packages: Iterable[str]) -> tuple[str, ...]:
    """The modules the zygotes import for a class whose notebooks import ``packages``
    (:func:`packages_imported`): numpy always; scipy's, sympy's or matplotlib's modules if
    asked for.

    Every kernel then has them without importing them (sympy alone is 0.3 s of CPU a kernel;
    a notebook drawing one figure took 0.5 s of CPU with ``import matplotlib.pyplot`` in the
    kernel, 0.016 s with it preloaded), and a class that uses none of them does not make each
    zygote pay for them (0.5 s of CPU at its start, and a larger process to fork for every
    notebook). An import this does not see (``exec``, ``importlib``) only costs that kernel
    the import; nothing else changes.
    """
    wanted = {"numpy", *packages}
    return tuple(m for package in PRELOADABLE if package in wanted for m in PRELOADABLE[package])
